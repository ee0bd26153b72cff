#pragma once
// Matrix assembly templated on the concrete kernel type, and the AnyKernel adaptor that
// exposes it. Three paths, chosen at compile time or from the kernel's properties:
//   - feature-map kernels (B-splines): G = Phi Phi^T with Phi sparse, cost O(support) per row;
//   - compactly supported kernels: only pairs closer than the support radius are evaluated;
//   - global kernels: the dense double loop, one inlined k(x, y) per entry.
// Derivatives of the sections, d/ds k(c, s), come from the kernel's closed form
// (DifferentiableKernel, DifferentiableFeatureMapKernel) or, without one, from the difference
// quotient of DerivativeStencil.
//
// Work counters (rkhs/core/work_counters.hpp): KernelModel's matrix methods and the bases count
// the kernel values a trial asks for, one count per matrix or basis call (a Gram matrix its
// n (n + 1) / 2 distinct entries, a cross matrix rows x cols, a diagonal its points, a basis
// evaluation its size() sections, a basis derivative size() derivative values), whatever path
// computes them. A call of one public method of a basis by another counts once.

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

/// KernelBasis of a kernel without a feature map: n inlined evaluations per point. Derivatives:
/// K::derivative when K is a DifferentiableKernel, otherwise `stencil` (n evaluations per
/// stencil point). `kernel` and `stencil` must outlive the basis.
template <KernelFunction K>
class DirectBasis final : public KernelBasis {
 public:
  DirectBasis(const K& kernel, std::span<const double> centres, const DerivativeStencil& stencil)
      : kernel_(kernel),
        stencil_(stencil),
        centres_(centres.begin(), centres.end()),
        phi_(centres.size()),
        dphi_(centres.size()) {}
  std::size_t size() const noexcept override { return centres_.size(); }
  void evaluate(double s, double* phi) const override {
    count_kernel_evaluations(centres_.size());
    sections(s, phi);
  }
  void set_map(const Eigen::MatrixXd& map) override {
    // A multiple of the identity (the gradient law) is applied as a scalar: O(n), not O(n^2).
    const auto scalar = identity_multiple(map);
    scale_ = scalar.value_or(0.0);
    map_ = scalar ? Eigen::MatrixXd() : map;
  }
  void evaluate_mapped(double s, double* out) const override {
    count_kernel_evaluations(centres_.size());
    if (map_.size() == 0) {
      sections(s, out);
      for (std::size_t i = 0; i < centres_.size(); ++i) out[i] *= scale_;
      return;
    }
    sections(s, phi_.data());
    Eigen::Map<Eigen::VectorXd>(out, map_.rows()).noalias() =
        map_ *
        Eigen::Map<const Eigen::VectorXd>(phi_.data(), static_cast<Eigen::Index>(phi_.size()));
  }
  void evaluate_derivative(double s, double* dphi) const override {
    count_kernel_derivative_evaluations(centres_.size());
    derivatives(s, dphi);
  }
  void evaluate_mapped_derivative(double s, double* out) const override {
    count_kernel_derivative_evaluations(centres_.size());
    if (map_.size() == 0) {
      derivatives(s, out);
      for (std::size_t i = 0; i < centres_.size(); ++i) out[i] *= scale_;
      return;
    }
    derivatives(s, dphi_.data());
    Eigen::Map<Eigen::VectorXd>(out, map_.rows()).noalias() =
        map_ *
        Eigen::Map<const Eigen::VectorXd>(dphi_.data(), static_cast<Eigen::Index>(dphi_.size()));
  }

