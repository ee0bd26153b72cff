#pragma once
// The sparse path of an approximation trial, for a kernel of compact support
// (KernelProperties::support_radius > 0): the Gram and cross matrices assembled sparse from a
// uniform cell grid, the Gram matrix factorised once by CHOLMOD's supernodal Cholesky
// factorisation (SuiteSparse, through Eigen's CholmodSupport) with its fill-reducing ordering.
//
// What it computes, per metric (docs/study-files.md, "[linear_algebra]"):
//   fill_distance, separation_distance     as the dense path
//   power_function_sup, _floor             P(s)^2 = k(s, s) - |L^-1 P k_X(s)|^2 and the floor's
//                                          |G^-1 k_X(s)|^2 = |L^-T L^-1 P k_X(s)|^2, by blocks of
//                                          evaluation points; with 2048 centres or more and
//                                          neither floor reported, the sup from local upper
//                                          bounds and a few points solved (bounded_power_sup)
//   l2_error, sup_error, error_floor       alpha = G^-1 f(X) and the sparse cross matrix, by
//                                          chunks of evaluation points
//   interpolant_native_norm                sqrt(alpha^T G alpha)
//   projection_norm_H_to_C                 the power function
// The round-off floors use lambda_max of G from Lanczos on the sparse matrix and lambda_min from
// Lanczos on G^-1 through the factor, the same estimates as GramSolver's
// GramSpectrumMode::estimate; when the study reports gram_condition_number, gram_min_eigenvalue
// or gram_max_eigenvalue, the same iterations resolved until an eigenvalue lies within 1e-11
// relative of each (lanczos_largest_resolved; the dense path's exact solve when they do not get
// there). Not computed: projection_operator_norm (the dense interpolation operator). A study
// that forces the sparse path and asks for it has its trials fail with that reason
// (choose_sparse); `auto` takes the dense path for it.
//
// Deterministic: the assembly runs in a fixed order on the calling thread; the blocks of
// evaluation points are independent (run_parts); CHOLMOD's own OpenMP loops only copy into
// disjoint columns, and the BLAS it calls (Debian's libblas.so.3 alternative) is asked for one
// thread when it is OpenBLAS (openblas_set_num_threads(1)).

#include <Eigen/SparseCore>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "rkhs/approx/approximation.hpp"

