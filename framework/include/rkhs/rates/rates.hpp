#pragma once
// Convergence rates of a metric along a refinement axis: pairwise (local) rates and
// least-squares fitted rates with standard errors and confidence intervals (docs/model.md
// section 5).
//
// Two models, both linear regressions of ln(y) (natural logarithm) on a transformed abscissa u:
//   power law    ln y = a + b ln x   algebraic convergence, x = n or fill distance h;
//   exponential  ln y = a + b x      spectral convergence of analytic kernels (Gaussian), x = n.
// In both, RateFit::rate is the slope b with its sign kept: an error decaying like n^-1.5 has
// rate -1.5, one decaying like exp(-0.3 n) has (exponential) rate -0.3.
//
// The regression is ordinary least squares on centred data (u - mean u, ln y - mean ln y), so
// large abscissae (ln n ~ 10, or n ~ 1e4 in the exponential model) do not cost digits. The
// standard error is the textbook one for the slope under i.i.d. normal residuals in ln y, and
// the confidence interval uses the Student t quantile with (points - 2) degrees of freedom.

#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace rkhs {

/// Which model a RateFit belongs to.
enum class RateModel {
  power_law,    ///< ln y = intercept + rate ln x
  exponential,  ///< ln y = intercept + rate x
};

/// The refinement axis a rate is measured against: the number of centres n, or the fill
/// distance h of the centres.
enum class Abscissa { n, fill_distance };

/// An interval for a fitted rate; an infinite end makes it a one-sided bound.
struct RateInterval {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
};

/// A fitted rate. All logarithms are natural.
struct RateFit {
  RateModel model = RateModel::power_law;
  double rate = 0.0;         ///< slope b; negative when y decreases as x grows
  double intercept = 0.0;    ///< a: ln y at u = 0 (x = 1 for the power law, x = 0 for exponential)
  double std_error = 0.0;    ///< standard error of the slope; NaN with exactly 2 points
  double confidence = 0.95;  ///< two-sided level of [ci_low, ci_high]
  double ci_low = 0.0;       ///< rate - t_{(1+confidence)/2, points-2} std_error; NaN with 2 points
  double ci_high = 0.0;      ///< rate + t_{(1+confidence)/2, points-2} std_error; NaN with 2 points
  /// 1 - SSE / SST of the regression in ln y; NaN when every used y is the same (SST = 0).
  double r_squared = 0.0;
  std::size_t points = 0;         ///< number of points the fit used (= used.size())
  double residual_std = 0.0;      ///< sqrt(SSE / (points - 2)), in units of ln y; NaN with 2 points
  std::vector<std::size_t> used;  ///< indices into the caller's x / y of the points used
  /// Empty when every point was used and the statistics are complete; otherwise one or more
  /// sentences separated by "; ", e.g. "excluded 2 of 12 points: 1 with non-finite value,
  /// 1 with zero or negative value" or "only 2 points: slope exact, no standard error or
  /// confidence interval".
  std::string note;
};

/// How far a fit's statistics may move when each value it used moves within its floor
/// (docs/verification.md, "Floors"): with d_i = floor_i / y_i the relative floor of point i (its
/// floor in ln y, to first order), w_i = (u_i - mean u) / S_uu the slope's weights and r the
/// residuals,
///   rate:      sum |w_i| d_i + t |d|_2 / sqrt((m - 2) S_uu)   (the slope, and its standard
///              error times the interval's t quantile: covers rate, std_error, ci_low, ci_high)
///   ln SSE:    -2 ln(1 - |d|_2 / |r|_2), +inf once |d|_2 >= |r|_2 (the residuals are floor)
///   r_squared: what |r + P d| and the spread of ln y can move 1 - SSE / SST by.
/// All 0 when every floor is 0.
struct FitFloors {
  double rate = 0.0;
  double log_sse = 0.0;
  double r_squared = 0.0;
};

/// FitFloors of `fit` (a fit of ln y on u: u = ln x for the power law, x for the exponential
/// model) from the abscissa `u`, the values `y` and their absolute `floors` (NaN or negative:
/// 0), all indexed like fit.used.
FitFloors fit_floors(const RateFit& fit, std::span<const double> u, std::span<const double> y,
                     std::span<const double> floors);

/// The floor of ln SSE for residuals of norm sqrt(sse) when the points move by
/// relative_floor_norm (|d|_2) in ln y: -2 ln(1 - |d| / sqrt(sse)), +inf at or beyond it.
double log_sse_floor(double sse, double relative_floor_norm);

/// Local rates between successive points: r_i = ln(y_{i+1} / y_i) / ln(x_{i+1} / x_i) for
/// i = 0 .. x.size() - 2 (result size x.size() - 1; empty when fewer than 2 points).
/// r_i is NaN when any of the four values is non-positive or non-finite, or when
/// x_{i+1} = x_i. Throws std::invalid_argument when x and y differ in size.
std::vector<double> pairwise_rates(std::span<const double> x, std::span<const double> y);

/// Least-squares power-law fit ln y = intercept + rate ln x.
///
/// Points whose x or y is non-finite, zero or negative are excluded (RateFit::used lists the
/// others; RateFit::note says how many were dropped and why). `x` may be any positive axis:
/// the number of centres n, or the fill distance h (then a rate of +2 means error ~ h^2).
///
/// Returns std::nullopt when fewer than 2 usable points remain or all usable x are equal: no
/// slope is defined, and callers explain that themselves (format_convergence_table does).
/// With exactly 2 usable points the slope is exact and std_error, ci_low, ci_high and
/// residual_std are NaN (the note says so).
///
/// Throws std::invalid_argument when x and y differ in size or confidence is not in (0, 1).
std::optional<RateFit> fit_power_law(std::span<const double> x, std::span<const double> y,
                                     double confidence = 0.95);

/// Least-squares exponential fit ln y = intercept + rate x (log-linear in x).
///
/// Same contract as fit_power_law, except that x may be zero or negative: only non-finite x
/// are excluded (y must still be finite and positive).
std::optional<RateFit> fit_exponential(std::span<const double> x, std::span<const double> y,
                                       double confidence = 0.95);

}  // namespace rkhs
