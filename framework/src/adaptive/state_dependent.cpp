#include "rkhs/adaptive/state_dependent.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "adaptive_metrics.hpp"
#include "rkhs/adaptive/breakpoints.hpp"
#include "rkhs/adaptive/excitation.hpp"
#include "rkhs/adaptive/learning_map.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/core/cancellation.hpp"

namespace rkhs {

std::vector<bool> visited_neighbourhood(const Domain& domain, std::span<const double> path,
                                        std::span<const double> points, double reach) {
  const auto d = static_cast<std::size_t>(domain.dimension);
  const std::size_t count = domain.point_count(points), samples = domain.point_count(path);
  std::vector<bool> inside(count, false);
  const double reach_squared = reach * reach;
  for (std::size_t k = 0; k < count; ++k) {
    const double* x = points.data() + k * d;
    for (std::size_t j = 0; j < samples && !inside[k]; ++j) {
      // The segment from path point j to point j + 1 (a single point for the last one), in
      // coordinates relative to point j: on a torus the shortest representatives.
      const double* a = path.data() + j * d;
      const double* b = j + 1 < samples ? a + d : a;
      double offset[Domain::max_dimension] = {0, 0, 0}, along[Domain::max_dimension] = {0, 0, 0};
      double length_squared = 0, projection = 0;
      for (std::size_t i = 0; i < d; ++i) {
        const int axis = static_cast<int>(i);
        offset[i] = domain.difference(x[i], a[i], axis);
        along[i] = domain.difference(b[i], a[i], axis);
        length_squared += along[i] * along[i];
        projection += offset[i] * along[i];
      }
      const double u = length_squared > 0 ? std::clamp(projection / length_squared, 0.0, 1.0) : 0.0;
      double distance_squared = 0;
      for (std::size_t i = 0; i < d; ++i) {
        const double gap = offset[i] - u * along[i];
        distance_squared += gap * gap;
      }
      inside[k] = distance_squared <= reach_squared;
    }
  }
  return inside;
}

std::string state_dependent_settings_error(const AdaptiveSettings& settings, double period) {
  if (settings.limit())
    return "laps = \"limit\" needs the lap map, which a state-dependent plant (f of its own "
           "state: a nonlinear system) does not have";
  if (settings.engine == AdaptiveEngine::lap_map)
    return "engine = \"lap_map\" needs a system linear in its state; a state-dependent plant "
           "steps through time (engine = \"time_stepping\" or \"automatic\")";
  if (settings.shuttle())
    return "a path (adaptive.path) moves along a track; a state-dependent plant's trajectory is "
           "its own state";
  if (!(period > 0) && !(settings.final_time > 0))
    return "this plant has no forcing period to count laps in: set adaptive.final_time";
  return {};
}

namespace {

// Throws std::invalid_argument for what a state-dependent trial cannot run (the header).
void check_trial(const AnyKernel& kernel, const Plant& plant, const LearningLaw& law,
                 const AdaptiveSettings& settings) {
  if (const auto error = state_dependent_settings_error(settings, plant.period()); !error.empty())
    throw std::invalid_argument(error);
  law.require_kernel(kernel);
  if (law.coordinates() != LawCoordinates::centres)
    throw std::invalid_argument(
        "a state-dependent plant learns in the span of the centres' sections (laws gradient and "
        "rkhs); feature coordinates are not supported for it");
  const int p = kernel.domain().dimension;  // read-out coordinates
  if (plant.readout().rows() != p)
    throw std::invalid_argument(
        fmt::format("the plant reads out {} coordinate{}; f on a domain of d = {} needs {}",
                    plant.readout().rows(), plant.readout().rows() == 1 ? "" : "s", p, p));
  if (p > 1 && !settings.snapshot_laps.empty())
    throw std::invalid_argument(
        "snapshots of the estimate (adaptive.snapshot_laps) are profiles along a domain of d = 1");
}

// f itself, or Pi_n f (then f lies in H_n and alpha* is the answer): along one read-out
// coordinate (road, road_slope) or at a point of R^p (point_road, point_road_gradient; the
// gradient of f by central differences, that of Pi_n f from the sections' gradients). Built in
// place (its functions refer to it).
struct PlantRoad {
  PlantRoad(const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
            const PointSections& sections, const Eigen::VectorXd& alpha_star, bool projected);
  PlantRoad(const PlantRoad&) = delete;
  PlantRoad& operator=(const PlantRoad&) = delete;

  /// f at a read-out point (p values).
  double at(const double* y) const { return p == 1 ? road(y[0]) : point_road(y); }

