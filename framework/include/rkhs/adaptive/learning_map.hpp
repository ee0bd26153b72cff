#pragma once
// The learning law's map M in psi(s) = M phi(s), in the cheapest exact form it has.
//
//   gradient law: M = Gamma^-1 I             -> a scalar:      O(n) per application
//   rkhs law:     M = Gamma^-1 G^+ of rank r -> V diag(w) V^T: O(n r) per application
//                 (a pseudo-inverse that keeps r < n / 2 eigenpairs of G)
//   otherwise:    M = Gamma^-1 G^-1          -> a dense matrix: O(n^2) per application
//
// The dense form is inherent to the rkhs law with a kernel whose Gram matrix is dense and of
// full numerical rank (Wendland with a wide support, Matern): G^-1 phi(s) are the values at s of
// the n cardinal functions of the centres, and the right-hand side needs all of them.
// Kernels with a finite feature map (multiscale B-splines) apply M through their basis instead
// (KernelBasis::set_map).

#include <Eigen/Dense>

namespace rkhs {

class GramSolver;

class LearningMap {
 public:
  enum class Form { scalar, low_rank, dense };

  /// M = c I (n x n).
  static LearningMap scalar(Eigen::Index n, double c);
  /// M = V diag(w) V^T (V is n x r, w has r entries).
  static LearningMap low_rank(Eigen::MatrixXd V, Eigen::VectorXd w);
  /// M as given (square). A multiple of the identity is recognised and kept as a scalar.
  static LearningMap dense(Eigen::MatrixXd M);
  /// G^-1 / gain in the solver's own terms: low rank when it is a pseudo-inverse of rank below
  /// n / 2 (where V diag(w) V^T costs less than the dense product), dense otherwise.
  static LearningMap gram_inverse(const GramSolver& solver, double gain);

  Form form() const noexcept { return form_; }
  Eigen::Index size() const noexcept { return n_; }
  /// r for the low-rank form, n otherwise.
  Eigen::Index rank() const noexcept;

  /// psi = M phi (n doubles each, distinct). Allocates nothing.
  void apply(const double* phi, double* psi) const;
  /// M as an n x n matrix (for a basis that applies it to its features, and for tests).
  Eigen::MatrixXd matrix() const;

 private:
  Form form_ = Form::scalar;
  Eigen::Index n_ = 0;
  double scale_ = 0.0;             // scalar: c
  Eigen::MatrixXd matrix_;         // dense: M; low_rank: V
  Eigen::VectorXd weights_;        // low_rank: w
  mutable Eigen::VectorXd scratch_;  // low_rank: V^T phi (r doubles)
};

}  // namespace rkhs
