#pragma once
// Wendland's compactly supported functions phi_{d,k} (Wendland, Scattered Data Approximation,
// Table 9.1: phi_{d,k} = I^k (1 - r)_+^l with l = floor(d/2) + k + 1, normalised to phi(0) = 1),
// r = |x - y| / radius. On a track or an interval (d = 1):
//
//   k = 0:  (1 - r)_+
//   k = 1:  (1 - r)_+^3 (3 r + 1)
//   k = 2:  (1 - r)_+^5 (8 r^2 + 5 r + 1)
//   k = 3:  (1 - r)_+^7 (21 r^3 + 19 r^2 + 7 r + 1);
//
// on a box or torus of d = 2 or 3 (l = k + 2 for both, so phi_{2,k} = phi_{3,k}):
//
//   k = 0:  (1 - r)_+^2
//   k = 1:  (1 - r)_+^4 (4 r + 1)
//   k = 2:  (1 - r)_+^6 (35 r^2 + 18 r + 3) / 3
//   k = 3:  (1 - r)_+^8 (32 r^3 + 25 r^2 + 8 r + 1).
//
// Parameters (study-file keys and CSV columns):
//   k       integer 0..3, default 1: smoothness (phi is C^{2k}).
//   radius  > 0, metres, default 1: the support radius rho.
// Interval domain: k = phi. Periodic domain: the finite sum of the images phi(|d + m L|/rho)
// that can be nonzero (|m| <= ceil(rho/L + 1/2)); exact, no truncation. In d > 1 a box gives
// k = phi, a torus the finite lattice sum over the images m in Z^d with |m_a| <= ceil(rho/L_a + 1/2)
// per axis (every image that can be nonzero; exact).
// The derivative below is that of the d = 1 functions (sections along a track).
// derivative(x, y) = d/dy k(x, y) from phi'(r):
//   k = 0:  -1
//   k = 1:  -12 r (1 - r)^2
//   k = 2:  -14 r (4 r + 1) (1 - r)^4
//   k = 3:  -6 r (35 r^2 + 18 r + 3) (1 - r)^6,           0 for r > 1,
// summed over the same images on a periodic domain. k = 0 has kinks at y = x and at distance
// rho: there it is the right-hand derivative in y, like every other value.
// Properties: strictly positive definite on R^d (hence on the torus), native space
// H^tau with tau = k + (d + 1)/2 (Wendland, Theorem 10.35: d/2 + k + 1/2; phi_{3,k} restricted
// to R^2 loses 1/2, the trace theorem), support radius rho (k(x, y) = 0 when the domain
// distance is >= rho), stationary, dimension d of the domain.
// Fails: ParameterError naming "radius" on a periodic domain when a kernel value would sum
// more than max_image_terms images (prod_a (2 M_a + 1)): in d = 1, radius > max_periods L.
// The kernel is then all but constant and each of its values costs millions of terms.

#include <cmath>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernels/periodic_images.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs::kernels {

class Wendland {
 public:
  /// The most images one kernel value sums on a periodic domain, 2 M + 1 with M = 2^20 (the
  /// bound of image_count for the other stationary kernels), and the largest radius / L on a
  /// track it allows (ceil(radius / L + 1/2) <= 2^20).
  static constexpr double max_image_terms = 2.0 * (1 << 20) + 1.0;
  static constexpr double max_periods = (1 << 20) - 1.0;

  static PluginInfo info();

  Wendland(const ParameterSet& parameters, const Domain& domain);

  /// phi_{3,k}(r) of the scaled distance r >= 0 (0 for r >= 1): the function for d = 2 and 3.
  static double phi_3(int smoothness, double r) noexcept {
    if (r >= 1.0) return 0.0;
    const double s = 1.0 - r, s2 = s * s, s4 = s2 * s2;
    switch (smoothness) {
      case 0:
        return s2;
      case 1:
        return s4 * (4.0 * r + 1.0);
      case 2:
        return s4 * s2 * ((35.0 * r + 18.0) * r + 3.0) * (1.0 / 3.0);
      default:
        return s4 * s4 * (((32.0 * r + 25.0) * r + 8.0) * r + 1.0);
    }
  }