 private:
  void sections(double s, double* phi) const {
    for (std::size_t i = 0; i < centres_.size(); ++i) phi[i] = kernel_(centres_[i], s);
  }
  void derivatives(double s, double* dphi) const {
    if constexpr (DifferentiableKernel<K>) {
      for (std::size_t i = 0; i < centres_.size(); ++i)
        dphi[i] = kernel_.derivative(centres_[i], s);
    } else {
      // The same sums, in the same order, as AnyKernel::derivative of each section.
      const auto stencil = stencil_.at(s);
      std::fill(dphi, dphi + centres_.size(), 0.0);
      for (int j = 0; j < stencil.size; ++j) {
        sections(stencil.point[j], phi_.data());
        for (std::size_t i = 0; i < centres_.size(); ++i) dphi[i] += stencil.weight[j] * phi_[i];
      }
    }
  }
  const K& kernel_;
  const DerivativeStencil& stencil_;
  std::vector<double> centres_;
  mutable std::vector<double> phi_, dphi_;
  Eigen::MatrixXd map_;  // empty when the map is scale_ times the identity
  double scale_ = 0.0;
};

/// KernelBasis through a sparse feature map: phi(s) = Phi_c f(s), with Phi_c (n x F) the
/// centres' features and f(s) the (few) features active at s. Derivatives: Phi_c f'(s) with
/// K::feature_derivatives (DifferentiableFeatureMapKernel), else K::derivative per centre
/// (DifferentiableKernel), else `stencil` applied to Phi_c f(.). `kernel` and `stencil` must
/// outlive the basis.
template <FeatureMapKernel K>
class FeatureBasis final : public KernelBasis {
 public:
  FeatureBasis(const K& kernel, std::span<const double> centres, const DerivativeStencil& stencil)
      : kernel_(kernel),
        stencil_(stencil),
        centre_features_(Eigen::MatrixXd(detail::feature_matrix(kernel, centres))),
        scratch_(centre_features_.rows()) {
    kernel_.features(0.0, active_);  // grows the scratch buffer once
    if constexpr (DifferentiableFeatureMapKernel<K>) kernel_.feature_derivatives(0.0, active_);
    if constexpr (!DifferentiableFeatureMapKernel<K> && DifferentiableKernel<K>)
      centres_.assign(centres.begin(), centres.end());
  }
  std::size_t size() const noexcept override {
    return static_cast<std::size_t>(centre_features_.rows());
  }
  void evaluate(double s, double* phi) const override {
    count_kernel_evaluations(size());
    apply(centre_features_, s, phi);
  }
  void set_map(const Eigen::MatrixXd& map) override {
    // c I (the gradient law) scales the features: O(n F), not the O(n^2 F) product (which
    // took 37 s at n = 4096, F = 10235).
    if (const auto scalar = identity_multiple(map))
      mapped_features_ = *scalar * centre_features_;
    else
      mapped_features_ = map * centre_features_;
    if constexpr (!DifferentiableFeatureMapKernel<K> && DifferentiableKernel<K>) map_ = map;
    if (scratch_.size() < mapped_features_.rows()) scratch_.resize(mapped_features_.rows());
  }
  void evaluate_mapped(double s, double* out) const override {
    count_kernel_evaluations(size());
    apply(mapped_features_, s, out);
  }
  void evaluate_derivative(double s, double* dphi) const override {
    count_kernel_derivative_evaluations(size());
    derivatives(s, dphi);
  }
  void evaluate_mapped_derivative(double s, double* out) const override {
    count_kernel_derivative_evaluations(size());
    if constexpr (!DifferentiableFeatureMapKernel<K> && DifferentiableKernel<K>) {
      const auto n = centre_features_.rows();
      derivatives(s, scratch_.data());
      Eigen::Map<Eigen::VectorXd>(out, map_.rows()).noalias() = map_ * scratch_.head(n);
    } else {
      apply_derivative(mapped_features_, s, out);
    }
  }

