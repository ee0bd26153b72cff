#pragma once
// Solves with a kernel Gram matrix G, saying what it did.
//
// The spectrum of G is computed once (symmetric eigen-decomposition) and decides the method:
//   - G is singular to working precision when lambda_min <= n eps lambda_max (docs/model.md
//     section 5);
//   - otherwise a Cholesky factorisation G = L L^T is used;
//   - a singular G is handled by the policy: a pseudo-inverse that drops the eigenvalues below
//     the cutoff n eps lambda_max, a Tikhonov-regularised Cholesky factorisation of
//     G + mu lambda_max I, or failure (SingularGramError).
// `method()` records the choice and its amount, for the trial's record.

#include <Eigen/Dense>
#include <optional>
#include <stdexcept>
#include <string>

namespace rkhs {

enum class SingularPolicy { pseudo_inverse, regularised, fail };

struct SolverOptions {
  SingularPolicy singular = SingularPolicy::pseudo_inverse;
  /// mu for SingularPolicy::regularised, relative to lambda_max; 0 picks n eps (the
  /// singularity threshold itself).
  double regularisation = 0.0;
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
};

class GramSolver {
 public:
  /// Factorises `gram` (symmetric, n x n, n >= 1). Throws SingularGramError when G is singular
  /// and the policy is `fail`, std::invalid_argument for an empty or non-finite matrix.
  GramSolver(const Eigen::MatrixXd& gram, const SolverOptions& options);

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

  /// The pseudo-inverse's kept eigenpairs, G^+ = V diag(1 / lambda) V^T (V is n x rank):
  /// null unless the method is the pseudo-inverse.
  const Eigen::MatrixXd* kept_vectors() const noexcept {
    return cholesky_ ? nullptr : &kept_vectors_;
  }
  const Eigen::VectorXd* kept_values() const noexcept {
    return cholesky_ ? nullptr : &kept_values_;
  }

 private:
  Eigen::Index n_ = 0;
  GramSpectrum spectrum_;
  std::string method_;
  std::optional<Eigen::LLT<Eigen::MatrixXd>> cholesky_;
  // Pseudo-inverse: G^+ = V_k diag(1 / lambda_k) V_k^T over the kept eigenpairs.
  Eigen::MatrixXd kept_vectors_;
  Eigen::VectorXd kept_values_;
};

}  // namespace rkhs
