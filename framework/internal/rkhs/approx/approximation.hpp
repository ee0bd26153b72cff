#pragma once
// Approximation trials: the space H_n of kernel sections at n centres and the projection Pi_n
// (docs/model.md sections 4 and 5). No ODE is involved: Pi_n f is the kernel interpolant of f.

#include <span>
#include <string>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/approx/metrics.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/approx/target.hpp"

namespace rkhs {

/// Fill distance h = sup_{x in Omega} min_i |x - c_i| (distance along the circle on a periodic
/// domain). Centres need not be sorted. +inf for no centres.
double fill_distance(std::span<const double> centres, const Domain& domain);
/// Separation distance q = min_{i != j} |c_i - c_j| / 2; NaN for fewer than two centres.
double separation_distance(std::span<const double> centres, const Domain& domain);

/// The floor of ||Pi f||_H = sqrt(alpha^T G alpha) = `norm` (approximation.cpp): the larger of
/// what a backward error of n eps lambda_max in G moves it by and what the data's round-off,
/// eps `data_norm`, becomes through the smallest eigenvalue the solve keeps.
double native_norm_floor(double norm, double coefficients_squared, double data_norm,
                         const GramSpectrum& spectrum, Eigen::Index n);

/// Names of the metrics of an approximation trial, in output order: the names of
/// MetricTable<ApproximationMetric> (rkhs/approx/metrics.hpp, which holds their units and
/// NaN rules).
///  fill_distance, separation_distance    geometry of the centres
///  gram_condition_number                 lambda_max / lambda_min, +inf when singular
///  gram_min_eigenvalue, gram_max_eigenvalue
///  power_function_sup                    max_m P_n(s_m) = ||I - Pi_n||_{H -> C} on the grid
///  power_function_floor                  round-off level of P_n: max_m sqrt(n eps lambda_max
///                                        |G^-1 k_X(s_m)|^2); below it P_n is not resolved
///  l2_error, sup_error                   ||f - Pi_n f|| in L2(Omega) and on the grid
///  error_floor                           round-off level of Pi_n f on the grid: max_m
///                                        n eps lambda_max |G^-1 k_X(s_m)| |alpha|
///  interpolant_native_norm               ||Pi_n f||_H = sqrt(alpha^T G alpha)
///  projection_norm_H_to_C                ||I - Pi||_{H -> C} = max_m ||(I - Pi)^* k(s_m, .)||_H
///  projection_operator_norm              ||Pi||_{H -> H}
const std::vector<std::string>& approximation_metric_names();

struct ApproximationMeasurement {
  MetricValues<ApproximationMetric> metrics;  ///< in approximation_metric_names() order
  /// The floor of each metric (MetricInfo::floor; NaN: exact, or not estimated by this trial).
  MetricValues<ApproximationMetric> floors;
  std::string solve_method;     ///< GramSolver::method()
  std::vector<std::string> flags;  ///< gram_singular, power_function_at_floor, sup_error_at_floor, ...
};

/// gram_condition_number, gram_min_eigenvalue and gram_max_eigenvalue with their floors (Weyl:
/// n eps lambda_max) when `work` has work_spectrum, and the gram_singular flag, into `out`.
void record_spectrum_metrics(const GramSpectrum& spectrum, Eigen::Index n, unsigned work,
                             ApproximationMeasurement& out);

/// The relative round-off of a solve with a Gram matrix of this spectrum and size n (backward
/// error n eps lambda_max, amplified by cond(G)), at most 1 (1 for a singular or unknown
/// spectrum): what a value computed from G^-1 is known to.
double solve_round_off(const GramSpectrum& spectrum, Eigen::Index n);

/// Measures Pi_n for `kernel` at `centres` on `evaluation_points` uniform points of the
/// kernel's domain: the metrics `selection` names (empty: all), computing only what they need
/// (MetricInfo::needs; the others are NaN). The Gram matrix is assembled and factorised once;
/// the power function, the errors and their floors come from one blocked pass over the points
/// (rkhs/core/concurrency.hpp run_parts: blocks run on idle threads of the caller's arena,
/// with results independent of how they are scheduled); projection_norm_H_to_C is the power
/// function and projection_operator_norm is measured on the operator built from the same
/// solver (interpolation_operator). The extreme eigenvalues are computed exactly only when a
/// gram_* metric is selected (GramSpectrumMode). Throws SingularGramError (policy `fail`) and
/// std::exception on bad input.
ApproximationMeasurement measure_approximation(const AnyKernel& kernel,
                                               const TargetFunction& target,
                                               std::span<const double> centres,
                                               std::size_t evaluation_points,
                                               const SolverOptions& solver,
                                               const MetricSelection& selection = {});

/// The same measurement from a Gram matrix `gram` of `centres` and its `solver` already built
/// by the caller (who needs them too: an adaptive trial), of every metric but the two
/// projection norms. The cross matrix
/// K_mi = k(s_m, c_i) on the evaluation points is moved into `*cross` when it is not null.
ApproximationMeasurement measure_approximation(const AnyKernel& kernel,
                                               const TargetFunction& target,
                                               std::span<const double> centres,
                                               std::size_t evaluation_points,
                                               const Eigen::MatrixXd& gram,
                                               const GramSolver& solver,
                                               Eigen::MatrixXd* cross = nullptr);

/// Sets projection_norm_H_to_C (work_projection_residual in `work`) and
/// projection_operator_norm (work_operator_norm) of `op` (projection.hpp's exact formulas, on
/// `evaluation_points` uniform points); flags projection_norm_at_floor when the norm is below
/// the round-off level sqrt(|S| eps max k(s, s)).
void measure_projection_norms(const AnyKernel& kernel, const ProjectionOperator& op,
                              std::size_t evaluation_points, ApproximationMeasurement& out,
                              unsigned work = work_projection_residual | work_operator_norm);

/// A trial of a projection whose space is not span{k(c_i, .)} (a level projection): every
/// metric of the table for H_j = span{b_i} and Pi f = sum_i c_i b_i, c = W f(S):
/// fill and separation distances of the mesh (the level's knots); Gram metrics and the power
/// function of the basis' H-Gram matrix G_B (P_j is the norm of the H-orthogonal projection onto
/// H_j, against which a projection that is not orthogonal can be compared); the errors of Pi f;
/// ||Pi f||_H = sqrt(c^T G_B c); and the projection norms (measure_projection_norms). Like
/// measure_approximation, only what the metrics of `selection` need (empty: all).
ApproximationMeasurement measure_projection(const AnyKernel& kernel, const TargetFunction& target,
                                            const ProjectionOperator& op,
                                            std::size_t evaluation_points,
                                            const SolverOptions& solver,
                                            const MetricSelection& selection = {});

/// A trial of the projection `name` that is not interpolation: builds its operator and measures
/// it (measure_projection), or, for a matrix-free projection (projection.hpp), lets it measure
/// itself on the evaluation grid. std::invalid_argument when `selection` (empty: all) names a
/// metric a matrix-free projection does not declare in ProjectionProperties::measures.
ApproximationMeasurement measure_projection_trial(std::string_view name,
                                                  const ParameterSet& parameters,
                                                  const ProjectionRequest& request,
                                                  const TargetFunction& target,
                                                  std::size_t evaluation_points,
                                                  const MetricSelection& selection = {});

/// The names of the metrics `selection` (empty: all) names that a matrix-free projection with
/// `properties` does not compute (ProjectionProperties::measures), in table order.
std::vector<std::string> unmeasured_metrics(const ProjectionProperties& properties,
                                            const MetricSelection& selection);

/// P_n(s) at each point, with the same solver (values below round-off clamped to 0), in the
/// blocks of measure_approximation.
Eigen::VectorXd power_function(const AnyKernel& kernel, const GramSolver& solver,
                               std::span<const double> centres, std::span<const double> points);

}  // namespace rkhs
