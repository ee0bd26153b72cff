#pragma once
// The averaged limit of the adaptive estimator: the L2(Omega)-orthogonal projection of the road
// onto H_n = span{k(c_i, .)}.
//
// Along the closed track s(t) = (v t) mod L, both learning laws (docs/model.md section 1) move
// alpha on the time scale of laps while the error e = x - xhat follows the road quasi-statically,
// e ~ -A^-1 B (f(s) - phi(s)^T alpha). As v -> 0 the learning law averages over a lap to
//
//   alpha' = c M (bbar - Mbar alpha),   c = 1/2 (A^-1 B)^T Q (A^-1 B) > 0,
//   Mbar = (1/L) int_0^L phi(s) phi(s)^T ds,   bbar = (1/L) int_0^L phi(s) f(s) ds,
//
// with phi(s) = (k(c_1, s), ..., k(c_n, s))^T, L the domain's length and M = Gamma^-1 I
// (gradient law) or Gamma^-1 G^-1 (rkhs law). For either (symmetric positive definite) M the
// rest point is the same, alpha = Mbar^-1 bbar: the coefficients of P_L2 f, the
// L2(Omega)-orthogonal projection of f onto H_n (Galerkin orthogonality:
// (f - P_L2 f, phi_i)_L2 = 0 for every i). This is the v -> 0 limit of the estimate.
// It is not Pi_n f, the H-orthogonal projection (the kernel interpolant).
//
// Mbar and bbar are computed by composite Gauss-Legendre quadrature (see AveragedLimitQuadrature
// for the rule and why it is accurate to round-off), and the normal equations are solved with
// GramSolver (Mbar is symmetric positive semidefinite, singular to working precision for a
// Gaussian with many centres, rank-deficient for a B-spline kernel with more centres than
// features).

#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// The q-point Gauss-Legendre rule on [-1, 1]: int_{-1}^{1} g ~ sum_k weights[k] g(nodes[k]),
/// exact for polynomials of degree <= 2q - 1. Nodes ascending (symmetric about 0), weights
/// positive. Nodes are found by Newton's method on the three-term recurrence of the Legendre
/// polynomial P_q, weights as 2 / ((1 - x^2) P_q'(x)^2); both to within a few ulps.
struct GaussLegendreRule {
  std::vector<double> nodes;
  std::vector<double> weights;
};
/// Throws std::invalid_argument for q == 0.
GaussLegendreRule gauss_legendre(std::size_t q);

/// The composite rule for Mbar and bbar.
///
/// The domain [0, L] is cut at the breakpoints: 0, L, the kernel's kink_points() (for a B-spline
/// kernel the finest knots, between which phi is polynomial), the road's kinks, and for a
/// stationary kernel that is not analytic (Wendland, Matern) the centres c_i, where k0(x - y) is
/// not smooth, and c_i +- support_radius when its support is compact (KernelProperties). Each piece
/// is cut into equal panels no longer than L / initial_panels, and each panel is integrated with
/// nodes_per_panel Gauss-Legendre nodes. Between breakpoints the integrands phi phi^T, phi f and
/// f^2 are smooth (polynomial for B-splines, analytic for the Gaussian and a sine road), so the
/// composite rule's error falls like h^(2q) with the panel length h once h resolves them: each
/// halving divides it by about 2^(2q) (1.7e7 for q = 12). The rule doubles the number of panels
/// (every panel split in two, so every panel is tested) until the change of Mbar and bbar between
/// two successive rules is at most `tolerance` relative to their scales (max_i Mbar_ii for Mbar,
/// max_i sqrt(Mbar_ii) rms(f) for bbar, the Cauchy-Schwarz bounds of their entries); the finer
/// rule is kept. The change is about the coarser rule's error, so the finer rule's is far below
/// `tolerance`, at round-off. A kernel's length scale and a road's variation need not be
/// known: a rule too coarse for them changes under halving and is refined.
///
/// For B-spline kernels of degree p <= 3, q = 12 >= p + 1 integrates phi phi^T exactly on every
/// knot interval; only phi f depends on the refinement.
struct AveragedLimitQuadrature {
  std::size_t nodes_per_panel = 12;  ///< q: exact for polynomials of degree <= 23 per panel
  std::size_t initial_panels = 32;   ///< panels are at most L / initial_panels long at first
  double tolerance = 1e-14;          ///< accepted relative change under panel doubling
  std::size_t min_refinements = 1;   ///< at least this many doublings (>= 1: one comparison)
  std::size_t max_nodes = std::size_t{1} << 21;  ///< no rule with more nodes is tried
  /// The part of the domain the path covers, [range_from, range_from + range_length] (a
  /// shuttle: AdaptiveSettings::shuttle_from), over which the averages are taken (1/l int_a^b);
  /// range_length = 0 for the whole domain.
  double range_from = 0;
  double range_length = 0;
};