 private:
  void derivatives(double s, double* dphi) const {
    if constexpr (!DifferentiableFeatureMapKernel<K> && DifferentiableKernel<K>) {
      for (std::size_t i = 0; i < centres_.size(); ++i)
        dphi[i] = kernel_.derivative(centres_[i], s);
    } else {
      apply_derivative(centre_features_, s, dphi);
    }
  }
  void apply(const Eigen::MatrixXd& columns, double s, double* out) const {
    kernel_.features(s, active_);
    accumulate(columns, out);
  }
  void accumulate(const Eigen::MatrixXd& columns, double* out) const {
    Eigen::Map<Eigen::VectorXd> result(out, columns.rows());
    result.setZero();
    for (std::size_t f = 0; f < active_.size(); ++f)
      result.noalias() += active_.value[f] * columns.col(active_.index[f]);
  }
  // d/ds of `columns` f(s): the features' derivatives, or the stencil's sum of apply().
  void apply_derivative(const Eigen::MatrixXd& columns, double s, double* out) const {
    if constexpr (DifferentiableFeatureMapKernel<K>) {
      kernel_.feature_derivatives(s, active_);
      accumulate(columns, out);
    } else {
      const auto stencil = stencil_.at(s);
      const auto rows = columns.rows();
      Eigen::Map<Eigen::VectorXd> result(out, rows);
      result.setZero();
      for (int j = 0; j < stencil.size; ++j) {
        apply(columns, stencil.point[j], scratch_.data());
        result.noalias() += stencil.weight[j] * scratch_.head(rows);
      }
    }
  }
  const K& kernel_;
  const DerivativeStencil& stencil_;
  Eigen::MatrixXd centre_features_;
  Eigen::MatrixXd mapped_features_;
  std::vector<double> centres_;  // only for K::derivative without feature derivatives
  Eigen::MatrixXd map_;          // likewise
  mutable SparseFeatures active_;
  mutable Eigen::VectorXd scratch_;
};

/// KernelBasis of the features themselves (feature coordinates, AnyKernel::feature_basis):
/// size() = F = K::feature_count(), phi_f(s) = psi_f(s). Each evaluation writes all F values: the
/// (p + 1)(J + 1) features active at s (for the B-spline kernel) and zeros, so it costs
/// O(active) kernel work and O(F) stores. Derivatives: K::feature_derivatives
/// (DifferentiableFeatureMapKernel), else `stencil` applied to the features. set_map(T) keeps a
/// multiple of the identity as a scalar (applied to the active features) and any other T
/// (rows x F) as the sum of its active columns. Nothing is allocated after construction.
/// `kernel` and `stencil` must outlive the basis.
template <FeatureMapKernel K>
class FeatureCoordinateBasis final : public KernelBasis {
 public:
  FeatureCoordinateBasis(const K& kernel, const DerivativeStencil& stencil)
      : kernel_(kernel),
        stencil_(stencil),
        count_(static_cast<Eigen::Index>(kernel.feature_count())),
        scratch_(static_cast<std::size_t>(count_)) {
    kernel_.features(0.0, active_);  // grows the scratch buffer once
    if constexpr (DifferentiableFeatureMapKernel<K>) kernel_.feature_derivatives(0.0, active_);
  }
  std::size_t size() const noexcept override { return static_cast<std::size_t>(count_); }
  void evaluate(double s, double* phi) const override {
    count_kernel_evaluations(size());
    kernel_.features(s, active_);
    scatter(1.0, phi);
  }
  void set_map(const Eigen::MatrixXd& map) override {
    const auto scalar = identity_multiple(map);
    scale_ = scalar.value_or(0.0);
    map_ = scalar ? Eigen::MatrixXd() : map;
  }
  void evaluate_mapped(double s, double* out) const override {
    count_kernel_evaluations(size());
    kernel_.features(s, active_);
    mapped(out);
  }
  void evaluate_derivative(double s, double* dphi) const override {
    count_kernel_derivative_evaluations(size());
    derivatives(s, dphi);
  }
  void evaluate_mapped_derivative(double s, double* out) const override {
    count_kernel_derivative_evaluations(size());
    if constexpr (DifferentiableFeatureMapKernel<K>) {
      kernel_.feature_derivatives(s, active_);
      mapped(out);
    } else {
      derivatives(s, scratch_.data());
      if (map_.size() == 0) {
        for (Eigen::Index f = 0; f < count_; ++f)
          out[f] = scale_ * scratch_[static_cast<std::size_t>(f)];
        return;
      }
      Eigen::Map<Eigen::VectorXd>(out, map_.rows()).noalias() =
          map_ * Eigen::Map<const Eigen::VectorXd>(scratch_.data(), count_);
    }
  }

