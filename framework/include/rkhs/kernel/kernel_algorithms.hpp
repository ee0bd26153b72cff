#pragma once
// Matrix assembly templated on the concrete kernel type, and the AnyKernel adaptor that
// exposes it. Three paths, chosen at compile time or from the kernel's properties:
//   - feature-map kernels (B-splines): G = Phi Phi^T with Phi sparse, cost O(support) per row;
//   - compactly supported kernels: only pairs closer than the support radius are evaluated;
//   - global kernels: the dense double loop, one inlined k(x, y) per entry.

#include <Eigen/Sparse>
#include <algorithm>
#include <numeric>

#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

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
  Eigen::SparseMatrix<double, Eigen::RowMajor> phi(static_cast<Eigen::Index>(points.size()),
                                                   static_cast<Eigen::Index>(kernel.feature_count()));
  phi.setFromTriplets(triplets.begin(), triplets.end());
  return phi;
}

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
    for (std::size_t i : hits) visit(m, i);
  }
}

}  // namespace detail

/// K_mi = k(points[m], centres[i]).
template <KernelFunction K>
Eigen::MatrixXd assemble_cross(const K& kernel, const Domain& domain,
                               std::span<const double> points, std::span<const double> centres) {
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
      detail::for_each_pair_within(domain, radius, points, centres, [&](std::size_t m, std::size_t i) {
        out(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(i)) = kernel(points[m], centres[i]);
      });
    } else {
      for (Eigen::Index i = 0; i < cols; ++i)
        for (Eigen::Index m = 0; m < rows; ++m) out(m, i) = kernel(points[m], centres[i]);
    }
    return out;
  }
}

/// G_ij = k(c_i, c_j), exactly symmetric.
template <KernelFunction K>
Eigen::MatrixXd assemble_gram(const K& kernel, const Domain& domain,
                              std::span<const double> centres) {
  const auto n = static_cast<Eigen::Index>(centres.size());
  Eigen::MatrixXd gram;
  if constexpr (FeatureMapKernel<K>) {
    gram = assemble_cross(kernel, domain, centres, centres);
  } else if (kernel.properties().support_radius > 0) {
    gram = assemble_cross(kernel, domain, centres, centres);
  } else {
    gram.resize(n, n);
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = j; i < n; ++i) gram(i, j) = kernel(centres[i], centres[j]);
  }
  // Symmetrise from the lower triangle: round-off in the two triangles may differ.
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = j + 1; i < n; ++i) gram(j, i) = gram(i, j);
  return gram;
}

/// KernelBasis of a kernel without a feature map: n inlined evaluations per point.
template <KernelFunction K>
class DirectBasis final : public KernelBasis {
 public:
  DirectBasis(const K& kernel, std::span<const double> centres)
      : kernel_(kernel), centres_(centres.begin(), centres.end()), phi_(centres.size()) {}
  std::size_t size() const noexcept override { return centres_.size(); }
  void evaluate(double s, double* phi) const override {
    for (std::size_t i = 0; i < centres_.size(); ++i) phi[i] = kernel_(centres_[i], s);
  }
  void set_map(const Eigen::MatrixXd& map) override {
    // A multiple of the identity (the gradient law) is applied as a scalar: O(n), not O(n^2).
    const bool scalar = map.rows() == map.cols() && map.rows() > 0 &&
                        map.isApprox(map(0, 0) * Eigen::MatrixXd::Identity(map.rows(), map.cols()), 0.0);
    scale_ = scalar ? map(0, 0) : 0.0;
    map_ = scalar ? Eigen::MatrixXd() : map;
  }
  void evaluate_mapped(double s, double* out) const override {
    if (map_.size() == 0) {
      evaluate(s, out);
      for (std::size_t i = 0; i < centres_.size(); ++i) out[i] *= scale_;
      return;
    }
    evaluate(s, phi_.data());
    Eigen::Map<Eigen::VectorXd>(out, map_.rows()).noalias() =
        map_ * Eigen::Map<const Eigen::VectorXd>(phi_.data(), static_cast<Eigen::Index>(phi_.size()));
  }

