#pragma once
// Persistence of excitation of the space an adaptive trial learns in (the paper's Def. 3.1), as
// measured over one lap of the closed track: the metric pe_level (docs/model.md section 14).
//
// The path s(t) excites a subspace S of the native space H persistently when, over every window
// of some length T0, the evaluations along it bound the H-norm from below:
//
//   (1/T0) int_t^{t+T0} g(s(tau))^2 dtau >= gamma ||g||_H^2   for every g in S,
//
// (g(s) = (k(s, .), g)_H). At constant speed on the closed track one lap, T0 = L / v, covers
// [0, L) once whatever t, so the best gamma over one lap is
//
//   pe_level = min_{g in S, g != 0} (1/L) int_0^L g(s)^2 ds / ||g||_H^2     (units of k).
//
//   S = H_n (gradient and rkhs laws): g = sum_i a_i k(c_i, .), g(s) = phi(s)^T a and
//     ||g||_H^2 = a^T G a, so pe_level = lambda_min of E a = lambda G a with
//     E = (1/L) int_0^L phi phi^T ds, the averaged Gram matrix Mbar of the averaged limit
//     (rkhs/adaptive/averaged_limit.hpp: composite Gauss-Legendre between the kernel's and the
//     road's kinks, exact for B-splines, converged to 1e-14 under panel doubling otherwise).
//   S = H in feature coordinates (rkhs_embedding): g = psi^T beta with beta in the range R of the
//     feature evaluations psi(s), where ||g||_H^2 = beta^T beta (the minimum over all
//     representations of g); R is the range of E = (1/L) int psi psi^T ds, so pe_level is the
//     smallest nonzero eigenvalue of E.
//
// pe_level decreases as S grows (nested centre sets give nested spaces), and is 0 on an
// infinite-dimensional H: it says how fast the slowest direction of S is learnt per lap.

#include <Eigen/Dense>
#include <limits>

#include "rkhs/approx/gram_solver.hpp"

namespace rkhs {

struct ExcitationLevel {
  /// pe_level; NaN when it has no significant digit (below).
  double value = std::numeric_limits<double>::quiet_NaN();
  /// First-order estimate of the round-off error of `value` (absolute; not a bound).
  double error_bound = 0;
  /// Whether value is resolved to 1%: error_bound <= 0.01 value.
  bool resolved = false;
  /// The dimension of the space measured (n for H_n; for feature coordinates the rank of E
  /// found, dim H).
  Eigen::Index dimension = 0;
  /// Directions of the space the path leaves unexcited to working precision: eigenvalues not
  /// above their own round-off estimate (excitation_level), or the rank E lacks (on_range, given
  /// the rank over the whole track). 0 on a closed lap around the track.
  Eigen::Index unexcited = 0;
};

/// pe_level on H_n: lambda_min of E a = lambda G a (`excitation` E and `gram` G, n x n, with
/// `spectrum` the GramSolver's spectrum of G). When G is singular to working precision
/// (spectrum.singular) the H-norm is not resolved on H_n and the value is NaN (the trial is
/// flagged gram_singular). Otherwise the generalized symmetric-definite eigenproblem is solved
/// through the Cholesky factor L of G (the eigenvalues of L^-1 E L^-T), whose round-off is of
/// the order of
///   error_bound = eps (lambda_max(E) + |value| lambda_max(G)) / lambda_min(G)
/// (eps ||E|| ||G^-1|| and eps |value| cond(G)). Measured against the same reduction in long
/// double (B-splines p = 1, 2 and the Gaussian sigma = 1 on the paper's track, cond(G) from 4
/// to 4e13) the actual error was 0.002 to 0.2 times this estimate. The value is unresolved
/// (flagged pe_level_unresolved) when the estimate exceeds 1% of it, and NaN when it does not
/// exceed the estimate (no significant digit; a negative value among them).
ExcitationLevel excitation_level(const Eigen::MatrixXd& excitation, const Eigen::MatrixXd& gram,
                                 const GramSpectrum& spectrum);

/// pe_level in feature coordinates from the eigenvalues of E (F of them, increasing): the
/// smallest eigenvalue above the cutoff F eps lambda_max(E) (below it lie E's zero eigenvalues,
/// the redundant directions, as computed). The computed eigenvalues are within about
/// F eps lambda_max(E) of the exact ones (error_bound), so the smallest nonzero one is
/// identified only when it lies clearly above the zeros: when it is below 100 times the cutoff
/// it is not resolved and the value is NaN.
ExcitationLevel excitation_level_on_range(const Eigen::VectorXd& eigenvalues);

}  // namespace rkhs
