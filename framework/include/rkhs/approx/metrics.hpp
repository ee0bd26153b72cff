#pragma once
// Metric tables: for each study kind, one enum naming its metrics and one constexpr table with,
// per metric, its output name, its plot label, how its round-off floor is estimated, its unit, meaning, whether
// NaN is a legitimate value and the flag that excludes it from rate fits. The enum order is the output order (trials.csv columns,
// `rkhs-study list metrics`, docs/metrics.md); trials fill their values by identifier.

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rkhs {

/// How a metric's floor is estimated: the size below which its value is not resolved, because
/// round-off, an integrator's tolerance or the step controller's decisions decide its digits
/// there (docs/metrics.md, "Floors"). A trial writes the floor beside the value (`<metric>_floor`
/// in trials.csv, `floors` in summary.json) for every rule but `exact`; a value at or below its
/// floor is flagged (the row's flag, or `<metric>_at_floor`) and left out of rate fits, and two
/// runs (two processors, two code paths of glibc's exp and log) agree within the larger floor.
enum class FloorRule {
  /// Correctly rounded arithmetic on exact inputs, or a count of the grid or of thresholded
  /// eigenvalues: the same value on every processor to a few ulps. No floor is written.
  exact,
  /// The round-off of the linear algebra that computes it, from the trial's own estimate:
  /// n eps lambda_max(G) propagated through the solve (the power function's and the errors'
  /// floors, an eigenvalue's perturbation bound, the projection norm's sqrt(|S| eps max k)).
  round_off,
  /// The tolerances of the adaptive integration that computes it (the integrator's rtol and
  /// atol, or the lap map's), at the scale of the integrated state: rtol |z| + atol.
  integration,
  /// From the floors of the values it is computed from, to first order (a ratio, a logarithm).
  propagated,
  /// A count of the integrator's work: the step controller accepts or rejects a step whose
  /// error estimate is near its tolerance according to the last bits of the state, so the count
  /// moves from processor to processor (215775 against 215794 steps; up to 0.84 % seen, and 28
  /// against 42 rejected steps). Its floor is 0.02 N + 3 sqrt(N) for a count N: a measure of
  /// work, compared as such, never flagged, never of the result.
  step_controller,
};

/// The rule's identifier ("exact", "round_off", ...), as `rkhs-study list metrics` prints it.
constexpr std::string_view floor_rule_name(FloorRule rule) {
  switch (rule) {
    case FloorRule::exact: return "exact";
    case FloorRule::round_off: return "round_off";
    case FloorRule::integration: return "integration";
    case FloorRule::propagated: return "propagated";
    case FloorRule::step_controller: return "step_controller";
  }
  return "";
}

/// What the approximation theory of the Sobolev and analytic kernels says about a metric
/// (rkhs/rates/theory.hpp turns it into a rate for a kernel's properties; docs/verification.md).
enum class TheoryLaw {
  none,                   ///< no theory rate
  power_function,         ///< ~ h^(tau - d/2), attained, for any centres
  error_sup_bound,        ///< <= C h^(tau - d/2) (|f - Pi f| <= P ||f||_H), for any centres
  error_l2_bound,         ///< <= C h^tau, for any centres
  projection_norm,        ///< ~ h^(tau - d/2) for a uniformly bounded projection of mesh h
  gram_min_eigenvalue,    ///< ~ q^(2 tau - d)
  gram_condition_number,  ///< ~ n q^-(2 tau - d) = h^(-2 tau); grows
  /// Multiscale interpolation (Wendland 2010): the error falls by a factor <= alpha < 1 from
  /// one level to the next, alpha independent of the level
  level_reduction,
};

/// The law's identifier ("power_function", ...), as `rkhs-study list metrics` prints it; "-"
/// for none.
constexpr std::string_view theory_law_name(TheoryLaw law) {
  switch (law) {
    case TheoryLaw::none: return "-";
    case TheoryLaw::power_function: return "power_function";
    case TheoryLaw::error_sup_bound: return "error_sup_bound";
    case TheoryLaw::error_l2_bound: return "error_l2_bound";
    case TheoryLaw::projection_norm: return "projection_norm";
    case TheoryLaw::gram_min_eigenvalue: return "gram_min_eigenvalue";
    case TheoryLaw::gram_condition_number: return "gram_condition_number";
    case TheoryLaw::level_reduction: return "level_reduction";
  }
  return "-";
}

/// One metric of a study kind: everything the framework knows about it, in one place. The
/// catalogue of a study kind (rkhs/study/study_kind.hpp) is its table's rows; `rkhs-study list
/// metrics` prints them and docs/metrics.md is checked against that listing.
struct MetricInfo {
  std::string_view name;  ///< column of trials.csv, key of study.metrics in study files
  /// A plot's axis label: a few words, no unit (the plots add physical units: m, s, laps), in
  /// gnuplot's enhanced text ("L^2 error": ^ and _ raise and lower the next character or {group})
  std::string_view label;
  FloorRule floor;        ///< how its floor is estimated (`exact`: none is written)
  /// m (arc length), s, 1 (dimensionless), count, [k] (units of the kernel), [f] (of the
  /// target f), [x] (of the plant state), [V] (of the Lyapunov function), or products of these
  std::string_view unit;
  std::string_view doc;   ///< one line
  bool may_be_nan;        ///< NaN by design in some trials; any other NaN fails the trial
  std::string_view flag;  ///< the flag that marks a value as round-off (docs/metrics.md), or ""
  /// Whether a value carrying `flag` is left out of rate fits (excluding_flag()). True for
  /// every flag but the adaptive trials' interpolant_*_at_floor, which mark values that fits
  /// still use (making them excluded changes adaptive studies' fitted rates).
  bool flag_excludes_from_fits = true;
  /// What a trial must compute to give this metric and decide its flag, as bits of the kind's
  /// work enum: ApproximationWork for approximation trials, AdaptiveWork for adaptive trials
  /// (which compute every other metric); 0 when it needs nothing beyond what every trial does.
  unsigned needs = 0;
  /// Taken on the evaluation grid s_m (a sup or an L2 norm over the domain): a study whose
  /// grid is no finer than its centres is refused when it asks for one (docs/metrics.md).
  bool on_grid = false;
  TheoryLaw theory = TheoryLaw::none;  ///< what theory predicts for it (approximation trials)
  /// Computed only by the matrix-free projections that declare it (ProjectionProperties::
  /// measures: the multilevel projection's level_* metrics), NaN in every other trial. A study
  /// that lists no metrics writes the metrics every one of its projections computes, so such a
  /// metric only when all its projections declare it.
  bool matrix_free_only = false;
};

/// One row of a metric table: the metric's facts and its identifier, the row's position
/// (checked at compile time).
template <class Metric>
struct MetricRow : MetricInfo {
  Metric id;
};

/// The rows of a table as MetricInfo, in table (output) order.
template <class Metric>
std::vector<MetricInfo> metric_infos();

/// Specialised per metric enum with `static constexpr std::array<MetricRow<Metric>, N> rows`.
template <class Metric>
struct MetricTable;

/// True when every row of the table sits at the position of its identifier.
template <class Metric>
constexpr bool table_in_enum_order() {
  const auto& rows = MetricTable<Metric>::rows;
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (static_cast<std::size_t>(rows[i].id) != i) return false;
  return true;
}

/// The flag a value of `row` at or below its floor carries: the row's own flag when it is a
/// floor flag of this metric ("<stem>_at_floor" with the metric's name starting with <stem>:
/// power_function_at_floor for power_function_sup), else "<name>_at_floor" ("" for an exact
/// metric).
inline std::string floor_flag(const MetricInfo& row) {
  if (row.floor == FloorRule::exact) return {};
  constexpr std::string_view suffix = "_at_floor";
  if (row.flag.ends_with(suffix) &&
      row.name.starts_with(row.flag.substr(0, row.flag.size() - suffix.size())))
    return std::string(row.flag);
  return std::string(row.name) + std::string(suffix);
}

/// The names of a table, in table (output) order.
template <class Metric>
std::vector<std::string> metric_table_names() {
  std::vector<std::string> names;
  for (const auto& row : MetricTable<Metric>::rows) names.emplace_back(row.name);
  return names;
}

template <class Metric>
std::vector<MetricInfo> metric_infos() {
  const auto& rows = MetricTable<Metric>::rows;
  return std::vector<MetricInfo>(rows.begin(), rows.end());
}

/// The values of one trial's metrics, NaN until set. Written by identifier
/// (`values[Metric::l2_error] = e`); read by identifier or by position (aligned with the
/// table, as study writers index them).
template <class Metric>
class MetricValues {
 public:
  static constexpr std::size_t count = MetricTable<Metric>::rows.size();
  MetricValues() : values_(count, std::numeric_limits<double>::quiet_NaN()) {}
  double& operator[](Metric metric) { return values_[static_cast<std::size_t>(metric)]; }
  double operator[](Metric metric) const { return values_[static_cast<std::size_t>(metric)]; }
  double operator[](std::size_t position) const { return values_[position]; }
  std::size_t size() const noexcept { return values_.size(); }
  /// The values in table order.
  const std::vector<double>& values() const& noexcept { return values_; }
  std::vector<double> values() && noexcept { return std::move(values_); }
  /// Sets every value to NaN.
  void clear() { std::fill(values_.begin(), values_.end(), std::numeric_limits<double>::quiet_NaN()); }

 private:
  std::vector<double> values_;
};

/// The parts of an approximation trial's work, as bits: a trial computes the union of the needs
/// of the metrics it is asked for (MetricInfo::needs, approximation_work()) and nothing else.
enum ApproximationWork : unsigned {
  /// The fill distance of the centres (a branch and bound over the domain in d > 1).
  work_fill = 1u << 0,
  /// The separation distance (all pairs of centres in d > 1).
  work_separation = 1u << 1,
  /// The extreme eigenvalues of G, exactly (a symmetric eigenvalue solve, O(n^3)); without it
  /// the solver estimates them (Lanczos) only to decide whether G is singular.
  work_spectrum = 1u << 2,
  /// P_n on the grid: the cross matrix block by block and one triangular solve per point.
  work_power = 1u << 3,
  /// |G^-1 k_X(s_m)|^2 on the grid, the round-off floors: a second triangular solve per point
  /// (implies work_power).
  work_cardinal = 1u << 4,
  /// The coefficients of Pi_n f (alpha = G^-1 f(X), or c = W f(S)).
  work_interpolant = 1u << 5,
  /// f - Pi_n f on the grid (the cross matrix times the coefficients).
  work_residual = 1u << 6,
  /// ||(I - Pi)^* k(s, .)||_H on the grid from the projection's own definition; for the
  /// interpolation projection it is the power function (work_power).
  work_projection_residual = 1u << 7,
  /// ||Pi||_{H -> H} of the built operator (the interpolation projection is then built too).
  work_operator_norm = 1u << 8,
  /// The extreme eigenvalues of a multilevel projection's finest Gram matrix (Lanczos on the
  /// sparse matrix and on its inverse through the factor).
  work_level_spectrum = 1u << 9,
};

/// Which metrics of a table a trial computes, by table position (true: computed). Empty means
/// every metric.
using MetricSelection = std::vector<bool>;

/// The union of MetricInfo::needs over the metrics `selection` names (every metric when empty).
template <class Metric>
unsigned work_needed(const MetricSelection& selection) {
  unsigned work = 0;
  const auto& rows = MetricTable<Metric>::rows;
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (selection.empty() || (i < selection.size() && selection[i])) work |= rows[i].needs;
  return work;
}

/// The metrics of an approximation trial (docs/metrics.md).
enum class ApproximationMetric : std::size_t {
  fill_distance,
  separation_distance,
  gram_condition_number,
  gram_min_eigenvalue,
  gram_max_eigenvalue,
  power_function_sup,
  power_function_floor,
  l2_error,
  sup_error,
  error_floor,
  interpolant_native_norm,
  projection_norm_H_to_C,
  projection_operator_norm,
  level_reduction_factor,
  level_condition_number,
  level_nonzeros,
};

template <>
struct MetricTable<ApproximationMetric> {
  using M = ApproximationMetric;
  using F = FloorRule;
  static constexpr auto rows = std::to_array<MetricRow<M>>({
      { {"fill_distance", "fill distance h", F::exact, "m", "h = sup_x min_i |x - c_i|", false, "", true,
       work_fill}, M::fill_distance},
      { {"separation_distance", "separation distance q", F::exact, "m",
       "q = min_{i != j} |c_i - c_j| / 2; NaN for a single centre", true, "", true,
       work_separation}, M::separation_distance},
      { {"gram_condition_number", "condition number of the Gram matrix", F::round_off, "1",
       "lambda_max / lambda_min of G, +inf when singular", false, "gram_singular", true,
       work_spectrum, false, TheoryLaw::gram_condition_number}, M::gram_condition_number},
      { {"gram_min_eigenvalue", "smallest eigenvalue of the Gram matrix", F::round_off, "[k]", "lambda_min(G)", false,
       "gram_singular", true,
       work_spectrum, false, TheoryLaw::gram_min_eigenvalue}, M::gram_min_eigenvalue},
      { {"gram_max_eigenvalue", "largest eigenvalue of the Gram matrix", F::round_off, "[k]", "lambda_max(G)", false, "", true,
       work_spectrum}, M::gram_max_eigenvalue},
      { {"power_function_sup", "power function, sup norm", F::round_off, "sqrt([k])",
       "max_m P_n(s_m) = ||I - Pi_n||_{H -> C} on the grid", false, "power_function_at_floor", true,
       work_power | work_cardinal, true, TheoryLaw::power_function}, M::power_function_sup},
      { {"power_function_floor", "round-off level of the power function", F::round_off, "sqrt([k])",
       "round-off level of P_n: max_m sqrt(n eps lambda_max |G^-1 k_X(s_m)|^2)", false, "", true,
       work_power | work_cardinal, true}, M::power_function_floor},
      { {"l2_error", "L^2 error", F::round_off, "[f] sqrt(m)", "||f - Pi_n f|| in L2(Omega)", false,
       "l2_error_at_floor", true,
       work_interpolant | work_residual | work_cardinal, true, TheoryLaw::error_l2_bound}, M::l2_error},
      { {"sup_error", "sup-norm error", F::round_off, "[f]", "max_m |f(s_m) - Pi_n f(s_m)|", false,
       "sup_error_at_floor", true,
       work_interpolant | work_residual | work_cardinal, true, TheoryLaw::error_sup_bound}, M::sup_error},
      { {"error_floor", "round-off level of the error", F::round_off, "[f]",
       "round-off level of Pi_n f: max_m n eps lambda_max |G^-1 k_X(s_m)| |alpha|", false, "", true,
       work_interpolant | work_cardinal, true}, M::error_floor},
      { {"interpolant_native_norm", "native norm of the interpolant", F::round_off, "[f] / sqrt([k])",
       "||Pi_n f||_H = sqrt(alpha^T G alpha)", false, "", true,
       work_interpolant}, M::interpolant_native_norm},
      { {"projection_norm_H_to_C", "norm of I - Π from H to C", F::round_off, "sqrt([k])",
       "max_m ||(I - Pi)^* k(s_m, .)||_H = ||I - Pi||_{H -> C} on the grid, from the "
       "projection's own definition (the power function for interpolation)",
       false, "projection_norm_at_floor", true,
       work_projection_residual, false, TheoryLaw::projection_norm}, M::projection_norm_H_to_C},
      { {"projection_operator_norm", "norm of Π on H", F::round_off, "1",
       "||Pi||_{H -> H}, measured (1 for an H-orthogonal projection)", false, "", true,
       work_operator_norm}, M::projection_operator_norm},
      { {"level_reduction_factor", "error reduction of the level", F::propagated, "1",
       "multilevel: ||e_j|| / ||e_{j-1}|| in L2(Omega) on the grid, e_j = f - s_0 - ... - s_j, "
       "e_{-1} = f; its floor from the two errors' floors; NaN for other projections", true, "", true,
       work_interpolant | work_residual, true, TheoryLaw::level_reduction, true}, M::level_reduction_factor},
      { {"level_condition_number", "condition number of the level's Gram matrix", F::round_off,
       "1",
       "multilevel: lambda_max / lambda_min of level j's sparse Gram matrix (Lanczos, each "
       "resolved to 1e-8 relative); NaN for other projections", true, "", true,
       work_level_spectrum, false, TheoryLaw::none, true}, M::level_condition_number},
      { {"level_nonzeros", "nonzeros of the level's Gram matrix", F::exact, "count",
       "multilevel: nonzero entries of level j's sparse Gram matrix; NaN for other projections",
       true, "", true, work_interpolant, false, TheoryLaw::none, true}, M::level_nonzeros},
  });
};
static_assert(table_in_enum_order<ApproximationMetric>());

}  // namespace rkhs
