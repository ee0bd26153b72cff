#pragma once
// Convergence rates predicted by approximation theory from a kernel's metadata
// (KernelProperties: Sobolev order tau, or analytic), for the metrics of approximation trials.
// These are the `theory = true` expectations of docs/verification.md, where the derivations
// and references are.
//
// Kernels whose native space is equivalent to the Sobolev space H^tau on a bounded domain in
// d dimensions, with fill distance h and separation distance q (quasi-uniform: q ~ h ~ n^-1/d):
//
//   power_function_sup     ~ h^(tau - d/2)   order attained (two-sided)    } in h for any
//   sup_error             <= C h^(tau - d/2)  upper bound only (|f - Pi f| <= P ||f||_H)   }
//   centres l2_error              <= C h^tau          upper bound only (smoother f converge faster)
//   } gram_min_eigenvalue    ~ q^(2 tau - d)   order attained (two-sided) gram_condition_number  ~
//   n q^-(2 tau - d) = h^(-2 tau)   (two-sided)
//
// The textbook "condition number ~ q^-(2 tau - d)" is the bound on 1 / lambda_min; for a fixed
// kernel on a bounded domain lambda_max grows like n (Gershgorin bounds it by n max k, the
// Rayleigh quotient of the all-ones vector by n times the mean of k), so the condition number
// grows like n q^-(2 tau - d) = q^-(2 tau) for quasi-uniform centres: n^(2 tau) in one dimension
// (measured: +2.0 for tau = 1 and +3.9 for tau = 2, docs/model.md section 8).
//
// Analytic kernels (Gaussian): every metric above converges (or grows) at least exponentially,
// so the theory is one-sided and qualitative: the exponential model describes the series
// better than any power law, and its rate has the right sign.
//
// Multiscale interpolation (the `multilevel` projection: level l interpolates the residual of
// the coarser ones on nested quasi-uniform centres, h_{l+1} = h_l / 2, with the kernel scaled to
// rho_l = nu h_l), for a kernel equivalent to H^tau, tau > d/2, and f in H^tau (Wendland, Numer.
// Math. 2010): for nu large enough there is alpha < 1 independent of the level with
// ||f - s_0 - ... - s_j||_L2 <= C alpha^(j+1) ||f||_H^tau, the residual's scaled native norm
// falling by alpha from each level to the next. So
//
//   level_reduction_factor <= alpha < 1 at every level, and bounded away from 1 as the levels
//   refine: every value below 1, and against ln h a slope of at least 0 (h^0 an upper bound;
//   a factor that creeps towards 1 as h falls has a negative slope and fails)
//
// The theorem states no rule for alpha (its constant is unknown), so only the bound is judged;
// for analytic kernels it says nothing.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/approx/metrics.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/rates/rates.hpp"

namespace rkhs {

struct TheoryRate {
  RateModel model = RateModel::power_law;  ///< power_law (Sobolev) or exponential (analytic)
  double h_exponent = 0.0;  ///< power law: the metric behaves like h^h_exponent
  /// True when the order is attained (the fitted rate must equal it within the tolerance);
  /// false when theory bounds the metric from above only (it may converge faster).
  bool sharp = true;
  int direction = -1;     ///< exponential: -1 the metric decays, +1 it grows
  int dimension = 1;      ///< d of the kernel's domain (KernelProperties::dimension)
  /// True when the statement in the fill distance h holds for any centres, quasi-uniform or
  /// not: the power function (P(x) <= C h^(tau - d/2) by a sampling inequality, >= c
  /// dist(x, X)^(tau - d/2) by a bump function in the largest hole) and the errors it bounds.
  /// False when the theory is stated in the separation distance q (the Gram matrix's
  /// eigenvalues), which is h only for quasi-uniform centres. Against n every theory needs
  /// quasi-uniform centres (h ~ n^-1/d).
  bool holds_for_any_centres = false;
  /// Why the statement needs quasi-uniform centres against ln h, for messages.
  std::string_view quasi_uniform_because =
      "the theory is stated in the separation distance q, which is h only for them";
  /// When the law also bounds every value (the multilevel reduction factor: below 1), that
  /// bound: each usable value must lie below it.
  std::optional<double> values_below;
  std::string statement;  ///< "power_function_sup ~ h^(tau - d/2) = h^0.5 (tau = 1, d = 1)"
};

/// The theory for `metric` and a kernel with `properties` (in properties.dimension dimensions), or
/// std::nullopt with the reason in `*why` (metric without a theory, kernel without a Sobolev
/// order and not analytic).
std::optional<TheoryRate> theory_rate(std::string_view metric, const KernelProperties& properties,
                                      std::string* why = nullptr);

/// The same for a metric's catalogue row: its TheoryLaw (rkhs/approx/metrics.hpp) is what
/// theory says about it; the name above looks up the approximation trials' row.
std::optional<TheoryRate> theory_rate(const MetricInfo& metric, const KernelProperties& properties,
                                      std::string* why = nullptr);

/// The metrics theory_rate knows: the approximation metrics whose row has a TheoryLaw, in
/// table order.
const std::vector<std::string>& theory_metrics();

/// Why `metric` has no theory rate when its row has no TheoryLaw: "no theory rate for metric
/// 'm' (theory covers ...)".
std::string no_theory_law(std::string_view metric);

/// The interval accepted for the fitted power-law slope against the study's abscissa, for an
/// algebraic theory: the slope is h_exponent against ln h, -h_exponent / d against ln n
/// (quasi-uniform centres). Sharp: slope +- tolerance; otherwise one-sided (at least as fast
/// as the theory, minus the tolerance). `*slope` receives the predicted slope.
RateInterval theory_interval(const TheoryRate& theory, Abscissa abscissa, double tolerance,
                             double* slope = nullptr);

}  // namespace rkhs
