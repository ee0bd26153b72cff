#pragma once
// Projections Pi_j : H -> H_j (paper Sec. 4, docs/model.md section 14): the finite-dimensional
// spaces of the approximations and how a function of H is mapped into them.
//
// Every projection is written in one form, which is what a plugin builds:
//
//   Pi f = sum_i c_i b_i,   c = W f(S),   b_i = sum_y E_yi k(y, .)
//
//   S  the sample points: Pi f depends on f only through its values there
//   W  dimension x |S|: the coefficient functionals (interpolation: G^-1; a quasi-interpolant:
//      local rows; an L2 projection: the mass-matrix solve times quadrature weights; the
//      H-orthogonal projection onto a subspace: G_B^-1 E^T, since (f, k(y, .))_H = f(y))
//   b_i the basis of H_j, as combinations of kernel sections at the basis points Y (exact for a
//      subspace of span{k(y, .)}: kernel sections at centres, or splines of a level j <= J
//      through the sections at the finest level's support centres, which span the B-spline
//      kernel's whole space)
//
// From this form and the kernel alone, the framework computes exactly, for any projection
// (projection_metrics.hpp): Pi f on a grid, ||Pi f||_H, the H-Gram matrix of the basis
// G_B = E^T K_YY E, the operator norm ||Pi||_{H -> H}, and ||I - Pi||_{H -> C} =
// sup_s ||(I - Pi)^* k(s, .)||_H, where (Pi^* k(s, .)) = sum_m (W^T E^T K_Y(s))_m k(S_m, .).
//
// A projection plugin is a class P with
//   static PluginInfo info();
//   explicit P(const ParameterSet&);
//   ProjectionProperties properties() const;      what it declares (contract-tested)
//   void build(const ProjectionRequest&, ProjectionOperator& out) const;
// registered with RKHS_REGISTER_PROJECTION(P) (through the same boundary rules as every plugin:
// the operator's storage is allocated on the caller's side by ProjectionOperator::resize).
//
// A matrix-free projection (ProjectionProperties::matrix_free) has no operator of this form that
// fits in memory (a multilevel interpolation at 2^18 centres): it measures a trial itself through
// Projection::measure() and declares which metrics of the approximation table it computes
// (ProjectionProperties::measures). A study that asks such a projection for another metric (the
// operator norms, the power function of one space) is refused when it is read, naming them;
// build() is not called for it.

#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/approx/metrics.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/domain.hpp"
#include "rkhs/core/registry.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// What decides the space H_j of a projection.
enum class ProjectionResolution {
  centres,  ///< H_n = span{k(c_i, .)} at the trial's n centres (the centres axis)
  level,    ///< H_j = the splines of level j; the trial's n is the number of level-j cells,
            ///< n = n0 2^j (h = h0 2^-j), and the centres axis is not used; for the
            ///< multilevel projection the number of centres of its finest level j
};

/// What a projection declares about itself; the contract test checks each claim.
struct ProjectionProperties {
  ProjectionResolution resolution = ProjectionResolution::centres;
  /// Pi_j Pi_k = Pi_j for j <= k (for nested resolutions: levels, or centre sets that grow by
  /// inclusion, such as uniform centres whose n doubles).
  bool nested = false;
  /// (f - Pi f, g)_H = 0 for every g in H_j: the H-orthogonal projection.
  bool h_orthogonal = false;
  /// sup_j ||Pi_j||_{H -> H} where it is known (1 for an H-orthogonal projection); empty
  /// otherwise (then only the measured projection_operator_norm says it).
  std::optional<double> operator_norm_bound;
  /// The kernel the projection needs ("bspline" for the spline spaces), empty for any kernel
  /// (a literal: nothing the plugin allocates crosses the boundary).
  std::string_view requires_kernel;
  /// Measures its trials itself (Projection::measure) instead of building a ProjectionOperator.
  bool matrix_free = false;
  /// A matrix-free projection's metrics: bit i set when it computes metric i of
  /// MetricTable<ApproximationMetric> (measured_metric_bit); unused otherwise.
  std::uint64_t measures = 0;
  /// Scales the kernel with its resolution (the multilevel projection: support radius
  /// rho_j = nu h_j on level j), so the theory of a fixed kernel (h^(tau - d/2), h^tau) does
  /// not describe its trials: `theory = true` is refused on its metrics but those of
  /// TheoryLaw::level_reduction (rkhs/rates/theory.hpp).
  bool kernel_scaled_with_level = false;
};

