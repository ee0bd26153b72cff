// The inverse multiquadric kernel as an rkhs-study plugin: what it declares (info), how it is
// built for a domain (the constructor), what theory may assume about it (properties), and the
// two lines that make it a plugin. The formulas are in inverse_multiquadric.hpp.
#include "inverse_multiquadric.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <type_traits>

#include "rkhs/kernel/kernel_algorithms.hpp"  // RKHS_REGISTER_KERNEL
#include "rkhs/plugin/module.hpp"             // RKHS_PLUGIN_MODULE

namespace imq {

// What makes the class a kernel: the KernelFunction concept of rkhs/kernel/kernel.hpp (info(), k(x, y),
// properties()) and a constructor from the parameters and the domain (one instance per trial).
// RKHS_REGISTER_KERNEL needs both; asserting them here reports a mistake at the class.
static_assert(rkhs::KernelFunction<InverseMultiquadric>);
static_assert(
    std::is_constructible_v<InverseMultiquadric, const rkhs::ParameterSet&, const rkhs::Domain&>);

rkhs::PluginInfo InverseMultiquadric::info() {
  return {
      "inverse_multiquadric",
      "inverse multiquadric (1 + (d/c)^2)^(-beta), periodised by its Fourier series",
      {rkhs::positive_parameter("beta", 1.0, "exponent beta (> 1/2 on a closed track)"),
       rkhs::positive_parameter("c", 1.0, "shape c, metres")},
      {{"periodic", "Fourier series (Poisson summation), truncated below 1e-16 k(0)"}},
  };
}

InverseMultiquadric::InverseMultiquadric(const rkhs::ParameterSet& parameters,
                                         const rkhs::Domain& domain)
    : beta_(parameters.real("beta")), c_(parameters.real("c")), domain_(domain) {
  if (!domain_.periodic) return;
  if (!(beta_ > 0.5))
    throw rkhs::ParameterError(
        "beta",
        "parameter 'beta' must be > 1/2 on a closed track (the sum of the images of "
        "(1 + (d/c)^2)^(-beta) diverges for beta <= 1/2), found " +
            rkhs::format_real(beta_));

  // Fourier transform of k0 at w > 0 and at 0 (header). x^nu K_nu(x) is computed as one
  // product; it underflows to 0 only far beyond the truncation point.
  const double pi = std::numbers::pi, length = domain_.length, nu = beta_ - 0.5;
  const double scale = c_ * 2.0 * std::sqrt(pi) / std::tgamma(beta_);
  auto transform = [&](double w) {
    const double x = c_ * w;
    return scale * std::pow(0.5 * x, nu) * std::cyl_bessel_k(nu, x);
  };
  coefficients_.push_back(c_ * std::sqrt(pi) * std::tgamma(nu) / std::tgamma(beta_) / length);

  // Truncation. a_j ~ j^(nu - 1/2) exp(-delta j), delta = 2 pi c / L: the ratios a_{j+1}/a_j tend
  // to exp(-delta), from above when nu >= 1/2 (non-increasing ratios), from below otherwise. So
  // with r = max(a_{J+1}/a_J, exp(-delta)), the omitted terms sum to at most a_{J+1}/(1 - r)
  // (a geometric series), which is what is compared with the tolerance.
  const double tolerance = 1e-16 * coefficients_[0];
  const double asymptotic_ratio = std::exp(-2.0 * pi * c_ / length);
  constexpr std::size_t max_terms = 1'000'000;
  double previous = 2.0 * transform(2.0 * pi / length) / length;
  for (std::size_t j = 1;; ++j) {
    coefficients_.push_back(previous);
    const double next = 2.0 * transform(2.0 * pi * static_cast<double>(j + 1) / length) / length;
    const double ratio = std::max(next / previous, asymptotic_ratio);
    if (next == 0.0 || (ratio < 1.0 && next / (1.0 - ratio) <= tolerance)) break;
    if (j == max_terms)
      throw rkhs::ParameterError("c",
                                 "parameter 'c' is too small for this track: its periodic "
                                 "kernel needs more than 10^6 Fourier terms");
    previous = next;
  }
}

rkhs::KernelProperties InverseMultiquadric::properties() const noexcept {
  rkhs::KernelProperties p;
  p.positive_definite = true;  // its Fourier transform is positive everywhere
  p.analytic = true;           // ... and decays exponentially: no Sobolev order
  p.support_radius = 0.0;      // global support
  p.stationary = true;
  p.periodic = domain_.periodic;
  return p;
}

}  // namespace imq

RKHS_REGISTER_KERNEL(imq::InverseMultiquadric)
RKHS_PLUGIN_MODULE("inverse_multiquadric")
