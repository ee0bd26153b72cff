#pragma once
// The Lyapunov equation A^T P + P A = -Q of the estimator (docs/model.md section 1).

#include <Eigen/Dense>

namespace rkhs {

struct LyapunovSolution {
  Eigen::MatrixXd P;          ///< symmetric positive definite solution
  /// Normwise backward error ||A^T P + P A + Q||_F / (2 ||A||_F ||P||_F + ||Q||_F): a few
  /// eps for a backward-stable solve, whatever the scaling of A.
  double relative_residual;
  double min_eigenvalue;      ///< smallest eigenvalue of P (> 0)
};

/// Solves A^T P + P A = -Q for P by the Bartels-Stewart method on the complex Schur form
/// A = U T U^*: T^* X + X T = -U^* Q U is solved column by column with triangular solves,
/// and P = Re(U X U^*), symmetrised. Cost O(d^3); no Kronecker system is formed.
///
/// Requires A (d x d) Hurwitz (every eigenvalue with negative real part) and Q (d x d)
/// symmetric positive definite. Throws std::invalid_argument naming the offending eigenvalue
/// when A is not Hurwitz or when Q is not symmetric positive definite, and std::runtime_error
/// when the computed P is not positive definite.
LyapunovSolution solve_lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q);

/// Throws std::invalid_argument when A has an eigenvalue with real part >= 0.
void require_hurwitz(const Eigen::MatrixXd& A);

}  // namespace rkhs
