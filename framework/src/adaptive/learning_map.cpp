#include "rkhs/adaptive/learning_map.hpp"

#include <stdexcept>

#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs {

LearningMap LearningMap::scalar(Eigen::Index n, double c) {
  LearningMap map;
  map.form_ = Form::scalar;
  map.n_ = n;
  map.scale_ = c;
  return map;
}

LearningMap LearningMap::low_rank(Eigen::MatrixXd V, Eigen::VectorXd w) {
  if (V.cols() != w.size())
    throw std::invalid_argument("LearningMap::low_rank: V needs one column per weight");
  LearningMap map;
  map.form_ = Form::low_rank;
  map.n_ = V.rows();
  map.matrix_ = std::move(V);
  map.weights_ = std::move(w);
  map.scratch_.resize(map.weights_.size());
  return map;
}

LearningMap LearningMap::dense(Eigen::MatrixXd M) {
  if (M.rows() != M.cols()) throw std::invalid_argument("LearningMap::dense: M must be square");
  if (const auto c = identity_multiple(M)) return scalar(M.rows(), *c);
  LearningMap map;
  map.form_ = Form::dense;
  map.n_ = M.rows();
  map.matrix_ = std::move(M);
  return map;
}

LearningMap LearningMap::gram_inverse(const GramSolver& solver, double gain) {
  const Eigen::Index n = solver.size();
  if (const auto* vectors = solver.kept_vectors(); vectors && 2 * vectors->cols() < n)
    return low_rank(*vectors, (gain * *solver.kept_values()).cwiseInverse());
  return dense(solver.solve(Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n))) / gain);
}

Eigen::Index LearningMap::rank() const noexcept {
  return form_ == Form::low_rank ? weights_.size() : n_;
}

void LearningMap::apply(const double* phi, double* psi) const {
  const Eigen::Map<const Eigen::VectorXd> in(phi, n_);
  Eigen::Map<Eigen::VectorXd> out(psi, n_);
  switch (form_) {
    case Form::scalar:
      out = scale_ * in;
      return;
    case Form::low_rank:
      scratch_.noalias() = matrix_.transpose() * in;
      scratch_.array() *= weights_.array();
      out.noalias() = matrix_ * scratch_;
      return;
    case Form::dense:
      out.noalias() = matrix_ * in;
      return;
  }
}

Eigen::MatrixXd LearningMap::matrix() const {
  switch (form_) {
    case Form::scalar:
      return scale_ * Eigen::MatrixXd::Identity(n_, n_);
    case Form::low_rank:
      return matrix_ * weights_.asDiagonal() * matrix_.transpose();
    case Form::dense:
      break;
  }
  return matrix_;
}

}  // namespace rkhs
