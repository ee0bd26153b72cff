#pragma once
// Matrix assembly templated on the concrete kernel type (kernel_algorithms.hpp builds the bases
// and the AnyKernel adaptor on it). Three paths, chosen at compile time or from the kernel's
// properties:
//   - feature-map kernels (B-splines): G = Phi Phi^T with Phi sparse, cost O(support) per row;
//   - compactly supported kernels: only pairs closer than the support radius are evaluated;
//   - global kernels: the dense double loop, one inlined k(x, y) per entry.
// Derivatives of the sections without a closed form come from the difference quotient of
// DerivativeStencil.

#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// c when `map` is exactly c I (square, non-empty), nothing otherwise: a learning map that a
/// basis applies as a scalar (the gradient law's Gamma^-1 I), O(n) instead of O(n^2).
inline std::optional<double> identity_multiple(const Eigen::MatrixXd& map) {
  if (map.rows() != map.cols() || map.rows() == 0) return std::nullopt;
  for (Eigen::Index j = 0; j < map.cols(); ++j)
    for (Eigen::Index i = 0; i < map.rows(); ++i)
      if (map(i, j) != (i == j ? map(0, 0) : 0.0)) return std::nullopt;
  return map(0, 0);
}

namespace detail {

/// Rows: points, columns: features. Each row holds the point's sparse features.
template <FeatureMapKernel K>
Eigen::SparseMatrix<double, Eigen::RowMajor> feature_matrix(const K& kernel,
                                                            std::span<const double> points) {
  SparseFeatures features;
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::size_t m = 0; m < points.size(); ++m) {
    kernel.features(points[m], features);
    for (std::size_t f = 0; f < features.size(); ++f)
      triplets.emplace_back(static_cast<int>(m), features.index[f], features.value[f]);
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> phi(
      static_cast<Eigen::Index>(points.size()), static_cast<Eigen::Index>(kernel.feature_count()));
  phi.setFromTriplets(triplets.begin(), triplets.end());
  return phi;
}

/// Kernel loops call check_cancelled() (core/cancellation.hpp) once per this many kernel
/// values: one value of a periodised kernel may sum up to 2^21 images (the bounds of
/// docs/study-files.md, milliseconds each), so a trial's deadline is seen within a fraction of
/// a second; a check (a clock read) costs about as much as one plain exponential.
inline constexpr std::size_t cancellation_stride = 32;

/// Calls visit(m, i) for every pair of point m and centre i with domain distance below
/// `radius` (and possibly a few more at the boundary of the window), in increasing i for each m.
template <class Visit>
void for_each_pair_within(const Domain& domain, double radius, std::span<const double> points,
                          std::span<const double> centres, Visit&& visit) {
  std::vector<std::size_t> order(centres.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<double> sorted(centres.size());
  for (std::size_t i = 0; i < centres.size(); ++i) sorted[i] = domain.wrap(centres[i]);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return sorted[a] < sorted[b]; });
  std::vector<double> keys(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) keys[k] = sorted[order[k]];
  std::vector<std::size_t> hits;
  const bool everything = domain.periodic && 2 * radius >= domain.length;
  for (std::size_t m = 0; m < points.size(); ++m) {
    hits.clear();
    if (everything) {
      for (std::size_t i = 0; i < centres.size(); ++i) hits.push_back(i);
    } else {
      const double x = domain.wrap(points[m]);
      auto add_range = [&](double lo, double hi) {
        auto first = std::lower_bound(keys.begin(), keys.end(), lo);
        auto last = std::upper_bound(keys.begin(), keys.end(), hi);
        for (auto it = first; it < last; ++it) hits.push_back(order[it - keys.begin()]);
      };
      add_range(x - radius, x + radius);
      if (domain.periodic) {
        if (x - radius < 0) add_range(x - radius + domain.length, domain.length);
        if (x + radius >= domain.length) add_range(0.0, x + radius - domain.length);
      }
      std::sort(hits.begin(), hits.end());
      hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    }
    for (std::size_t k = 0; k < hits.size(); ++k) {
      if (k % cancellation_stride == 0) check_cancelled();
      visit(m, hits[k]);
    }
  }
}

