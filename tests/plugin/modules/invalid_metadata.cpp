// A plugin whose parameter declaration is invalid (its default is out of its own range), next to
// a valid kernel: the whole module is refused and the valid kernel is rolled back.
#include "rkhs/plugin/module.hpp"
#include "tiny_kernel.hpp"

namespace {
struct Valid {
  static rkhs::PluginInfo info() { return {"valid_before_invalid", "valid", {}, {}}; }
};
struct Invalid {
  static rkhs::PluginInfo info() {
    return {"invalid_metadata_kernel",
            "a width with a negative default",
            {rkhs::positive_parameter("width", -1.0, "must be > 0")},
            {}};
  }
};
}  // namespace

RKHS_REGISTER_KERNEL(rkhs::test_plugins::TinyKernel<Valid>)
RKHS_REGISTER_KERNEL(rkhs::test_plugins::TinyKernel<Invalid>)
RKHS_PLUGIN_MODULE("invalid_metadata")
