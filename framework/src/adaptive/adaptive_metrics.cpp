// The metrics the road trial and the state-dependent trial share (adaptive_metrics.hpp), and
// the floors of an adaptive trial's metrics (set_integration_floors, set_static_floors).
#include "adaptive_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "rkhs/core/cancellation.hpp"

namespace rkhs {

namespace {

const Eigen::MatrixXd& checked(const Eigen::MatrixXd& gram) {
  check_cancelled();
  return gram;
}

Eigen::VectorXd projection_coefficients(const TargetFunction& target,
                                        std::span<const double> centres, Eigen::Index n,
                                        const GramSolver& solver) {
  Eigen::VectorXd at_centres(n);
  target.evaluate(centres, std::span<double>(at_centres.data(), static_cast<std::size_t>(n)));
  return solver.solve(at_centres);  // Pi_n f = sum alpha*_i phi_i
}

}  // namespace

StaticPart::StaticPart(const AnyKernel& kernel, const TargetFunction& target,
                       std::span<const double> centres, std::size_t evaluation_points,
                       const SolverOptions& solver_options)
    : n(static_cast<Eigen::Index>(kernel.domain().point_count(centres))),
      gram(kernel.gram(centres)),
      solver(checked(gram), solver_options),
      approximation(measure_approximation(kernel, target, centres, evaluation_points, checked(gram),
                                          solver, &cross)),
      alpha_star(projection_coefficients(target, centres, n, solver)) {}

void StaticPart::record(AdaptiveMeasurement& out) const {
  using M = AdaptiveMetric;
  using Static = ApproximationMetric;
  auto& metrics = out.metrics;
  metrics[M::fill_distance] = approximation.metrics[Static::fill_distance];
  metrics[M::separation_distance] = approximation.metrics[Static::separation_distance];
  metrics[M::gram_condition_number] = approximation.metrics[Static::gram_condition_number];
  metrics[M::power_function_sup] = approximation.metrics[Static::power_function_sup];
  out.solve_method = approximation.solve_method;
  for (const auto& flag : approximation.flags)
    out.flags.push_back(
        flag == "sup_error_at_floor" || flag == "l2_error_at_floor" ? "interpolant_" + flag : flag);
}

TimeSample adaptive_sample(double t, const double* z, Eigen::Index d,
                           const Eigen::VectorXd& coefficients_star, const Eigen::MatrixXd& P,
                           double gamma, const Eigen::MatrixXd* gram, double& largest_state_pair) {
  const Eigen::Map<const Eigen::VectorXd> x(z, d), xhat(z + d, d),
      alpha(z + 2 * d, coefficients_star.size());
  const Eigen::VectorXd e = x - xhat;
  const Eigen::VectorXd coefficient_gap = coefficients_star - alpha;
  const double weighted =
      gram ? coefficient_gap.dot(*gram * coefficient_gap) : coefficient_gap.squaredNorm();
  largest_state_pair = std::max(largest_state_pair, x.norm() + xhat.norm());
  return {t, e.norm(), 0.5 * e.dot(P * e) + 0.5 * gamma * weighted};
}

void set_plant_hypotheses(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q,
                          const Eigen::MatrixXd& P, AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const double d = static_cast<double>(A.rows());
  // A symmetric eigensolver's eigenvalues are exact for a matrix within a few d eps ||S|| of S.
  const Eigen::MatrixXd minus_symmetric = -0.5 * (A + A.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> coercivity(minus_symmetric,
                                                                  Eigen::EigenvaluesOnly);
  out.metrics[M::coercivity_of_minus_a] = coercivity.eigenvalues()(0);
  out.floors[M::coercivity_of_minus_a] = 4.0 * d * eps * minus_symmetric.norm();
  const Eigen::MatrixXd away = P - Eigen::MatrixXd::Identity(P.rows(), P.cols());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> distance(0.5 * (away + away.transpose()),
                                                                Eigen::EigenvaluesOnly);
  out.metrics[M::lyapunov_p_distance_from_identity] = distance.eigenvalues().cwiseAbs().maxCoeff();
  // P's error from its residual R = A^T P + P A + Q: ||R|| / (2 min |Re lambda(A)|), the norm of
  // the inverse Lyapunov operator for a normal A (an estimate otherwise), and never below the
  // round-off of P itself.
  const Eigen::MatrixXd residual = A.transpose() * P + P * A + Q;
  const double decay = A.eigenvalues().real().cwiseAbs().minCoeff();
  out.floors[M::lyapunov_p_distance_from_identity] =
      std::max(4.0 * d * eps * P.norm(), decay > 0 ? residual.norm() / (2.0 * decay) : 0.0);
}

Eigen::VectorXd set_shared_metrics(const FinalState& state, AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  const auto l2 = [&](const Eigen::VectorXd& v) {
    return state.domain.l2_norm(
        std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
  };
  const Eigen::VectorXd &f = state.f, &estimate = state.estimate;
  // Errors at T on the evaluation grid.
  const Eigen::VectorXd interpolant_residual = f - state.projection, residual = f - estimate;
  metrics[M::interpolant_l2_error] = l2(interpolant_residual);
  metrics[M::interpolant_sup_error] = interpolant_residual.cwiseAbs().maxCoeff();
  metrics[M::l2_error] = l2(residual);
  metrics[M::sup_error] = residual.cwiseAbs().maxCoeff();
  metrics[M::gap_to_projection] = l2(estimate - state.projection);
  // The state: |x - xhat| at T and over the samples, and V.
  const Eigen::Index d = state.d;
  metrics[M::final_state_error] = (state.z.head(d) - state.z.segment(d, d)).norm();
  double max_state_error = 0, max_increase = 0;
  for (std::size_t k = 0; k < out.samples.size(); ++k) {
    max_state_error = std::max(max_state_error, out.samples[k].state_error);
    if (k > 0)
      max_increase = std::max(max_increase, out.samples[k].lyapunov - out.samples[k - 1].lyapunov);
  }
  metrics[M::max_state_error] = max_state_error;
  if (state.projected_road) {
    // c* is the true coefficient vector only when the road lies in H_n.
    const double v0 = out.samples.front().lyapunov;
    metrics[M::coefficient_error] = (state.coefficients - state.coefficients_star).norm() /
                                    std::max(state.coefficients_star.norm(), 1e-300);
    metrics[M::lyapunov_max_increase] = v0 > 0 ? max_increase / v0 : max_increase;
    metrics[M::lyapunov_ratio] =
        v0 > 0 ? out.samples.back().lyapunov / v0 : std::numeric_limits<double>::quiet_NaN();
  }
  // P_L2 f, the averaged limit of the law.
  const Eigen::VectorXd l2_projection_residual = f - state.l2_projection;
  metrics[M::l2_projection_l2_error] = l2(l2_projection_residual);
  metrics[M::l2_projection_sup_error] = l2_projection_residual.cwiseAbs().maxCoeff();
  metrics[M::gap_to_l2_projection] = l2(estimate - state.l2_projection);
  set_static_floors(state.fixed.approximation, state.l2_projection_spectrum,
                    state.l2_projection_size, l2(state.l2_projection),
                    state.l2_projection.cwiseAbs().maxCoeff(), out);
  // Persistence of excitation (rkhs/adaptive/excitation.hpp).
  metrics[M::pe_level] = state.excitation.value;
  out.floors[M::pe_level] = state.excitation.error_bound;
  metrics[M::unexcited_dimension] = state.unexcited;
  if (state.unexcited > 0) {
    // Def. 3.1 fails: the infimum over the space is 0 to working precision.
    metrics[M::pe_level] = 0.0;
    out.flags.push_back("not_persistently_excited");
  } else if (!state.excitation.resolved && state.excitation_resolvable) {
    out.flags.push_back("pe_level_unresolved");
  }
  return residual;
}

void set_cost_metrics(const IntegrationStats& stats, std::size_t rhs_evaluations,
                      std::size_t jacobian_evaluations, AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  out.metrics[M::steps] = static_cast<double>(stats.steps);
  out.metrics[M::rejected_steps] = static_cast<double>(stats.rejected_steps);
  out.metrics[M::segments] = static_cast<double>(stats.segments);
  out.metrics[M::rhs_evaluations] = static_cast<double>(rhs_evaluations);
  out.metrics[M::jacobian_evaluations] = static_cast<double>(jacobian_evaluations);
}

double integration_error(const Domain& domain, const Eigen::VectorXd& estimate,
                         const Eigen::VectorXd& estimate_ref) {
  const auto l2 = [&](const Eigen::VectorXd& v) {
    return domain.l2_norm(std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
  };
  return l2(estimate - estimate_ref) / std::max(l2(estimate_ref), 1e-300);
}

void set_integration_floors(const AdaptiveSettings& settings, AdaptiveEngine engine,
                            const Domain& domain, const Eigen::VectorXd& estimate,
                            const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star,
                            double largest_state_pair, Eigen::Index d, double basis_scale,
                            double radius_uncertainty, AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  auto& floors = out.floors;
  const double radius = metrics[M::learning_spectral_radius];
  if (engine == AdaptiveEngine::lap_map && radius > 0 && radius < 1) {
    floors[M::learning_spectral_radius] = radius_uncertainty;
    const double log_radius = std::log(radius);
    floors[M::slowest_time_constant_laps] = radius_uncertainty / (radius * log_radius * log_radius);
    floors[M::laps_to_limit] =
        metrics[M::laps_to_limit] * radius_uncertainty / (radius * std::abs(log_radius));
  }
  // The lap map's state comes from its powers or limit, whose floors the caller measures
  // (measure_adaptive); the integrator's tolerances give the samples' (max_state_error, V).
  const double rtol = settings.integrator_rtol, atol = settings.integrator_atol;
  if (!(rtol > 0 && atol >= 0 && std::isfinite(rtol) && std::isfinite(atol))) return;
  const auto l2 = [&](const Eigen::VectorXd& v) {
    return domain.l2_norm(std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
  };
  const double l2_floor = rtol * l2(estimate) + atol * basis_scale * std::sqrt(domain.volume());
  for (const M metric : {M::l2_error, M::gap_to_projection, M::gap_to_l2_projection,
                         M::path_l2_error, M::off_path_l2_error})
    floors[metric] = l2_floor;
  floors[M::sup_error] =
      rtol * (estimate.size() ? estimate.cwiseAbs().maxCoeff() : 0.0) + atol * basis_scale;
  floors[M::coefficient_error] =
      (rtol * alpha.norm() + atol * std::sqrt(static_cast<double>(alpha.size()))) /
      std::max(alpha_star.norm(), 1e-300);
  const double state_floor =
      rtol * largest_state_pair + atol * std::sqrt(2.0 * static_cast<double>(d));
  floors[M::final_state_error] = state_floor;
  floors[M::max_state_error] = state_floor;
  if (!out.samples.empty() && out.samples.front().lyapunov > 0) {
    double largest = 0;
    for (const auto& sample : out.samples) largest = std::max(largest, sample.lyapunov);
    // V is quadratic in the state: twice its relative tolerance.
    const double lyapunov_floor = 2 * rtol * largest / out.samples.front().lyapunov;
    floors[M::lyapunov_ratio] = lyapunov_floor;
    floors[M::lyapunov_max_increase] = lyapunov_floor;
  }
  floors[M::lap_map_residual] = rtol;
}

void set_static_floors(const ApproximationMeasurement& approximation, const GramSpectrum& spectrum,
                       Eigen::Index n, double l2_projection_l2, double l2_projection_sup,
                       AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  using Static = ApproximationMetric;
  for (auto [adaptive, static_metric] :
       {std::pair{M::gram_condition_number, Static::gram_condition_number},
        {M::power_function_sup, Static::power_function_sup},
        {M::interpolant_l2_error, Static::l2_error},
        {M::interpolant_sup_error, Static::sup_error}})
    out.floors[adaptive] = approximation.floors[static_metric];
  const double relative = solve_round_off(spectrum, n);
  out.floors[M::l2_projection_l2_error] = relative * l2_projection_l2;
  out.floors[M::l2_projection_sup_error] = relative * l2_projection_sup;
}

}  // namespace rkhs
