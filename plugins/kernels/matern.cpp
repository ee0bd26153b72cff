#include "rkhs/kernels/matern.hpp"

#include <fmt/format.h>

#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs::kernels {

PluginInfo Matern::info() {
  auto nu = real_parameter("nu", 1.5, "smoothness nu (half-integer); Sobolev order tau = nu + d/2");
  nu.allowed = {0.5, 1.5, 2.5};
  return {
      "matern",
      "Matern kernel with nu = 1/2, 3/2, 5/2 (scikit-learn convention), periodised by images",
      {nu, positive_parameter("length_scale", 1.0, "length scale l, metres")},
      {{"periodic", "sum of all images, in closed form"}},
  };
}

Matern::Matern(const ParameterSet& parameters, const Domain& domain)
    : nu_(parameters.real("nu")), length_scale_(parameters.real("length_scale")), domain_(domain) {
  if (nu_ == 0.5)
    order_ = 0;
  else if (nu_ == 1.5)
    order_ = 1;
  else if (nu_ == 2.5)
    order_ = 2;
  else
    throw ParameterError("nu", fmt::format("parameter 'nu' must be one of 0.5, 1.5, 2.5, found {}",
                                           format_real(nu_)));
  if (!(length_scale_ > 0) || !std::isfinite(length_scale_))
    throw ParameterError("length_scale", "parameter 'length_scale' must be > 0 and finite");
  rate_ = std::sqrt(2.0 * nu_) / length_scale_;
  if (domain_.periodic && domain_.dimension > 1)
    throw ParameterError("nu", fmt::format("the Matern kernel is not periodised on a torus "
                                           "(d = {}); use a box (periodic = false)",
                                           domain_.dimension));
  if (domain_.periodic) {
    period_ = rate_ * domain_.length;
    const double q = std::exp(-period_), one_minus_q = -std::expm1(-period_);
    geometric_[0] = 1.0 / one_minus_q;
    geometric_[1] = q / (one_minus_q * one_minus_q);
    geometric_[2] = q * (1.0 + q) / (one_minus_q * one_minus_q * one_minus_q);
  }
}

KernelProperties Matern::properties() const noexcept {
  KernelProperties p;
  p.positive_definite = true;
  p.sobolev_order = nu_ + 0.5 * domain_.dimension;
  p.dimension = domain_.dimension;
  p.analytic = false;
  p.support_radius = 0.0;
  p.stationary = true;
  p.periodic = domain_.periodic;
  return p;
}

}  // namespace rkhs::kernels

RKHS_REGISTER_KERNEL(rkhs::kernels::Matern)