 private:
  void derivatives(double s, double* dphi) const {
    if constexpr (DifferentiableFeatureMapKernel<K>) {
      kernel_.feature_derivatives(s, active_);
      scatter(1.0, dphi);
    } else {
      const auto stencil = stencil_.at(s);
      std::fill(dphi, dphi + count_, 0.0);
      for (int j = 0; j < stencil.size; ++j) {
        kernel_.features(stencil.point[j], active_);
        for (std::size_t f = 0; f < active_.size(); ++f)
          dphi[active_.index[f]] += stencil.weight[j] * active_.value[f];
      }
    }
  }
  // out = scale * (the active values at their indices), zero elsewhere (F entries).
  void scatter(double scale, double* out) const {
    std::fill(out, out + count_, 0.0);
    for (std::size_t f = 0; f < active_.size(); ++f)
      out[active_.index[f]] += scale * active_.value[f];
  }
  // out = T (the active values at their indices): c times them for T = c I.
  void mapped(double* out) const {
    if (map_.size() == 0) {
      scatter(scale_, out);
      return;
    }
    Eigen::Map<Eigen::VectorXd> result(out, map_.rows());
    result.setZero();
    for (std::size_t f = 0; f < active_.size(); ++f)
      result.noalias() += active_.value[f] * map_.col(active_.index[f]);
  }
  const K& kernel_;
  const DerivativeStencil& stencil_;
  Eigen::Index count_;
  mutable SparseFeatures active_;
  mutable std::vector<double> scratch_;
  Eigen::MatrixXd map_;  // empty when the map is scale_ times the identity
  double scale_ = 1.0;
};

/// The AnyKernel adaptor of a concrete kernel type.
template <KernelFunction K>
class KernelModel final : public AnyKernel {
 public:
  KernelModel(const ParameterSet& parameters, const Domain& domain)
      : kernel_(checked_domain(domain, parameters), domain),
        name_(K::info().name),
        parameters_(parameters),
        domain_(domain),
        properties_(kernel_.properties()),
        kinks_(sorted_kinks(kernel_, domain, properties_)),
        stencil_(domain, exact_derivative ? std::vector<double>{} : kinks_) {}

  /// True when K gives its derivatives in closed form.
  static constexpr bool exact_derivative =
      DifferentiableKernel<K> || DifferentiableFeatureMapKernel<K>;

  const K& kernel() const noexcept { return kernel_; }

  const std::string& name() const noexcept override { return name_; }
  const ParameterSet& parameters() const noexcept override { return parameters_; }
  const Domain& domain() const noexcept override { return domain_; }
  const KernelProperties& properties() const noexcept override { return properties_; }