/// The averaged limit at fixed centres and road.
struct AveragedLimit {
  Eigen::VectorXd coefficients;      ///< alpha with Mbar alpha = bbar: P_L2 f = sum_i alpha_i phi_i
  Eigen::MatrixXd averaged_gram;     ///< Mbar = (1/L) int phi phi^T (the L2 Gram matrix / L)
  Eigen::VectorXd averaged_load;     ///< bbar = (1/L) int phi f
  std::string solve_method;          ///< GramSolver::method() for Mbar ("cholesky", ...)
  GramSpectrum spectrum;             ///< of Mbar: condition number, singular to working precision
  /// The eigenvalues the solve for `coefficients` divides by: Mbar's, or those a pseudo-inverse
  /// keeps (lambda_min its smallest kept one). The coefficients' round-off is
  /// solve_round_off(solved_spectrum, Mbar's size) (rkhs/approx/approximation.hpp).
  GramSpectrum solved_spectrum;
  std::size_t quadrature_nodes = 0;  ///< nodes of the accepted rule
  std::size_t panels = 0;            ///< panels of the accepted rule
  std::size_t refinements = 0;       ///< panel doublings from the initial rule to the accepted one
  /// The relative change of Mbar and bbar at the last doubling (the convergence measure).
  double quadrature_change = 0;
  /// Whether quadrature_change <= tolerance. False when max_nodes stopped the refinement (a
  /// road with an undeclared kink, or a length scale far below L / max_nodes); the last rule is
  /// returned and its change says how far from converged it is.
  bool quadrature_converged = false;
  /// The eigenvalues of Mbar, increasing (averaged_limit_in_features only; empty otherwise).
  Eigen::VectorXd averaged_gram_eigenvalues;
};

/// The averaged (v -> 0) limit of the adaptive estimator on `kernel`'s domain: the coefficients
/// of the L2(Omega)-orthogonal projection of `road` onto span{k(c_i, .)} (see the file comment).
/// `road(s)` is evaluated for s in [0, L]; `road_kinks` are the points of [0, L) where the road
/// is not smooth (TargetFunction::kink_points(); any order, duplicates allowed). The kernel's
/// kinks are added here. Mbar is solved with GramSolver under `solver` (SingularGramError when
/// it is singular and the policy is fail). Evaluates phi through one kernel.basis(centres) of
/// its own. Throws std::invalid_argument for no centres or an invalid quadrature.
AveragedLimit averaged_limit(const AnyKernel& kernel, std::span<const double> centres,
                             const std::function<double(double)>& road,
                             std::span<const double> road_kinks, const SolverOptions& solver,
                             const AveragedLimitQuadrature& quadrature = {});

/// The averaged limit of the estimator in feature coordinates (the rkhs_embedding law,
/// docs/model.md section 14): fhat = sum_f beta_f psi_f over the kernel's finite feature map
/// (AnyKernel::feature_basis), so Mbar = E = (1/L) int psi psi^T ds (F x F) and bbar =
/// (1/L) int psi f ds, and P_L2 f is the L2(Omega)-orthogonal projection of the road onto H
/// itself. The features are redundant, E is singular by design: beta = E^+ bbar over the
/// eigenvalues above F eps lambda_max (the minimum-norm solution, in the range of E, whatever
/// the study's solver policy), and `solve_method` says so. The same composite rule as
/// averaged_limit (the breakpoints of the kernel and the road; no centres), accumulated over
/// the few features nonzero at each node; the eigen-decomposition of E costs O(F^3) and its
/// eigenvalues are kept (averaged_gram_eigenvalues). Throws std::invalid_argument, naming the
/// kernel, when it has no finite feature map.
AveragedLimit averaged_limit_in_features(const AnyKernel& kernel,
                                         const std::function<double(double)>& road,
                                         std::span<const double> road_kinks,
                                         const AveragedLimitQuadrature& quadrature = {});

}  // namespace rkhs
