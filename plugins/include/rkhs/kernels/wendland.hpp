#pragma once
// Wendland's compactly supported functions for d = 1 (Wendland, Scattered Data Approximation,
// Table 9.1: phi_{1,k} = I^k (1 - r)_+^l with l = floor(d/2) + k + 1, normalised to phi(0) = 1):
//
//   k = 0:  (1 - r)_+
//   k = 1:  (1 - r)_+^3 (3 r + 1)
//   k = 2:  (1 - r)_+^5 (8 r^2 + 5 r + 1)
//   k = 3:  (1 - r)_+^7 (21 r^3 + 19 r^2 + 7 r + 1),        r = |x - y| / radius.
//
// Parameters (study-file keys and CSV columns):
//   k       integer 0..3, default 1: smoothness (phi is C^{2k}).
//   radius  > 0, metres, default 1: the support radius rho.
// Interval domain: k = phi. Periodic domain: the finite sum of the images phi(|d + m L|/rho)
// that can be nonzero (|m| <= ceil(rho/L + 1/2)); exact, no truncation.
// derivative(x, y) = d/dy k(x, y) from phi'(r):
//   k = 0:  -1
//   k = 1:  -12 r (1 - r)^2
//   k = 2:  -14 r (4 r + 1) (1 - r)^4
//   k = 3:  -6 r (35 r^2 + 18 r + 3) (1 - r)^6,           0 for r > 1,
// summed over the same images on a periodic domain. k = 0 has kinks at y = x and at distance
// rho: there it is the right-hand derivative in y, like every other value.
// Properties: strictly positive definite on R (hence on the circle), native space H^{k+1}
// (= d/2 + k + 1/2), support radius rho (k(x, y) = 0 when the domain distance is >= rho),
// stationary.
// Fails: nothing beyond the parameter declarations.

#include <cmath>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernels/periodic_images.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs::kernels {

class Wendland {
 public:
  static PluginInfo info();

  Wendland(const ParameterSet& parameters, const Domain& domain);

  /// phi_{1,k}(r) of the scaled distance r >= 0 (0 for r >= 1).
  static double phi(int smoothness, double r) noexcept {
    if (r >= 1.0) return 0.0;
    const double s = 1.0 - r, s2 = s * s;
    switch (smoothness) {
      case 0:
        return s;
      case 1:
        return s2 * s * (3.0 * r + 1.0);
      case 2:
        return s2 * s2 * s * ((8.0 * r + 5.0) * r + 1.0);
      default:
        return s2 * s2 * s2 * s * (((21.0 * r + 19.0) * r + 7.0) * r + 1.0);
    }
  }

  /// phi_{1,k}'(r), the polynomial piece's derivative, for 0 <= r <= 1.
  static double phi_slope(int smoothness, double r) noexcept {
    const double s = 1.0 - r, s2 = s * s;
    switch (smoothness) {
      case 0:
        return -1.0;
      case 1:
        return -12.0 * r * s2;
      case 2:
        return -14.0 * r * (4.0 * r + 1.0) * s2 * s2;
      default:
        return -6.0 * r * ((35.0 * r + 18.0) * r + 3.0) * s2 * s2 * s2;
    }
  }

  double profile(double distance) const noexcept {
    // A division, not a multiplication by 1/radius: distance >= radius must give r >= 1 exactly.
    return phi(smoothness_, distance / radius_);
  }

  /// The left-hand derivative of phi(|d| / rho) in the signed distance d, i.e. (d = x - y) the
  /// right-hand derivative in y: at d = 0 and |d| = rho the side on which y grows.
  double profile_slope(double d) const noexcept {
    if (d > 0) {
      const double r = d / radius_;
      return r > 1.0 ? 0.0 : phi_slope(smoothness_, r) / radius_;
    }
    const double r = -d / radius_;
    return r >= 1.0 ? 0.0 : -phi_slope(smoothness_, r) / radius_;
  }

  double operator()(double x, double y) const noexcept {
    if (!domain_.periodic) return profile(std::abs(x - y));
    return sum_of_images([this](double r) { return profile(r); }, domain_.difference(x, y),
                         domain_.length, images_);
  }

  /// d/dy k(x, y) (d = x - y, so d/dy = -d/dd).
  double derivative(double x, double y) const noexcept {
    if (!domain_.periodic) return -profile_slope(x - y);
    return -sum_of_image_slopes([this](double r) { return profile_slope(r); },
                                domain_.difference(x, y), domain_.length, images_);
  }

  KernelProperties properties() const noexcept;

  int smoothness() const noexcept { return smoothness_; }
  double radius() const noexcept { return radius_; }

 private:
  int smoothness_;
  double radius_;
  Domain domain_;
  int images_ = 0;
};

}  // namespace rkhs::kernels
