#include "rkhs/adaptive/adaptive.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/adaptive/averaged_limit.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"

namespace rkhs {

const std::vector<std::string>& adaptive_metric_names() {
  static const std::vector<std::string> names = metric_table_names<AdaptiveMetric>();
  return names;
}

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

enum BreakpointRole : unsigned { sample = 1u, snapshot = 2u };

struct Breakpoint {
  double t;
  unsigned roles = 0;
  std::size_t snapshot_index = 0;
};

// Sample times, snapshot times and (when the integrator restarts there) the times at which
// s(t) = v t mod L crosses a kink, merged; times closer than 1e-12 T are one breakpoint.
std::vector<Breakpoint> breakpoints(const AdaptiveSettings& settings, const Domain& domain,
                                    double final_time, const std::vector<double>& kinks,
                                    bool restart_at_kinks) {
  std::vector<Breakpoint> points{{0.0, sample, 0}};
  const double laps_total = final_time * settings.speed / domain.length;
  const auto samples = static_cast<std::size_t>(
      std::max(1.0, std::ceil(laps_total * static_cast<double>(settings.samples_per_lap))));
  for (std::size_t k = 1; k <= samples; ++k)
    points.push_back(
        {final_time * static_cast<double>(k) / static_cast<double>(samples), sample, 0});
  for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i) {
    const double t = settings.snapshot_laps[i] * domain.length / settings.speed;
    if (t <= final_time * (1 + 1e-12)) points.push_back({std::min(t, final_time), snapshot, i});
  }
  if (restart_at_kinks) {
    const double lap_time = domain.length / settings.speed;
    for (double lap = 0; lap * lap_time < final_time; ++lap)
      for (double kink : kinks) {
        const double t = (lap * domain.length + kink) / settings.speed;
        if (t > 0 && t < final_time) points.push_back({t, 0, 0});
      }
  }
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  std::vector<Breakpoint> merged;
  const double tolerance = 1e-12 * final_time;
  for (const auto& p : points) {
    if (!merged.empty() && p.t - merged.back().t <= tolerance) {
      merged.back().roles |= p.roles;
      if (p.roles & snapshot) merged.back().snapshot_index = p.snapshot_index;
    } else {
      merged.push_back(p);
    }
  }
  return merged;
}

}  // namespace

AdaptiveSystem::LearningSignal learning_signal_for(const AnyKernel& kernel) {
  // A feature basis applies M to its precomputed features, cheaper than M phi for a full M.
  return kernel.feature_count() > 0 ? AdaptiveSystem::LearningSignal::by_basis
                                    : AdaptiveSystem::LearningSignal::from_phi;
}

