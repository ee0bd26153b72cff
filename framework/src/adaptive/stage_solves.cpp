#include "rkhs/adaptive/stage_solves.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace rkhs {

LinearSolver linear_solver_from_name(std::string_view name) {
  if (name == "structured") return LinearSolver::structured;
  if (name == "dense") return LinearSolver::dense;
  throw std::invalid_argument(
      fmt::format("unknown linear solver '{}' (allowed: structured, dense)", name));
}

StageSolves::StageSolves(const AdaptiveSystem& system, LinearSolver kind)
    : system_(system), kind_(system.state_dependent() ? LinearSolver::dense : kind) {
  if (kind_ == LinearSolver::dense) jacobian_.resize(system.dimension(), system.dimension());
}

void StageSolves::linearize(double t, const double* z) {
  if (kind_ == LinearSolver::structured)
    system_.linearize(t, linearization_);
  else if (system_.state_dependent()) {
    if (!z) throw std::logic_error("the stage solves of a state-dependent system need the state");
    system_.jacobian_matrix(z, t, jacobian_.data());
  } else
    system_.jacobian_matrix(t, jacobian_.data());
}

namespace {

template <class Matrix, class Scalar>
void factor_dense(const Eigen::Ref<const Eigen::MatrixXd>& jacobian, Scalar shift, Matrix& matrix,
                  Eigen::PartialPivLU<Matrix>& lu) {
  matrix = -jacobian.template cast<Scalar>();
  matrix.diagonal().array() += shift;
  lu.compute(matrix);
  if (!(lu.matrixLU().diagonal().cwiseAbs().minCoeff() > 0))
    throw SingularStageMatrix("c I - J is singular in a stage solve");
}

}  // namespace

void StageSolves::factor(double t, const double* z, double real_shift) {
  linearize(t, z);
  if (kind_ == LinearSolver::structured)
    real_.factor(linearization_, real_shift);
  else
    factor_dense(Eigen::MatrixXd(jacobian_), real_shift, real_matrix_, real_lu_);
}

void StageSolves::factor(double t, const double* z, double real_shift,
                         std::complex<double> complex_shift) {
  linearize(t, z);
  if (kind_ == LinearSolver::structured) {
    real_.factor(linearization_, real_shift);
    complex_.factor(linearization_, complex_shift);
  } else {
    const Eigen::MatrixXd jacobian = jacobian_;
    factor_dense(jacobian, real_shift, real_matrix_, real_lu_);
    factor_dense(jacobian, complex_shift, complex_matrix_, complex_lu_);
  }
}

void StageSolves::solve_real(Eigen::Ref<Eigen::MatrixXd> rhs) const {
  if (kind_ == LinearSolver::structured)
    real_.solve_in_place(rhs);
  else
    rhs = real_lu_.solve(rhs);
}

void StageSolves::solve_complex(Eigen::Ref<Eigen::MatrixXcd> rhs) const {
  if (kind_ == LinearSolver::structured)
    complex_.solve_in_place(rhs);
  else
    rhs = complex_lu_.solve(rhs);
}

}  // namespace rkhs
