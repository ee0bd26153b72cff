#pragma once
// Kernels: what a kernel type must provide (concepts), the facts theory needs about it
// (KernelProperties), and the type-erased AnyKernel through which trials use it.
//
// A kernel plugin is a concrete class K with
//   static PluginInfo info();                      name, doc, parameters (registry.hpp)
//   K(const ParameterSet&, const Domain&);          may throw ParameterError / invalid_argument
//   double operator()(double x, double y) const;    k(x, y) for x, y in the domain, periodised
//                                                   when the domain is periodic
//   KernelProperties properties() const;
// and, optionally, a sparse feature map (FeatureMapKernel) through which Gram and cross
// matrices are assembled, and the derivative of its sections in closed form
// (DifferentiableKernel: derivative(c, s) = d/ds k(c, s); for a feature map also
// feature_derivatives, DifferentiableFeatureMapKernel). Without them, derivatives are difference
// quotients (DerivativeStencil in kernel_algorithms.hpp). It registers with RKHS_REGISTER_KERNEL(K)
// in its own .cpp file. Hot loops (Gram assembly, cross matrices, error evaluation) are
// instantiated for K, so the compiler inlines k(x, y); type erasure happens once per trial, at
// AnyKernel.

#include <Eigen/Dense>
#include <concepts>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs {

/// What approximation theory needs to know about a kernel instance.
struct KernelProperties {
  bool positive_definite = true;  ///< strictly positive definite on distinct points
  /// Native space equivalent to the Sobolev space H^tau(Omega) (Omega of `dimension` d): tau.
  /// Empty when the kernel is analytic (Gaussian) or has no Sobolev-equivalent native space.
  std::optional<double> sobolev_order;
  bool analytic = false;        ///< infinitely smooth, spectral (exponential) convergence
  double support_radius = 0.0;  ///< k(x, y) = 0 when |x - y| >= radius; 0 means global support
  bool stationary = true;       ///< k(x, y) depends on x - y only
  bool periodic = false;        ///< periodised on a periodic domain
  /// d, the dimension of the domain the kernel is defined on: what the rates theory predicts
  /// depends on it (h ~ n^-1/d, tau - d/2). A kernel reports its domain's dimension (1 for a
  /// track or an interval); read it from here, never assume it.
  int dimension = 1;
};

/// Nonzero entries of a sparse feature vector phi(x), with k(x, y) = sum_f phi_f(x) phi_f(y).
struct SparseFeatures {
  std::vector<std::int32_t> index;
  std::vector<double> value;
  void clear() noexcept {
    index.clear();
    value.clear();
  }
  void push(std::int32_t i, double v) {
    index.push_back(i);
    value.push_back(v);
  }
  std::size_t size() const noexcept { return index.size(); }
};

template <class K>
concept KernelFunction = requires(const K& k, double x, double y) {
  { k(x, y) } -> std::convertible_to<double>;
  { k.properties() } -> std::convertible_to<KernelProperties>;
  { K::info() } -> std::convertible_to<PluginInfo>;
};

/// A kernel defined on domains of more than one dimension: `k(x, y)` with x and y pointers to
/// d = domain.dimension coordinates each (periodised per axis on a torus). Its properties()
/// give the `dimension` of the domain it was made for and tau for that d. A kernel without it
/// is one-dimensional: KernelModel refuses a domain with d > 1 for it.
template <class K>
concept PointKernel = KernelFunction<K> && requires(const K& k, const double* x, const double* y) {
  { k(x, y) } -> std::convertible_to<double>;
};

/// A kernel with a finite sparse feature map: `features(x, f)` clears f and appends the
/// nonzero features at x (indices < feature_count(); no allocation once f has grown to its
/// largest size).
template <class K>
concept FeatureMapKernel = KernelFunction<K> && requires(const K& k, double x, SparseFeatures& f) {
  k.features(x, f);
  { k.feature_count() } -> std::convertible_to<std::size_t>;
};

/// A kernel whose sections have a derivative in closed form: `k.derivative(c, s)` is
/// d/ds k(c, s), the derivative in the SECOND argument, periodised like k(c, s) on a periodic
/// domain. Where the section is not differentiable (a kink), it is the right-hand derivative
/// unless the kernel's header says otherwise.
template <class K>
concept DifferentiableKernel = KernelFunction<K> && requires(const K& k, double x, double y) {
  { k.derivative(x, y) } -> std::convertible_to<double>;
};

/// A kernel on domains of d > 1 with the gradient of its sections in closed form:
/// `k.gradient(x, y, g)` writes the d components of grad_y k(x, y) (periodised like k on a
/// torus). Where a section is not differentiable (the centre of a kernel with a cusp, nu = 1/2
/// or Wendland k = 0 at y = x) the kernel's header says what it writes.
template <class K>
concept GradientKernel = PointKernel<K> &&
    requires(const K& k, const double* x, const double* y, double* g) {
  k.gradient(x, y, g);
};