  const Domain& domain;
  const int p;
  const Eigen::Index n;
  std::unique_ptr<KernelBasis> basis;
  std::vector<double> phi;
  std::function<double(double)> road, road_slope;
  std::function<double(const double*)> point_road;
  std::function<void(const double*, double*)> point_road_gradient;
};

PlantRoad::PlantRoad(const AnyKernel& kernel, const TargetFunction& target,
                     std::span<const double> centres, const PointSections& sections,
                     const Eigen::VectorXd& alpha_star, bool projected)
    : domain(kernel.domain()),
      p(domain.dimension),
      n(static_cast<Eigen::Index>(domain.point_count(centres))),
      basis(p == 1 ? kernel.basis(centres) : nullptr),
      phi(static_cast<std::size_t>(n) * static_cast<std::size_t>(p)) {
  if (projected) {
    road = [this, &alpha_star](double y) {
      basis->evaluate(y, phi.data());
      return Eigen::Map<const Eigen::VectorXd>(phi.data(), n).dot(alpha_star);
    };
    road_slope = [this, &alpha_star](double y) {
      basis->evaluate_derivative(y, phi.data());
      return Eigen::Map<const Eigen::VectorXd>(phi.data(), n).dot(alpha_star);
    };
    point_road = [this, &alpha_star, &sections](const double* y) {
      sections.evaluate(y, phi.data());
      return Eigen::Map<const Eigen::VectorXd>(phi.data(), n).dot(alpha_star);
    };
    point_road_gradient = [this, &alpha_star, &sections](const double* y, double* g) {
      sections.gradient(y, phi.data());
      const Eigen::Map<const Eigen::MatrixXd> slopes(phi.data(), n, p);
      Eigen::Map<Eigen::VectorXd>(g, p).noalias() = slopes.transpose() * alpha_star;
    };
    return;
  }
  road = [&target](double y) { return target(y); };
  road_slope = [&target](double y) { return target.slope(y); };
  point_road = [this, &target](const double* y) {
    double value = 0;
    target.evaluate(std::span<const double>(y, std::size_t(p)), std::span<double>(&value, 1));
    return value;
  };
  point_road_gradient = [this](const double* y, double* g) {
    // Central differences with step 1e-6 of each axis' extent; one-sided within that step of a
    // box's faces (the target need not exist beyond them).
    double point[Domain::max_dimension] = {0, 0, 0};
    std::copy(y, y + p, point);
    for (int a = 0; a < p; ++a) {
      const double extent = domain.extent(a), step = 1e-6 * extent;
      const double up = domain.periodic || y[a] + step <= extent ? step : 0.0;
      const double down = domain.periodic || y[a] - step >= 0.0 ? step : 0.0;
      point[a] = y[a] + up;
      const double high = point_road(point);
      point[a] = y[a] - down;
      const double low = point_road(point);
      point[a] = y[a];
      g[a] = (high - low) / (up + down);
    }
  };
}

// What the integration observes: samples of |x - xhat| and V, snapshots, and over the second
// half of the run the visited range of y and the excitation E.
struct TrajectoryObserver {
  const AdaptiveSystem& system;
  const Domain& domain;
  const std::vector<Breakpoint>& points;
  double final_time;
  Eigen::Index d, n;
  const Eigen::VectorXd& alpha_star;
  const Eigen::MatrixXd& P;
  double gamma;
  const Eigen::MatrixXd* gram;  ///< W = G of V (rkhs law), or null (W = I)
  const std::function<void(const double*, double*)>& evaluate_phi;  ///< phi at a read-out
  const PlantRoad& road;
  const Eigen::MatrixXd& snapshot_cross;
  AdaptiveMeasurement& out;

  double largest_state_pair = 0;  ///< max over the samples of |x| + |xhat| (the floors' scale)
  Eigen::MatrixXd excitation = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd phi = Eigen::VectorXd(n), excitation_load = Eigen::VectorXd::Zero(n);
  std::size_t excitation_samples = 0;
  // The visited set: [min y, max y] in d = 1; in d > 1 the neighbourhood of the polyline through
  // the sampled read-outs (visited_points, p values each).
  double visited_low = std::numeric_limits<double>::infinity(), visited_high = -visited_low;
  std::vector<double> visited_points = {};
  bool left_domain = false;

