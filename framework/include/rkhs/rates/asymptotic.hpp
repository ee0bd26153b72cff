#pragma once
// The asymptotic regime of a convergence series: which points a rate fit may use (the
// asymptotic window, without the pre-asymptotic head and without a floor), and which rate model
// describes the series, algebraic (power law, log-log) or exponential (log-linear in n).
// docs/verification.md states the rules with their formulas; in short:
//
//   u_i = ln x_i (power law, x = n or h) or n_i (exponential),  v_i = ln y_i,
//   r_i = (v_{i+1} - v_i) / (u_{i+1} - u_i)             pairwise rates of the usable points,
//   R   = median r_i                                     the bulk rate,
//   s   = robust scale of the second differences of v   the noise in ln y,
//   T_i = max(0.1 |R|, 4 sqrt(2) s / |u_{i+1} - u_i|)    what a rate may differ from R by.
//
// A floor is a trailing run of rates that have stalled, sign(R) (R - r_i) > T_i, or at least
// two trailing rates that collapsed to |r_i| <= 0.1 |R| (round-off, a singular Gram matrix, an
// integration tolerance); the head is a leading run with |r_i - R| > T_i. Both are removed, R and s recomputed on what remains, until nothing changes;
// a window keeps at least 3 points. The noise term makes the rule scale with the scatter of the
// series, so noisy series are not trimmed by chance (the CI keeps its coverage) while exact
// series are trimmed as soon as a rate is off by 10 %.
//
// Each model gets its own window and fit. The preferred model is the one that fits its own
// window better than the other model fits that same window, measured by
// ΔAIC = m ln(SSE_other / SSE_model) (both models have two parameters, so this is the AIC
// difference); when both models win on their own windows the larger per-point advantage wins.
// The evidence is decisive when ΔAIC >= 2 on at least 4 points (with 3, each model's SSE has
// one degree of freedom and their ratio is mostly chance).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rkhs/rates/corrected_fit.hpp"
#include "rkhs/rates/rates.hpp"

namespace rkhs {

/// A fit window set by the user (`[rates]` or an `[[expect]]` table, docs/verification.md): the
/// usable points with n_from <= n <= n_to and h_from <= h <= h_to (ends optional, inclusive),
/// then the last `last` of them. A set window replaces the automatic one: the fit uses exactly
/// these points, without head or floor detection and without the pre-asymptotic term.
struct FitWindow {
  std::optional<double> n_from, n_to, h_from, h_to;
  std::optional<std::size_t> last;
  bool empty() const { return !n_from && !n_to && !h_from && !h_to && !last; }
  /// The keys as written, e.g. "n_from = 32, last = 4"; "" when empty.
  std::string text() const;
};

/// The usable points of a series split into head, window and floor. All indices are positions
/// in the caller's arrays, increasing.
struct AsymptoticWindow {
  std::vector<std::size_t> points;  ///< the window: what the fit uses
  std::vector<std::size_t> head;    ///< usable points before it, excluded as pre-asymptotic
  std::vector<std::size_t> floor;   ///< usable points after it, excluded as a floor
  double bulk_rate = 0.0;           ///< R: the median pairwise rate of the window (NaN if < 2 points)
  double noise = 0.0;               ///< s: the noise in ln y estimated from the window
  /// Empty when nothing was excluded; otherwise sentences like "head n = 10..20 excluded
  /// (pairwise rates 0.88, 0.95 differ from the bulk rate 1.00 by more than 0.10)".
  std::string note;
};

/// A series that does not vary with n (docs/verification.md, "Constant series"): every point of
/// `points` lies within value +- band, and band is within the values' floors or within the
/// relative band asked (default_constant_within of |value|). Such a series is reported as its
/// value and band, never as a rate: a slope fitted through it is noise.
struct ConstantSeries {
  double value = 0.0;  ///< the midpoint of the extreme values of the points
  double band = 0.0;   ///< half their spread: |y_i - value| <= band for every point
  /// The largest floor among the points (0 without floors).
  double floor = 0.0;
  /// The values agree within their floors: the intervals y_i +- floor_i share a point.
  bool within_floors = false;
  /// The relative band the series was judged against (the larger of this and the floors').
  double within = 0.0;
  std::vector<std::size_t> points;  ///< positions in the caller's arrays, increasing
  std::vector<std::size_t> head;    ///< usable points before them, excluded as pre-asymptotic

