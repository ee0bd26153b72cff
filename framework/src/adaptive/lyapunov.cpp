#include "rkhs/adaptive/lyapunov.hpp"

#include <fmt/format.h>

#include <complex>
#include <stdexcept>

namespace rkhs {

void require_hurwitz(const Eigen::MatrixXd& A) {
  if (A.rows() != A.cols() || A.rows() == 0) throw std::invalid_argument("A must be square");
  const Eigen::VectorXcd eigenvalues = A.eigenvalues();
  for (Eigen::Index i = 0; i < eigenvalues.size(); ++i)
    if (!(eigenvalues(i).real() < 0))
      throw std::invalid_argument(fmt::format(
          "A is not Hurwitz: eigenvalue {:.6g}{:+.6g}i has a non-negative real part, so the "
          "Lyapunov equation has no positive definite solution",
          eigenvalues(i).real(), eigenvalues(i).imag()));
}

LyapunovSolution solve_lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q) {
  require_hurwitz(A);
  const Eigen::Index d = A.rows();
  if (Q.rows() != d || Q.cols() != d)
    throw std::invalid_argument(fmt::format("Q must be {} x {} like A", d, d));
  if ((Q - Q.transpose()).norm() > 1e-12 * Q.norm())
    throw std::invalid_argument("Q must be symmetric");
  if (Eigen::LLT<Eigen::MatrixXd>(Q).info() != Eigen::Success)
    throw std::invalid_argument("Q must be positive definite");

  const Eigen::ComplexSchur<Eigen::MatrixXd> schur(A);
  const Eigen::MatrixXcd& U = schur.matrixU();
  const Eigen::MatrixXcd& T = schur.matrixT();
  const Eigen::MatrixXcd C = -(U.adjoint() * Q.cast<std::complex<double>>() * U);
  // Column j of T^* X + X T = C:  (T^* + T_jj I) X_j = C_j - sum_{k<j} T_kj X_k.
  Eigen::MatrixXcd X(d, d);
  const Eigen::MatrixXcd T_adjoint = T.adjoint();  // lower triangular
  for (Eigen::Index j = 0; j < d; ++j) {
    Eigen::VectorXcd rhs = C.col(j);
    for (Eigen::Index k = 0; k < j; ++k) rhs -= T(k, j) * X.col(k);
    Eigen::MatrixXcd shifted = T_adjoint;
    shifted.diagonal().array() += T(j, j);
    X.col(j) = shifted.triangularView<Eigen::Lower>().solve(rhs);
  }
  Eigen::MatrixXd P = (U * X * U.adjoint()).real();
  P = 0.5 * (P + P.transpose()).eval();

  LyapunovSolution out;
  out.relative_residual =
      (A.transpose() * P + P * A + Q).norm() / (2 * A.norm() * P.norm() + Q.norm());
  out.min_eigenvalue = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues()(0);
  if (!(out.min_eigenvalue > 0))
    throw std::runtime_error(
        fmt::format("Lyapunov solution is not positive definite (smallest eigenvalue {:.3e})",
                    out.min_eigenvalue));
  out.P = std::move(P);
  return out;
}

}  // namespace rkhs