  void observe(std::size_t k, const double* z);
  /// E and its load r = mean f(y) phi(y) as means over the samples, after the integration.
  void finish();
};

void TrajectoryObserver::observe(std::size_t k, const double* z) {
  check_cancelled();
  const int p = domain.dimension;
  const Breakpoint& point = points[k];
  double y[Domain::max_dimension] = {0, 0, 0};
  system.readout_point(z, y);
  // Beyond the interval or box by more than 1e-6 of its extent: a read-out that runs along
  // a face (a path on the box's edge) stays within its integration error of it.
  for (int a = 0; a < p; ++a) {
    const double slack = 1e-6 * domain.extent(a);
    if (!domain.periodic && (y[a] < -slack || y[a] > domain.extent(a) + slack)) left_domain = true;
  }
  if (point.roles & sample_role) {
    out.samples.push_back(
        adaptive_sample(point.t, z, d, alpha_star, P, gamma, gram, largest_state_pair));
    if (point.t >= 0.5 * final_time) {
      evaluate_phi(y, phi.data());
      excitation.selfadjointView<Eigen::Lower>().rankUpdate(phi);
      excitation_load += road.at(y) * phi;
      ++excitation_samples;
      visited_low = std::min(visited_low, y[0]);
      visited_high = std::max(visited_high, y[0]);
      visited_points.insert(visited_points.end(), y, y + p);
    }
  }
  if (point.roles & snapshot_role) {
    const Eigen::VectorXd estimate =
        snapshot_cross * Eigen::Map<const Eigen::VectorXd>(z + 2 * d, n);
    out.snapshots[point.snapshot_index].estimate.assign(estimate.data(),
                                                        estimate.data() + estimate.size());
  }
}

void TrajectoryObserver::finish() {
  excitation = excitation.selfadjointView<Eigen::Lower>();
  if (excitation_samples > 0) {
    excitation /= static_cast<double>(excitation_samples);
    excitation_load /= static_cast<double>(excitation_samples);
  }
  if (left_domain) out.flags.push_back("readout_left_domain");
}

// P_L2 f along the trajectory: the g in H_n of least H-norm that minimises the time average
// of (f - g)^2(y(t)) over the second half, E a = r with r = mean f(y) phi(y) (the minimum
// G-norm solution through G = L L^T: a = L^-T (L^-1 E L^-T)^+ L^-1 r). The pseudo-inverse
// drops the eigenvalues of L^-1 E L^-T within its round-off, eps max(n, cond(G)) times the
// largest (`condition`: cond(G)): directions the trajectory excites less than that are not
// determined by it (in d > 1 a curve grazes many supports, and keeping them made P_L2 f off the
// curve noise). Its coefficients.
Eigen::VectorXd trajectory_l2_projection(const Eigen::MatrixXd& gram,
                                         const Eigen::MatrixXd& excitation,
                                         const Eigen::VectorXd& excitation_load, double condition) {
  const Eigen::Index n = gram.rows();
  Eigen::LLT<Eigen::MatrixXd> cholesky(gram);
  if (cholesky.info() != Eigen::Success)
    return excitation.completeOrthogonalDecomposition().solve(excitation_load);
  const auto L = cholesky.matrixL();
  Eigen::MatrixXd reduced = L.solve(excitation);
  reduced = L.solve(reduced.transpose()).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(reduced);
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const double cutoff =
      std::numeric_limits<double>::epsilon() *
      std::max(static_cast<double>(n), std::isfinite(condition) ? condition : 0.0) *
      std::max(values.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::VectorXd w = eigen.eigenvectors().transpose() * L.solve(excitation_load);
  for (Eigen::Index i = 0; i < n; ++i) w(i) = values(i) > cutoff ? w(i) / values(i) : 0.0;
  return L.transpose().solve(eigen.eigenvectors() * w);
}

// path_l2_error and off_path_l2_error: the error `residual` (on `grid`) on and off the visited
// set, and visited_rms_error: f - fhat(T) at the sampled read-outs of the second half.
void set_visited_errors(const TrajectoryObserver& seen, const std::vector<double>& grid,
                        const Eigen::VectorXd& residual, const Eigen::VectorXd& alpha,
                        AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  const Domain& domain = seen.domain;
  const int p = domain.dimension;
  auto& metrics = out.metrics;
  if (p > 1) {  // On and off the visited set: the grid points within the centres' fill distance
                // of the polyline through the sampled read-outs, with the L2 norm's weights
                // (the two parts add up to l2_error^2).
    const auto l2 = [&](const Eigen::VectorXd& v) {
      return domain.l2_norm(std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
    };
    const double reach = metrics[M::fill_distance];
    const auto on_path = visited_neighbourhood(domain, seen.visited_points, grid, reach);
    Eigen::VectorXd on = residual, off = residual;
    for (Eigen::Index k = 0; k < residual.size(); ++k)
      (on_path[static_cast<std::size_t>(k)] ? off : on)(k) = 0;
    metrics[M::path_l2_error] = l2(on);
    metrics[M::off_path_l2_error] = l2(off);
  } else {  // On and off the visited set [min y, max y], with the weights of the L2 norm's rule
            // (the rectangle rule on a circle, the trapezoid rule on an interval): the two
            // parts add up to l2_error^2.
    double on = 0, off = 0;
    const std::size_t count = grid.size();
    for (std::size_t k = 0; k < count; ++k) {
      const double r = residual(static_cast<Eigen::Index>(k));
      const double weight = domain.periodic || count == 1
                                ? domain.length / static_cast<double>(count)
                                : (k == 0 || k + 1 == count ? 0.5 : 1.0) * domain.length /
                                      static_cast<double>(count - 1);
      (grid[k] >= seen.visited_low && grid[k] <= seen.visited_high ? on : off) += weight * r * r;
    }
    metrics[M::path_l2_error] = std::sqrt(on);
    metrics[M::off_path_l2_error] = std::sqrt(off);
  }
  const std::size_t visited = seen.visited_points.size() / static_cast<std::size_t>(p);
  Eigen::VectorXd phi(seen.n);
  double sum = 0;
  for (std::size_t k = 0; k < visited; ++k) {
    const double* y = seen.visited_points.data() + k * static_cast<std::size_t>(p);
    seen.evaluate_phi(y, phi.data());
    const double r = seen.road.at(y) - phi.dot(alpha);
    sum += r * r;
  }
  metrics[M::visited_rms_error] =
      visited > 0 ? std::sqrt(sum / static_cast<double>(visited)) : std::nan("");
}

}  // namespace

AdaptiveMeasurement measure_state_dependent(const AnyKernel& kernel, const TargetFunction& target,
                                            std::span<const double> centres, const Plant& plant,
                                            const LearningLaw& law, const Integrator& integrator,
                                            const AdaptiveSettings& settings,
                                            std::size_t evaluation_points,
                                            const SolverOptions& solver_options,
                                            const Integrator* reference) {
  check_trial(kernel, plant, law, settings);
  const Domain& domain = kernel.domain();
  const int p = domain.dimension;  // read-out coordinates
  using M = AdaptiveMetric;
  AdaptiveMeasurement out;
  out.engine = AdaptiveEngine::time_stepping;

  // The static part on Omega: H_n, Pi_n f, and the cross matrix on the evaluation grid.
  const StaticPart fixed(kernel, target, centres, evaluation_points, solver_options);
  fixed.record(out);
  const Eigen::Index n = fixed.n;
  const Eigen::VectorXd& alpha_star = fixed.alpha_star;
  const double gamma = law.gain();
  const auto basis = p == 1 ? kernel.basis(centres) : nullptr;
  const PointSections sections(kernel, centres);
  const LearningMap learning_map = law.uses_gram_inverse()
                                       ? LearningMap::gram_inverse(fixed.solver, gamma)
                                       : LearningMap::scalar(n, 1.0 / gamma);
  const Eigen::MatrixXd& A = plant.A();
  const Eigen::VectorXd& B = plant.B();
  const Eigen::Index d = A.rows();
  const Eigen::MatrixXd Q = settings.q.for_dimension(d);
  const Eigen::MatrixXd P = solve_lyapunov(A, Q).P;
  set_plant_hypotheses(A, Q, P, out);
  const PlantRoad road(kernel, target, centres, sections, alpha_star, settings.projected_road);

  std::unique_ptr<AdaptiveSystem> made;
  if (p == 1) {
    made =
        std::make_unique<AdaptiveSystem>(A, B, P, *basis, learning_map, road.road, road.road_slope,
                                         domain, 1.0, learning_signal_for(kernel));
    made->set_state_readout(plant);
  } else {
    made = std::make_unique<AdaptiveSystem>(A, B, P, sections, learning_map, plant, road.point_road,
                                            road.point_road_gradient, domain);
  }
  AdaptiveSystem& system = *made;

  // One lap = one forcing period. The breakpoints of a track whose lap takes that long (speed
  // L / period) are the samples and snapshots; no kink restarts (phi(y(t)) has its kinks where
  // the trajectory crosses a knot, not at times known in advance).
  const double final_time =
      settings.final_time > 0 ? settings.final_time : settings.laps * plant.period();
  const double lap_time = plant.period() > 0 ? plant.period() : final_time;
  AdaptiveSettings timing = settings;
  timing.speed = domain.length / lap_time;
  timing.final_time = final_time;
  const auto points = adaptive_breakpoints(timing, domain, 0.0, final_time, {}, false);
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(),
                 [](const auto& breakpoint) { return breakpoint.t; });

  Eigen::VectorXd z0 = Eigen::VectorXd::Zero(system.dimension());
  if (const Eigen::VectorXd& x0 = plant.initial_state(); x0.size() > 0) {
    if (x0.size() != d)
      throw std::invalid_argument(
          fmt::format("the plant's initial state has {} values, expected {}", x0.size(), d));
    z0.head(d) = x0;
    z0.segment(d, d) = x0;
  }

  const auto grid = domain.uniform_points(evaluation_points);
  const auto snapshot_grid = domain.uniform_points(settings.snapshot_points);
  const Eigen::MatrixXd snapshot_cross =
      settings.snapshot_laps.empty() ? Eigen::MatrixXd() : kernel.cross(snapshot_grid, centres);
  const std::function<void(const double*, double*)> evaluate_phi = [&](const double* y,
                                                                       double* phi) {
    if (p == 1)
      basis->evaluate(y[0], phi);
    else
      sections.evaluate(y, phi);
  };
  out.snapshots.resize(settings.snapshot_laps.size());
  for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i)
    out.snapshots[i].lap = settings.snapshot_laps[i];
  TrajectoryObserver seen{system,
                          domain,
                          points,
                          final_time,
                          d,
                          n,
                          alpha_star,
                          P,
                          gamma,
                          law.uses_gram_inverse() ? &fixed.gram : nullptr,
                          evaluate_phi,
                          road,
                          snapshot_cross,
                          out};
  Eigen::VectorXd z = z0;
  const IntegrationStats stats = integrator.integrate(
      system, z, times, [&](std::size_t k, const double* state) { seen.observe(k, state); });
  seen.finish();

