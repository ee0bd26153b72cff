#include "rkhs/approx/gram_solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rkhs/approx/dense_kernels.hpp"
#include "rkhs/approx/lanczos.hpp"
#include "rkhs/approx/symmetric_eigen.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"

namespace rkhs {

namespace {
constexpr double eps = std::numeric_limits<double>::epsilon();

// Strips of columns of an n x n matrix for run_parts: [strip_begin(p, n), strip_begin(p + 1, n)),
// a fixed partition (so nothing computed in strips depends on the thread count).
constexpr Eigen::Index strip_columns = 256;
std::size_t strip_count(Eigen::Index n) {
  return static_cast<std::size_t>((n + strip_columns - 1) / strip_columns);
}
Eigen::Index strip_begin(std::size_t p, Eigen::Index n) {
  return std::min(n, static_cast<Eigen::Index>(p) * strip_columns);
}

}  // namespace

GramSolver::GramSolver(const Eigen::MatrixXd& gram, const SolverOptions& options,
                       GramSpectrumMode mode)
    : n_(gram.rows()) {
  if (n_ == 0 || gram.cols() != n_)
    throw std::invalid_argument("Gram matrix must be square, n >= 1");
  if (!gram.allFinite()) throw std::invalid_argument("Gram matrix has non-finite entries");
  if (mode == GramSpectrumMode::estimate) {
    factorise(gram);
    if (factored_) {
      // The two iterations are independent: they run as two parts (the solves with the
      // factor are memory-bound vector solves, G v goes by strips of columns of the symmetric
      // G, (G v)_strip = G(:, strip)^T v).
      double lambda_max = 0, inverse_max = 0;
      run_parts(2, [&](std::size_t part) {
        if (part == 0) {
          lambda_max = lanczos_largest(
              [&](const auto& in, Eigen::VectorXd& out) {
                run_parts(strip_count(n_), [&](std::size_t p) {
                  const Eigen::Index first = strip_begin(p, n_),
                                     count = strip_begin(p + 1, n_) - first;
                  out.segment(first, count).noalias() =
                      gram.middleCols(first, count).transpose() * in;
                });
              },
              n_, 1e-13, 80);
        } else {
          inverse_max = lanczos_largest(
              [&](const auto& in, Eigen::VectorXd& out) {
                out = in;
                factor_.triangularView<Eigen::Lower>().solveInPlace(out);
                factor_.transpose().triangularView<Eigen::Upper>().solveInPlace(out);
              },
              n_, 1e-4, 40);  // only decides singularity, with a margin of 100
        }
      });
      const double lambda_min = 1.0 / inverse_max;  // >= the true lambda_min
      const double cutoff = static_cast<double>(n_) * eps * lambda_max;
      if (lambda_min > 100.0 * cutoff) {
        spectrum_ = {lambda_min, lambda_max, lambda_max / lambda_min, false, true};
        method_ = "cholesky";
        return;
      }
    }
  }
  decide_from_eigenvalues(gram, options);
}

void GramSolver::decide_from_eigenvalues(const Eigen::MatrixXd& gram,
                                         const SolverOptions& options) {
  // The eigenvalues alone (the same values as with the eigenvectors: the tridiagonal QR
  // iteration does not depend on whether they are accumulated); the vectors only when the
  // pseudo-inverse needs them. Each solve is Eigen's SelfAdjointEigenSolver bit for bit,
  // with the trial's deadline and stop request checked between its O(n^2) steps
  // (symmetric_eigen.hpp).
  check_cancelled();
  count_factorisation();  // a symmetric eigenvalue solve
  const SymmetricEigen eigen = symmetric_eigen(gram, false);
  if (eigen.info != Eigen::Success)
    throw std::runtime_error("symmetric eigen-decomposition of the Gram matrix did not converge");
  const Eigen::VectorXd& values = eigen.values;  // increasing
  spectrum_ = {};
  spectrum_.lambda_min = values(0);
  spectrum_.lambda_max = values(n_ - 1);
  const double cutoff = static_cast<double>(n_) * eps * spectrum_.lambda_max;
  spectrum_.singular = !(spectrum_.lambda_min > cutoff);
  spectrum_.condition_number = spectrum_.singular ? std::numeric_limits<double>::infinity()
                                                  : spectrum_.lambda_max / spectrum_.lambda_min;

  check_cancelled();
  if (!spectrum_.singular) {
    if (!factored_) factorise(gram);
    if (factored_) {
      method_ = "cholesky";
      return;
    }
    // Not numerically positive definite after all: treat as singular.
    spectrum_.singular = true;
    spectrum_.condition_number = std::numeric_limits<double>::infinity();
  }
  factored_ = false;
  factor_.resize(0, 0);

  switch (options.singular) {
    case SingularPolicy::fail:
      throw SingularGramError(fmt::format(
          "Gram matrix singular to working precision (lambda_min = {:.3e}, lambda_max = {:.3e}, "
          "n eps lambda_max = {:.3e}); choose solver.singular = \"pseudo_inverse\" or "
          "\"regularised\" to proceed",
          spectrum_.lambda_min, spectrum_.lambda_max, cutoff));
    case SingularPolicy::regularised:
      factorise_shifted(gram, options);
      return;
    case SingularPolicy::pseudo_inverse: {
      count_factorisation();
      const SymmetricEigen pairs = symmetric_eigen(gram, true);
      if (pairs.info != Eigen::Success)
        throw std::runtime_error(
            "symmetric eigen-decomposition of the Gram matrix did not converge");
      const Eigen::VectorXd& pair_values = pairs.values;
      Eigen::Index first = 0;
      while (first < n_ && !(pair_values(first) > cutoff)) ++first;
      const Eigen::Index rank = n_ - first;
      kept_vectors_ = pairs.vectors.rightCols(rank);
      kept_values_ = pair_values.tail(rank);
      method_ = fmt::format("pseudo-inverse (rank {} of {}, cutoff {:.3e} lambda_max)", rank, n_,
                            static_cast<double>(n_) * eps);
      return;
    }
  }
}

void GramSolver::factorise_shifted(const Eigen::MatrixXd& gram, const SolverOptions& options) {
  const double mu =
      options.regularisation > 0 ? options.regularisation : static_cast<double>(n_) * eps;
  Eigen::MatrixXd shifted = gram;
  shifted.diagonal().array() += mu * spectrum_.lambda_max;
  factorise(shifted);
  if (!factored_)
    throw SingularGramError(fmt::format(
        "regularised Gram matrix (mu = {:.3e} lambda_max) is still not positive definite", mu));
  method_ = fmt::format("regularised (mu = {:.3e} lambda_max)", mu);
}

void GramSolver::factorise(const Eigen::MatrixXd& matrix) {
  count_factorisation();
  // Copied in strips: the first touch of a large new block's pages (page faults) in parallel.
  factor_.resize(n_, n_);
  run_parts(strip_count(n_), [&](std::size_t p) {
    const Eigen::Index first = strip_begin(p, n_), count = strip_begin(p + 1, n_) - first;
    factor_.middleCols(first, count) = matrix.middleCols(first, count);
  });
  factored_ = dense::parallel_cholesky(dense::kernels(), factor_.data(), n_, factor_.outerStride());
}

void GramSolver::solve_lower_in_place(Eigen::Ref<Eigen::MatrixXd> x) const {
  if (!factored_) throw std::logic_error("GramSolver: no Cholesky factor to solve with");
  dense::kernels().solve_lower(factor_.data(), n_, factor_.outerStride(), x.data(), x.cols(),
                               x.outerStride());
}

void GramSolver::solve_lower_transposed_in_place(Eigen::Ref<Eigen::MatrixXd> x) const {
  if (!factored_) throw std::logic_error("GramSolver: no Cholesky factor to solve with");
  dense::kernels().solve_lower_transposed(factor_.data(), n_, factor_.outerStride(), x.data(),
                                          x.cols(), x.outerStride());
}

Eigen::MatrixXd GramSolver::solve(const Eigen::MatrixXd& b) const {
  if (factored_) {
    Eigen::MatrixXd x = b;
    solve_lower_in_place(x);
    solve_lower_transposed_in_place(x);
    return x;
  }
  Eigen::MatrixXd projected = kept_vectors_.transpose() * b;
  projected.array().colwise() /= kept_values_.array();
  return kept_vectors_ * projected;
}

Eigen::VectorXd GramSolver::solve(const Eigen::VectorXd& b) const {
  return solve(Eigen::MatrixXd(b)).col(0);
}

void GramSolver::quadratic_forms(const Eigen::MatrixXd& columns, Eigen::VectorXd& quadratic,
                                 Eigen::VectorXd& solution_norm_squared) const {
  Eigen::MatrixXd scratch = columns;
  quadratic.resize(columns.cols());
  solution_norm_squared.resize(columns.cols());
  quadratic_forms_in_place(scratch, quadratic.data(), solution_norm_squared.data());
}

void GramSolver::quadratic_forms_in_place(Eigen::Ref<Eigen::MatrixXd> columns, double* quadratic,
                                          double* solution_norm_squared) const {
  const Eigen::Index count = columns.cols();
  Eigen::Map<Eigen::VectorXd> q(quadratic, count);
  if (factored_) {
    // k^T G^-1 k = |L^-1 k|^2 and G^-1 k = L^-T (L^-1 k).
    solve_lower_in_place(columns);
    q = columns.colwise().squaredNorm().transpose();
    if (solution_norm_squared) {
      solve_lower_transposed_in_place(columns);
      Eigen::Map<Eigen::VectorXd>(solution_norm_squared, count) =
          columns.colwise().squaredNorm().transpose();
    }
    return;
  }
  Eigen::MatrixXd projected = kept_vectors_.transpose() * columns;  // V^T k
  Eigen::MatrixXd scaled = projected.array().colwise() / kept_values_.array().sqrt();
  q = scaled.colwise().squaredNorm().transpose();
  if (solution_norm_squared) {
    projected.array().colwise() /= kept_values_.array();
    Eigen::Map<Eigen::VectorXd>(solution_norm_squared, count) =
        projected.colwise().squaredNorm().transpose();
  }
}

}  // namespace rkhs
