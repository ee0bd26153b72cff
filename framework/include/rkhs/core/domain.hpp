#pragma once
// The domain Omega of the estimated function, a box in R^d (d = 1, 2, 3):
//   d = 1: a closed track [0, L) (periodic) or an interval [0, L]; arc length s in metres;
//   d = 2, 3: the box [0, L] x [0, W] (x [0, H]), or the torus [0, L) x [0, W) (x [0, H)) when
//   periodic (every axis identified with its own period).
//
// Points. A point has d coordinates; a set of N points travels as a flat span of N d values,
// point p's coordinates at [p d, p d + d) (row-major, the layout of an N x d matrix). In d = 1 a
// point set is the list of arc lengths.

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace rkhs {

struct Domain {
  /// The largest dimension a domain may have.
  static constexpr int max_dimension = 3;
  /// The range of every extent, metres: beyond it the squared distances, volumes and spline
  /// knots the kernels and metrics compute (L^3, L^2 d, n0 2^J L / L) leave the range of double
  /// (a B-spline on a track of length 3e307 indexed its features with an infinite knot
  /// position). Study files are refused outside it (docs/study-files.md).
  static constexpr double min_extent = 1e-100;
  static constexpr double max_extent = 1e100;

  double length = 1.0;   ///< L > 0: extent of axis 1 (the track's length in d = 1), metres
  bool periodic = true;  ///< true: every axis is periodic (a circle, a torus)
  int dimension = 1;     ///< d in 1..max_dimension
  double width = 0.0;    ///< W > 0: extent of axis 2 (d >= 2), metres; unused in d = 1
  double height = 0.0;   ///< H > 0: extent of axis 3 (d = 3), metres; unused below

  /// The extent of axis `axis` (0-based): length, width, height.
  double extent(int axis) const noexcept { return axis == 0 ? length : axis == 1 ? width : height; }
  /// The d-dimensional volume |Omega| (the length in d = 1).
  double volume() const noexcept {
    double v = 1.0;
    for (int a = 0; a < dimension; ++a) v *= extent(a);
    return v;
  }
  /// Number of points in a flat point set (values.size() / d).
  std::size_t point_count(std::span<const double> coordinates) const noexcept {
    return coordinates.size() / static_cast<std::size_t>(dimension);
  }
  /// Throws std::invalid_argument unless d is in 1..3 and every extent is in
  /// [min_extent, max_extent].
  void validate() const;

  /// Coordinate x of axis `axis` mapped into [0, extent) on a periodic domain; unchanged
  /// otherwise. wrap(s) is axis 0 (the track).
  double wrap(double x, int axis = 0) const noexcept {
    if (!periodic) return x;
    const double period = extent(axis);
    double r = std::fmod(x, period);
    return r < 0 ? r + period : r;
  }
  /// Signed difference x - y along axis `axis`; on a periodic domain the representative in
  /// [-P/2, P/2] (P the axis' period).
  double difference(double x, double y, int axis = 0) const noexcept {
    double d = x - y;
    if (periodic) {
      const double period = extent(axis);
      d -= period * std::nearbyint(d / period);
    }
    return d;
  }
  /// |x - y| along axis 0, on a periodic domain the distance along the circle.
  double distance(double x, double y) const noexcept { return std::abs(difference(x, y)); }
  /// |x - y|^2 between two points of d coordinates each (the torus distance when periodic).
  double squared_distance(const double* x, const double* y) const noexcept {
    double sum = 0.0;
    for (int a = 0; a < dimension; ++a) {
      const double d = difference(x[a], y[a], a);
      sum += d * d;
    }
    return sum;
  }

  /// Points per axis of uniform_points(count): count itself in d = 1, otherwise the m with
  /// m^d closest to count (at least 2).
  std::size_t points_per_axis(std::size_t count) const;
  /// Uniform evaluation points, as a flat point set. In d = 1, `count` points: s_m = m L / M on
  /// a periodic domain (docs/model.md section 5), m L / (M - 1) on an interval (both end points
  /// included). In d > 1 the tensor grid of m = points_per_axis(count) such points per axis
  /// (m^d points, axis 1 varying fastest).
  std::vector<double> uniform_points(std::size_t count) const;
  /// Quadrature for the L2(Omega) norm of values at the points of uniform_points(M) (values
  /// holds one value per point): per axis L / M each on a periodic axis (the rectangle rule,
  /// exact for trigonometric polynomials), the trapezoid rule on an interval; in d > 1 their
  /// tensor product. Throws std::invalid_argument when the number of values is not m^d.
  double l2_norm(std::span<const double> values) const;
  /// "[0, 25) periodic", "[0, 1] x [0, 2]", "[0, 1) x [0, 1) periodic (torus)": for messages.
  std::string describe() const;
};

}  // namespace rkhs
