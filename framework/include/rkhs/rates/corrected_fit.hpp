#pragma once
// A power law with a pre-asymptotic term: the rate of a series whose pairwise rates bend
// smoothly towards their limit (docs/verification.md, "Bends").
//
//   y = C x^p (1 + D (t / t_f)^-q),   t = x (x grows under refinement, x = n) or 1/x (x = h),
//
// with t_f the finest point's t, so D is the relative size of the correction at the finest
// point and q > 0 how fast it fades. This is the first term of the expansion of an error or a
// condition number in the mesh size beyond its leading order; a straight line through
// (ln x, ln y) fitted to such a series is biased towards the coarse points' rates, and its CI,
// which takes the bend for noise, is both wide and off-centre (pairwise rates 4.56, 4.22, 4.10,
// 4.04, 4.02 fit 4.09 [4.02, 4.16]; this model gives 4.00 +- 0.01).
//
// The four parameters (ln C, p, D, q) are fitted by least squares in ln y: a grid over q with
// the linearised model ln(1 + z) ~ z for the start, then Levenberg-Marquardt on the exact model.
// The CI of p is the Student-t interval with points - 4 degrees of freedom from the covariance
// s^2 (J^T J)^-1 of all four parameters at the optimum, so the uncertainty of q and D widens
// it. Like any regression CI it measures how well the model describes the points, not how far
// they are from the limit: callers use it only where the pairwise rates bend monotonically.

#include <optional>
#include <span>

#include "rkhs/rates/rates.hpp"

namespace rkhs {

struct CorrectedRateFit {
  /// p with its standard error and CI (RateFit::points, used, intercept = ln C at x = 1,
  /// residual_std with points - 4 degrees of freedom, r_squared in ln y).
  RateFit fit;
  double order = 0.0;       ///< q > 0: the correction fades like t^-q
  double correction = 0.0;  ///< D: the correction's relative size at the finest point
  /// Sums of squared residuals in ln y of this model and of the straight line on the same
  /// points, and the difference of their small-sample AIC (AICc, k parameters cost
  /// 2k + 2k(k + 1) / (m - k - 1)): m ln(SSE_line / SSE) - 36 on 6 points, - 21 on 7, - 14.9
  /// on 8, ... towards - 4; positive when the correction earns its two parameters.
  double sse = 0.0, line_sse = 0.0, advantage = 0.0;
};

/// Fits y = C x^p (1 + D (t / t_f)^-q) to the points (x_i, y_i), all finite and positive, with
/// t = x when `refines_upward` (x = n) and t = 1/x otherwise (x = h). Returns std::nullopt with
/// fewer than 6 points (AICc needs m > k + 1 = 5 to weigh four parameters), when the abscissae are not distinct, or when the fit does not settle on
/// an interior optimum (q outside [0.05, 10], 1 + D (t/t_f)^-q <= 0 at a point, a singular
/// covariance): no pre-asymptotic term describes the series then. Throws std::invalid_argument
/// when x and y differ in size or confidence is not in (0, 1).
std::optional<CorrectedRateFit> fit_power_law_corrected(std::span<const double> x,
                                                        std::span<const double> y,
                                                        bool refines_upward,
                                                        double confidence = 0.95);

}  // namespace rkhs
