#pragma once
// The multiscale B-spline kernel (docs/model.md section 3; paper Sec. 2.1), d = 1:
//
//   k(u, v) = sum_{j=0}^{J} 2^{j (d - 2r)} sum_k N_p(2^j u / h0 - k) N_p(2^j v / h0 - k),
//
// and on a box or torus of d = 2, 3 the same sum over the tensor-product B-splines of each level,
// N(x) = prod_a N_p(x_a) with h0_a = L_a / n0 on axis a and k in Z^d: the sum over k factorises,
//
//   k(u, v) = sum_j 2^{j (d - 2r)} prod_a sum_{k_a} N_p(2^j u_a / h0_a - k_a) N_p(2^j v_a / h0_a - k_a),
//
// evaluated so, level by level, O(d (p + 1) (J + 1)) per pair (operator() of two points). Its
// native space is equivalent to H^r(Omega) for d/2 < r < p + 1/2; it has sum_j prod_a n_{j,a}
// features (n_{j,a} = n0 2^j, + p on an interval), the rank bound of its Gram matrices.
//
// N_p the cardinal B-spline of degree p with knots 0, 1, ..., p + 1, h0 = L / n0, and
// n_j = n0 2^j cells on level j.
//   Periodic domain [0, L): k = 0 .. n_j - 1, spline indices wrap modulo n_j.
//   Interval [0, L]: every k whose support meets [0, n_j), i.e. k = -p .. n_j - 1 (n_j + p
//   splines per level), no wrapping. Points outside [0, L] are clamped to it.
//
// Parameters (study-file keys and CSV columns):
//   degree  integer 0..3, default 1: p (1 = hat, the paper's "first order"; 2 = quadratic).
//   r       > 0, default = degree: level weights 2^{j (1 - 2r)}. When r is not given it equals
//           degree; degree 0 then needs an explicit r.
//   n0      integer 1..8192, default 4: cells on level 0 (h0 = L / n0). Periodic: n0 >= p + 1.
//   J       integer 0..16, default 6: finest level.
//
// The kernel is evaluated through its sparse feature map, never by a dense double loop:
//   phi_{j,k}(u) = 2^{j (1 - 2r) / 2} N_p(2^j u / h0 - k),
//   k(u, v) = sum_{j,k} phi_{j,k}(u) phi_{j,k}(v),
// with feature index offset_j + k (periodic, k wrapped into [0, n_j)) or offset_j + k + p
// (interval). Each point has exactly (p + 1)(J + 1) features (some may be 0 at knots).
// operator() forms the same products on the stack, O((p + 1)(J + 1)), without allocation.
// Arguments must be finite.
//
// Derivatives: N_p'(x) = N_{p-1}(x) - N_{p-1}(x - 1) (0 for p = 0), so
//   d/dv phi_{j,k}(v) = 2^{j (1 - 2r) / 2} (2^j / h0) N_p'(2^j v / h0 - k);
// feature_derivatives(v) gives them with the indices of features(v), derivative(u, v) =
// d/dv k(u, v) = sum_{j,k} phi_{j,k}(u) phi_{j,k}'(v). At a knot (as located by the rounding
// of 2^j v / h0), where the derivative of a degree-1 spline jumps, both give the right-hand
// derivative (the piece of the cell to the right; degree 0 gives 0 everywhere); on an interval,
// at v = L the left-hand one, and outside [0, L] the derivative at the clamped point.
//
// Properties: positive SEMIdefinite only (positive_definite = false). The level spaces are
// nested, so k has rank n_J (periodic) or n_J + p (interval), fewer than feature_count():
// a Gram matrix of more centres than that is singular (n_J = 256 with the defaults).
// Native space equivalent to H^r when d/2 < r < p + 1/2 (the limit J -> infinity;
// sobolev_order is empty otherwise). Support radius (p + 1) h0 (a level-0 spline; in d > 1
// sqrt(d) (p + 1) max_a h0_a, the Euclidean distance beyond which some axis is separated by
// more than a level-0 support); not stationary; dimension d of the domain.
// Fails: ParameterError naming "n0" when the domain is periodic and n0 < degree + 1 (a spline
// would overlap its own periodic copy), naming "r" when degree = 0 and r is not given, and
// naming "degree" / "J" / "n0" for values outside their declared ranges.

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs::kernels {

class MultiscaleBSpline {
 public:
  static constexpr int max_degree = 3;
  static constexpr int max_level = 16;  ///< largest J
  static constexpr int max_n0 = 8192;   ///< keeps feature indices within int32
  /// Most knots (features) on an axis, n0 (2^(J+1) - 1) (+ (J + 1) degree on an interval):
  /// 128 MiB of knots; J = 16 with n0 = 8192 has 1.07e9.
  static constexpr std::int64_t max_knots = std::int64_t{1} << 24;

  static PluginInfo info();

  MultiscaleBSpline(const ParameterSet& parameters, const Domain& domain);

  /// N_p(x): the cardinal B-spline of degree p = 0..3 with knots 0..p+1; 0 outside [0, p + 1)
  /// (right-open, so N_0 is the indicator of [0, 1)).
  static double cardinal_bspline(int degree, double x) noexcept {
    if (!(x >= 0.0) || x >= degree + 1) return 0.0;
    const double cell = std::floor(x);
    std::array<double, max_degree + 1> piece{};
    pieces(degree, x - cell, piece.data());
    return piece[static_cast<std::size_t>(cell)];
  }

  /// k(u, v), the dot product of the two sparse feature vectors.
  double operator()(double u, double v) const noexcept {
    const double x0 = level0(u), y0 = level0(v);
    std::array<double, max_degree + 1> nx{}, ny{};
    double sum = 0.0;
    for (int j = 0; j <= levels_; ++j) {
      const Cell cx = cell_at(x0, j), cy = cell_at(y0, j);
      const std::int32_t cells = n0_ << j;
      std::int32_t shift = cx.index - cy.index;
      if (periodic_) {
        if (shift < 0) shift += cells;  // in [0, n_j)
        if (shift > degree_ && shift < cells - degree_) continue;
      } else if (shift > degree_ || shift < -degree_) {
        continue;
      }
      pieces(degree_, cx.t, nx.data());
      pieces(degree_, cy.t, ny.data());
      const double w = weight_[j];
      // Spline k = cx - ix = cy - iy (mod n_j when periodic): iy = ix - shift.
      for (int ix = 0; ix <= degree_; ++ix) {
        int iy = ix - shift;
        if (periodic_ && iy < 0) iy += cells;
        if (iy < 0 || iy > degree_) continue;
        sum += (w * nx[ix]) * (w * ny[iy]);
      }
    }
    return sum;
  }

  /// k(u, v) for points of d = 2 or 3 coordinates: the level sums of the tensor-product
  /// splines, each the product over the axes of the one-dimensional sums (file comment).
  double operator()(const double* u, const double* v) const noexcept {
    double sum = 0.0;
    for (int j = 0; j <= levels_; ++j) {
      double product = point_weight_[j];
      for (int a = 0; a < dimension_ && product != 0.0; ++a)
        product *= level_sum(level0(u[a], axis_length_[a]), level0(v[a], axis_length_[a]), j);
      sum += product;
    }
    return sum;
  }

  /// grad_v k(u, v) for points of d = 2 or 3 coordinates: per level, each axis' factor
  /// differentiated in v_a (d/dv_a of N_p(2^j v_a / h0_a - k) is 2^j / h0_a N_p'), times the
  /// other axes' factors. At a knot, the right-hand derivative (as derivative()); on a box, 0
  /// outside [0, L_a], where the point is clamped.
  void gradient(const double* u, const double* v, double* g) const noexcept {
    for (int a = 0; a < dimension_; ++a) g[a] = 0.0;
    double sums[3] = {0, 0, 0}, slopes[3] = {0, 0, 0};
    for (int j = 0; j <= levels_; ++j) {
      for (int a = 0; a < dimension_; ++a) {
        const double x0 = level0(u[a], axis_length_[a]), y0 = level0(v[a], axis_length_[a]);
        sums[a] = level_sum(x0, y0, j);
        const bool clamped = !periodic_ && (v[a] < 0.0 || v[a] > axis_length_[a]);
        slopes[a] = clamped ? 0.0 : level_slope(x0, y0, j) * scale_[j] * n0_ / axis_length_[a];
      }
      for (int a = 0; a < dimension_; ++a) {
        double product = point_weight_[j] * slopes[a];
        for (int b = 0; b < dimension_; ++b)
          if (b != a) product *= sums[b];
        g[a] += product;
      }
    }
  }

  /// d/dv k(u, v), the dot product of u's features with v's feature derivatives.
  double derivative(double u, double v) const noexcept {
    const double x0 = level0(u), y0 = level0(v);
    std::array<double, max_degree + 1> nx{}, dny{};
    double sum = 0.0;
    for (int j = 0; j <= levels_; ++j) {
      const Cell cx = cell_at(x0, j), cy = cell_at(y0, j);
      const std::int32_t cells = n0_ << j;
      std::int32_t shift = cx.index - cy.index;
      if (periodic_) {
        if (shift < 0) shift += cells;
        if (shift > degree_ && shift < cells - degree_) continue;
      } else if (shift > degree_ || shift < -degree_) {
        continue;
      }
      pieces(degree_, cx.t, nx.data());
      piece_slopes(degree_, cy.t, dny.data());
      for (int ix = 0; ix <= degree_; ++ix) {
        int iy = ix - shift;
        if (periodic_ && iy < 0) iy += cells;
        if (iy < 0 || iy > degree_) continue;
        sum += (weight_[j] * nx[ix]) * (slope_weight_[j] * dny[iy]);
      }
    }
    return sum;
  }

  /// Clears `out` and appends the (p + 1)(J + 1) features of u, level by level.
  void features(double u, SparseFeatures& out) const { append_levels(u, out, pieces, weight_); }

  /// Clears `out` and appends d/du of the features of u, with the indices and in the order of
  /// features(u).
  void feature_derivatives(double u, SparseFeatures& out) const {
    append_levels(u, out, piece_slopes, slope_weight_);
  }

  /// Features of the map: on a track or an interval those of features(); in d > 1 the
  /// tensor-product splines of all levels, sum_j prod_a n_{j,a} (the rank bound of Gram
  /// matrices; they are evaluated by operator() of two points, not through a feature vector).
  std::size_t feature_count() const noexcept {
    if (dimension_ == 1) return static_cast<std::size_t>(offset_[levels_ + 1]);
    std::size_t total = 0;
    for (int j = 0; j <= levels_; ++j) {
      std::size_t level = 1;
      for (int a = 0; a < dimension_; ++a)
        level *= static_cast<std::size_t>(offset_[j + 1] - offset_[j]);
      total += level;
    }
    return total;
  }

  KernelProperties properties() const noexcept;

  /// Arc lengths in [0, L) where the kernel sections are not smooth: the knots of the finest
  /// level, s = k L / (n0 2^J). An integrator restarts there (docs/model.md section 8).
  std::vector<double> kink_points() const {
    const std::int64_t cells = std::int64_t{n0_} << levels_;
    std::vector<double> out(static_cast<std::size_t>(cells));
    for (std::int64_t k = 0; k < cells; ++k)
      out[static_cast<std::size_t>(k)] = length_ * static_cast<double>(k) / static_cast<double>(cells);
    return out;
  }

  int degree() const noexcept { return degree_; }
  double r() const noexcept { return r_; }
  int n0() const noexcept { return n0_; }
  int levels() const noexcept { return levels_; }  ///< J

 private:
  /// Clears `out` and appends, level by level, the p + 1 values `level_pieces` gives on the
  /// cell of u, each times its level's entry of `level_weights`: features() with the pieces and
  /// the weights, feature_derivatives() with their slopes and slope weights.
  void append_levels(double u, SparseFeatures& out,
                     void (*level_pieces)(int, double, double*) noexcept,
                     const std::array<double, max_level + 1>& level_weights) const {
    out.clear();
    const double x0 = level0(u);
    std::array<double, max_degree + 1> n{};
    for (int j = 0; j <= levels_; ++j) {
      const Cell c = cell_at(x0, j);
      const std::int32_t cells = n0_ << j;
      level_pieces(degree_, c.t, n.data());
      for (int i = degree_; i >= 0; --i) {
        const std::int32_t k = c.index - i;
        const std::int32_t slot = periodic_ ? (k < 0 ? k + cells : k) : k + degree_;
        out.push(offset_[j] + slot, level_weights[j] * n[i]);
      }
    }
  }

  /// out[i] = N_p(t + i) for i = 0..p and t in [0, 1]: the polynomial pieces of N_p.
  static void pieces(int degree, double t, double* out) noexcept {
    const double s = 1.0 - t;
    switch (degree) {
      case 0:
        out[0] = 1.0;
        return;
      case 1:
        out[0] = t;
        out[1] = s;
        return;
      case 2:
        out[0] = 0.5 * t * t;
        out[1] = 0.5 + t * s;  // (1 + 2t - 2t^2) / 2
        out[2] = 0.5 * s * s;
        return;
      default: {
        const double t2 = t * t, t3 = t2 * t;
        out[0] = t3 * (1.0 / 6.0);
        out[1] = (1.0 + 3.0 * (t + t2 - t3)) * (1.0 / 6.0);
        out[2] = (4.0 - 6.0 * t2 + 3.0 * t3) * (1.0 / 6.0);
        out[3] = s * s * s * (1.0 / 6.0);
        return;
      }
    }
  }

  /// out[i] = N_p'(t + i) = N_{p-1}(t + i) - N_{p-1}(t + i - 1) for i = 0..p and t in [0, 1]:
  /// the derivatives of the pieces (all 0 for p = 0).
  static void piece_slopes(int degree, double t, double* out) noexcept {
    if (degree == 0) {
      out[0] = 0.0;
      return;
    }
    std::array<double, max_degree + 1> lower{};  // room for pieces() of any degree
    pieces(degree - 1, t, lower.data());
    for (int i = 0; i <= degree; ++i)
      out[i] = (i < degree ? lower[i] : 0.0) - (i > 0 ? lower[i - 1] : 0.0);
  }

  struct Cell {
    std::int32_t index;  ///< level-j cell holding the point: [index, index + 1) in knot units
    double t;            ///< position in the cell, [0, 1]
  };

  /// u in level-0 knot units, in [0, n0] (periodic: wrapped first; interval: clamped), on an
  /// axis of extent `length` (the track's by default).
  double level0(double u) const noexcept { return level0(u, length_); }
  double level0(double u, double length) const noexcept {
    // A point that is not finite (the state of a trial that diverged) has the features of 0:
    // its cell index stays in range, and the trial fails on its non-finite values.
    if (!std::isfinite(u)) return 0.0;
    if (periodic_) {
      double w = std::fmod(u, length);
      if (w < 0) w += length;
      return w * n0_ / length;
    }
    const double clamped = u < 0.0 ? 0.0 : (u > length ? length : u);
    const double x0 = clamped * n0_ / length;
    return x0 > n0_ ? static_cast<double>(n0_) : x0;
  }

  /// sum_k N_p(2^j x0 - k) N_p(2^j y0 - k) on level j, unweighted, for level-0 coordinates
  /// x0, y0 of one axis (k wrapped modulo n_j when periodic): the factor of one axis.
  double level_sum(double x0, double y0, int j) const noexcept {
    return level_product(x0, y0, j, pieces);
  }

  /// sum_k N_p(2^j x0 - k) N_p'(2^j y0 - k) on level j: level_sum's derivative in the cell
  /// coordinate of y0 (multiply by 2^j n0 / L for the derivative in v).
  double level_slope(double x0, double y0, int j) const noexcept {
    return level_product(x0, y0, j, piece_slopes);
  }

  /// sum_k N_p(2^j x0 - k) Y(2^j y0 - k) on level j, Y the pieces `y_pieces` gives at y0's cell
  /// (the splines themselves or their slopes).
  double level_product(double x0, double y0, int j,
                       void (*y_pieces)(int, double, double*) noexcept) const noexcept {
    const Cell cx = cell_at(x0, j), cy = cell_at(y0, j);
    const std::int32_t cells = n0_ << j;
    std::int32_t shift = cx.index - cy.index;
    if (periodic_) {
      if (shift < 0) shift += cells;
      if (shift > degree_ && shift < cells - degree_) return 0.0;
    } else if (shift > degree_ || shift < -degree_) {
      return 0.0;
    }
    std::array<double, max_degree + 1> nx{}, ny{};
    pieces(degree_, cx.t, nx.data());
    y_pieces(degree_, cy.t, ny.data());
    double sum = 0.0;
    for (int ix = 0; ix <= degree_; ++ix) {
      int iy = ix - shift;
      if (periodic_ && iy < 0) iy += cells;
      if (iy < 0 || iy > degree_) continue;
      sum += nx[ix] * ny[iy];
    }
    return sum;
  }

  /// The level-j cell of the level-0 coordinate x0 in [0, n0]. Scaling by 2^j is exact.
  Cell cell_at(double x0, int level) const noexcept {
    const double x = x0 * scale_[level];
    const std::int32_t cells = n0_ << level;
    auto index = static_cast<std::int32_t>(x);  // x >= 0: truncation is floor
    if (index >= cells) {
      // x = n_j (rounding of u just below L, or u = L on the interval).
      if (periodic_) return {index - cells, x - index};
      index = cells - 1;
    }
    return {index, x - index};
  }

  int degree_;
  double r_;
  int n0_;
  int levels_;
  double length_;
  bool periodic_;
  std::array<double, max_level + 1> scale_{};         ///< 2^j
  std::array<double, max_level + 1> weight_{};        ///< 2^{j (1 - 2r) / 2}
  std::array<double, max_level + 1> slope_weight_{};  ///< weight_[j] 2^j / h0 (d/du of features)
  std::array<std::int32_t, max_level + 2> offset_{};  ///< first feature index of level j
  int dimension_ = 1;                                  ///< d of the domain
  std::array<double, Domain::max_dimension> axis_length_{};  ///< L_a, the extents
  std::array<double, max_level + 1> point_weight_{};   ///< 2^{j (d - 2r)}, d > 1
};

}  // namespace rkhs::kernels
