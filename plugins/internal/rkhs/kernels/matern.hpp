#pragma once
// The Matern kernel with half-integer smoothness, in scikit-learn's parametrisation
// (sklearn.gaussian_process.kernels.Matern), d = |x - y|, l = length_scale:
//
//   nu = 0.5:  exp(-d/l)
//   nu = 1.5:  (1 + sqrt(3) d/l) exp(-sqrt(3) d/l)
//   nu = 2.5:  (1 + sqrt(5) d/l + 5 d^2 / (3 l^2)) exp(-sqrt(5) d/l)
//
// Parameters (study-file keys and CSV columns):
//   nu            one of 0.5, 1.5, 2.5, default 1.5: the smoothness.
//   length_scale  > 0, metres, default 1.
// Interval domain: k = k0. Periodic domain: the sum of all images k0(d + m L), m in Z, summed
// in closed form (no truncation, O(1) for any length_scale / L): the image distances on either
// side of x form an arithmetic sequence a, a + L, a + 2L, ..., and
//   sum_m (a + m L)^j exp(-c (a + m L)),  j = 0, 1, 2,
// are derivatives of a geometric series in q = exp(-c L) (see periodic_side below).
// derivative(x, y) = d/dy k(x, y) from the profiles' derivatives in a = sqrt(2 nu) d / l,
//   nu = 0.5:  -exp(-a)
//   nu = 1.5:  -a exp(-a)
//   nu = 2.5:  -a (1 + a) / 3 exp(-a),
// times sqrt(2 nu) / l; on a periodic domain the derivatives of the closed-form image sums
// (periodic_side_slope). nu = 0.5 has a kink at y = x: there it is the right-hand derivative.
// On a box of d = 2, 3: the radial Matern function of |x - y| (the same profiles); a torus of
// d > 1 is refused (no closed-form lattice sum; ParameterError naming "nu").
// Properties: strictly positive definite, native space H^{nu + d/2} (Wendland, Scattered Data
// Approximation, Theorem 10.12: the Fourier transform decays like (1 + |w|^2)^-(nu + d/2)),
// global support, stationary, dimension d of the domain.
// Fails: ParameterError naming "nu" for any other nu (also checked by the declaration).

#include <cmath>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs::kernels {

class Matern {
 public:
  static PluginInfo info();

  Matern(const ParameterSet& parameters, const Domain& domain);

  /// k0 at distance `distance` >= 0.
  double profile(double distance) const noexcept {
    const double a = distance * rate_;  // sqrt(2 nu) d / l
    switch (order_) {
      case 0:
        return std::exp(-a);
      case 1:
        return (1.0 + a) * std::exp(-a);
      default:
        return (1.0 + a + a * a * (1.0 / 3.0)) * std::exp(-a);
    }
  }

  /// d/dd k0(d) at distance d >= 0 (at 0 the right-hand derivative).
  double profile_slope(double distance) const noexcept {
    const double a = distance * rate_;
    switch (order_) {
      case 0:
        return -rate_ * std::exp(-a);
      case 1:
        return -rate_ * a * std::exp(-a);
      default:
        return -rate_ * a * (1.0 + a) * (1.0 / 3.0) * std::exp(-a);
    }
  }

  double operator()(double x, double y) const noexcept {
    if (!domain_.periodic) return profile(std::abs(x - y));
    const double d = domain_.distance(x, y);  // in [0, L/2]
    return periodic_side(rate_ * d) + periodic_side(rate_ * (domain_.length - d));
  }

  /// d/dy k(x, y): the distance |x - y| grows with y when y >= x (right-hand at y = x).
  double derivative(double x, double y) const noexcept {
    const double difference = domain_.periodic ? domain_.difference(x, y) : x - y;
    const double direction = difference > 0 ? -1.0 : 1.0;  // d|x - y| / dy
    const double d = std::abs(difference);
    if (!domain_.periodic) return direction * profile_slope(d);
    return direction * rate_ *
           (periodic_side_slope(rate_ * d) - periodic_side_slope(rate_ * (domain_.length - d)));
  }

  /// k(x, y) for points of d = 2 or 3 coordinates on a box: the profile of |x - y|.
  double operator()(const double* x, const double* y) const noexcept {
    return profile(std::sqrt(domain_.squared_distance(x, y)));
  }

  /// grad_y k(x, y) on a box: k0'(r) (y - x) / r; 0 at r = 0 (nu = 1/2 has its cusp there, the
  /// others a zero slope).
  void gradient(const double* x, const double* y, double* g) const noexcept {
    const int d = domain_.dimension;
    const double r = std::sqrt(domain_.squared_distance(x, y));
    const double factor = r > 0.0 ? profile_slope(r) / r : 0.0;
    for (int a = 0; a < d; ++a) g[a] = factor * (y[a] - x[a]);
  }

  KernelProperties properties() const noexcept;

  double nu() const noexcept { return nu_; }

 private:
  /// sum_{m >= 0} k0 at the scaled distances s + m T (T = rate L), i.e. with
  /// E_j = sum_m (s + m T)^j e^{-(s + m T)} = e^{-s} sum_m (s + m T)^j q^m:
  ///   E_0 = e^{-s} / (1 - q)
  ///   E_1 = e^{-s} (s / (1 - q) + T q / (1 - q)^2)
  ///   E_2 = e^{-s} (s^2 / (1 - q) + 2 s T q / (1 - q)^2 + T^2 q (1 + q) / (1 - q)^3)
  /// and k0 = E_0 (nu = 1/2), E_0 + E_1 (3/2), E_0 + E_1 + E_2 / 3 (5/2). All terms are positive.
  double periodic_side(double s) const noexcept {
    const double e = std::exp(-s);
    const double e0 = geometric_[0];
    if (order_ == 0) return e * e0;
    const double e1 = s * geometric_[0] + period_ * geometric_[1];
    if (order_ == 1) return e * (e0 + e1);
    const double e2 =
        s * (s * geometric_[0] + 2.0 * period_ * geometric_[1]) + period_ * period_ * geometric_[2];
    return e * (e0 + e1 + e2 * (1.0 / 3.0));
  }

  /// d/ds periodic_side(s): -E_0 (nu = 1/2), -E_1 (3/2), -(E_1 + E_2) / 3 (5/2), since
  /// E_j' = j E_{j-1} - E_j term by term.
  double periodic_side_slope(double s) const noexcept {
    const double e = std::exp(-s);
    if (order_ == 0) return -e * geometric_[0];
    const double e1 = s * geometric_[0] + period_ * geometric_[1];
    if (order_ == 1) return -e * e1;
    const double e2 =
        s * (s * geometric_[0] + 2.0 * period_ * geometric_[1]) + period_ * period_ * geometric_[2];
    return -e * (e1 + e2) * (1.0 / 3.0);
  }

  double nu_;
  double length_scale_;
  int order_;    ///< nu - 1/2
  double rate_;  ///< sqrt(2 nu) / length_scale
  Domain domain_;
  double period_ = 0;                ///< T = rate L
  double geometric_[3] = {0, 0, 0};  ///< 1/(1-q), q/(1-q)^2, q(1+q)/(1-q)^3 with q = e^{-T}
};

}  // namespace rkhs::kernels
