// A plugin whose info() throws, next to a valid kernel: the module is refused with the
// exception's message, and the valid kernel is rolled back.
#include <stdexcept>

#include "rkhs/plugin/module.hpp"
#include "tiny_kernel.hpp"

namespace {
struct Valid {
  static rkhs::PluginInfo info() { return {"valid_before_throwing", "valid", {}, {}}; }
};
struct Throws {
  static rkhs::PluginInfo info() { throw std::runtime_error("cannot read the declaration"); }
};
}  // namespace

RKHS_REGISTER_KERNEL(rkhs::test_plugins::TinyKernel<Valid>)
RKHS_REGISTER_KERNEL(rkhs::test_plugins::TinyKernel<Throws>)
RKHS_PLUGIN_MODULE("info_throws")