/// K_mi = k(x_m, c_i) for flat point sets in d > 1 dimensions: the dense double loop, one
/// inlined k(x, y) per entry (a compactly supported kernel returns 0 beyond its radius at the
/// cost of a distance).
template <PointKernel K>
Eigen::MatrixXd assemble_point_cross(const K& kernel, const Domain& domain,
                                     std::span<const double> points,
                                     std::span<const double> centres) {
  const auto d = static_cast<std::size_t>(domain.dimension);
  const auto rows = static_cast<Eigen::Index>(domain.point_count(points));
  const auto cols = static_cast<Eigen::Index>(domain.point_count(centres));
  Eigen::MatrixXd out(rows, cols);
  for (Eigen::Index i = 0; i < cols; ++i) {
    const double* c = centres.data() + static_cast<std::size_t>(i) * d;
    for (Eigen::Index m0 = 0; m0 < rows; m0 += cancellation_stride) {
      check_cancelled();
      const Eigen::Index m1 = std::min<Eigen::Index>(rows, m0 + cancellation_stride);
      for (Eigen::Index m = m0; m < m1; ++m)
        out(m, i) = kernel(points.data() + static_cast<std::size_t>(m) * d, c);
    }
  }
  return out;
}

}  // namespace detail

/// The difference quotient that stands in for d/ds where a kernel type has no closed form:
/// f'(s) ~ sum_j weight_j f(point_j), for any function f of s (one section k(c, .) for
/// AnyKernel::derivative, all n sections at once for a KernelBasis: the same points and weights,
/// so both give the same values).
///
/// Step h = 1e-7 L. The central difference (f(s + h) - f(s - h)) / 2h errs by h^2 |f'''| / 6
/// (truncation) plus about eps max|f| / h (rounding of f). For a kernel of width l, relative to
/// the slope scale |f| / l, that is (h / l)^2 / 6 + eps l / h: below 2e-8 for every width from
/// L / 1000 to 10 L, whereas 1e-6 L would lose 2e-7 to truncation at L / 1000 and 1e-5 L
/// would lose 2e-5. The divisor is the difference of the rounded arguments, so rounding s + h
/// costs nothing.
///
/// Next to a kink point kappa (|s - kappa| < h; the points of AnyKernel::kink_points) the
/// central difference would straddle the kink, so the stencil is one-sided and second order,
/// +-(-3 f(s) + 4 f(s +- h) - f(s +- 2h)) / 2h (error h^2 |f'''| / 3) on the side away from the
/// kink: the right-hand derivative for s >= kappa (at the kink itself too), the left-hand one for
/// s < kappa. On an interval the ends are treated as kinks, so points outside [0, L] are never
/// used (inward at the ends; at s = L the left-hand derivative). Assumes kink points at least
/// 3h apart.
class DerivativeStencil {
 public:
  /// Step relative to the domain length (see above).
  static constexpr double relative_step = 1e-7;

  struct Stencil {
    int size = 0;
    std::array<double, 3> point{};
    std::array<double, 3> weight{};
  };

  /// `kinks`: points in [0, L) where the differentiated functions are not smooth.
  DerivativeStencil(const Domain& domain, std::vector<double> kinks)
      : domain_(domain), step_(relative_step * domain.length), kinks_(std::move(kinks)) {
    std::sort(kinks_.begin(), kinks_.end());
  }

  double step() const noexcept { return step_; }