  /// band / |value|; +inf for a value of 0 with a band, 0 for both 0.
  double relative_band() const;
  /// "1.0000000000 ± 1.3e-11 (within the values' floors) on n = 10..100" or "3.7690 ± 0.00027
  /// (0.0072 %) on n = 40..100": the value to the digits its band leaves, the band to 2
  /// significant digits, labels from `labels` (the n of the trials).
  std::string text(std::span<const double> labels) const;
};

/// The relative band within which a series counts as constant unless a study sets its own
/// (`[rates] constant_within`): 1 % of its value.
inline constexpr double default_constant_within = 0.01;

/// The constant a series is, or nothing: tested on `points` (at least 3 finite values, any
/// sign), constant when (max - min) / 2 <= max(within |value|, 4 ulps) or when the intervals
/// y_i +- floor_i share a point. `floors` as analyse_series takes them (empty: none).
std::optional<ConstantSeries> detect_constant(std::span<const double> y,
                                              std::span<const double> floors,
                                              const std::vector<std::size_t>& points,
                                              double within = default_constant_within);

/// One rate model applied to a series: its window, its fit on the window, and the pairwise
/// rates of the whole series under this model.
struct ModelAnalysis {
  RateModel model = RateModel::power_law;
  AsymptoticWindow window;
  std::optional<RateFit> fit;  ///< on window.points (RateFit::used holds positions); empty if < 2
  /// How far the fit's statistics move with the values within their floors (zero without).
  FitFloors floors;
  /// Size y.size() - 1 over every point given (usable or not), NaN where undefined.
  std::vector<double> pairwise;
  /// ΔAIC of this model over the other on this model's window, m ln(SSE_other / SSE_this):
  /// positive when this model fits its own window better. NaN with fewer than 3 points.
  double advantage = 0.0;
  /// How far `advantage` moves with the values within their floors (0 without floors).
  double advantage_floor = 0.0;
};

/// Both models and which one describes the series.
struct SeriesAnalysis {
  ModelAnalysis power_law;
  ModelAnalysis exponential;
  /// The better-fitting model; empty when the models cannot be compared (fewer than 3 points
  /// in either window, or neither wins on its own window).
  std::optional<RateModel> preferred;
  /// ΔAIC of the preferred model over the other on the preferred model's window (>= 0);
  /// NaN when `preferred` is empty.
  double evidence = 0.0;
  /// Points of the preferred model's window, on which `evidence` was measured (0 when none).
  std::size_t evidence_points = 0;
  /// How far `evidence` moves with the values within their floors: m times the floors of both
  /// models' ln SSE on that window (+inf when the residuals are at the floors). 0 without floors.
  double evidence_floor = 0.0;
  /// The model whose fit is reported: exponential when it is preferred decisively, otherwise
  /// the power law (the convention of rates against ln n or ln h).
  RateModel reported = RateModel::power_law;
  /// One sentence on the choice, e.g. "exponential model preferred (ΔAIC = 9.8 over the power
  /// law on n = 10..60)".
  std::string note;

  /// ΔAIC >= 2 beyond its floor, on at least 4 points.
  bool decisive() const {
    return preferred.has_value() && evidence - evidence_floor >= 2.0 && evidence_points >= 4;
  }
  const ModelAnalysis& analysis(RateModel model) const {
    return model == RateModel::power_law ? power_law : exponential;
  }
  const ModelAnalysis& reported_analysis() const { return analysis(reported); }

