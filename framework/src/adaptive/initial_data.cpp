// Theorem 1 of the paper (existence, uniqueness and Lipschitz dependence on the initial data;
// docs/theorems.md) on a road trial: its hypotheses, the embedding constant C of H in C(Omega)
// and the Lipschitz constant L of the error system's right-hand side, and its conclusion
// measured, the distance between two trajectories started from different initial data.
//
// The error system in X = (e, c~) = (x - xhat, c* - c), normed by |e|^2 + c~^T W c~ (W = G for
// the rkhs law, whose V weighs the coefficients so; I for the gradient law and in feature
// coordinates), is linear in X along the path s(t):
//   e' = A e + B phi(s)^T c~,   c~' = -Gamma^-1 W^+ phi(s) B^T P e.
// With u = W^(1/2) c~ and w = W^(+1/2) phi(s) its generator is [[A, B w^T], [-w B^T P / Gamma, 0]],
// whose norm is that of the (d + 1) x (d + 1) matrix with |w| in place of w (the u part
// orthogonal to w is in its kernel and outside its range). L is its largest norm over the grid.
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "rkhs/adaptive/breakpoints.hpp"
#include "rkhs/core/cancellation.hpp"
#include "road_trial.hpp"

namespace rkhs {

namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();

/// |w(s_m)|^2 = phi(s_m)^T W^+ phi(s_m) on the evaluation grid.
Eigen::VectorXd squared_signal_norms(const RoadTrial& trial) {
  if (trial.in_features)
    return Eigen::VectorXd(trial.grid_features.cwiseAbs2() *
                           Eigen::VectorXd::Ones(trial.grid_features.cols()));
  const Eigen::MatrixXd& cross = trial.fixed.cross;  // phi(s_m)^T, one row per grid point
  if (!trial.gram_inverse) return cross.rowwise().squaredNorm();
  const Eigen::MatrixXd solved = trial.fixed.solver.solve(Eigen::MatrixXd(cross.transpose()));
  return (cross.array() * solved.transpose().array()).rowwise().sum().cwiseMax(0.0);
}

/// ||[[A, B w], [-w B^T P / Gamma, 0]]||_2 for the scalar w.
double generator_norm(const Eigen::MatrixXd& A, const Eigen::VectorXd& B, const Eigen::MatrixXd& P,
                      double gamma, double w) {
  const Eigen::Index d = A.rows();
  Eigen::MatrixXd generator = Eigen::MatrixXd::Zero(d + 1, d + 1);
  generator.topLeftCorner(d, d) = A;
  generator.topRightCorner(d, 1) = B * w;
  generator.bottomLeftCorner(1, d) = -(w / gamma) * (P * B).transpose();
  return Eigen::JacobiSVD<Eigen::MatrixXd>(generator).singularValues()(0);
}

}  // namespace

void RoadTrial::measure_initial_data_dependence() {
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  // The hypotheses: C = sup sqrt(k(s, s)), and L.
  const Eigen::VectorXd diagonal = kernel.diagonal(grid);
  metrics[M::embedding_constant] = std::sqrt(std::max(diagonal.maxCoeff(), 0.0));
  out.floors[M::embedding_constant] = 4.0 * eps * metrics[M::embedding_constant];
  const Eigen::MatrixXd& A = plant.A();
  const Eigen::VectorXd& B = plant.B();
  const Eigen::VectorXd signal = squared_signal_norms(*this);
  double lipschitz = 0;
  for (Eigen::Index k = 0; k < signal.size(); ++k)
    lipschitz = std::max(lipschitz, generator_norm(A, B, P, gamma, std::sqrt(signal(k))));
  metrics[M::lipschitz_constant] = lipschitz;
  out.floors[M::lipschitz_constant] = 4.0 * static_cast<double>(d + 1) * eps * lipschitz;
  if (engine != AdaptiveEngine::time_stepping || sampled_states.empty()) return;

  // The conclusion: a second trajectory from x0 + dx, xhat0 - dx, alpha0 + dc, with |2 dx| and
  // ||dc||_W equal and as large as the first trajectory's largest ||X||, and at least 1 (the
  // system is linear in X, so their distance does not depend on the size; at that size it
  // stands well above the integration's error, atol included).
  const auto x_norm = [&](const Eigen::VectorXd& z) {
    const Eigen::VectorXd e = z.head(d) - z.segment(d, d);
    const Eigen::VectorXd c = z.tail(coefficients);
    const double weighted = gram_inverse ? c.dot(fixed.gram * c) : c.squaredNorm();
    return std::sqrt(e.squaredNorm() + std::max(weighted, 0.0));
  };
  double largest = 0;
  for (const auto& state : sampled_states) largest = std::max(largest, x_norm(state));
  const double size = std::max(largest, 1.0);
  Eigen::VectorXd dc = Eigen::VectorXd::Ones(coefficients);
  const double dc_norm =
      x_norm((Eigen::VectorXd(m) << Eigen::VectorXd::Zero(2 * d), dc).finished());
  if (!(dc_norm > 0)) return;  // W vanishes on the ones: no perturbation to measure
  Eigen::VectorXd perturbed = Eigen::VectorXd::Zero(m);
  const Eigen::VectorXd dx = Eigen::VectorXd::Constant(d, 0.5 * size / std::sqrt(double(d)));
  perturbed.head(d) = dx;
  perturbed.segment(d, d) = -dx;
  perturbed.tail(coefficients) = (size / dc_norm) * dc;
  const double initial_distance = x_norm(perturbed);

  const double final_time = settings.final_time_or_laps(domain.length);
  const auto points = adaptive_breakpoints(settings, domain, 0.0, final_time, kinks,
                                           integrator.restarts_at_kinks());
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });
  std::size_t sampled = 0;
  double ratio = 0, exponent = -std::numeric_limits<double>::infinity(), exponent_at = 0,
         ratio_at_exponent = 0, largest_perturbed = 0;
  integrator.integrate(*system, perturbed, times, [&](std::size_t k, const double* at) {
    check_cancelled();
    if (!(points[k].roles & sample_role) || sampled >= sampled_states.size()) return;
    const Eigen::Map<const Eigen::VectorXd> z2(at, m);
    largest_perturbed = std::max(largest_perturbed, x_norm(z2));
    const double r = x_norm(z2 - sampled_states[sampled]) / initial_distance;
    const double t = points[k].t;
    ++sampled;
    ratio = std::max(ratio, r);
    if (t > 0 && r > 0 && std::log(r) / t > exponent) {
      exponent = std::log(r) / t;
      exponent_at = t;
      ratio_at_exponent = r;
    }
  });
  metrics[M::initial_data_lipschitz] = ratio;
  // Both integrations err by about rtol |X| + atol per component.
  const double rtol = settings.integrator_rtol, atol = settings.integrator_atol;
  const double distance_floor =
      (rtol * (largest + largest_perturbed) + 2 * atol * std::sqrt(static_cast<double>(m))) /
      initial_distance;
  if (rtol > 0) out.floors[M::initial_data_lipschitz] = distance_floor;
  // The smallest L' >= 0 (Theorem 1's L is positive): 0 when the distance never grows, and
  // then no floor (the value is not a measured growth that round-off could have made).
  if (exponent > 0) {
    metrics[M::lipschitz_exponent] = exponent;
    if (rtol > 0)
      out.floors[M::lipschitz_exponent] = distance_floor / (ratio_at_exponent * exponent_at);
  } else if (exponent_at > 0) {
    metrics[M::lipschitz_exponent] = 0.0;
  }
}

}  // namespace rkhs
