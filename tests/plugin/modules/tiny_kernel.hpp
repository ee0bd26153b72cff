#pragma once
// A minimal kernel for the loader tests' modules: a Gaussian of width 1 whose name and parameter
// declarations each module chooses.
#include <cmath>

#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs::test_plugins {

template <class Declaration>
struct TinyKernel {
  static PluginInfo info() { return Declaration::info(); }
  TinyKernel(const ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    const double d = domain_.difference(x, y);
    return std::exp(-d * d);
  }
  KernelProperties properties() const noexcept {
    KernelProperties p;
    p.analytic = true;
    p.periodic = domain_.periodic;
    return p;
  }
  Domain domain_;
};

}  // namespace rkhs::test_plugins