  double evaluate(double x, double y) const override {
    require_one_dimensional("evaluate");
    return kernel_(x, y);
  }
  double evaluate_point(std::span<const double> x, std::span<const double> y) const override {
    const auto d = static_cast<std::size_t>(domain_.dimension);
    if (x.size() != d || y.size() != d)
      throw std::invalid_argument("AnyKernel::evaluate_point: points of " +
                                  std::to_string(x.size()) + " and " + std::to_string(y.size()) +
                                  " coordinates on a domain of dimension " + std::to_string(d));
    if (d == 1) return kernel_(x[0], y[0]);
    if constexpr (PointKernel<K>)
      return kernel_(x.data(), y.data());
    else
      throw std::logic_error("unreachable: a one-dimensional kernel on a domain of d > 1");
  }
  double derivative(double x, double y) const override {
    require_one_dimensional("derivative");
    if constexpr (DifferentiableKernel<K>) {
      return kernel_.derivative(x, y);
    } else if constexpr (DifferentiableFeatureMapKernel<K>) {
      // sum_f phi_f(x) phi_f'(y); allocates (a call per value, for tests and contracts).
      SparseFeatures at_x, slopes_at_y;
      kernel_.features(x, at_x);
      kernel_.feature_derivatives(y, slopes_at_y);
      double sum = 0.0;
      for (std::size_t a = 0; a < at_x.size(); ++a)
        for (std::size_t b = 0; b < slopes_at_y.size(); ++b)
          if (at_x.index[a] == slopes_at_y.index[b]) sum += at_x.value[a] * slopes_at_y.value[b];
      return sum;
    } else {
      return stencil_.apply([&](double t) { return kernel_(x, t); }, y);
    }
  }
  bool has_exact_derivative() const noexcept override { return exact_derivative; }
  void gradient_point(std::span<const double> x, std::span<const double> y,
                      std::span<double> out) const override {
    const auto d = static_cast<std::size_t>(domain_.dimension);
    if (x.size() != d || y.size() != d || out.size() != d)
      throw std::invalid_argument("AnyKernel::gradient_point: points of " +
                                  std::to_string(x.size()) + " and " + std::to_string(y.size()) +
                                  " coordinates and " + std::to_string(out.size()) +
                                  " outputs on a domain of dimension " + std::to_string(d));
    if (d == 1) {
      out[0] = derivative(x[0], y[0]);
      return;
    }
    if constexpr (GradientKernel<K>) {
      kernel_.gradient(x.data(), y.data(), out.data());
    } else if constexpr (PointKernel<K>) {
      double point[Domain::max_dimension] = {0, 0, 0};
      for (std::size_t a = 0; a < d; ++a) point[a] = y[a];
      for (std::size_t a = 0; a < d; ++a) {
        const double extent = domain_.extent(static_cast<int>(a)), step = 1e-6 * extent;
        // Central, or one-sided next to a box's face (points beyond it are outside Omega).
        const double up = domain_.periodic || y[a] + step <= extent ? step : 0.0;
        const double down = domain_.periodic || y[a] - step >= 0.0 ? step : 0.0;
        point[a] = y[a] + up;
        const double high = kernel_(x.data(), point);
        point[a] = y[a] - down;
        const double low = kernel_(x.data(), point);
        point[a] = y[a];
        out[a] = (high - low) / (up + down);
      }
    }
  }
  bool has_exact_gradient() const noexcept override {
    return domain_.dimension == 1 ? exact_derivative : GradientKernel<K>;
  }
  void gram_into(std::span<const double> centres, Eigen::Ref<Eigen::MatrixXd> out) const override {
    const std::size_t n = domain_.point_count(centres);
    require_flat(centres, "gram_into");
    require_size(out.rows(), out.cols(), n, n, "gram_into");
    count_kernel_evaluations(std::uint64_t{n} * (n + 1) / 2);
    assemble_gram_into(kernel_, domain_, centres, out);
  }
  void cross_into(std::span<const double> points, std::span<const double> centres,
                  Eigen::Ref<Eigen::MatrixXd> out) const override {
    require_flat(points, "cross_into");
    require_flat(centres, "cross_into");
    require_size(out.rows(), out.cols(), domain_.point_count(points), domain_.point_count(centres),
                 "cross_into");
    count_kernel_evaluations(std::uint64_t{domain_.point_count(points)} *
                             domain_.point_count(centres));
    out = assemble_cross(kernel_, domain_, points, centres);
  }
  void diagonal_into(std::span<const double> points, std::span<double> out) const override {
    require_flat(points, "diagonal_into");
    const std::size_t count = domain_.point_count(points);
    require_size(static_cast<Eigen::Index>(out.size()), 1, count, 1, "diagonal_into");
    count_kernel_evaluations(count);
    if (domain_.dimension == 1) {
      for (std::size_t m = 0; m < count; ++m) {
        if (m % detail::cancellation_stride == 0) check_cancelled();
        out[m] = kernel_(points[m], points[m]);
      }
      return;
    }
    if constexpr (PointKernel<K>) {
      const auto d = static_cast<std::size_t>(domain_.dimension);
      for (std::size_t m = 0; m < count; ++m) {
        if (m % detail::cancellation_stride == 0) check_cancelled();
        out[m] = kernel_(points.data() + m * d, points.data() + m * d);
      }
    }
  }
  std::size_t feature_count() const noexcept override {
    if constexpr (FeatureMapKernel<K>)
      return kernel_.feature_count();
    else
      return 0;
  }
  std::unique_ptr<KernelBasis> basis(std::span<const double> centres) const override {
    require_one_dimensional("basis");
    if constexpr (FeatureMapKernel<K>)
      return std::make_unique<FeatureBasis<K>>(kernel_, centres, stencil_);
    else
      return std::make_unique<DirectBasis<K>>(kernel_, centres, stencil_);
  }
  std::unique_ptr<KernelBasis> feature_basis() const override {
    require_one_dimensional("feature_basis");
    if constexpr (FeatureMapKernel<K>)
      return std::make_unique<FeatureCoordinateBasis<K>>(kernel_, stencil_);
    else
      return nullptr;
  }
  void list_kink_points(const std::function<void(double)>& sink) const override {
    for (double s : kinks_) sink(s);
  }