/// A feature-map kernel with the derivatives of its features in closed form:
/// `feature_derivatives(s, f)` clears f and appends d/ds of the features at s with the SAME
/// indices in the same order as features(s, f) (so a basis can apply them to columns it
/// precomputed for features(); no allocation once f has grown to its largest size).
template <class K>
concept DifferentiableFeatureMapKernel = FeatureMapKernel<K> &&
    requires(const K& k, double x, SparseFeatures& f) {
  k.feature_derivatives(x, f);
};

/// The n kernel sections phi_i = k(c_i, .) at fixed centres, evaluated at one point at a time:
/// the inner loop of an ODE right-hand side. One virtual call evaluates all n sections with the
/// concrete kernel inlined; nothing is allocated after construction. Not thread-safe (it owns
/// scratch buffers): one basis per trial.
class KernelBasis {
 public:
  virtual ~KernelBasis() = default;
  virtual std::size_t size() const noexcept = 0;
  /// phi[i] = k(c_i, s) for i < size().
  virtual void evaluate(double s, double* phi) const = 0;
  /// Fixes a linear map T (rows x size()) for evaluate_mapped. For feature-map kernels T Phi_c
  /// is precomputed, so a mapped evaluation costs O(rows x features at s), not O(rows x n).
  virtual void set_map(const Eigen::MatrixXd& map) = 0;
  /// out = T phi(s), out.size() == T.rows().
  virtual void evaluate_mapped(double s, double* out) const = 0;
  /// dphi[i] = d/ds k(c_i, s) for i < size(): the kernel's closed form where it has one
  /// (AnyKernel::has_exact_derivative()), otherwise the difference quotient of
  /// DerivativeStencil (kernel_algorithms.hpp: step 1e-7 L, one-sided next to a kink), the
  /// same values as AnyKernel::derivative. Nothing is allocated.
  virtual void evaluate_derivative(double s, double* dphi) const = 0;
  /// out = T dphi(s), T the map of set_map (out.size() == T.rows()). Nothing is allocated.
  virtual void evaluate_mapped_derivative(double s, double* out) const = 0;
};

/// A kernel instance behind a virtual interface: the registry boundary. Each method runs a
/// whole loop on the concrete kernel type. KernelModel (kernel_algorithms.hpp), which every
/// registered kernel is wrapped in, counts the values its matrix methods and bases compute into
/// the trial's work counters (core/work_counters.hpp), so kernel plugins count without code of
/// their own.
///
/// The boundary owns nothing across it (plugin/module.hpp): a kernel may live in a plugin
/// module built by another compiler invocation, whose Eigen may allocate differently (alignment,
/// vectorisation, sanitizers). So no virtual returns an Eigen object or a container: the
/// virtuals write into storage the caller owns and has sized (`*_into`) or hand values to a
/// caller's sink, and the non-virtual conveniences (gram(), cross(), diagonal(), kink_points())
/// allocate on the caller's side.
class AnyKernel {
 public:
  virtual ~AnyKernel() = default;

  virtual const std::string& name() const noexcept = 0;
  virtual const ParameterSet& parameters() const noexcept = 0;
  virtual const Domain& domain() const noexcept = 0;
  virtual const KernelProperties& properties() const noexcept = 0;

