#pragma once
// The inverse multiquadric kernel, an rkhs-study plugin (docs/writing-a-kernel.md walks through
// this file and inverse_multiquadric.cpp).
//
//   k0(x, y) = (1 + (|x - y| / c)^2)^(-beta),   c > 0 (metres), beta > 0.
//
// Parameters (study-file keys and CSV columns):
//   beta  > 0, default 1: the exponent; > 1/2 on a closed track (see below).
//   c     > 0, metres, default 1: the shape (width) parameter.
// Interval domain [0, L]: k = k0.
// Periodic domain [0, L): the periodisation k(s, t) = sum_{m in Z} k0(s - t + m L). Its images
// decay only like |m|^(-2 beta): the sum diverges for beta <= 1/2 (refused: there is no such
// kernel), and for beta > 1/2 a truncated image sum would need ~ (c/L)^2 / tolerance images to
// reach round-off (10^15 for beta = 1). By Poisson summation the same kernel is the Fourier series
//   k(d) = (1/L) [F(0) + 2 sum_{j >= 1} F(w_j) cos(w_j d)],   w_j = 2 pi j / L,
// with F the Fourier transform of k0,
//   F(w) = c 2 sqrt(pi) / Gamma(beta) (c w / 2)^(beta - 1/2) K_{beta - 1/2}(c w),
//   F(0) = c sqrt(pi) Gamma(beta - 1/2) / Gamma(beta),
// whose terms decay like exp(-c w_j): about 37 L / (2 pi c) terms reach 1e-16 of k(0). The
// series is truncated there (omitted terms < 1e-16 F(0)/L, bound in the .cpp). Every kept
// coefficient is positive, so the truncated kernel is itself positive semidefinite.
// derivative(x, y) = d/dy k(x, y) (optional for a kernel; without it rkhs-study differences k):
// 2 beta (x - y) / c^2 (1 + ((x - y) / c)^2)^(-beta - 1) on an interval, and the series
// differentiated term by term, (2 pi / L) sum_j j a_j sin(j theta), on a closed track (its terms
// j a_j still decay like exp(-c w_j), so the truncation costs ~ 37 L / (2 pi c) eps k(0) / c).
// Properties: strictly positive definite (F > 0), analytic (F decays exponentially: spectral
// convergence), global support, stationary.
// Fails: ParameterError for beta <= 1/2 on a closed track, or when more than 10^6 Fourier terms
// would be needed (c < ~ L / 10^5).

#include <cmath>
#include <cstddef>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace imq {

class InverseMultiquadric {
 public:
  static rkhs::PluginInfo info();

  InverseMultiquadric(const rkhs::ParameterSet& parameters, const rkhs::Domain& domain);

  double operator()(double x, double y) const noexcept {
    if (!domain_.periodic) return profile(x - y);
    return fourier_series(domain_.difference(x, y));
  }

  /// d/dy k(x, y), the derivative of the section k(x, .).
  double derivative(double x, double y) const noexcept {
    if (!domain_.periodic) return -profile_slope(x - y);
    return fourier_series_slope(domain_.difference(x, y));
  }

  rkhs::KernelProperties properties() const noexcept;

  /// k0 at signed distance d.
  double profile(double d) const noexcept {
    const double r = d / c_;
    return std::pow(1.0 + r * r, -beta_);
  }
  /// d/dd k0(d) at signed distance d.
  double profile_slope(double d) const noexcept {
    const double r = d / c_;
    return -2.0 * beta_ * r / c_ * std::pow(1.0 + r * r, -beta_ - 1.0);
  }
  /// Terms of the Fourier series after the constant (0 on an interval).
  std::size_t fourier_terms() const noexcept {
    return coefficients_.empty() ? 0 : coefficients_.size() - 1;
  }

 private:
  /// sum_j a_j cos(j theta), theta = 2 pi d / L, with cos(j theta) from a rotation recurrence
  /// (rounding grows like j eps, negligible against the decay of a_j). Exactly even in d.
  double fourier_series(double d) const noexcept {
    const double theta = 2.0 * 3.14159265358979323846 * d / domain_.length;
    const double cos1 = std::cos(theta), sin1 = std::sin(theta);
    double cosj = 1.0, sinj = 0.0, sum = 0.0;
    for (double a : coefficients_) {
      sum += a * cosj;
      const double next = cosj * cos1 - sinj * sin1;
      sinj = sinj * cos1 + cosj * sin1;
      cosj = next;
    }
    return sum;
  }

  /// -d/dd of fourier_series(d) = (2 pi / L) sum_j j a_j sin(j theta), by the same recurrence.
  double fourier_series_slope(double d) const noexcept {
    const double frequency = 2.0 * 3.14159265358979323846 / domain_.length;
    const double theta = frequency * d;
    const double cos1 = std::cos(theta), sin1 = std::sin(theta);
    double cosj = 1.0, sinj = 0.0, sum = 0.0, j = 0.0;
    for (double a : coefficients_) {
      sum += j * a * sinj;
      const double next = cosj * cos1 - sinj * sin1;
      sinj = sinj * cos1 + cosj * sin1;
      cosj = next;
      j += 1.0;
    }
    return frequency * sum;
  }

  double beta_;
  double c_;
  rkhs::Domain domain_;
  std::vector<double> coefficients_;  ///< a_0 = F(0)/L, a_j = 2 F(w_j)/L; empty on an interval
};

}  // namespace imq