 private:
  const K& kernel_;
  std::vector<double> centres_;
  mutable std::vector<double> phi_;
  Eigen::MatrixXd map_;  // empty when the map is scale_ times the identity
  double scale_ = 0.0;
};

/// KernelBasis through a sparse feature map: phi(s) = Phi_c f(s), with Phi_c (n x F) the
/// centres' features and f(s) the (few) features active at s.
template <FeatureMapKernel K>
class FeatureBasis final : public KernelBasis {
 public:
  FeatureBasis(const K& kernel, std::span<const double> centres)
      : kernel_(kernel),
        centre_features_(Eigen::MatrixXd(detail::feature_matrix(kernel, centres))) {
    kernel_.features(0.0, active_);  // grows the scratch buffer once
  }
  std::size_t size() const noexcept override {
    return static_cast<std::size_t>(centre_features_.rows());
  }
  void evaluate(double s, double* phi) const override { apply(centre_features_, s, phi); }
  void set_map(const Eigen::MatrixXd& map) override { mapped_features_ = map * centre_features_; }
  void evaluate_mapped(double s, double* out) const override { apply(mapped_features_, s, out); }

 private:
  void apply(const Eigen::MatrixXd& columns, double s, double* out) const {
    kernel_.features(s, active_);
    Eigen::Map<Eigen::VectorXd> result(out, columns.rows());
    result.setZero();
    for (std::size_t f = 0; f < active_.size(); ++f)
      result.noalias() += active_.value[f] * columns.col(active_.index[f]);
  }
  const K& kernel_;
  Eigen::MatrixXd centre_features_;
  Eigen::MatrixXd mapped_features_;
  mutable SparseFeatures active_;
};

/// The AnyKernel adaptor of a concrete kernel type.
template <KernelFunction K>
class KernelModel final : public AnyKernel {
 public:
  KernelModel(const ParameterSet& parameters, const Domain& domain)
      : kernel_(parameters, domain),
        name_(K::info().name),
        parameters_(parameters),
        domain_(domain),
        properties_(kernel_.properties()) {}

  const K& kernel() const noexcept { return kernel_; }

  const std::string& name() const noexcept override { return name_; }
  const ParameterSet& parameters() const noexcept override { return parameters_; }
  const Domain& domain() const noexcept override { return domain_; }
  const KernelProperties& properties() const noexcept override { return properties_; }

  double evaluate(double x, double y) const override { return kernel_(x, y); }
  Eigen::MatrixXd gram(std::span<const double> centres) const override {
    return assemble_gram(kernel_, domain_, centres);
  }
  Eigen::MatrixXd cross(std::span<const double> points,
                        std::span<const double> centres) const override {
    return assemble_cross(kernel_, domain_, points, centres);
  }
  Eigen::VectorXd diagonal(std::span<const double> points) const override {
    Eigen::VectorXd out(static_cast<Eigen::Index>(points.size()));
    for (std::size_t m = 0; m < points.size(); ++m)
      out(static_cast<Eigen::Index>(m)) = kernel_(points[m], points[m]);
    return out;
  }
  std::size_t feature_count() const noexcept override {
    if constexpr (FeatureMapKernel<K>) return kernel_.feature_count();
    else return 0;
  }
  std::unique_ptr<KernelBasis> basis(std::span<const double> centres) const override {
    if constexpr (FeatureMapKernel<K>) return std::make_unique<FeatureBasis<K>>(kernel_, centres);
    else return std::make_unique<DirectBasis<K>>(kernel_, centres);
  }
  std::vector<double> kink_points() const override {
    std::vector<double> kinks;
    if constexpr (requires { kernel_.kink_points(); }) kinks = kernel_.kink_points();
    if (domain_.periodic && !properties_.periodic) kinks.push_back(0.0);
    std::sort(kinks.begin(), kinks.end());
    kinks.erase(std::unique(kinks.begin(), kinks.end()), kinks.end());
    return kinks;
  }

 private:
  K kernel_;
  std::string name_;
  ParameterSet parameters_;
  Domain domain_;
  KernelProperties properties_;
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
