// A plugin registering a kernel named like a built-in: refused as a duplicate name.
#include "rkhs/plugin/module.hpp"
#include "tiny_kernel.hpp"

namespace {
struct SecondGaussian {
  static rkhs::PluginInfo info() { return {"gaussian", "a second 'gaussian'", {}, {}}; }
};
}  // namespace

RKHS_REGISTER_KERNEL(rkhs::test_plugins::TinyKernel<SecondGaussian>)
RKHS_PLUGIN_MODULE("duplicate_kernel_name")
