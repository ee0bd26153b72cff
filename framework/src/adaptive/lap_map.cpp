#include "rkhs/adaptive/lap_map.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "rkhs/adaptive/radau.hpp"
#include "rkhs/adaptive/stage_solves.hpp"
#include "rkhs/adaptive/stepping.hpp"

namespace rkhs {

namespace {

/// The lap map's dimension() + 1 columns as a RadauProblem: the first dimension() columns
/// follow z' = J(t) z (sensitivities to the initial state), the last z' = J(t) z + g(t).
class LapColumns {
 public:
  explicit LapColumns(AdaptiveSystem& system)
      : system_(system), solves_(system, LinearSolver::structured) {}
  Eigen::Index rows() const { return system_.dimension(); }
  Eigen::Index columns() const { return system_.dimension() + 1; }
  void rhs(double t, const Eigen::MatrixXd& z, Eigen::MatrixXd& dz) {
    system_.rhs_columns(z.data(), dz.data(), z.cols(), t);
  }
  void factor(double t, const Eigen::MatrixXd&, double real_shift,
              std::complex<double> complex_shift) {  // J(t): linear in the columns
    solves_.factor(t, real_shift, complex_shift);
  }
  void solve_real(Eigen::MatrixXd& r) const { solves_.solve_real(r); }
  void solve_complex(Eigen::MatrixXcd& r) const { solves_.solve_complex(r); }

 private:
  AdaptiveSystem& system_;
  StageSolves solves_;
};

}  // namespace

LapMap compute_lap_map(AdaptiveSystem& system, double lap_time,
                       std::span<const double> breakpoints, double atol, double rtol,
                       std::int64_t max_steps) {
  const Eigen::Index m = system.dimension();
  std::vector<double> times{0.0};
  for (double t : breakpoints)
    if (t > 0 && t < lap_time) times.push_back(t);
  times.push_back(lap_time);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());

  const auto rhs_before = system.rhs_evaluations();
  const auto jacobians_before = system.jacobian_evaluations();
  LapColumns problem(system);
  RadauIIA5<LapColumns> stepper(problem, atol, rtol);
  Eigen::MatrixXd start = Eigen::MatrixXd::Zero(m, m + 1);
  start.leftCols(m).setIdentity();
  Eigen::VectorXd z = Eigen::Map<const Eigen::VectorXd>(start.data(), start.size());
  LapMap out;
  out.stats = drive_steps(stepper, z, times, [](std::size_t, const double*) {},
                          {max_steps, 0.0, false, " (in the lap map)"});
  const Eigen::Map<const Eigen::MatrixXd> end(z.data(), m, m + 1);
  out.monodromy = end.leftCols(m);
  out.offset = end.col(m);
  out.rhs_evaluations = system.rhs_evaluations() - rhs_before;
  out.jacobian_evaluations = system.jacobian_evaluations() - jacobians_before;
  return out;
}

LapMapCache::Found LapMapCache::find_or_compute(
    const std::string& key, const std::function<LapMap()>& compute) {
  std::promise<std::shared_ptr<const LapMap>> promise;
  std::shared_future<std::shared_ptr<const LapMap>> future;
  bool computes = false;
  {
    std::lock_guard lock(mutex_);
    const auto found = maps_.find(key);
    if (found != maps_.end()) {
      future = found->second;
    } else {
      future = promise.get_future().share();
      maps_.emplace(key, future);
      computes = true;
    }
  }
  if (computes) {
    try {
      promise.set_value(std::make_shared<const LapMap>(compute()));
    } catch (...) {
      promise.set_exception(std::current_exception());
    }
  }
  return {future.get(), computes};
}

LapPowers::LapPowers(const LapMap& map) {
  const Eigen::Index m = map.monodromy.rows();
  Eigen::MatrixXd augmented = Eigen::MatrixXd::Zero(m + 1, m + 1);
  augmented.topLeftCorner(m, m) = map.monodromy;
  augmented.topRightCorner(m, 1) = map.offset;
  augmented(m, m) = 1;
  powers_.reserve(64);
  powers_.push_back(std::move(augmented));
  for (int k = 1; k < 64; ++k) powers_.push_back(powers_.back() * powers_.back());
}

Eigen::VectorXd LapPowers::advance(const Eigen::VectorXd& z0, std::uint64_t laps) const {
  const Eigen::Index m = z0.size();
  Eigen::VectorXd v(m + 1);
  v.head(m) = z0;
  v(m) = 1;
  for (int k = 0; laps != 0; ++k, laps >>= 1)
    if (laps & 1u) v = powers_[static_cast<std::size_t>(k)] * v;
  return v.head(m);
}

PeriodicLimit periodic_limit(const LapMap& map, const Eigen::VectorXd& z0,
                             Eigen::Index plant_dimension, double cutoff, double map_error) {
  const Eigen::MatrixXd& phi = map.monodromy;
  const Eigen::Index m = phi.rows();
  const Eigen::MatrixXd gap = Eigen::MatrixXd::Identity(m, m) - phi;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(gap, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const auto& sigma = svd.singularValues();
  const double threshold = cutoff * std::max(1.0, sigma(0));
  PeriodicLimit out;
  out.unexcited_directions = 0;
  const Eigen::VectorXd residual = phi * z0 + map.offset - z0;
  Eigen::VectorXd projected = svd.matrixU().transpose() * residual;
  for (Eigen::Index i = 0; i < m; ++i) {
    if (sigma(i) > threshold) {
      projected(i) /= sigma(i);
    } else {
      projected(i) = 0;
      ++out.unexcited_directions;
    }
  }
  out.state = z0 + svd.matrixV() * projected;

  const Eigen::Index learning = m - plant_dimension;
  const Eigen::MatrixXd block = phi.bottomRightCorner(learning, learning);
  Eigen::EigenSolver<Eigen::MatrixXd> eigen(block, /*computeEigenvectors=*/true);
  double radius = 0;
  Eigen::Index attained = -1;
  for (Eigen::Index i = 0; i < learning; ++i) {
    const auto lambda = eigen.eigenvalues()(i);
    if (std::abs(1.0 - lambda) > threshold && std::abs(lambda) > radius) {
      radius = std::abs(lambda);
      attained = i;
    }
  }
  out.spectral_radius = radius;
  out.spectral_radius_uncertainty = std::numeric_limits<double>::quiet_NaN();
  if (attained >= 0) {
    // The left eigenvector: the eigenvector of Phi^T for the eigenvalue nearest lambda.
    const auto lambda = eigen.eigenvalues()(attained);
    Eigen::EigenSolver<Eigen::MatrixXd> transposed(block.transpose(), true);
    Eigen::Index nearest = 0;
    for (Eigen::Index i = 1; i < learning; ++i)
      if (std::abs(transposed.eigenvalues()(i) - lambda) <
          std::abs(transposed.eigenvalues()(nearest) - lambda))
        nearest = i;
    const Eigen::VectorXcd x = eigen.eigenvectors().col(attained);
    const Eigen::VectorXcd y = transposed.eigenvectors().col(nearest);
    const double condition = std::abs(y.dot(x.conjugate())) / (x.norm() * y.norm());
    // ||Phi||_2 <= 1 + ||I - Phi||_2 = 1 + sigma_max(I - Phi).
    out.spectral_radius_uncertainty = map_error * (1.0 + sigma(0)) / condition;
  }
  out.slowest_time_constant_laps =
      radius > 0 && radius < 1 ? -1.0 / std::log(radius)
                               : (radius >= 1 ? std::numeric_limits<double>::infinity() : 0.0);
  return out;
}

}  // namespace rkhs
