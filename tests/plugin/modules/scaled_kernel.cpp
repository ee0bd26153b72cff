// A Gaussian kernel of width RKHS_TEST_KERNEL_WIDTH, a constant of the source: the same module
// built twice with two widths (scaled_kernel_1, scaled_kernel_2), as a user rebuilds a plugin
// after changing a constant. Trials it computed must not be reused from the store once the
// module changed (run/trial_identity.hpp; tests/cli/test_store_cli.cpp).
#include <cmath>

#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/plugin/module.hpp"

#ifndef RKHS_TEST_KERNEL_WIDTH
#error "RKHS_TEST_KERNEL_WIDTH is defined by tests/plugin/CMakeLists.txt"
#endif

namespace {

struct ScaledGaussian {
  static rkhs::PluginInfo info() {
    return {"scaled_gaussian", "a Gaussian of a width fixed when the module is built", {}, {}};
  }
  ScaledGaussian(const rkhs::ParameterSet&, const rkhs::Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    const double d = domain_.difference(x, y) / RKHS_TEST_KERNEL_WIDTH;
    return std::exp(-d * d);
  }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.analytic = true;
    p.periodic = domain_.periodic;
    return p;
  }
  rkhs::Domain domain_;
};

}  // namespace

RKHS_REGISTER_KERNEL(ScaledGaussian)
RKHS_PLUGIN_MODULE("scaled_kernel")