  /// The points and weights at s.
  Stencil at(double s) const noexcept {
    const double h = step_;
    int side = 0;  // 0: central, +1: forward (right-hand), -1: backward (left-hand)
    if (!domain_.periodic && s < h) {
      side = +1;
    } else if (!domain_.periodic && domain_.length - s < h) {
      side = -1;
    } else if (const double offset = offset_from_nearest_kink(s); std::abs(offset) < h) {
      side = offset >= 0 ? +1 : -1;
    }
    Stencil out;
    if (side == 0) {
      const double ahead = s + h, behind = s - h;
      const double inverse = 1.0 / (ahead - behind);
      out.size = 2;
      out.point = {ahead, behind, 0.0};
      out.weight = {inverse, -inverse, 0.0};
      return out;
    }
    const double near = s + side * h, far = s + side * 2.0 * h;
    const double inverse = side / (2.0 * (near - s) * side);  // +-1 / 2h, h as rounded
    out.size = 3;
    out.point = {s, near, far};
    out.weight = {-3.0 * inverse, 4.0 * inverse, -inverse};
    return out;
  }

  /// sum_j weight_j f(point_j) at s.
  template <class F>
  double apply(F&& f, double s) const {
    const Stencil stencil = at(s);
    double sum = 0.0;
    for (int j = 0; j < stencil.size; ++j) sum += stencil.weight[j] * f(stencil.point[j]);
    return sum;
  }

 private:
  /// s - kappa for the nearest kink point kappa (the periodic difference on a periodic domain);
  /// infinity when there is none.
  double offset_from_nearest_kink(double s) const noexcept {
    if (kinks_.empty()) return std::numeric_limits<double>::infinity();
    const double x = domain_.wrap(s);
    const auto next = std::lower_bound(kinks_.begin(), kinks_.end(), x);
    double best = std::numeric_limits<double>::infinity();
    auto consider = [&](double kappa) {
      const double offset = domain_.difference(x, kappa);
      if (std::abs(offset) < std::abs(best)) best = offset;
    };
    if (next != kinks_.end()) consider(*next);
    if (next != kinks_.begin()) consider(*(next - 1));
    if (domain_.periodic) {
      consider(kinks_.front());
      consider(kinks_.back());
    }
    return best;
  }

  Domain domain_;
  double step_;
  std::vector<double> kinks_;
};

/// K_mi = k(points[m], centres[i]).
template <KernelFunction K>
Eigen::MatrixXd assemble_cross(const K& kernel, const Domain& domain,
                               std::span<const double> points, std::span<const double> centres) {
  if constexpr (PointKernel<K>) {
    if (domain.dimension > 1) return detail::assemble_point_cross(kernel, domain, points, centres);
  }
  const auto rows = static_cast<Eigen::Index>(points.size());
  const auto cols = static_cast<Eigen::Index>(centres.size());
  if constexpr (FeatureMapKernel<K>) {
    const auto phi_points = detail::feature_matrix(kernel, points);
    const auto phi_centres = detail::feature_matrix(kernel, centres);
    // Wide supports make K dense: a sparse x dense product is then ~3x faster than
    // sparse x sparse; narrow supports keep the sparse product (cost ~ nonzeros of K).
    const double support = kernel.properties().support_radius;
    const bool dense_result = support <= 0 || 2 * support > 0.25 * domain.length;
    if (dense_result) return phi_points * Eigen::MatrixXd(phi_centres.transpose());
    Eigen::SparseMatrix<double, Eigen::RowMajor> product = phi_points * phi_centres.transpose();
    return Eigen::MatrixXd(product);
  } else {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(rows, cols);
    const double radius = kernel.properties().support_radius;
    if (radius > 0) {
      detail::for_each_pair_within(
          domain, radius, points, centres, [&](std::size_t m, std::size_t i) {
            out(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(i)) =
                kernel(points[m], centres[i]);
          });
    } else {
      for (Eigen::Index i = 0; i < cols; ++i)
        for (Eigen::Index m0 = 0; m0 < rows; m0 += detail::cancellation_stride) {
          check_cancelled();
          const Eigen::Index m1 = std::min<Eigen::Index>(rows, m0 + detail::cancellation_stride);
          for (Eigen::Index m = m0; m < m1; ++m) out(m, i) = kernel(points[m], centres[i]);
        }
    }
    return out;
  }
}

