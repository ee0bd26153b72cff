// A kernel compiled as if it were a built-in: it registers while dlopen runs, before the loader
// could check the module's ABI. The loader must notice and refuse the module.
#undef RKHS_BUILDING_PLUGIN
#include "tiny_kernel.hpp"

namespace {
struct Early {
  static rkhs::PluginInfo info() {
    return {"registers_early_kernel", "registered too early", {}, {}};
  }
};
}  // namespace

RKHS_REGISTER_KERNEL(rkhs::test_plugins::TinyKernel<Early>)
