#pragma once
// Solves with a kernel Gram matrix G, saying what it did.
//
// The extreme eigenvalues of G decide the method:
//   - G is singular to working precision when lambda_min <= n eps lambda_max (docs/model.md
//     section 5);
//   - otherwise a Cholesky factorisation G = L L^T is used;
//   - a singular G is handled by the policy: a pseudo-inverse that drops the eigenvalues below
//     the cutoff n eps lambda_max, a Tikhonov-regularised Cholesky factorisation of
//     G + mu lambda_max I, or failure (SingularGramError).
// `method()` records the choice and its amount, for the trial's record.
//
// How the extreme eigenvalues are found is the caller's choice (GramSpectrumMode): exactly, by a
// symmetric eigenvalue solve (O(n^3), several times a Cholesky factorisation), when the trial
// reports them; or, when it does not, estimated by Lanczos iterations on G and on G^-1 through
// the Cholesky factor (O(n^2) each), only to decide singularity. The estimate of lambda_min
// is never below the true one; when it is within a factor 100 of the threshold, or the
// factorisation fails, the exact solve decides, so both modes take the same decision.
//
// Between its O(n^3) steps, and inside them (between the O(n^2) steps of the symmetric
// eigenvalue solves, symmetric_eigen.hpp, and between the panels and tiles of the Cholesky
// factorisation, dense_kernels.hpp), it calls check_cancelled() (core/cancellation.hpp): inside
// a trial a passed deadline or a stop request ends it there (TrialTimeLimitExceeded,
// TrialCancelled), within tens of milliseconds at n = 6000.

#include <Eigen/Dense>
#include <optional>
#include <stdexcept>
#include <string>

namespace rkhs {

enum class SingularPolicy { pseudo_inverse, regularised, fail };

/// The linear algebra of an approximation trial: a study's `[linear_algebra] solver`
/// (docs/study-files.md).
enum class GramAlgebra {
  dense,      ///< the dense Gram matrix and GramSolver: every metric
  sparse,     ///< CHOLMOD's sparse Cholesky factorisation, for a compactly supported kernel
              ///< (rkhs/approx/sparse_gram.hpp says which metrics it computes)
  automatic,  ///< sparse where sparse_gram.hpp's choose_sparse says so, dense elsewhere
};

struct SolverOptions {
  SingularPolicy singular = SingularPolicy::pseudo_inverse;
  /// mu for SingularPolicy::regularised, relative to lambda_max; 0 picks n eps (the
  /// singularity threshold itself).
  double regularisation = 0.0;
  GramAlgebra algebra = GramAlgebra::dense;
};

class SingularGramError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GramSpectrum {
  double lambda_min = 0;        ///< smallest eigenvalue (may be <= 0 from round-off)
  double lambda_max = 0;        ///< largest eigenvalue
  double condition_number = 0;  ///< lambda_max / lambda_min, +inf when singular
  bool singular = false;        ///< lambda_min <= n eps lambda_max
  /// lambda_min and lambda_max are Lanczos estimates (GramSpectrumMode::estimate): lambda_max
  /// to about 1e-12 relative, lambda_min an upper bound good to a few digits; not for output.
  bool estimated = false;
};

/// How GramSolver finds the extreme eigenvalues of G (see the file comment).
enum class GramSpectrumMode {
  exact,     ///< symmetric eigenvalue solve: what gram_* metrics report
  estimate,  ///< Lanczos estimates, enough to decide singularity and scale round-off floors
};

class GramSolver {
 public:
  /// Factorises `gram` (symmetric, n x n, n >= 1). Throws SingularGramError when G is singular
  /// and the policy is `fail`, std::invalid_argument for an empty or non-finite matrix.
  GramSolver(const Eigen::MatrixXd& gram, const SolverOptions& options,
             GramSpectrumMode mode = GramSpectrumMode::exact);

  const GramSpectrum& spectrum() const noexcept { return spectrum_; }
  /// "cholesky", "pseudo-inverse (rank 63 of 100, cutoff 2.1e-14 lambda_max)" or
  /// "regularised (mu = 2.2e-14 lambda_max)".
  const std::string& method() const noexcept { return method_; }
  Eigen::Index size() const noexcept { return n_; }

  /// x with G x = b (in the least-squares / regularised sense when G is singular).
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;

  /// For each column k of `columns`: the quadratic form k^T G^-1 k (the pseudo-inverse or the
  /// regularised inverse when G is singular) and ||G^-1 k||^2 (which bounds how round-off in G
  /// propagates into it). Cost O(n^2) per column.
  void quadratic_forms(const Eigen::MatrixXd& columns, Eigen::VectorXd& quadratic,
                       Eigen::VectorXd& solution_norm_squared) const;
  /// The same for the columns of `columns` (n x B), overwritten as scratch, into
  /// quadratic[0..B) and, when `solution_norm_squared` is not null, into it: the block form the
  /// blocked power function uses (no allocation for a Cholesky factor; a pseudo-inverse
  /// allocates its rank x B projections).
  void quadratic_forms_in_place(Eigen::Ref<Eigen::MatrixXd> columns, double* quadratic,
                                double* solution_norm_squared) const;

  /// The Cholesky factor L of G = L L^T in the lower triangle (the strict upper triangle is
  /// unspecified): null unless the method is "cholesky".
  const Eigen::MatrixXd* cholesky_lower() const noexcept {
    return factored_ && method_ == "cholesky" ? &factor_ : nullptr;
  }
  /// x := L^-1 x and x := L^-T x for the factor of the method (G's, or G + mu lambda_max I's);
  /// only when the method is a Cholesky factorisation (cholesky or regularised).
  void solve_lower_in_place(Eigen::Ref<Eigen::MatrixXd> x) const;
  void solve_lower_transposed_in_place(Eigen::Ref<Eigen::MatrixXd> x) const;
  /// The pseudo-inverse's kept eigenpairs, G^+ = V diag(1 / lambda) V^T (V is n x rank):
  /// null unless the method is the pseudo-inverse.
  const Eigen::MatrixXd* kept_vectors() const noexcept {
    return factored_ ? nullptr : &kept_vectors_;
  }
  const Eigen::VectorXd* kept_values() const noexcept {
    return factored_ ? nullptr : &kept_values_;
  }

 private:
  // The exact decision (the eigenvalues of G), keeping a Cholesky factor already computed.
  void decide_from_eigenvalues(const Eigen::MatrixXd& gram, const SolverOptions& options);
  void factorise_shifted(const Eigen::MatrixXd& gram, const SolverOptions& options);
  // factor_ := chol(matrix) with the dense kernels (rkhs/approx: dense_kernels.hpp); factored_
  // says whether it succeeded.
  void factorise(const Eigen::MatrixXd& matrix);

  Eigen::Index n_ = 0;
  GramSpectrum spectrum_;
  std::string method_;
  Eigen::MatrixXd factor_;  // L in the lower triangle, when factored_
  bool factored_ = false;
  // Pseudo-inverse: G^+ = V_k diag(1 / lambda_k) V_k^T over the kept eigenpairs.
  Eigen::MatrixXd kept_vectors_;
  Eigen::VectorXd kept_values_;
};

}  // namespace rkhs
