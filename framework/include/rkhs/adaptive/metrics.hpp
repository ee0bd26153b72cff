#pragma once
// The metric table of adaptive trials (see rkhs/approx/metrics.hpp for what a table holds).
// The first four are the approximation trial's metrics of the same name; interpolant_* are its
// l2_error and sup_error (of Pi_n f); l2_projection_* measure P_L2 f, the L2(Omega)-orthogonal
// projection (the averaged limit, rkhs/adaptive/averaged_limit.hpp); the rest measure the learned
// estimate and the integration, and pe_level the excitation of the law's space by one lap
// (rkhs/adaptive/excitation.hpp).

#include "rkhs/approx/metrics.hpp"

namespace rkhs {

enum class AdaptiveMetric : std::size_t {
  fill_distance,
  separation_distance,
  gram_condition_number,
  power_function_sup,
  interpolant_l2_error,
  interpolant_sup_error,
  l2_error,
  sup_error,
  gap_to_projection,
  l2_projection_l2_error,
  l2_projection_sup_error,
  gap_to_l2_projection,
  coefficient_error,
  final_state_error,
  max_state_error,
  lyapunov_max_increase,
  lyapunov_ratio,
  steps,
  rejected_steps,
  segments,
  rhs_evaluations,
  jacobian_evaluations,
  learning_spectral_radius,
  slowest_time_constant_laps,
  laps_to_limit,
  unexcited_directions,
  lap_map_residual,
  integration_error,
  pe_level,
  projection_norm_H_to_C,
  projection_operator_norm,
  projected_l2_error,
  estimate_gap_H,
  estimate_gap_C,
  state_gap,
  plant_gap,
  gap_effectivity_H,
  gap_effectivity_C,
  unexcited_dimension,
  path_l2_error,
  off_path_l2_error,
  reference_norm_H_to_C,
  learning_decay_rate,
  averaged_decay_rate,
  pe_decay_ratio,
  visited_rms_error,
  kernel_diagonal_l1,
  coercivity_of_minus_a,
  lyapunov_p_distance_from_identity,
  embedding_constant,
  lipschitz_constant,
  initial_data_lipschitz,
  lipschitz_exponent,
};

/// The optional parts of an adaptive trial's work, as bits of MetricInfo::needs: a trial does
/// one when the study asks for a metric that needs it (trial_adaptive_settings); every other
/// metric is computed by every trial.
enum AdaptiveWork : unsigned {
  /// Theorem 1's dependence on the initial data: its constants and a second trajectory from
  /// perturbed initial data (AdaptiveSettings::initial_data_dependence).
  adaptive_work_initial_data = 1u << 0,
};

template <>
struct MetricTable<AdaptiveMetric> {
  using M = AdaptiveMetric;
  using F = FloorRule;
  static constexpr auto rows = std::to_array<MetricRow<M>>({
      { {"fill_distance", "fill distance h", F::exact, "m", "h = sup_x min_i |x - c_i|", false, ""}, M::fill_distance},
      { {"separation_distance", "separation distance q", F::exact, "m",
       "q = min_{i != j} |c_i - c_j| / 2; NaN for a single centre", true, ""}, M::separation_distance},
      { {"gram_condition_number", "condition number of the Gram matrix", F::round_off, "1",
       "lambda_max / lambda_min of G, +inf when singular", false, "gram_singular"}, M::gram_condition_number},
      { {"power_function_sup", "power function, sup norm", F::round_off, "sqrt([k])", "max_m P_n(s_m) on the grid",
       false, "power_function_at_floor", true, 0, true}, M::power_function_sup},
      { {"interpolant_l2_error", "L^2 error of the interpolant", F::round_off, "[f] sqrt(m)",
       "||f - Pi_n f|| in L2(Omega), f the road", false, "interpolant_l2_error_at_floor", false, 0, true}, M::interpolant_l2_error},
      { {"interpolant_sup_error", "sup-norm error of the interpolant", F::round_off, "[f]", "max_m |f(s_m) - Pi_n f(s_m)|",
       false, "interpolant_sup_error_at_floor", false, 0, true}, M::interpolant_sup_error},
      { {"l2_error", "L^2 error", F::integration, "[f] sqrt(m)", "||f - fhat(T)|| in L2(Omega)", false, "", true, 0, true}, M::l2_error},
      { {"sup_error", "sup-norm error", F::integration, "[f]", "max_m |f(s_m) - fhat(T)(s_m)|", false, "", true, 0, true}, M::sup_error},
      { {"gap_to_projection", "L^2 gap to the projection", F::integration, "[f] sqrt(m)",
       "||fhat(T) - Pi_n f|| in L2(Omega)", false, "", true, 0, true}, M::gap_to_projection},
      { {"l2_projection_l2_error", "L^2 error of the L^2 projection", F::round_off, "[f] sqrt(m)",
       "||f - P_L2 f|| in L2(Omega), P_L2 f the v -> 0 limit of fhat (adaptive/averaged_limit.hpp)",
       false, "l2_projection_unconverged", true, 0, true}, M::l2_projection_l2_error},
      { {"l2_projection_sup_error", "sup-norm error of the L^2 projection", F::round_off, "[f]", "max_m |f(s_m) - P_L2 f(s_m)|",
       false, "l2_projection_unconverged", true, 0, true}, M::l2_projection_sup_error},
      { {"gap_to_l2_projection", "L^2 gap to the L^2 projection", F::integration, "[f] sqrt(m)",
       "||fhat(T) - P_L2 f|| in L2(Omega)", false, "l2_projection_unconverged", true, 0, true}, M::gap_to_l2_projection},
      { {"coefficient_error", "relative coefficient error", F::integration, "1",
       "|alpha(T) - alpha*| / |alpha*|; NaN unless the road is Pi_n f", true, ""}, M::coefficient_error},
      { {"final_state_error", "final state error", F::integration, "[x]", "|x(T) - xhat(T)|", false, ""}, M::final_state_error},
      { {"max_state_error", "largest state error", F::integration, "[x]", "max over the samples of |x - xhat|", false,
       ""}, M::max_state_error},
      { {"lyapunov_max_increase", "largest relative increase of V", F::integration, "1",
       "largest increase of V between samples / V(0); NaN unless the road is Pi_n f", true, ""}, M::lyapunov_max_increase},
      { {"lyapunov_ratio", "V(T) / V(0)", F::integration, "1", "V(T) / V(0); NaN unless the road is Pi_n f", true,
       ""}, M::lyapunov_ratio},
      { {"steps", "accepted steps", F::step_controller, "count", "accepted integration steps", false, ""}, M::steps},
      { {"rejected_steps", "rejected steps", F::step_controller, "count", "rejected integration steps", false, ""}, M::rejected_steps},
      { {"segments", "smooth segments", F::exact, "count", "smooth segments integrated", false, ""}, M::segments},
      { {"rhs_evaluations", "right-hand-side evaluations", F::step_controller, "count",
       "right-hand-side evaluations (two per Jacobian included)", false, ""}, M::rhs_evaluations},
      { {"jacobian_evaluations", "Jacobian evaluations", F::step_controller, "count", "Jacobian evaluations", false, ""}, M::jacobian_evaluations},
      { {"learning_spectral_radius", "spectral radius of the lap map", F::integration, "1",
       "largest |eigenvalue| of the lap map's learning block (xhat, alpha), unexcited "
       "directions left out; NaN unless engine = lap_map",
       true, ""}, M::learning_spectral_radius},
      { {"slowest_time_constant_laps", "slowest time constant", F::propagated, "laps",
       "-1 / ln(learning_spectral_radius); NaN unless engine = lap_map", true, ""}, M::slowest_time_constant_laps},
      { {"laps_to_limit", "laps to the limit", F::propagated, "laps",
       "laps until ||fhat - fhat(limit)|| in L2 is 1% of ||fhat(0) - fhat(limit)||; NaN unless "
       "engine = lap_map, and NaN flagged laps_to_limit_unresolved when not reached within 50 "
       "time constants of the slowest excited mode",
       true, "laps_to_limit_unresolved"}, M::laps_to_limit},
      { {"unexcited_directions", "unexcited directions", F::exact, "count",
       "directions of z that one lap leaves unchanged (eigenvalue 1 of the lap map); NaN unless "
       "engine = lap_map",
       true, ""}, M::unexcited_directions},
      { {"lap_map_residual", "lap map residual", F::integration, "1",
       "|z(T) integrated over the last lap - z(T) from the lap map| / |z(T)|; NaN unless "
       "engine = lap_map with whole laps",
       true, ""}, M::lap_map_residual},
      { {"integration_error", "relative integration error", F::integration, "1",
       "||fhat(T) - fhat_ref(T)|| / ||fhat_ref(T)|| in L2(Omega), fhat_ref integrated with "
       "[adaptive] reference (time stepping, same breakpoints); NaN without a reference",
       true, ""}, M::integration_error},
      { {"pe_level", "persistence of excitation level", F::round_off, "[k]",
       "persistence of excitation over one lap: lambda_min of E a = lambda G a, "
       "E = (1/L) int phi phi^T ds, G the Gram matrix (rkhs_embedding: the smallest nonzero "
       "eigenvalue of E over the features); NaN when G is singular to working precision",
       true, "pe_level_unresolved"}, M::pe_level},
      // Theorem 4.1 ([[projection]] in an adaptive study; rkhs/adaptive/finite_to_infinite.hpp):
      // the finite estimator of the trial's projection Pi_j beside the infinite one (the law,
      // rkhs_embedding), sup over the breakpoints of [0, T].
      { {"projection_norm_H_to_C", "norm of I - Π from H to C", F::round_off, "sqrt([k])",
       "||I - Pi_j||_{H -> C} = max_m ||(I - Pi_j)^* k(s_m, .)||_H on the grid; NaN without "
       "[[projection]]",
       true, "projection_norm_at_floor"}, M::projection_norm_H_to_C},
      { {"projection_operator_norm", "norm of Π on H", F::round_off, "1",
       "||Pi_j||_{H -> H}, measured; NaN without [[projection]]", true, ""}, M::projection_operator_norm},
      { {"projected_l2_error", "L^2 error of the projected estimate", F::integration, "[f] sqrt(m)",
       "||f - Pi_j^* fhat_j(T)|| in L2(Omega), the finite estimator's error; NaN without "
       "[[projection]]",
       true, ""}, M::projected_l2_error},
      { {"estimate_gap_H", "estimate gap in H", F::integration, "[f] / sqrt([k])",
       "sup_t ||fhat(t) - Pi_j^* fhat_j(t)||_H; NaN without [[projection]]", true,
       "estimate_gap_at_integration_floor"}, M::estimate_gap_H},
      { {"estimate_gap_C", "estimate gap in C", F::integration, "[f]",
       "sup_t max_m |fhat(t)(s_m) - Pi_j^* fhat_j(t)(s_m)|; NaN without [[projection]]", true,
       "estimate_gap_at_integration_floor"}, M::estimate_gap_C},
      { {"state_gap", "state gap", F::integration, "[x]",
       "sup_t |xhat(t) - xhat_j(t)|; NaN without [[projection]]", true,
       "estimate_gap_at_integration_floor"}, M::state_gap},
      { {"plant_gap", "plant gap", F::integration, "[x]",
       "sup_t |x(t) - x_j(t)| between the two integrations of the plant (their integration "
       "error); NaN without [[projection]]",
       true, ""}, M::plant_gap},
      { {"gap_effectivity_H", "gap effectivity in H", F::propagated, "[f] / [k]",
       "estimate_gap_H / projection_norm_H_to_C (bounded in j by Theorem 4.1); NaN without "
       "[[projection]]",
       true, "projection_norm_at_floor"}, M::gap_effectivity_H},
      { {"gap_effectivity_C", "gap effectivity in C", F::propagated, "[f] / sqrt([k])",
       "estimate_gap_C / projection_norm_H_to_C; NaN without [[projection]]", true,
       "projection_norm_at_floor"}, M::gap_effectivity_C},
      // Persistence of excitation along the path ([adaptive] path; docs/theorems.md).
      { {"unexcited_dimension", "unexcited dimension", F::exact, "count",
       "directions of the law's space the path leaves unexcited to working precision (0 on laps "
       "around the track; flag not_persistently_excited when > 0); NaN when G is singular",
       true, ""}, M::unexcited_dimension},
      { {"path_l2_error", "L^2 error on the path", F::integration, "[f] sqrt(m)",
       "||f - fhat(T)|| in L2 over the part of the track the path covers (a state-dependent "
       "plant: the read-out's range over the second half of the run, in d > 1 the points "
       "within the fill distance of its orbit); NaN on laps around it",
       true, ""}, M::path_l2_error},
      { {"off_path_l2_error", "L^2 error off the path", F::integration, "[f] sqrt(m)",
       "||f - fhat(T)|| in L2 over the rest of the track (of Omega); NaN on laps around it", true,
       ""}, M::off_path_l2_error},
      { {"reference_norm_H_to_C", "reference norm from H to C", F::round_off, "sqrt([k])",
       "rkhs_embedding with a reference resolution H_N standing in for H: ||I - Pi_N||_{H -> C} "
       "on the grid, the rate of its own distance from the estimator in H (Theorem 4.1); NaN "
       "otherwise",
       true, ""}, M::reference_norm_H_to_C},
      // The decay of ||f - fhat||_H against the PE level (Theorem 3.3; docs/theorems.md).
      { {"learning_decay_rate", "learning decay rate", F::propagated, "1/s",
       "-ln(learning_spectral_radius) / lap time: the asymptotic decay rate of ||f~||_H; NaN "
       "unless engine = lap_map, or when the lap map's error may exceed it",
       true, "decay_rate_unresolved"}, M::learning_decay_rate},
      { {"averaged_decay_rate", "averaged decay rate", F::propagated, "1/s",
       "H(0) pe_level / Gamma, H(0) = B^T P (-A)^-1 B: the slowest rate of the averaged law "
       "(docs/model.md section 14); NaN for the gradient law",
       true, "pe_level_unresolved"}, M::averaged_decay_rate},
      { {"pe_decay_ratio", "decay ratio of excitation", F::propagated, "1",
       "learning_decay_rate / averaged_decay_rate: 1 in the averaging limit (slow path, slow "
       "learning); NaN unless both are defined",
       true, "decay_rate_unresolved"}, M::pe_decay_ratio},
      { {"visited_rms_error", "RMS error where visited", F::integration, "[f]",
       "state-dependent plants: the root mean square of f - fhat(T) at the read-outs sampled over "
       "the second half of the run, where the trajectory went (what it can teach); NaN otherwise",
       true, ""}, M::visited_rms_error},
      // The hypotheses of Theorem 3 (PE => ||f - fhat||_H -> 0; docs/theorems.md): (i) k(x(.),
      // x(.)) in L^1(0, inf), or (ii) -A coercive with Gamma = P = I (law_gamma is a column).
      { {"kernel_diagonal_l1", "L^1 norm of k(x, x) over the horizon", F::round_off, "[k] s",
       "int_0^T k(x(t), x(t)) dt: T times the mean of k(s, s) over the part of the track the "
       "path covers (constant speed); it grows like T unless k(x, x) -> 0, so hypothesis (i) "
       "of Theorem 3 fails on every path that keeps k(x, x) > 0; NaN in the periodic limit "
       "(laps = \"limit\", where it is infinite) and for state-dependent plants",
       true, ""}, M::kernel_diagonal_l1},
      { {"coercivity_of_minus_a", "coercivity constant of -A", F::round_off, "1/s",
       "c = lambda_min(-(A + A^T) / 2), the largest c with (-A v, v) >= c |v|^2: hypothesis (ii) "
       "of Theorem 3 needs c > 0",
       false, ""}, M::coercivity_of_minus_a},
      { {"lyapunov_p_distance_from_identity", "distance of P from I", F::round_off, "1",
       "||P - I||_2, P the solution of A^T P + P A = -Q that the law uses: hypothesis (ii) of "
       "Theorem 3 needs P = I (0)",
       false, ""}, M::lyapunov_p_distance_from_identity},
      // Theorem 1 (existence, uniqueness, Lipschitz dependence on the initial data;
      // docs/theorems.md): its hypotheses, the embedding constant C and the Lipschitz constant
      // L of the error system, and what they bound, the measured dependence on the initial data.
      // Computed when a study asks for one of the four (needs adaptive_work_initial_data; road
      // plants; NaN otherwise).
      { {"embedding_constant", "embedding constant of H in C", F::round_off, "sqrt([k])",
       "C = max_m sqrt(k(s_m, s_m)) on the grid, the smallest C with ||f||_C <= C ||f||_H: "
       "Theorem 1 needs it finite; NaN unless asked for",
       true, "", true, adaptive_work_initial_data}, M::embedding_constant},
      { {"lipschitz_constant", "Lipschitz constant of the error system", F::round_off, "1/s",
       "L = max_m ||[[A, -B w_m], [w_m B^T P / Gamma, 0]]||_2, w_m = sqrt(phi(s_m)^T W^+ "
       "phi(s_m)) (W = G for the rkhs law, I for the gradient law and in feature coordinates): "
       "the norm of the error system's generator in |e|^2 + c^T W c; NaN unless asked for",
       true, "", true, adaptive_work_initial_data}, M::lipschitz_constant},
      { {"initial_data_lipschitz", "measured Lipschitz constant of the initial data", F::integration,
       "1",
       "max over the samples of ||X1(t) - X2(t)|| / ||X1(0) - X2(0)||, X = (x - xhat, alpha) in "
       "the norm of lipschitz_constant, the second trajectory started from x0, xhat0, alpha0 "
       "perturbed: Theorem 1's Lipschitz map from the initial data into C([0, T]); NaN unless "
       "asked for, and with the lap map",
       true, "", true, adaptive_work_initial_data}, M::initial_data_lipschitz},
      { {"lipschitz_exponent", "measured growth exponent", F::integration, "1/s",
       "max(0, max over the samples t > 0 of ln(||X1(t) - X2(t)|| / ||X1(0) - X2(0)||) / t): "
       "the smallest L' >= 0 with distance <= e^{L' t} at every sample, at most "
       "lipschitz_constant (Gronwall); NaN unless asked for, and with the lap map",
       true, "", true, adaptive_work_initial_data}, M::lipschitz_exponent},
  });
};
static_assert(table_in_enum_order<AdaptiveMetric>());

}  // namespace rkhs
