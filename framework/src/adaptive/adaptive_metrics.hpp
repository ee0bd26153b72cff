#pragma once
// What the road trial (measure_adaptive) and the state-dependent trial (measure_state_dependent)
// measure alike, written once: the static part on Omega, the samples of |x - xhat| and V, and
// the metrics of the estimate and the state at the final time (docs/metrics.md).

#include <Eigen/Dense>
#include <span>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/excitation.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/gram_solver.hpp"

namespace rkhs {

/// The static part of an adaptive trial on Omega: the space H_n of the n centres (its Gram
/// matrix and solver), the projection Pi_n f = sum alpha*_i k(c_i, .) of the target, and the
/// cross matrix of the sections on the evaluation grid, which serve the adaptive part too.
/// Built in place (the solver refers to the Gram matrix).
struct StaticPart {
  StaticPart(const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
             std::size_t evaluation_points, const SolverOptions& solver_options);
  StaticPart(const StaticPart&) = delete;
  StaticPart& operator=(const StaticPart&) = delete;

  Eigen::Index n;  ///< the centres
  Eigen::MatrixXd gram;
  GramSolver solver;
  Eigen::MatrixXd cross;  ///< the sections on the evaluation grid, one row per point
  ApproximationMeasurement approximation;
  Eigen::VectorXd alpha_star;

  /// Writes the static metrics (fill and separation distances, the Gram matrix's condition
  /// number, the power function), the solve method and the approximation's flags (its error
  /// floors as interpolant_...) to `out`.
  void record(AdaptiveMeasurement& out) const;
};

/// The sample at time t of the state z = (x, xhat, c) (d, d and coefficients_star.size()
/// values): |x - xhat| and V = 1/2 e^T P e + 1/2 gamma (c* - c)^T W (c* - c), W the Gram matrix
/// `gram` or I when it is null. Raises `largest_state_pair` to |x| + |xhat| (the floors' scale).
TimeSample adaptive_sample(double t, const double* z, Eigen::Index d,
                           const Eigen::VectorXd& coefficients_star, const Eigen::MatrixXd& P,
                           double gamma, const Eigen::MatrixXd* gram, double& largest_state_pair);

/// What both trials know at the final time T, on the evaluation grid.
struct FinalState {
  const Domain& domain;
  const StaticPart& fixed;
  const Eigen::VectorXd& f;                  ///< the road (f, or Pi_n f) on the grid
  const Eigen::VectorXd& estimate;           ///< fhat(T)
  const Eigen::VectorXd& projection;         ///< Pi_n f
  const Eigen::VectorXd& l2_projection;      ///< P_L2 f, the averaged limit of the law
  /// The eigenvalues the solve for P_L2 f's coefficients divided by, and the matrix's size:
  /// its floors are solve_round_off of them (rkhs/approx/approximation.hpp).
  const GramSpectrum& l2_projection_spectrum;
  Eigen::Index l2_projection_size;
  const Eigen::VectorXd& z;                  ///< the state (x, xhat, c) at T
  Eigen::Index d;                            ///< the plant's dimension
  const Eigen::VectorXd& coefficients;       ///< c(T) = z.tail(...)
  const Eigen::VectorXd& coefficients_star;  ///< those of Pi_n f in the law's coordinates
  bool projected_road;                       ///< the road is Pi_n f: c* is the true value
  ExcitationLevel excitation;                ///< pe_level of the space the law learns in
  double unexcited;                          ///< unexcited_dimension (NaN: not known)
  bool excitation_resolvable;  ///< an unresolved pe_level is flagged pe_level_unresolved
};

/// The adaptive metrics both trials compute alike (docs/metrics.md), from `state` and the
/// samples already in `out`: the errors of fhat(T) and of Pi_n f against the road (l2_error,
/// sup_error, interpolant_l2_error, interpolant_sup_error), gap_to_projection, the state errors
/// (final_state_error, max_state_error), V (lyapunov_ratio, lyapunov_max_increase) and
/// coefficient_error for a projected road, the errors of P_L2 f and the gap to it, pe_level and
/// unexcited_dimension with their flags (not_persistently_excited, pe_level_unresolved), and the
/// floors of the static part (set_static_floors). Returns the residual f - fhat(T) on the grid.
Eigen::VectorXd set_shared_metrics(const FinalState& state, AdaptiveMeasurement& out);

/// Theorem 3's hypothesis (ii), which the plant and the law decide before any run:
/// coercivity_of_minus_a = lambda_min(-(A + A^T) / 2) and lyapunov_p_distance_from_identity =
/// ||P - I||_2 (P the solution of A^T P + P A = -Q), with their floors.
void set_plant_hypotheses(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q,
                          const Eigen::MatrixXd& P, AdaptiveMeasurement& out);

/// The cost metrics: steps, rejected_steps, segments, rhs_evaluations, jacobian_evaluations.
void set_cost_metrics(const IntegrationStats& stats, std::size_t rhs_evaluations,
                      std::size_t jacobian_evaluations, AdaptiveMeasurement& out);

/// integration_error: ||fhat(T) - fhat_ref(T)||_L2 / ||fhat_ref(T)||_L2 on the grid.
double integration_error(const Domain& domain, const Eigen::VectorXd& estimate,
                         const Eigen::VectorXd& estimate_ref);

}  // namespace rkhs
