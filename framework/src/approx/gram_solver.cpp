#include "rkhs/approx/gram_solver.hpp"

#include <fmt/format.h>

#include <limits>

namespace rkhs {

GramSolver::GramSolver(const Eigen::MatrixXd& gram, const SolverOptions& options)
    : n_(gram.rows()) {
  if (n_ == 0 || gram.cols() != n_) throw std::invalid_argument("Gram matrix must be square, n >= 1");
  if (!gram.allFinite()) throw std::invalid_argument("Gram matrix has non-finite entries");
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
  if (eigen.info() != Eigen::Success)
    throw std::runtime_error("symmetric eigen-decomposition of the Gram matrix did not converge");
  const Eigen::VectorXd& values = eigen.eigenvalues();  // increasing
  constexpr double eps = std::numeric_limits<double>::epsilon();
  spectrum_.lambda_min = values(0);
  spectrum_.lambda_max = values(n_ - 1);
  const double cutoff = static_cast<double>(n_) * eps * spectrum_.lambda_max;
  spectrum_.singular = !(spectrum_.lambda_min > cutoff);
  spectrum_.condition_number = spectrum_.singular
                                   ? std::numeric_limits<double>::infinity()
                                   : spectrum_.lambda_max / spectrum_.lambda_min;

  if (!spectrum_.singular) {
    cholesky_.emplace(gram);
    if (cholesky_->info() == Eigen::Success) {
      method_ = "cholesky";
      return;
    }
    cholesky_.reset();  // not numerically positive definite after all: treat as singular
    spectrum_.singular = true;
    spectrum_.condition_number = std::numeric_limits<double>::infinity();
  }

  switch (options.singular) {
    case SingularPolicy::fail:
      throw SingularGramError(fmt::format(
          "Gram matrix singular to working precision (lambda_min = {:.3e}, lambda_max = {:.3e}, "
          "n eps lambda_max = {:.3e}); choose solver.singular = \"pseudo_inverse\" or "
          "\"regularised\" to proceed",
          spectrum_.lambda_min, spectrum_.lambda_max, cutoff));
    case SingularPolicy::regularised: {
      const double mu =
          options.regularisation > 0 ? options.regularisation : static_cast<double>(n_) * eps;
      Eigen::MatrixXd shifted = gram;
      shifted.diagonal().array() += mu * spectrum_.lambda_max;
      cholesky_.emplace(shifted);
      if (cholesky_->info() != Eigen::Success)
        throw SingularGramError(fmt::format(
            "regularised Gram matrix (mu = {:.3e} lambda_max) is still not positive definite", mu));
      method_ = fmt::format("regularised (mu = {:.3e} lambda_max)", mu);
      return;
    }
    case SingularPolicy::pseudo_inverse: {
      Eigen::Index first = 0;
      while (first < n_ && !(values(first) > cutoff)) ++first;
      const Eigen::Index rank = n_ - first;
      kept_vectors_ = eigen.eigenvectors().rightCols(rank);
      kept_values_ = values.tail(rank);
      method_ = fmt::format("pseudo-inverse (rank {} of {}, cutoff {:.3e} lambda_max)", rank, n_,
                            static_cast<double>(n_) * eps);
      return;
    }
  }
}

Eigen::MatrixXd GramSolver::solve(const Eigen::MatrixXd& b) const {
  if (cholesky_) return cholesky_->solve(b);
  Eigen::MatrixXd projected = kept_vectors_.transpose() * b;
  projected.array().colwise() /= kept_values_.array();
  return kept_vectors_ * projected;
}

Eigen::VectorXd GramSolver::solve(const Eigen::VectorXd& b) const {
  return solve(Eigen::MatrixXd(b)).col(0);
}

void GramSolver::quadratic_forms(const Eigen::MatrixXd& columns, Eigen::VectorXd& quadratic,
                                 Eigen::VectorXd& solution_norm_squared) const {
  if (cholesky_) {
    // k^T G^-1 k = |L^-1 k|^2 and G^-1 k = L^-T (L^-1 k).
    Eigen::MatrixXd half = cholesky_->matrixL().solve(columns);
    quadratic = half.colwise().squaredNorm().transpose();
    cholesky_->matrixU().solveInPlace(half);
    solution_norm_squared = half.colwise().squaredNorm().transpose();
    return;
  }
  Eigen::MatrixXd projected = kept_vectors_.transpose() * columns;  // V^T k
  Eigen::MatrixXd scaled = projected.array().colwise() / kept_values_.array().sqrt();
  quadratic = scaled.colwise().squaredNorm().transpose();
  projected.array().colwise() /= kept_values_.array();
  solution_norm_squared = projected.colwise().squaredNorm().transpose();
}

}  // namespace rkhs
