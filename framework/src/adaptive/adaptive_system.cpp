#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/stepping.hpp"

namespace rkhs {

AdaptiveSystem::AdaptiveSystem(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                               const Eigen::MatrixXd& P, KernelBasis& basis,
                               const LearningMap& learning_map,
                               const std::function<double(double)>& road,
                               const std::function<double(double)>& road_slope,
                               const Domain& domain, double speed, LearningSignal signal)
    : A_(A),
      B_(B),
      b_(P * B),
      basis_(&basis),
      road_(&road),
      road_slope_(&road_slope),
      domain_(domain),
      speed_(speed),
      d_(A.rows()),
      n_(static_cast<Eigen::Index>(basis.size())),
      signal_(signal),
      phi_(basis.size()),
      psi_(basis.size()),
      dphi_(basis.size()),
      dpsi_(basis.size()) {
  if (learning_map.size() != n_)
    throw std::invalid_argument(fmt::format("the learning map is {} x {}, the basis has {} sections",
                                            learning_map.size(), learning_map.size(), n_));
  if (signal_ == LearningSignal::by_basis)
    basis_->set_map(learning_map.matrix());
  else
    map_ = learning_map;
}

AdaptiveSystem::AdaptiveSystem(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                               const Eigen::MatrixXd& P, KernelBasis& basis,
                               const Eigen::MatrixXd& learning_map,
                               const std::function<double(double)>& road,
                               const std::function<double(double)>& road_slope,
                               const Domain& domain, double speed, LearningSignal signal)
    : AdaptiveSystem(A, B, P, basis, LearningMap::dense(learning_map), road, road_slope, domain,
                     speed, signal) {}

AdaptiveSystem::AdaptiveSystem(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                               const Eigen::MatrixXd& P, const PointSections& sections,
                               const LearningMap& learning_map, const Plant& plant,
                               const std::function<double(const double*)>& f,
                               const std::function<void(const double*, double*)>& f_gradient,
                               const Domain& domain)
    : A_(A),
      B_(B),
      b_(P * B),
      domain_(domain),
      speed_(1.0),
      d_(A.rows()),
      n_(sections.size()),
      plant_(&plant),
      sections_(&sections),
      readout_matrix_(plant.readout()),
      readout_offsets_(plant.readout_offset()),
      point_road_(&f),
      point_road_gradient_(&f_gradient),
      signal_(LearningSignal::from_phi),
      map_(learning_map),
      phi_(static_cast<std::size_t>(n_)),
      psi_(static_cast<std::size_t>(n_)),
      dphi_(static_cast<std::size_t>(n_)),
      dpsi_(static_cast<std::size_t>(n_)) {
  const Eigen::Index p = sections.dimension();
  if (learning_map.size() != n_)
    throw std::invalid_argument(fmt::format("the learning map is {} x {}, the basis has {} sections",
                                            learning_map.size(), learning_map.size(), n_));
  if (readout_matrix_.rows() != p || readout_matrix_.cols() != d_)
    throw std::invalid_argument(fmt::format(
        "the plant's read-out C is {} x {}; f on a domain of d = {} needs {} x {} (y = C x + y0 "
        "in the domain)",
        readout_matrix_.rows(), readout_matrix_.cols(), p, p, d_));
  if (readout_offsets_.size() == 0) readout_offsets_ = Eigen::VectorXd::Zero(p);
  if (readout_offsets_.size() != p)
    throw std::invalid_argument(fmt::format(
        "the plant's read-out offset has {} values, expected {}", readout_offsets_.size(), p));
  known_.resize(d_);
  known_time_.resize(d_);
  known_jacobian_.resize(d_, d_);
  y_.resize(p);
  road_gradient_.resize(p);
  slope_of_estimate_.resize(p);
  readout_row_.resize(d_);
  dphi_points_.resize(n_, p);
  dpsi_points_.resize(n_, p);
}

void AdaptiveSystem::set_state_readout(const Plant& plant) {
  const Eigen::MatrixXd& c = plant.readout();
  const Eigen::VectorXd& offset = plant.readout_offset();
  if (sections_)
    throw std::logic_error("set_state_readout: this system already reads out p > 1 coordinates");
  if (c.rows() != 1 || c.cols() != d_)
    throw std::invalid_argument(fmt::format(
        "the plant's read-out C is {} x {}; a state-dependent trial needs 1 x {} (f of one "
        "read-out coordinate y = c^T x + y0)",
        c.rows(), c.cols(), d_));
  if (offset.size() > 1)
    throw std::invalid_argument(
        fmt::format("the plant's read-out offset has {} values, expected 1", offset.size()));
  plant_ = &plant;
  readout_ = c.row(0).transpose();
  readout_offset_ = offset.size() == 1 ? offset(0) : 0.0;
  known_.resize(d_);
  known_time_.resize(d_);
  known_jacobian_.resize(d_, d_);
}

void AdaptiveSystem::evaluate_basis(double s) const {
  basis_->evaluate(s, phi_.data());
  if (signal_ == LearningSignal::by_basis)
    basis_->evaluate_mapped(s, psi_.data());
  else
    map_.apply(phi_.data(), psi_.data());
}

double AdaptiveSystem::evaluate_sections(const double* x) const {
  readout_point(x, y_.data());
  sections_->evaluate(y_.data(), phi_.data());
  map_.apply(phi_.data(), psi_.data());
  return (*point_road_)(y_.data());
}

void AdaptiveSystem::rhs(const double* z, double* dz, double t) const {
  ++rhs_count_;
  using Vector = Eigen::Map<const Eigen::VectorXd>;
  double road = 0;
  if (sections_) {
    road = evaluate_sections(z);
  } else {
    const double s = plant_ ? readout(z) : arc_length(t);
    evaluate_basis(s);
    road = (*road_)(s);
  }
  const Vector x(z, d_), xhat(z + d_, d_), alpha(z + 2 * d_, n_);
  Eigen::Map<Eigen::VectorXd> dx(dz, d_), dxhat(dz + d_, d_), dalpha(dz + 2 * d_, n_);
  const double estimate = Vector(phi_.data(), n_).dot(alpha);
  const double error = b_.dot(x - xhat);  // B^T P (x - xhat)
  dx.noalias() = A_ * x + B_ * road;
  dxhat.noalias() = A_ * xhat + B_ * estimate;
  dalpha = error * Vector(psi_.data(), n_);
  if (plant_) {
    plant_->known_dynamics(t, z, known_.data(), nullptr, nullptr);
    dx += known_;
    dxhat += known_;
  }
}

void AdaptiveSystem::jacobian(const double* z, double* J, double t, double* dfdt) const {
  jacobian_matrix(z, t, J);
  time_derivative(z, t, dfdt);
}

void AdaptiveSystem::jacobian_matrix(const double* z, double t, double* J) const {
  if (!plant_) {
    jacobian_matrix(t, J);
    return;
  }
  if (sections_) {
    state_jacobian(z, t, J);
    return;
  }
  ++jacobian_count_;
  const Eigen::Index m = dimension();
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jac(J, m, m);
  jac.setZero();
  const double y = readout(z);
  evaluate_basis(y);
  basis_->evaluate_derivative(y, dphi_.data());
  if (signal_ == LearningSignal::by_basis)
    basis_->evaluate_mapped_derivative(y, dpsi_.data());
  else
    map_.apply(dphi_.data(), dpsi_.data());
  using Vector = Eigen::Map<const Eigen::VectorXd>;
  const Vector phi(phi_.data(), n_), psi(psi_.data(), n_), dphi(dphi_.data(), n_),
      dpsi(dpsi_.data(), n_);
  const Vector x(z, d_), xhat(z + d_, d_), alpha(z + 2 * d_, n_);
  plant_->known_dynamics(t, z, known_.data(), known_jacobian_.data(), nullptr);
  const double error = b_.dot(x - xhat);
  jac.block(0, 0, d_, d_) = A_ + known_jacobian_;
  jac.block(0, 0, d_, d_).noalias() += ((*road_slope_)(y) * B_) * readout_.transpose();
  jac.block(d_, 0, d_, d_) = known_jacobian_;
  jac.block(d_, 0, d_, d_).noalias() += (dphi.dot(alpha) * B_) * readout_.transpose();
  jac.block(d_, d_, d_, d_) = A_;
  jac.block(d_, 2 * d_, d_, n_).noalias() = B_ * phi.transpose();
  jac.block(2 * d_, 0, n_, d_).noalias() = psi * b_.transpose();
  jac.block(2 * d_, 0, n_, d_).noalias() += (error * dpsi) * readout_.transpose();
  jac.block(2 * d_, d_, n_, d_).noalias() = -psi * b_.transpose();
}

void AdaptiveSystem::state_jacobian(const double* z, double t, double* J) const {
  ++jacobian_count_;
  const Eigen::Index m = dimension(), p = dphi_points_.cols();
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jac(J, m, m);
  jac.setZero();
  evaluate_sections(z);
  sections_->gradient(y_.data(), dphi_points_.data());
  for (Eigen::Index a = 0; a < p; ++a)
    map_.apply(dphi_points_.col(a).data(), dpsi_points_.col(a).data());
  (*point_road_gradient_)(y_.data(), road_gradient_.data());
  using Vector = Eigen::Map<const Eigen::VectorXd>;
  const Vector phi(phi_.data(), n_), psi(psi_.data(), n_);
  const Vector x(z, d_), xhat(z + d_, d_), alpha(z + 2 * d_, n_);
  plant_->known_dynamics(t, z, known_.data(), known_jacobian_.data(), nullptr);
  const double error = b_.dot(x - xhat);
  const Eigen::MatrixXd& C = readout_matrix_;
  jac.block(0, 0, d_, d_) = A_ + known_jacobian_;
  readout_row_.noalias() = road_gradient_.transpose() * C;  // grad f(y)^T C
  jac.block(0, 0, d_, d_).noalias() += B_ * readout_row_;
  jac.block(d_, 0, d_, d_) = known_jacobian_;
  slope_of_estimate_.noalias() = dphi_points_.transpose() * alpha;  // grad fhat(y)
  readout_row_.noalias() = slope_of_estimate_.transpose() * C;
  jac.block(d_, 0, d_, d_).noalias() += B_ * readout_row_;
  jac.block(d_, d_, d_, d_) = A_;
  jac.block(d_, 2 * d_, d_, n_).noalias() = B_ * phi.transpose();
  jac.block(2 * d_, 0, n_, d_).noalias() = psi * b_.transpose();
  jac.block(2 * d_, 0, n_, d_).noalias() += error * (dpsi_points_ * C);
  jac.block(2 * d_, d_, n_, d_).noalias() = -psi * b_.transpose();
}

void AdaptiveSystem::jacobian_matrix(double t, double* J) const {
  if (plant_)
    throw std::logic_error(
        "the Jacobian of a state-dependent system depends on the state: jacobian_matrix(z, t, J)");
  ++jacobian_count_;
  const Eigen::Index m = dimension();
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jac(J, m, m);
  jac.setZero();
  const double s = arc_length(t);
  evaluate_basis(s);
  const Eigen::Map<const Eigen::VectorXd> phi(phi_.data(), n_), psi(psi_.data(), n_);
  jac.block(0, 0, d_, d_) = A_;
  jac.block(d_, d_, d_, d_) = A_;
  jac.block(d_, 2 * d_, d_, n_).noalias() = B_ * phi.transpose();
  jac.block(2 * d_, 0, n_, d_).noalias() = psi * b_.transpose();
  jac.block(2 * d_, d_, n_, d_).noalias() = -psi * b_.transpose();
}

void AdaptiveSystem::time_derivative(const double* z, double t, double* dfdt) const {
  if (plant_) {  // F depends on t only through h
    plant_->known_dynamics(t, z, known_.data(), nullptr, known_time_.data());
    Eigen::Map<Eigen::VectorXd> out(dfdt, dimension());
    out.setZero();
    out.head(d_) = known_time_;
    out.segment(d_, d_) = known_time_;
    return;
  }
  // F depends on t only through s = v t: dF/dt = v dF/ds.
  const double s = arc_length(t);
  basis_->evaluate_derivative(s, dphi_.data());
  const Eigen::Map<const Eigen::VectorXd> dphi(dphi_.data(), n_);
  if (signal_ == LearningSignal::by_basis)
    basis_->evaluate_mapped_derivative(s, dpsi_.data());
  else
    map_.apply(dphi_.data(), dpsi_.data());
  using Vector = Eigen::Map<const Eigen::VectorXd>;
  const Vector x(z, d_), xhat(z + d_, d_), alpha(z + 2 * d_, n_);
  Eigen::Map<Eigen::VectorXd> dx(dfdt, d_), dxhat(dfdt + d_, d_), dalpha(dfdt + 2 * d_, n_);
  const double error = b_.dot(x - xhat);
  // d/dt of phi(s(t)) is s'(t) phi'(s); on a shuttle's way back phi' at a kink is the right-hand
  // derivative in s where the step needs the left-hand one: only dF/dt of a step that starts on
  // a kink point is affected (Rosenbrock methods), and restarts keep kinks at segment ends.
  const double velocity = path_velocity(t);
  dx = B_ * (velocity * (*road_slope_)(s));
  dxhat = B_ * (velocity * dphi.dot(alpha));
  dalpha = (velocity * error) * Vector(dpsi_.data(), n_);
}

void AdaptiveSystem::linearize(double t, CoupledLinearization& out) const {
  if (plant_)
    throw std::logic_error(
        "a state-dependent system has no structured linearization in t alone (its Jacobian "
        "depends on the state)");
  ++jacobian_count_;
  evaluate_basis(arc_length(t));
  out.A = &A_;
  out.B = &B_;
  out.b = &b_;
  out.phi = Eigen::Map<const Eigen::VectorXd>(phi_.data(), n_);
  out.psi = Eigen::Map<const Eigen::VectorXd>(psi_.data(), n_);
}

void AdaptiveSystem::rhs_columns(const double* Z, double* dZ, Eigen::Index columns,
                                 double t) const {
  if (plant_)
    throw std::logic_error("a state-dependent system is not linear in z: it has no lap map");
  ++rhs_count_;
  const double s = arc_length(t);
  evaluate_basis(s);
  const Eigen::Index m = dimension();
  const Eigen::Map<const Eigen::MatrixXd> z(Z, m, columns);
  Eigen::Map<Eigen::MatrixXd> dz(dZ, m, columns);
  const Eigen::Map<const Eigen::VectorXd> phi(phi_.data(), n_), psi(psi_.data(), n_);
  const auto x = z.topRows(d_), xhat = z.middleRows(d_, d_), alpha = z.bottomRows(n_);
  // Whole blocks at once: d x d products and rank-one updates over the columns.
  column_scratch_.resize(2, columns);
  auto estimate = column_scratch_.row(0), error = column_scratch_.row(1);
  estimate.noalias() = phi.transpose() * alpha;
  error.noalias() = b_.transpose() * x;
  error.noalias() -= b_.transpose() * xhat;
  dz.topRows(d_).noalias() = A_ * x;
  dz.middleRows(d_, d_).noalias() = A_ * xhat;
  dz.middleRows(d_, d_).noalias() += B_ * estimate;
  dz.bottomRows(n_).noalias() = psi * error;
  dz.col(columns - 1).head(d_) += B_ * (*road_)(s);
}

namespace detail {

void throw_step_underflow(double t) {
  throw std::runtime_error(fmt::format("step size underflow at t = {:.6g} s", t));
}

void throw_step_budget_exhausted(std::int64_t max_steps, double t, double final_time) {
  throw std::runtime_error(
      fmt::format("step budget exhausted (max_steps = {}) at t = {:.6g} s of {:.6g} s",
                  max_steps, t, final_time));
}

void throw_non_finite_state(double t, const std::string& hint) {
  throw std::runtime_error(fmt::format("state became non-finite at t = {:.6g} s{}", t, hint));
}

}  // namespace detail

}  // namespace rkhs