  /// d/dr phi_{3,k}(r) for r >= 0 (0 for r >= 1):
  ///   k = 0: -2 (1 - r),  1: -20 r (1 - r)^3,  2: -(56/3) r (5 r + 1) (1 - r)^5,
  ///   k = 3: -22 r (16 r^2 + 7 r + 1) (1 - r)^7.
  static double phi_3_slope(int smoothness, double r) noexcept {
    if (r >= 1.0) return 0.0;
    const double s = 1.0 - r, s2 = s * s, s3 = s2 * s;
    switch (smoothness) {
      case 0:
        return -2.0 * s;
      case 1:
        return -20.0 * r * s3;
      case 2:
        return -(56.0 / 3.0) * r * (5.0 * r + 1.0) * s3 * s2;
      default:
        return -22.0 * r * ((16.0 * r + 7.0) * r + 1.0) * s3 * s3 * s;
    }
  }

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

  /// k(x, y) for points of d = 2 or 3 coordinates: phi_{3,k}(|x - y| / rho), summed over the
  /// lattice images on a torus.
  double operator()(const double* x, const double* y) const noexcept {
    const int d = domain_.dimension;
    double difference[Domain::max_dimension] = {0, 0, 0};
    for (int a = 0; a < d; ++a) difference[a] = domain_.difference(x[a], y[a], a);
    if (!domain_.periodic) {
      double sum = 0.0;
      for (int a = 0; a < d; ++a) sum += difference[a] * difference[a];
      return phi_3(smoothness_, std::sqrt(sum) / radius_);
    }
    // Every image m in [-M_a, M_a]^d: an odometer over the axes.
    int m[Domain::max_dimension] = {0, 0, 0};
    for (int a = 0; a < d; ++a) m[a] = -axis_images_[a];
    double total = 0.0;
    while (true) {
      double sum = 0.0;
      for (int a = 0; a < d; ++a) {
        const double t = difference[a] + m[a] * domain_.extent(a);
        sum += t * t;
      }
      total += phi_3(smoothness_, std::sqrt(sum) / radius_);
      int a = 0;
      for (; a < d && m[a] == axis_images_[a]; ++a) m[a] = -axis_images_[a];
      if (a == d) break;
      ++m[a];
    }
    return total;
  }

  /// grad_y k(x, y) for points of d = 2 or 3 coordinates: phi_{3,k}'(r / rho) / rho times
  /// (y - x) / r, summed over the same lattice images as k on a torus; 0 at r = 0 (where k = 0
  /// has its cusp and k >= 1 a zero slope).
  void gradient(const double* x, const double* y, double* g) const noexcept {
    const int d = domain_.dimension;
    double difference[Domain::max_dimension] = {0, 0, 0};
    for (int a = 0; a < d; ++a) {
      difference[a] = domain_.difference(x[a], y[a], a);
      g[a] = 0.0;
    }
    int m[Domain::max_dimension] = {0, 0, 0};
    if (domain_.periodic)
      for (int a = 0; a < d; ++a) m[a] = -axis_images_[a];
    while (true) {
      double t[Domain::max_dimension] = {0, 0, 0}, sum = 0.0;
      for (int a = 0; a < d; ++a) {
        t[a] = difference[a] + (domain_.periodic ? m[a] * domain_.extent(a) : 0.0);
        sum += t[a] * t[a];
      }
      const double r = std::sqrt(sum);
      if (r > 0.0 && r < radius_) {
        // t = x - y: d r / d y_a = -t_a / r.
        const double factor = -phi_3_slope(smoothness_, r / radius_) / (radius_ * r);
        for (int a = 0; a < d; ++a) g[a] += factor * t[a];
      }
      if (!domain_.periodic) break;
      int a = 0;
      for (; a < d && m[a] == axis_images_[a]; ++a) m[a] = -axis_images_[a];
      if (a == d) break;
      ++m[a];
    }
  }

  KernelProperties properties() const noexcept;

  int smoothness() const noexcept { return smoothness_; }
  double radius() const noexcept { return radius_; }

 private:
  int smoothness_;
  double radius_;
  Domain domain_;
  int images_ = 0;
  int axis_images_[Domain::max_dimension] = {0, 0, 0};  ///< M_a of the torus' lattice sum
};

}  // namespace rkhs::kernels