static_assert(MetricTable<ApproximationMetric>::rows.size() <= 64,
              "ProjectionProperties::measures holds a bit per approximation metric");

/// The bit of `metric` in ProjectionProperties::measures.
constexpr std::uint64_t measured_metric_bit(ApproximationMetric metric) {
  return std::uint64_t{1} << static_cast<std::size_t>(metric);
}

/// The metrics a projection with `properties` computes, as measured_metric_bit()s: its
/// ProjectionProperties::measures when it is matrix-free, else every metric of the table but the
/// matrix-free projections' own (MetricInfo::matrix_free_only).
constexpr std::uint64_t computed_metric_bits(const ProjectionProperties& properties) {
  if (properties.matrix_free) return properties.measures;
  std::uint64_t bits = 0;
  for (const auto& row : MetricTable<ApproximationMetric>::rows)
    if (!row.matrix_free_only) bits |= measured_metric_bit(row.id);
  return bits;
}

/// The properties in words, for `rkhs-study list projection` and the docs: "resolution: level;
/// nested; H-orthogonal; ||Pi_j|| <= 1; kernel: bspline".
std::string describe_projection(const ProjectionProperties& properties);

/// What a projection is built for: the kernel (its space H), the trial's n and, for a centre
/// projection, its centres; the solver options for Gram solves.
struct ProjectionRequest {
  const AnyKernel& kernel;
  std::size_t n = 0;                ///< the trial's n (level projections: cells n0 2^j)
  std::span<const double> centres;  ///< the trial's centres (centre projections only)
  SolverOptions solver;
};

/// What a matrix-free projection measures a trial on: the kernel, the target, the trial's n,
/// the evaluation points (the study's uniform grid) and the ApproximationWork bits its selected
/// metrics need (MetricInfo::needs; a metric whose needs are all 0 is always wanted).
struct ProjectionTrial {
  const AnyKernel& kernel;
  const TargetFunction& target;
  std::size_t n = 0;
  std::span<const double> points;
  SolverOptions solver;
  unsigned work = 0;
};

/// A matrix-free projection's measurement, in storage the caller owns: the plugin writes the
/// values (and the floors it estimates; NaN: none) of the metrics it declares by identifier, and
/// adds flags and its solve method through the framework's functions.
class ProjectionMeasurement {
 public:
  MetricValues<ApproximationMetric> metrics, floors;
  void add_flag(std::string_view flag);
  void set_solve_method(std::string_view method);
  const std::vector<std::string>& flags() const noexcept { return flags_; }
  const std::string& solve_method() const noexcept { return solve_method_; }

 private:
  std::vector<std::string> flags_;
  std::string solve_method_;
};

/// The operator in the form of the file comment, in storage the caller owns. A plugin calls
/// resize() once, then fills every entry through the accessors; resize(), set_mesh() and
/// set_solve_method() are compiled into the framework, so every allocation happens on the
/// caller's side of the plugin boundary.
class ProjectionOperator {
 public:
  /// Sizes S, W, Y and E (entries zero) and clears the rest. S and Y are flat point sets of
  /// `point_dimension` coordinates per point (the domain's d, core/domain.hpp): samples() holds
  /// samples x point_dimension values.
  void resize(std::size_t dimension, std::size_t samples, std::size_t basis_points,
              std::size_t point_dimension = 1);
  /// |S|, the number of sample points (samples().size() / point dimension).
  std::size_t sample_count() const noexcept { return static_cast<std::size_t>(weights_.cols()); }