 private:
  // The kink points of K (if it names any) and the seam of a periodic domain when K is not
  // periodic, sorted and unique.
  static std::vector<double> sorted_kinks(const K& kernel, const Domain& domain,
                                          const KernelProperties& properties) {
    std::vector<double> kinks;
    if constexpr (requires { kernel.kink_points(); }) kinks = kernel.kink_points();
    if (domain.periodic && !properties.periodic) kinks.push_back(0.0);
    std::sort(kinks.begin(), kinks.end());
    kinks.erase(std::unique(kinks.begin(), kinks.end()), kinks.end());
    return kinks;
  }
  // The domain, after checking that K is defined on it: a kernel without the point form
  // k(const double*, const double*) is one-dimensional.
  static const ParameterSet& checked_domain(const Domain& domain, const ParameterSet& parameters) {
    domain.validate();
    if (domain.dimension > 1 && !PointKernel<K>)
      throw std::invalid_argument("kernel '" + K::info().name +
                                  "' is defined on one-dimensional domains only; this domain has "
                                  "d = " +
                                  std::to_string(domain.dimension));
    return parameters;
  }
  void require_one_dimensional(const char* method) const {
    if (domain_.dimension != 1)
      throw std::logic_error(std::string("AnyKernel::") + method +
                             " is defined on one-dimensional domains only (d = " +
                             std::to_string(domain_.dimension) + ")");
  }
  void require_flat(std::span<const double> points, const char* method) const {
    if (points.size() % static_cast<std::size_t>(domain_.dimension) != 0)
      throw std::invalid_argument(
          std::string("AnyKernel::") + method + ": " + std::to_string(points.size()) +
          " coordinates are not whole points of dimension " + std::to_string(domain_.dimension));
  }
  static void require_size(Eigen::Index rows, Eigen::Index cols, std::size_t expected_rows,
                           std::size_t expected_cols, const char* method) {
    if (rows != static_cast<Eigen::Index>(expected_rows) ||
        cols != static_cast<Eigen::Index>(expected_cols))
      throw std::invalid_argument(std::string("AnyKernel::") + method + ": output is " +
                                  std::to_string(rows) + " x " + std::to_string(cols) +
                                  ", expected " + std::to_string(expected_rows) + " x " +
                                  std::to_string(expected_cols));
  }

 private:
  K kernel_;
  std::string name_;
  ParameterSet parameters_;
  Domain domain_;
  KernelProperties properties_;
  std::vector<double> kinks_;  // list_kink_points
  DerivativeStencil stencil_;  // used only without exact derivatives; holds the kinks then
};

/// Registers kernel type K (its info() and a KernelModel<K> factory) into kernel_registry().
/// Never throws; a failure is recorded in kernel_registry().errors() (register_plugin).
template <KernelFunction K>
bool register_kernel() noexcept {
  return register_plugin<K, KernelModel<K>>(kernel_registry());
}

}  // namespace rkhs

/// Registers a kernel type at start-up. Use once, at namespace scope, in the kernel's .cpp file.
/// In a plugin module (RKHS_BUILDING_PLUGIN) the registration waits for the loader's ABI check.
#define RKHS_REGISTER_KERNEL(Type) \
  RKHS_REGISTRAR(rkhs_kernel_registered_, ::rkhs::register_kernel<Type>())