AdaptiveMeasurement measure_adaptive(const AnyKernel& kernel, const TargetFunction& target,
                                     std::span<const double> centres, const Plant& plant,
                                     const LearningLaw& law, const Integrator& integrator,
                                     const AdaptiveSettings& settings,
                                     std::size_t evaluation_points,
                                     const SolverOptions& solver_options) {
  const Domain& domain = kernel.domain();
  const auto n = static_cast<Eigen::Index>(centres.size());
  using M = AdaptiveMetric;
  using Static = ApproximationMetric;
  AdaptiveMeasurement out;
  auto& metrics = out.metrics;

  // The static part: the space H_n and the projection Pi_n of the target. The Gram matrix, its
  // solver and the cross matrix on the evaluation grid serve the adaptive part too.
  const Eigen::MatrixXd gram = kernel.gram(centres);
  check_cancelled();
  const GramSolver solver(gram, solver_options);
  check_cancelled();
  Eigen::MatrixXd cross;
  const auto approximation = measure_approximation(kernel, target, centres, evaluation_points,
                                                   gram, solver, &cross);
  metrics[M::fill_distance] = approximation.metrics[Static::fill_distance];
  metrics[M::separation_distance] = approximation.metrics[Static::separation_distance];
  metrics[M::gram_condition_number] = approximation.metrics[Static::gram_condition_number];
  metrics[M::power_function_sup] = approximation.metrics[Static::power_function_sup];
  out.solve_method = approximation.solve_method;
  for (const auto& flag : approximation.flags)
    out.flags.push_back(
        flag == "sup_error_at_floor" || flag == "l2_error_at_floor" ? "interpolant_" + flag : flag);

  Eigen::VectorXd at_centres(n);
  target.evaluate(centres, std::span<double>(at_centres.data(), centres.size()));
  const Eigen::VectorXd alpha_star = solver.solve(at_centres);  // Pi_n f = sum alpha*_i phi_i
  const double gamma = law.gain();
  const Eigen::MatrixXd learning_map =
      law.uses_gram_inverse()
          ? Eigen::MatrixXd(solver.solve(Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n))) / gamma)
          : Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n) / gamma);
  const Eigen::MatrixXd& A = plant.A();
  const Eigen::VectorXd& B = plant.B();
  const Eigen::Index d = A.rows();
  const Eigen::MatrixXd Q = parse_matrix(settings.q, d);
  if (Q.rows() != d || Q.cols() != d)
    throw std::invalid_argument(
        fmt::format("Q is {} x {}, the plant needs {} x {}", Q.rows(), Q.cols(), d, d));
  const auto lyapunov = solve_lyapunov(A, Q);
  const Eigen::MatrixXd& P = lyapunov.P;

  // The road that drives the plant: f itself, or its projection Pi_n f (then f lies in H_n).
  const auto basis = kernel.basis(centres);
  const auto road_basis = kernel.basis(centres);
  std::vector<double> road_phi(centres.size());
  const std::function<double(double)> road =
      settings.projected_road ? std::function<double(double)>([&](double s) {
        road_basis->evaluate(s, road_phi.data());
        return Eigen::Map<const Eigen::VectorXd>(road_phi.data(), n).dot(alpha_star);
      })
                              : std::function<double(double)>([&](double s) { return target(s); });

  AdaptiveSystem system(A, B, P, *basis, learning_map, road, domain, settings.speed,
                        learning_signal_for(kernel));
  const double final_time = settings.final_time_or_laps(domain.length);
  if (!(final_time > 0)) throw std::invalid_argument("the final time must be positive");
  auto kinks = kernel.kink_points();  // of phi(s), and of f (a sampled road)
  if (!settings.projected_road)
    for (double kink : target.kink_points()) kinks.push_back(kink);
  const auto points =
      breakpoints(settings, domain, final_time, kinks, integrator.restarts_at_kinks());
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });

  // V = 1/2 e^T P e + 1/2 Gamma (alpha* - alpha)^T W (alpha* - alpha), W = G (rkhs law) or I.
  const auto snapshot_grid = domain.uniform_points(settings.snapshot_points);
  const Eigen::MatrixXd snapshot_cross =
      settings.snapshot_laps.empty() ? Eigen::MatrixXd() : kernel.cross(snapshot_grid, centres);
  out.snapshots.resize(settings.snapshot_laps.size());
  for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i)
    out.snapshots[i].lap = settings.snapshot_laps[i];
  auto observe = [&](std::size_t k, const double* z) {
    check_cancelled();  // every breakpoint, also for integrators from plugins
    const Eigen::Map<const Eigen::VectorXd> x(z, d), xhat(z + d, d), alpha(z + 2 * d, n);
    if (points[k].roles & sample) {
      const Eigen::VectorXd e = x - xhat;
      const Eigen::VectorXd coefficient_gap = alpha_star - alpha;
      const double weighted = law.uses_gram_inverse() ? coefficient_gap.dot(gram * coefficient_gap)
                                                      : coefficient_gap.squaredNorm();
      out.samples.push_back({points[k].t, e.norm(), 0.5 * e.dot(P * e) + 0.5 * gamma * weighted});
    }
    if (points[k].roles & snapshot) {
      const Eigen::VectorXd estimate = snapshot_cross * alpha;
      out.snapshots[points[k].snapshot_index].estimate.assign(estimate.data(),
                                                              estimate.data() + estimate.size());
    }
  };
  Eigen::VectorXd z = Eigen::VectorXd::Zero(2 * d + n);
  const auto stats = integrator.integrate(system, z, times, observe);
  out.road.resize(snapshot_grid.size());
  for (std::size_t m = 0; m < snapshot_grid.size(); ++m) out.road[m] = road(snapshot_grid[m]);

  // Errors at T on the M-point grid.
  const auto grid = domain.uniform_points(evaluation_points);  // the rows of `cross`
  Eigen::VectorXd f(static_cast<Eigen::Index>(grid.size()));
  for (std::size_t m = 0; m < grid.size(); ++m) f(static_cast<Eigen::Index>(m)) = road(grid[m]);
  const Eigen::VectorXd alpha = z.tail(n);
  const Eigen::VectorXd estimate = cross * alpha, projection = cross * alpha_star;
  auto l2 = [&](const Eigen::VectorXd& v) {
    return domain.l2_norm(std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
  };
  const Eigen::VectorXd interpolant_residual = f - projection, residual = f - estimate;
  metrics[M::interpolant_l2_error] = l2(interpolant_residual);
  metrics[M::interpolant_sup_error] = interpolant_residual.cwiseAbs().maxCoeff();
  metrics[M::l2_error] = l2(residual);
  metrics[M::sup_error] = residual.cwiseAbs().maxCoeff();
  metrics[M::gap_to_projection] = l2(estimate - projection);
  metrics[M::final_state_error] = (z.head(d) - z.segment(d, d)).norm();
  double max_state_error = 0, max_increase = 0;
  for (std::size_t k = 0; k < out.samples.size(); ++k) {
    max_state_error = std::max(max_state_error, out.samples[k].state_error);
    if (k > 0)
      max_increase = std::max(max_increase, out.samples[k].lyapunov - out.samples[k - 1].lyapunov);
  }
  metrics[M::max_state_error] = max_state_error;
  if (settings.projected_road) {
    // alpha* is the true coefficient vector only when the road lies in H_n.
    const double v0 = out.samples.front().lyapunov;
    metrics[M::coefficient_error] =
        (alpha - alpha_star).norm() / std::max(alpha_star.norm(), 1e-300);
    metrics[M::lyapunov_max_increase] = v0 > 0 ? max_increase / v0 : max_increase;
    metrics[M::lyapunov_ratio] = v0 > 0 ? out.samples.back().lyapunov / v0 : nan;
  }
  {  // P_L2 f, the averaged (v -> 0) limit of either law, on the same grid.
    const auto limit = averaged_limit(kernel, centres, road, kinks, solver_options);
    const Eigen::VectorXd l2_projection = cross * limit.coefficients;
    const Eigen::VectorXd l2_projection_residual = f - l2_projection;
    metrics[M::l2_projection_l2_error] = l2(l2_projection_residual);
    metrics[M::l2_projection_sup_error] = l2_projection_residual.cwiseAbs().maxCoeff();
    metrics[M::gap_to_l2_projection] = l2(estimate - l2_projection);
    if (!limit.quadrature_converged) out.flags.push_back("l2_projection_unconverged");
  }
  metrics[M::steps] = static_cast<double>(stats.steps);
  metrics[M::rejected_steps] = static_cast<double>(stats.rejected_steps);
  metrics[M::segments] = static_cast<double>(stats.segments);
  metrics[M::rhs_evaluations] = static_cast<double>(system.rhs_evaluations());
  metrics[M::jacobian_evaluations] = static_cast<double>(system.jacobian_evaluations());
  return out;
}

}  // namespace rkhs