  std::size_t dimension() const noexcept { return static_cast<std::size_t>(weights_.rows()); }
  std::span<double> samples() noexcept { return samples_; }
  std::span<const double> samples() const noexcept { return samples_; }
  Eigen::Ref<Eigen::MatrixXd> weights() noexcept { return weights_; }  ///< W: dim x |S|
  const Eigen::MatrixXd& weights() const noexcept { return weights_; }
  std::span<double> basis_points() noexcept { return basis_points_; }
  std::span<const double> basis_points() const noexcept { return basis_points_; }
  /// E: |Y| x dim, b_i = sum_y E_yi k(y, .).
  Eigen::Ref<Eigen::MatrixXd> basis_coefficients() noexcept { return basis_coefficients_; }
  const Eigen::MatrixXd& basis_coefficients() const noexcept { return basis_coefficients_; }

  /// The level j of a level projection (NaN for a centre projection).
  double level = std::numeric_limits<double>::quiet_NaN();
  /// The mesh of H_j: its centres, or the knots of level j (fill and separation distances).
  void set_mesh(std::span<const double> points);
  const std::vector<double>& mesh() const noexcept { return mesh_; }
  /// How the plugin solved what it solved ("cholesky", "pseudo-inverse (...)"), for the record.
  void set_solve_method(std::string_view method);
  const std::string& solve_method() const noexcept { return solve_method_; }

 private:
  std::vector<double> samples_, basis_points_, mesh_;
  Eigen::MatrixXd weights_, basis_coefficients_;
  std::string solve_method_;
};

/// A matrix-free projection's trial predicted before anything is built (Projection::footprint):
/// its peak memory and what it factorises, summed over everything it factorises.
struct ProjectionFootprint {
  double megabytes = 0;  ///< peak MiB of its matrices and vectors
  double gram_nonzeros = 0, factor_nonzeros = 0;
  double flops = 0;  ///< of its factorisations and evaluations, for the scheduler's order
};

/// A projection family Pi_j (see the file comment).
class Projection {
 public:
  virtual ~Projection() = default;
  virtual ProjectionProperties properties() const = 0;
  /// Throws std::invalid_argument, as build() would, when the projection cannot be built for
  /// `kernel` and `n` (an n that is not a level, ...), without building anything: what a study
  /// file is checked with. The kernel named by properties().requires_kernel is checked by the
  /// caller.
  virtual void check(const AnyKernel& kernel, std::size_t n) const = 0;
  /// Builds Pi_j for `request` into `out`. Throws std::invalid_argument naming what does not
  /// fit (a kernel it cannot work with, an n that is not n0 2^j with j <= J, ...).
  virtual void build(const ProjectionRequest& request, ProjectionOperator& out) const = 0;
  /// A matrix-free projection's trial (properties().matrix_free): sets every metric of
  /// properties().measures whose needs intersect trial.work (or are 0), with the kernel and n that
  /// check() accepted. Throws std::invalid_argument as build() does. The default throws
  /// std::logic_error: a projection with an operator is measured from it.
  virtual void measure(const ProjectionTrial& trial, ProjectionMeasurement& out) const;
  /// A matrix-free projection's prediction of a trial with `kernel` and `n` on
  /// `evaluation_points` points, which run and validate compare with limits.matrix_megabytes.
  /// Empty (the default): the trial's matrices are estimated dense, n x n. Throws
  /// std::invalid_argument as check() does.
  virtual std::optional<ProjectionFootprint> footprint(const AnyKernel& kernel, std::size_t n,
                                                       std::size_t evaluation_points) const;
};

using ProjectionRegistry = Registry<Projection>;
/// The projection registry (defined in this layer, registries.cpp), named projection_kind_name.
inline constexpr std::string_view projection_kind_name = "projection";
ProjectionRegistry& projection_registry();

/// The name of the projection of studies that declare none: kernel interpolation at the
/// centres, the H-orthogonal projection onto span{k(c_i, .)}.
inline constexpr std::string_view default_projection = "interpolation";

/// Registers projection type P (static info(), constructor from ParameterSet). Never throws; a
/// failure is recorded in projection_registry().errors() (register_plugin).
template <class P>
bool register_projection() noexcept {
  return register_plugin<P>(projection_registry());
}

