#pragma once
// The kernel contract (docs/style.md practice 6): what every kernel plugin must satisfy, as named
// checks with measured values. The contract test (tests/plugin/test_kernel_contract.cpp) runs it
// on every registered kernel; `rkhs-study verify-plugin` runs it on a plugin's kernels
// (plugin_verification.hpp).
//
// Checked on one kernel instance, on its own domain (a track, an interval, or a box or torus in
// R^d: there with points of d coordinates, periods and shifts along every axis, and the
// derivative checks skipped):
//   metadata            tau > d/2 when a Sobolev order is declared, not both analytic and
//                       Sobolev, support radius >= 0, a finite feature map is not strictly
//                       positive definite, dimension = the domain's
//   diagonal            k(x, x) >= 0 and not identically 0
//   symmetry            |k(x, y) - k(y, x)| <= 1e-14 max k(x, x)
//   periodicity         declared periodic exactly when the domain is; on a periodic domain
//                       |k(x + L, y) - k(x, y)| and |k(x, y - 2L) - k(x, y)| <= 1e-11 max k
//   compact support     k(x, y) = 0 when the domain distance is >= the declared radius
//   stationarity        k(x + t, y + t) = k(x, y) to 1e-11 max k, when declared stationary
//   Gram symmetric, Gram diagonal, cross matrix   gram(), cross(), diagonal() agree with k(x, y)
//   Gram positive semidefinite                     lambda_min >= -64 n eps lambda_max at 40
//                       scattered points and at random point sets of 10, 25 and 50 points
//   feature-map rank    rank(G) <= feature_count() (finite feature maps only)
//   derivative          derivative(c, s) (closed form or the fallback difference) agrees with a
//                       Richardson-extrapolated central difference of k(c, .) (Ridders' method)
//                       to 1e-6 max(max |dk/ds|, max k / L), at pairs (c, s) whose difference
//                       stencil stays away from the section's possible kinks: kink_points(), s = c,
//                       |s - c| = support radius, and an interval's ends
//   basis derivative    a basis' evaluate_derivative equals derivative(c_i, s), and
//                       evaluate_mapped_derivative equals T times it, to 1e-12 of the same scale
//                       (plus the rounding a difference quotient amplifies, without closed forms)
//   power function      P^2 >= 0, P^2 = 0 at the centres, P^2 non-increasing from 4 to 8 to 16
//                       nested centres (skipped, with the reason, when round-off makes the
//                       comparison meaningless)
// Tolerances are relative to max k(x, x) and derived in the implementation's comments.

#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// One named check of the contract.
struct ContractCheck {
  std::string name;  ///< e.g. "symmetry"
  bool passed = true;
  bool skipped = false;  ///< does not apply to this instance (detail says why); counts as passed
  std::string detail;    ///< what was measured, against which tolerance
};

struct ContractReport {
  std::vector<ContractCheck> checks;
  bool passed() const noexcept;
  /// Failed checks as "name: detail" lines.
  std::vector<std::string> failures() const;
  /// How many of the two nested comparisons (4 -> 8, 8 -> 16) of the power function were
  /// meaningful and checked (see power function above).
  int monotonicity_comparisons = 0;
};

/// Runs every check of the contract on `kernel` (on kernel.domain()). Never throws for a kernel
/// that violates the contract; exceptions thrown by the kernel itself propagate.
ContractReport check_kernel_contract(const AnyKernel& kernel);

/// f'(s) by Richardson extrapolation of central differences (Ridders' method): the tableau of
/// (f(s + h) - f(s - h)) / 2h for h = h0, h0 / 1.4, h0 / 1.4^2, ..., its entry with the smallest
/// estimated error, tried from h0 = `largest_step` down to 1e-3 of it. f must be smooth on
/// [s - largest_step, s + largest_step]. `error` receives the estimate.
double richardson_derivative(const std::function<double(double)>& f, double s, double largest_step,
                             double& error);

/// `count` points in [0, L) from the golden-ratio sequence: spread out, off every uniform grid.
std::vector<double> golden_ratio_points(std::size_t count, double length, double start = 0.1234);
/// `count` points of `domain` as a flat point set: golden_ratio_points in d = 1; in d > 1 the
/// Kronecker sequence of the generalised golden ratio (every prefix spread out, nested).
std::vector<double> scattered_points(const Domain& domain, std::size_t count, double start);
/// c_i = i L / n, i = 0..n-1: nested when n doubles, on both kinds of domain.
std::vector<double> nested_uniform_centres(std::size_t n, double length);

/// P_X(x)^2 = k(x, x) - k_X(x)^T G^+ k_X(x) at `points`, with G^+ the eigen-decomposition
/// pseudo-inverse (eigenvalues <= 1e3 n eps lambda_max dropped), and a round-off bound.
///
/// Bound: the computed quadratic form equals a^T (G + dG) a-type perturbations with
/// ||dG|| ~ n eps lambda_max and a = G^-1 k_X(x), ||a||^2 <= k(x, x) / lambda_min (because
/// a^T G a = k_X^T G^-1 k_X <= k(x, x)), so |error| <~ n eps (lambda_max / lambda_min) k(x, x).
/// `tolerance` = 32 n eps kappa max_x k(x, x), kappa over the eigenvalues kept.
struct PowerFunctionSquared {
  Eigen::VectorXd squared;
  double tolerance = 0;
  double condition = 0;  ///< lambda_max / smallest kept eigenvalue
  int dropped = 0;       ///< eigenvalues treated as zero
};
PowerFunctionSquared power_function_squared(const AnyKernel& kernel,
                                            const std::vector<double>& centres,
                                            const std::vector<double>& points);

}  // namespace rkhs