  if (p == 1) {
    out.road.resize(snapshot_grid.size());
    for (std::size_t k = 0; k < snapshot_grid.size(); ++k)
      out.road[k] = road.road(snapshot_grid[k]);
  }
  const std::size_t grid_count = domain.point_count(grid);
  Eigen::VectorXd f(static_cast<Eigen::Index>(grid_count));
  for (std::size_t k = 0; k < grid_count; ++k)
    f(static_cast<Eigen::Index>(k)) = road.at(grid.data() + k * static_cast<std::size_t>(p));
  const Eigen::VectorXd alpha = z.tail(n);
  const Eigen::VectorXd estimate = fixed.cross * alpha, projection = fixed.cross * alpha_star;
  const Eigen::VectorXd l2_projection =
      fixed.cross * trajectory_l2_projection(fixed.gram, seen.excitation, seen.excitation_load,
                                             out.metrics[M::gram_condition_number]);
  // Persistence of excitation along the trajectory.
  const GramSpectrum& spectrum = fixed.solver.spectrum();
  const auto level = excitation_level(seen.excitation, fixed.gram, spectrum);
  const Eigen::VectorXd residual = set_shared_metrics(
      {domain, fixed, f, estimate, projection, l2_projection, spectrum, fixed.n, z, d, alpha,
       alpha_star, settings.projected_road, level,
       spectrum.singular ? std::nan("") : static_cast<double>(level.unexcited), !spectrum.singular},
      out);
  set_visited_errors(seen, grid, residual, alpha, out);
  set_integration_floors(
      settings, AdaptiveEngine::time_stepping, domain, estimate, alpha, alpha_star,
      seen.largest_state_pair, d,
      fixed.cross.size() ? fixed.cross.cwiseAbs().rowwise().sum().maxCoeff() : 0.0,
      std::numeric_limits<double>::quiet_NaN(), out);
  out.floors[M::visited_rms_error] = out.floors[M::sup_error];
  set_cost_metrics(stats, system.rhs_evaluations(), system.jacobian_evaluations(), out);
  if (reference) {
    const auto started = std::chrono::steady_clock::now();
    Eigen::VectorXd z_ref = z0;
    reference->integrate(system, z_ref, times,
                         [](std::size_t, const double*) { check_cancelled(); });
    out.reference_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    out.metrics[M::integration_error] =
        integration_error(domain, estimate, fixed.cross * z_ref.tail(n));
  }
  return out;
}

}  // namespace rkhs