/// Pi_j as a concrete operator: makes the plugin `name` and builds it for `request`.
/// std::invalid_argument for a matrix-free projection (it has no operator).
ProjectionOperator build_projection(std::string_view name, const ParameterSet& parameters,
                                    const ProjectionRequest& request);

/// The interpolation projection onto span{k(c_i, .)} (the built-in `interpolation`) from a Gram
/// matrix of `centres` and its solver already built: an H-orthonormal basis b = E^T k_X with
/// W = E^T, E = L^-T from G = L L^T, or V diag(lambda^-1/2) over the pseudo-inverse's kept
/// eigenpairs; with a regularised solver the basis k(c_i, .) itself and W = G_mu^-1. Then
/// ||(I - Pi)^* k(s, .)||^2 comes out as k(s, s) - |L^-1 k_X(s)|^2, the power function's
/// backward-stable form. No second factorisation.
void interpolation_operator(const AnyKernel& kernel, std::span<const double> centres,
                            const Eigen::MatrixXd& gram, const GramSolver& solver,
                            ProjectionOperator& out);

// The exact quantities of a built operator for its kernel (the file comment's formulas). Each
// costs a few kernel matrices on S and Y; nothing is approximated beyond round-off.

/// b_i(s_m): points.size() x dimension, K(points, Y) E.
Eigen::MatrixXd projection_basis_values(const AnyKernel& kernel, const ProjectionOperator& op,
                                        std::span<const double> points);
/// (Pi f)(s_m) from f's values at the sample points S (c = W f(S)).
Eigen::VectorXd apply_projection(const AnyKernel& kernel, const ProjectionOperator& op,
                                 const Eigen::VectorXd& at_samples, std::span<const double> points);
/// G_B = E^T K_YY E: the H inner products (b_i, b_k)_H of the basis.
Eigen::MatrixXd projection_basis_gram(const AnyKernel& kernel, const ProjectionOperator& op);
/// ||(I - Pi)^* k(s, .)||_H at each point: sqrt(k(s, s) - 2 c^T K_S(s) + c^T K_SS c) with
/// c = W^T E^T K_Y(s) (clamped at 0 before the root). Its sup is ||I - Pi||_{H -> C}; for the
/// H-orthogonal projection onto span{k(c_i, .)} it is the power function.
Eigen::VectorXd projection_residual_norms(const AnyKernel& kernel, const ProjectionOperator& op,
                                          std::span<const double> points);
/// The round-off level of projection_residual_norms on `points`: the squared norm is a
/// difference of terms of size k(s, s), so below sqrt(|S| eps max_m k(s_m, s_m)) it is round-off
/// (the flag projection_norm_at_floor).
double projection_norm_floor(const AnyKernel& kernel, const ProjectionOperator& op,
                             std::span<const double> points);
/// The same for a projection with `sample_count` sample points (n for interpolation at n
/// centres), without an operator.
double projection_norm_floor(const AnyKernel& kernel, std::size_t sample_count,
                             std::span<const double> points);
/// ||Pi||_{H -> H} = sqrt(lambda_max(R^T W K_SS W^T R)) with G_B = R R^T: the largest
/// ||Pi f||_H over ||f||_H = 1 (f ranges over H, seen by Pi through f(S)).
/// With `floor`, also its round-off floor (FloorRule::round_off): the value times
/// m eps (cond(G_B) + a(E, K_BB) + a(W^T, K_SS)) / 2, m the largest of dim, the samples and the
/// basis points (the terms each entry sums), where cond(G_B) is the ratio of the basis
/// Gram matrix's largest eigenvalue to its smallest one above dim eps lambda_max (its
/// eigendecomposition) and a(C, K) = ||C||_2^2 ||K||_inf / ||C^T K C||_2 the amplification of
/// the coefficients' own round-off (cond(K) for coefficients that are solves with K, as the
/// orthonormal bases and interpolation weights are; about 1 for coefficients that are data).
double projection_operator_norm(const AnyKernel& kernel, const ProjectionOperator& op,
                                double* floor = nullptr);

}  // namespace rkhs

#define RKHS_REGISTER_PROJECTION(Type) \
  RKHS_REGISTRAR(rkhs_projection_registered_, ::rkhs::register_projection<Type>())