  /// k(x, y) on a one-dimensional domain. A virtual call per value: use the matrix methods in
  /// loops. On a domain of d > 1 it throws std::logic_error (use evaluate_point).
  virtual double evaluate(double x, double y) const = 0;
  /// k(x, y) for two points of d = domain().dimension coordinates each (x.size() == y.size()
  /// == d, std::invalid_argument otherwise); in d = 1 the same as evaluate(x[0], y[0]).
  virtual double evaluate_point(std::span<const double> x, std::span<const double> y) const = 0;
  /// d/dy k(x, y), the derivative of the section k(x, .) (periodised on a periodic domain). A
  /// virtual call per value, for tests and contracts: use KernelBasis along a path. The kernel's
  /// closed form when has_exact_derivative(), otherwise a difference quotient with step
  /// 1e-7 L, one-sided next to a kink point (DerivativeStencil in kernel_algorithms.hpp).
  virtual double derivative(double x, double y) const = 0;
  /// True when the kernel type gives its derivatives in closed form (DifferentiableKernel or
  /// DifferentiableFeatureMapKernel).
  virtual bool has_exact_derivative() const noexcept = 0;
  /// out = grad_y k(x, y), d = domain().dimension values, for points of d coordinates each
  /// (std::invalid_argument for other sizes). In d = 1 the same as derivative(x[0], y[0]); in
  /// d > 1 the kernel's closed form when has_exact_gradient() (GradientKernel), otherwise central
  /// differences per axis with step 1e-6 of the axis' extent (one-sided within that step of a
  /// box's faces). A virtual call per point, for tests, contracts and read-outs of one point.
  virtual void gradient_point(std::span<const double> x, std::span<const double> y,
                              std::span<double> out) const = 0;
  /// True when gradient_point is a closed form (in d = 1: has_exact_derivative()).
  virtual bool has_exact_gradient() const noexcept = 0;
  /// Point sets (centres, points) are flat: N points of d = domain().dimension coordinates
  /// each, N d values (core/domain.hpp); in d = 1 a list of arc lengths.
  ///
  /// out(i, j) = k(c_i, c_j): `out` is n x n (n centres), sized by the caller; the
  /// result is symmetric. Throws std::invalid_argument when `out` has another size.
  virtual void gram_into(std::span<const double> centres,
                         Eigen::Ref<Eigen::MatrixXd> out) const = 0;
  /// out(m, i) = k(s_m, c_i): `out` is (points) x (centres), sized by the caller.
  /// Throws std::invalid_argument when `out` has another size.
  virtual void cross_into(std::span<const double> points, std::span<const double> centres,
                          Eigen::Ref<Eigen::MatrixXd> out) const = 0;
  /// out[m] = k(s_m, s_m); one value per point (std::invalid_argument otherwise).
  virtual void diagonal_into(std::span<const double> points, std::span<double> out) const = 0;
  /// Number of features of a finite feature map, 0 when the kernel has none.
  virtual std::size_t feature_count() const noexcept = 0;
  /// The sections k(c_i, .) at `centres`, for evaluation along a path. Made and destroyed by
  /// the kernel's own code (the virtual destructor), so it may cross the boundary. One-dimensional
  /// domains only (std::logic_error otherwise), like derivative() and feature_basis().
  virtual std::unique_ptr<KernelBasis> basis(std::span<const double> centres) const = 0;
  /// The features psi_f of a finite feature map themselves as a basis of size
  /// feature_count(): evaluate(s, phi) writes phi[f] = psi_f(s), zero but for the few features
  /// active at s (feature coordinates: fhat = sum_f beta_f psi_f spans the whole native space H,
  /// docs/model.md section 14). Null when the kernel has no finite feature map. Made and
  /// destroyed by the kernel's own code, like basis().
  virtual std::unique_ptr<KernelBasis> feature_basis() const = 0;
  /// Calls sink(s) for every point s in [0, L) where kernel sections are not smooth (finest
  /// B-spline knots; the seam 0 for a kernel that is not periodic on a periodic domain), in
  /// increasing order, each once. No call when the sections are smooth.
  virtual void list_kink_points(const std::function<void(double)>& sink) const = 0;

  // Conveniences on the caller's side of the boundary: they allocate the result here and let
  // the virtuals above fill it.

  /// G_ij = k(c_i, c_j), n x n, symmetric.
  Eigen::MatrixXd gram(std::span<const double> centres) const {
    const auto n = static_cast<Eigen::Index>(domain().point_count(centres));
    Eigen::MatrixXd out(n, n);
    gram_into(centres, out);
    return out;
  }
  /// K_mi = k(s_m, c_i), points.size() x centres.size().
  Eigen::MatrixXd cross(std::span<const double> points, std::span<const double> centres) const {
    Eigen::MatrixXd out(static_cast<Eigen::Index>(domain().point_count(points)),
                        static_cast<Eigen::Index>(domain().point_count(centres)));
    cross_into(points, centres, out);
    return out;
  }
  /// k(s_m, s_m) for each point.
  Eigen::VectorXd diagonal(std::span<const double> points) const {
    const std::size_t count = domain().point_count(points);
    Eigen::VectorXd out(static_cast<Eigen::Index>(count));
    diagonal_into(points, std::span<double>(out.data(), count));
    return out;
  }
  /// The kink points of list_kink_points, sorted. Empty when smooth.
  std::vector<double> kink_points() const {
    std::vector<double> out;
    list_kink_points([&](double s) { out.push_back(s); });
    return out;
  }
};

using KernelRegistry = Registry<AnyKernel, const Domain&>;

/// The kernel registry (a function-local static defined in this layer, kernel.cpp), named
/// kernel_kind_name in messages and in the table of plugin kinds.
inline constexpr std::string_view kernel_kind_name = "kernel";
KernelRegistry& kernel_registry();

/// Creates a kernel from the registry. Throws std::invalid_argument for an unknown name and
/// ParameterError for invalid parameters.
std::unique_ptr<AnyKernel> make_kernel(std::string_view name, const ParameterSet& parameters,
                                       const Domain& domain);

/// The properties of the kernel `name` with `parameters` on `domain`: the one place upper
/// layers (theory, verdicts, plots, `list`) read a kernel's facts from. Throws as make_kernel.
KernelProperties kernel_properties(std::string_view name, const ParameterSet& parameters,
                                   const Domain& domain);

/// The properties in words, for `rkhs-study list` and `verify-plugin`: "positive definite,
/// Sobolev order tau = 1, support radius 1, stationary, periodic, d = 1".
std::string describe_properties(const KernelProperties& properties);

}  // namespace rkhs