namespace detail {
/// The lower triangle of the dense Gram matrix, G_ij = kernel(c_i, c_j) for i >= j (`at(i)`
/// points to c_i), mirrored into the upper one: one evaluation per pair. The columns are split
/// into strips of about equal area that run through run_parts (the idle threads of the
/// caller's arena); every entry is computed by itself, so the matrix does not depend on the
/// thread count.
template <class Evaluate>
void assemble_symmetric(Eigen::Ref<Eigen::MatrixXd> gram, Evaluate&& evaluate) {
  const Eigen::Index n = gram.rows();
  const auto strips = static_cast<std::size_t>(n >= 256 ? std::min<Eigen::Index>(64, n / 32) : 1);
  // Strip p holds columns [first(p), first(p + 1)): equal shares of the n (n + 1) / 2 entries.
  auto first = [&](std::size_t p) {
    const double share = static_cast<double>(p) / static_cast<double>(strips);
    return p >= strips ? n
                       : static_cast<Eigen::Index>(
                             std::floor(static_cast<double>(n) * (1.0 - std::sqrt(1.0 - share))));
  };
  run_parts(strips, [&](std::size_t p) {
    for (Eigen::Index j = first(p); j < first(p + 1); ++j) {
      for (Eigen::Index i0 = j; i0 < n; i0 += cancellation_stride) {
        check_cancelled();
        const Eigen::Index i1 = std::min<Eigen::Index>(n, i0 + cancellation_stride);
        for (Eigen::Index i = i0; i < i1; ++i) gram(i, j) = evaluate(i, j);
      }
      // Row j right of the diagonal: entries no other strip writes.
      for (Eigen::Index i = j + 1; i < n; ++i) gram(j, i) = gram(i, j);
    }
  });
}
}  // namespace detail

/// G_ij = k(c_i, c_j), exactly symmetric, into `gram` (n x n, sized by the caller): the dense
/// kernels straight into it, in strips on the idle threads of the caller's arena.
template <KernelFunction K>
void assemble_gram_into(const K& kernel, const Domain& domain, std::span<const double> centres,
                        Eigen::Ref<Eigen::MatrixXd> gram) {
  const auto n = static_cast<Eigen::Index>(domain.point_count(centres));
  if (domain.dimension > 1) {
    if constexpr (PointKernel<K>) {
      const auto d = static_cast<std::size_t>(domain.dimension);
      detail::assemble_symmetric(gram, [&](Eigen::Index i, Eigen::Index j) {
        return kernel(centres.data() + static_cast<std::size_t>(i) * d,
                      centres.data() + static_cast<std::size_t>(j) * d);
      });
      return;
    }
    gram = assemble_cross(kernel, domain, centres, centres);
  } else if constexpr (FeatureMapKernel<K>) {
    gram = assemble_cross(kernel, domain, centres, centres);
  } else if (kernel.properties().support_radius > 0) {
    gram = assemble_cross(kernel, domain, centres, centres);
  } else {
    detail::assemble_symmetric(gram, [&](Eigen::Index i, Eigen::Index j) {
      return kernel(centres[static_cast<std::size_t>(i)], centres[static_cast<std::size_t>(j)]);
    });
    return;
  }
  // Symmetrise from the lower triangle: round-off in the two triangles may differ.
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = j + 1; i < n; ++i) gram(j, i) = gram(i, j);
}

/// G_ij = k(c_i, c_j), exactly symmetric.
template <KernelFunction K>
Eigen::MatrixXd assemble_gram(const K& kernel, const Domain& domain,
                              std::span<const double> centres) {
  const auto n = static_cast<Eigen::Index>(domain.point_count(centres));
  Eigen::MatrixXd gram(n, n);
  assemble_gram_into(kernel, domain, centres, gram);
  return gram;
}

}  // namespace rkhs