  /// The power law with a pre-asymptotic term (rkhs/rates/corrected_fit.hpp), fitted when the
  /// power law's pairwise rates bend monotonically towards a limit (each successive change of
  /// the same sign and no larger than the one before) on at least 6 points: the window with
  /// its head, or failing that the window alone. Empty otherwise, and with a set window.
  std::optional<CorrectedRateFit> corrected;
  /// Positions of the points `corrected` used (its RateFit::used holds positions too).
  std::vector<std::size_t> corrected_points;
  /// How far `corrected`'s statistics move with the values within their floors, measured: the
  /// largest change over two refits with each value moved by its floor, up where the slope's
  /// weight is positive and down where it is negative, and the reverse (a nonlinear fit has no
  /// first-order formula here). rate covers p, its standard error and interval; log_sse holds
  /// the advantage's change. 0 without floors.
  FitFloors corrected_floors;
  /// The bend describes the series: the power law is reported, and the correction earns its
  /// two parameters (ΔAICc = corrected->advantage >= 2 over the straight line on its points).
  /// Rate verdicts then judge the corrected fit.
  bool bends() const {
    return reported == RateModel::power_law && corrected && corrected->advantage >= 2.0;
  }
  /// The fit a power-law rate verdict judges: corrected when bends(), else power_law.fit;
  /// nullptr when there is none.
  const RateFit* power_law_rate_fit() const {
    if (bends()) return &corrected->fit;
    return power_law.fit ? &*power_law.fit : nullptr;
  }
  /// Set when the user chose the window (FitWindow::text(), e.g. "n_from = 32"), else "".
  std::string set_window;
  /// Set when the series does not vary with n: on all usable points (of the set window, when
  /// there is one), or else without the shortest leading part of the power law's automatic
  /// head that leaves a constant (the head bounds what may be left out). A constant
  /// series is reported as its value and band; the model fits above stay for reference only.
  std::optional<ConstantSeries> constant;
};

/// The asymptotic window of the points (u_i, v_i), i < u.size(), already transformed (u = ln x
/// or n, v = ln y) and all finite. Positions in the result index u. Fewer than 4 points, or an
/// abscissa that is not strictly monotone, give the whole range (with a note in the latter
/// case). `labels[i]` names point i in notes (the n of the trial), same size as u.
/// Throws std::invalid_argument when the sizes differ.
AsymptoticWindow detect_asymptotic_window(std::span<const double> u, std::span<const double> v,
                                          std::span<const double> labels);

/// Analyses a series y over the refinement axis: `x` is the power law's abscissa (n or fill
/// distance h), `n` the exponential model's (and the labels in notes). Points with
/// usable[i] == false (failed trials, flagged values) and points with a non-finite or
/// non-positive value or abscissa are left out before anything else. Throws
/// std::invalid_argument when the sizes differ or confidence is not in (0, 1). A non-empty
/// `window` restricts the points (h_from and h_to apply to x) and replaces the automatic
/// window; fewer than 2 points in it leave both models without a fit. `floors` (empty, or one
/// absolute floor per point: MetricInfo::floor) give the fits' FitFloors and the evidence's.
/// `constant_within` is the relative band of detect_constant.
SeriesAnalysis analyse_series(std::span<const double> x, std::span<const double> n,
                              std::span<const double> y, const std::vector<bool>& usable,
                              double confidence = 0.95, const FitWindow& window = {},
                              std::span<const double> floors = {},
                              double constant_within = default_constant_within);

/// Pairwise exponential rates ln(y_{i+1} / y_i) / (n_{i+1} - n_i), the counterpart of
/// pairwise_rates; NaN where a value is non-positive or non-finite or n_{i+1} = n_i.
std::vector<double> pairwise_exponential_rates(std::span<const double> n,
                                               std::span<const double> y);

/// "10..60" or "10" (a single point) for labels of the given positions; "" when empty.
std::string label_range(std::span<const double> labels, const std::vector<std::size_t>& positions);

}  // namespace rkhs
