#pragma once
// The domain Omega of the estimated function: a closed track [0, L) (periodic) or an interval
// [0, L]. Arc length s is in metres.

#include <cmath>
#include <span>
#include <vector>

namespace rkhs {

struct Domain {
  double length = 1.0;   ///< L > 0, metres
  bool periodic = true;  ///< true: [0, L) with s and s + L identified

  /// s mapped into [0, L) on a periodic domain; unchanged on an interval.
  double wrap(double s) const noexcept {
    if (!periodic) return s;
    double r = std::fmod(s, length);
    return r < 0 ? r + length : r;
  }
  /// Signed difference x - y; on a periodic domain the representative in [-L/2, L/2].
  double difference(double x, double y) const noexcept {
    double d = x - y;
    if (periodic) d -= length * std::nearbyint(d / length);
    return d;
  }
  /// |x - y|, on a periodic domain the distance along the circle.
  double distance(double x, double y) const noexcept { return std::abs(difference(x, y)); }

  /// M evaluation points: s_m = m L / M on a periodic domain (docs/model.md section 5),
  /// m L / (M - 1) on an interval (both end points included).
  std::vector<double> uniform_points(std::size_t count) const;
  /// Quadrature weights for the L2(Omega) norm on uniform_points(count): L / M each on a
  /// periodic domain (the rectangle rule, exact for trigonometric polynomials), the trapezoid
  /// rule on an interval.
  double l2_norm(std::span<const double> values) const;
};

}  // namespace rkhs
