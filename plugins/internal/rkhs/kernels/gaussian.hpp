#pragma once
// The Gaussian kernel (docs/model.md section 3; paper Sec. 5 and Sec. 2).
//
//   k0(x, y) = exp(-|x - y|^2 / (2 sigma^2))    convention = "2sigma2" (default, paper Sec. 5)
//   k0(x, y) = exp(-|x - y|^2 / sigma^2)        convention = "sigma2"  (paper Sec. 2)
//
// Parameters (study-file keys and CSV columns):
//   sigma       > 0, metres, default 1: the width.
//   convention  "2sigma2" | "sigma2", default "2sigma2".
// Interval domain [0, L]: k = k0. Periodic domain [0, L): k(s, t) = sum_{m in Z} k0(s - t + m L),
// truncated to |m| <= M where the omitted images are below 1e-16 k0(0) (periodic_images.hpp);
// M is computed once by the constructor and grows like sigma / L (M = 17 for sigma = 50,
// L = 25, "2sigma2"; M = 0 for sigma = 1 on the paper's track).
// derivative(x, y) = d/dy k(x, y): for k0, 2 (x - y) / (c sigma^2) k0(x, y) (c = 2 or 1); on a
// periodic domain the sum of the same images' derivatives. The omitted images' derivatives are
// below 1e-15 k0(0) / sigma (r e^{-r^2/2} decreases where e^{-r^2/2} < 1e-16).
// On a box or torus of d = 2, 3: k0(x, y) = exp(-|x - y|^2 / (c sigma^2)); on a torus the lattice
// sum of its images, the product over axes of the per-axis image sums above.
// Properties: strictly positive definite, analytic (no Sobolev order), global support,
// stationary, dimension d of the domain. Wide Gaussians (sigma of the order of L or larger) have
// Gram matrices that are singular to double precision: the kernel is still evaluated correctly, the
// trial reports it. Fails: ParameterError naming "sigma" on a periodic domain when sigma exceeds
// max_periods times the period (the track's length, or any axis' extent of a torus): the image sum
// would need close to image_count's cap of 2^20 images each side (M = 6.9e5 for "sigma2", 9.8e5 for
// "2sigma2" at sigma / L = 1e5), millions of exponentials per kernel value, for a kernel that
// is constant to double precision from sigma / L ~ 2 on (its variation is
// exp(-pi^2 c sigma^2 / L^2) of its mean).

#include <cmath>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernels/periodic_images.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs::kernels {

class Gaussian {
 public:
  /// The largest sigma / L on a periodic domain (per axis on a torus): see "Fails" above.
  static constexpr double max_periods = 1e5;

  static PluginInfo info();

  Gaussian(const ParameterSet& parameters, const Domain& domain);

  /// exp(-d^2 / (c sigma^2)) with c = 2 or 1, d >= 0 a distance on the line.
  double profile(double distance) const noexcept {
    return std::exp(-distance * distance * inverse_scale_);
  }

  /// d/dd profile(d) for a signed distance d: -2 d / (c sigma^2) profile(d).
  double profile_slope(double d) const noexcept { return -2.0 * d * inverse_scale_ * profile(d); }

  double operator()(double x, double y) const noexcept {
    if (!domain_.periodic) return profile(x - y);
    return sum_of_images([this](double r) { return profile(r); }, domain_.difference(x, y),
                         domain_.length, images_);
  }

  /// d/dy k(x, y) (d = x - y, so d/dy = -d/dd).
  double derivative(double x, double y) const noexcept {
    if (!domain_.periodic) return -profile_slope(x - y);
    return -sum_of_image_slopes([this](double r) { return profile_slope(r); },
                                domain_.difference(x, y), domain_.length, images_);
  }

  /// k(x, y) for points of d = 2 or 3 coordinates: exp(-|x - y|^2 / (c sigma^2)); on a torus
  /// the sum over the lattice images, which factorises into the per-axis image sums (the
  /// Gaussian is a product over axes), each truncated like the track's.
  double operator()(const double* x, const double* y) const noexcept {
    double product = 1.0;
    for (int a = 0; a < domain_.dimension; ++a) {
      const double d = domain_.difference(x[a], y[a], a);
      product *= domain_.periodic ? sum_of_images([this](double r) { return profile(r); }, d,
                                                  domain_.extent(a), axis_images_[a])
                                  : profile(d);
    }
    return product;
  }

  /// grad_y k(x, y) for points of d = 2 or 3 coordinates: each axis' factor differentiated (on
  /// a torus its image sum's slope, truncated like the sum), times the other axes' factors.
  void gradient(const double* x, const double* y, double* g) const noexcept {
    const int d = domain_.dimension;
    double value[Domain::max_dimension] = {1, 1, 1}, slope[Domain::max_dimension] = {0, 0, 0};
    for (int a = 0; a < d; ++a) {
      const double t = domain_.difference(x[a], y[a], a);  // x - y: d/dy = -d/dt
      if (domain_.periodic) {
        value[a] = sum_of_images([this](double r) { return profile(r); }, t, domain_.extent(a),
                                 axis_images_[a]);
        slope[a] = -sum_of_image_slopes([this](double r) { return profile_slope(r); }, t,
                                        domain_.extent(a), axis_images_[a]);
      } else {
        value[a] = profile(t);
        slope[a] = -profile_slope(t);
      }
    }
    for (int a = 0; a < d; ++a) {
      double product = slope[a];
      for (int b = 0; b < d; ++b)
        if (b != a) product *= value[b];
      g[a] = product;
    }
  }

  KernelProperties properties() const noexcept;

  double sigma() const noexcept { return sigma_; }
  /// Images each side of the periodic sum (0 on an interval).
  int image_count() const noexcept { return images_; }

 private:
  double sigma_;
  double inverse_scale_;  ///< 1 / (c sigma^2)
  Domain domain_;
  int images_ = 0;
  int axis_images_[Domain::max_dimension] = {0, 0, 0};  ///< images per axis on a torus
};

}  // namespace rkhs::kernels