namespace rkhs {

// What the dense path (approximation.cpp) and the sparse path (sparse_approximation.cpp) share,
// so that the two give the same metrics, floors and flags from what their passes found.

/// What a pass over the evaluation points gives, one entry per point.
struct GridPass {
  Eigen::VectorXd power_squared;          ///< max(0, k(s,s) - k_X^T G^-1 k_X)
  Eigen::VectorXd solution_norm_squared;  ///< |G^-1 k_X(s_m)|^2 (work_cardinal)
  Eigen::VectorXd residual;               ///< f(s_m) - Pi_n f(s_m) (work_residual)
};

/// Where a trial reports neither power_function_floor nor error_floor and has at least this many
/// centres, both paths take the floors from a sample of the evaluation points (docs/metrics.md,
/// "Floors"): the dense path every 17th point and the points that set a sup, the sparse path the
/// points bounded_power_sup evaluates (below). With fewer centres the floors stay the maximum
/// over every point (n^2 M flops for the dense path's second solve, about 2.6 s at n = 2047,
/// M = 16384 on one AVX2 core): rate fits weigh values by their floors, and a sampled floor (up
/// to 1.75 times lower on scattered_centres) moves their statistics (a Delta AIC note of 20
/// became 16); every shipped study of the interpolation path is below it.
inline constexpr std::size_t sampled_floor_min_centres = 2048;

/// Whether a trial of n centres that computes `selection` (empty: every metric) takes its floors
/// from a sample of the evaluation points: n >= sampled_floor_min_centres and neither
/// power_function_floor nor error_floor selected. The rule of both paths: the dense path then
/// solves the second (cardinal) system at the sample only; the sparse path also takes
/// power_function_sup from bounded_power_sup, solving for about a hundred points, not for
/// every one.
bool floors_from_sample(std::size_t n, const MetricSelection& selection);

/// Sets, from `pass` over `points`, what `work` asks of the interpolant Pi_n f = sum_i alpha_i
/// k(c_i, .) of n centres: the power function's sup and floor, the native norm
/// (native_norm_squared = alpha^T G alpha) and the error floor, the L2 and sup errors, and
/// ||I - Pi_n||_{H -> C}, with their floors and the *_at_floor flags (approximation.cpp).
void record_interpolant_metrics(const AnyKernel& kernel, std::span<const double> points,
                                Eigen::Index n, const GramSpectrum& spectrum, unsigned work,
                                const Eigen::VectorXd& alpha, double native_norm_squared,
                                double target_norm_at_centres, const GridPass& pass,
                                ApproximationMeasurement& out);

/// Leaves NaN in every metric `selection` does not name (empty: keeps all).
void keep_selected(const MetricSelection& selection, ApproximationMeasurement& out);

/// Asks the BLAS behind CHOLMOD (Debian's libblas.so.3 alternative: reference BLAS, or OpenBLAS
/// when installed) for one thread, once per process (openblas_set_num_threads(1) when the symbol
/// is loaded): a trial's values must not depend on the threads a BLAS starts. Every caller of
/// CHOLMOD calls it first (the sparse path, multilevel interpolation).
void single_threaded_blas();

/// Runs `analyse` (a CHOLMOD analysis: analyzePattern), one at a time in the process: CHOLMOD's
/// METIS ordering draws from a process-wide random state that each call reseeds, so two analyses at
/// once (two trials on two threads) interleave their draws and order differently from run to run
/// (seen: 2.88e8 against 2.92e8 nonzeros in L for the same matrix of 35937 centres, and values that
/// moved in their last digits). Every analysis of the sparse path and of the multilevel
/// projection goes through here.
void analyse_one_at_a_time(const std::function<void()>& analyse);

/// The n x n Gram matrix G_ij = k(c_i, c_j) of a kernel with support_radius > 0, both
/// triangles stored (column-major, compressed), without its zeros but for the diagonal. Each
/// entry of the upper triangle is computed once (AnyKernel::cross_into on the centres of two
/// neighbouring cells) and mirrored, so G is exactly symmetric. std::invalid_argument for a kernel
/// of global support.
Eigen::SparseMatrix<double> sparse_gram(const AnyKernel& kernel, std::span<const double> centres);

/// The (centres) x (points) matrix whose column m is k_X(s_m) = (k(s_m, c_i))_i, without its
/// zeros, by cells like sparse_gram.
Eigen::SparseMatrix<double> sparse_cross_columns(const AnyKernel& kernel,
                                                 std::span<const double> points,
                                                 std::span<const double> centres);

/// The nonzeros of the Gram matrix of n centres spread over the domain, predicted before
/// anything is built: n + n (n - 1) min(1, omega_d rho^d / |Omega|) (omega_d rho^d the volume of
/// the kernel's support); n^2 for global support.
double predicted_gram_nonzeros(const KernelProperties& properties, const Domain& domain,
                               std::size_t n);

/// The sparse path's factorisation of the Gram matrix of n quasi-uniform centres, predicted
/// before anything is built (sparse_prediction.cpp): the nonzeros of G (predicted_gram_nonzeros)
/// and, from a geometric nested dissection of the domain (slabs as thick as the support radius
/// across the longest axis of each box, the ordering METIS finds on such a graph), the nonzeros
/// of L and the flops of the factorisation. About n log n nonzeros in L in 2-D and n^(4/3) in
/// 3-D for a fixed number of neighbours; within a factor 2 of CHOLMOD's own count on grids
/// (tests/approx/test_sparse_approximation.cpp). A kernel of global support: the dense factor.
struct SparseFactorPrediction {
  double gram_nonzeros = 0;
  double factor_nonzeros = 0;
  double factor_flops = 0;
};
SparseFactorPrediction predict_sparse_factor(const KernelProperties& properties,
                                             const Domain& domain, std::size_t n);

/// The nonzeros of L that CHOLMOD's analysis of `gram` (its fill-reducing ordering, as the
/// sparse path orders it) finds, without factorising.
double analysed_factor_nonzeros(const Eigen::SparseMatrix<double>& gram);

/// Computes, for the evaluation points `indices` (at most a few dozen), their exact P(s)^2 and
/// |G^-1 k_X(s)|^2 into `power_squared` and `solution_norm_squared`; called from several threads
/// at once on disjoint blocks.
using ExactPowerBlock = std::function<void(std::span<const std::size_t> indices,
                                           Eigen::Ref<Eigen::VectorXd> power_squared,
                                           Eigen::Ref<Eigen::VectorXd> solution_norm_squared)>;

/// The points bounded_power_sup computed exactly, in the order it computed them, with their
/// values; `refined` counts the points whose bounds it tightened (0: none).
struct BoundedPowerSup {
  std::vector<std::size_t> evaluated;
  Eigen::VectorXd power_squared;
  Eigen::VectorXd solution_norm_squared;
  std::size_t refined = 0;
};

/// The largest P(s)^2 over `points`, found with few exact evaluations
/// (sparse_power_bound.cpp): the power function of a subset Y of the centres bounds that of all
/// of them from above (P_X(s) <= P_Y(s): a larger space approximates k(s, .) at least as well),
/// so every point gets the bound P_Y(s)^2 of the 64 centres nearest the middle of its cell (a
/// dense 64 x 64 Cholesky factorisation per cell of about one centre, shared by the points in
/// it), plus an allowance for the bound's round-off (10^3 |Y| eps cond(L_Y) (k(s, s) +
/// |L_Y^-1 k_Y(s)|^2), cond(L_Y) estimated by the ratio of L_Y's extreme diagonal entries). The
/// points `always` and the 32 largest bounds are evaluated exactly first (`exact`), then the
/// largest bounds left in rounds of two blocks of 32, until no bound left reaches the largest
/// exact value; when more than 256 candidates are left once, their bounds are tightened with the
/// 256 centres nearest each point. The largest of `power_squared` is then the largest P^2 over
/// every point, as exactly as the exact evaluations compute it; its point is among `evaluated`.
/// Every step runs in a fixed order, so the points evaluated do not depend on the threads.
/// Without `search`, only the points `always` are evaluated (a sample for the floors).
BoundedPowerSup bounded_power_sup(const AnyKernel& kernel, std::span<const double> centres,
                                  std::span<const double> points,
                                  std::span<const std::size_t> always, const ExactPowerBlock& exact,
                                  bool search = true);

/// Whether measure_approximation takes the sparse path for `kernel` at n centres, computing
/// `work` (ApproximationWork bits): never for GramAlgebra::dense; always for `sparse`, which
/// throws std::invalid_argument naming the reason when the kernel has global support or `work`
/// needs a metric the sparse path does not compute; for `automatic` when the kernel has compact
/// support, `work` needs no such metric and predicted_gram_nonzeros is at most a quarter of n^2.
bool choose_sparse(const AnyKernel& kernel, std::size_t n, const SolverOptions& options,
                   unsigned work);

/// measure_approximation on the sparse path (the metrics `selection` names, empty: all).
/// Empty when the factorisation cannot decide: G is not positive definite to working precision
/// for CHOLMOD, or the Lanczos estimate of lambda_min is within a factor 100 of the singularity
/// threshold n eps lambda_max; the dense path then measures (GramSolver's exact decision and
/// its singular policy).
std::optional<ApproximationMeasurement> measure_sparse_approximation(
    const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
    std::size_t evaluation_points, const SolverOptions& solver, const MetricSelection& selection);

}  // namespace rkhs
