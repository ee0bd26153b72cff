#pragma once
// The kernel bases and the AnyKernel adaptor (KernelModel), templated on the concrete kernel
// type, on the matrix assembly of kernel_assembly.hpp.
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
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/kernel_assembly.hpp"

namespace rkhs {

/// A kernel whose values come cheapest a block at a time: a kernel written in another
/// language whose every call has a fixed cost (a Python kernel, numpy-vectorised,
/// python/src/plugins.cpp), where one call per value would dominate. `k.block(a, b, out)`
/// writes out(i, j) = k(a_i, b_j) for two flat point sets (core/domain.hpp; out is sized by the
/// caller, a rows x b rows) and `k.diagonal(points, out)` writes out[m] = k(s_m, s_m). Through
/// KernelModel a Gram matrix is one block (its upper triangle mirrored, so it is exactly
/// symmetric), a cross matrix one block per chunk of at most block_chunk_values entries (the run
/// can stop between chunks), and a basis evaluation one block of the n centres against the
/// point. The per-value k(x, y) of KernelFunction is still used, for single values.
template <class K>
concept BlockKernel = KernelFunction<K> &&
    requires(const K& k, std::span<const double> a, std::span<const double> b,
             Eigen::Ref<Eigen::MatrixXd> out, std::span<double> diagonal) {
  k.block(a, b, out);
  k.diagonal(a, diagonal);
};

/// The largest number of entries one BlockKernel::block call of a cross matrix computes.
inline constexpr std::size_t block_chunk_values = std::size_t{1} << 20;

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
    if constexpr (BlockKernel<K>) {
      const auto n = static_cast<Eigen::Index>(centres_.size());
      kernel_.block(centres_, std::span<const double>(&s, 1),
                    Eigen::Map<Eigen::MatrixXd>(phi, n, 1));
    } else {
      for (std::size_t i = 0; i < centres_.size(); ++i) phi[i] = kernel_(centres_[i], s);
    }
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
  /// K(parameters, domain, extra...): `extra` for a kernel type whose instances need more than
  /// their parameters (a Python kernel: the class it calls). A K with a member name() is named
  /// by it (one C++ type behind several registered kernels), any other by K::info().name.
  template <class... Extra>
  KernelModel(const ParameterSet& parameters, const Domain& domain, Extra&&... extra)
      : kernel_(checked_domain(domain, parameters), domain, std::forward<Extra>(extra)...),
        name_(registered_name(kernel_)),
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
    if constexpr (BlockKernel<K>) {
      kernel_.block(centres, centres, out);
      out.template triangularView<Eigen::StrictlyLower>() = out.transpose();
    } else {
      assemble_gram_into(kernel_, domain_, centres, out);
    }
  }
  void cross_into(std::span<const double> points, std::span<const double> centres,
                  Eigen::Ref<Eigen::MatrixXd> out) const override {
    require_flat(points, "cross_into");
    require_flat(centres, "cross_into");
    require_size(out.rows(), out.cols(), domain_.point_count(points), domain_.point_count(centres),
                 "cross_into");
    count_kernel_evaluations(std::uint64_t{domain_.point_count(points)} *
                             domain_.point_count(centres));
    if constexpr (BlockKernel<K>) {
      const std::size_t rows = domain_.point_count(points), cols = domain_.point_count(centres);
      const std::size_t chunk =
          std::max<std::size_t>(1, block_chunk_values / std::max<std::size_t>(1, cols));
      const auto dim = static_cast<std::size_t>(domain_.dimension);
      for (std::size_t first = 0; first < rows; first += chunk) {
        check_cancelled();
        const std::size_t count = std::min(chunk, rows - first);
        kernel_.block(
            points.subspan(first * dim, count * dim), centres,
            out.middleRows(static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(count)));
      }
    } else {
      out = assemble_cross(kernel_, domain_, points, centres);
    }
  }
  void diagonal_into(std::span<const double> points, std::span<double> out) const override {
    require_flat(points, "diagonal_into");
    const std::size_t count = domain_.point_count(points);
    require_size(static_cast<Eigen::Index>(out.size()), 1, count, 1, "diagonal_into");
    count_kernel_evaluations(count);
    if constexpr (BlockKernel<K>) {
      kernel_.diagonal(points, out);
      return;
    }
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
  static std::string registered_name(const K& kernel) {
    if constexpr (requires { kernel.name(); })
      return std::string(kernel.name());
    else
      return K::info().name;
  }
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
