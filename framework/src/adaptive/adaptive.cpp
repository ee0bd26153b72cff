#include "rkhs/adaptive/adaptive.hpp"

#include <fmt/format.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "rkhs/adaptive/averaged_limit.hpp"
#include "rkhs/adaptive/excitation.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/state_dependent.hpp"
#include "rkhs/core/cancellation.hpp"
#include "road_trial.hpp"

namespace rkhs {

std::string describe_integrator(const IntegratorProperties& properties) {
  if (!properties.implicit()) return "explicit";
  return fmt::format("implicit, {} factorisation{} per step, {} stage solves",
                     properties.factorisations_per_step,
                     properties.factorisations_per_step == 1 ? "" : "s",
                     properties.structured_stage_solves ? "structured" : "dense");
}

const std::vector<std::string>& adaptive_metric_names() {
  static const std::vector<std::string> names = metric_table_names<AdaptiveMetric>();
  return names;
}
AdaptiveSystem::LearningSignal learning_signal_for(const AnyKernel& kernel) {
  // A feature basis applies M to its precomputed features, cheaper than M phi for a full M.
  return kernel.feature_count() > 0 ? AdaptiveSystem::LearningSignal::by_basis
                                    : AdaptiveSystem::LearningSignal::from_phi;
}

namespace {

// The reference solution integration_error compares with: the state at the last breakpoint,
// integrated from z = 0 with `reference` through `points` (what the trial's time stepping lands
// on, with the reference's own kink restarts). Observes nothing but cancellation.
Eigen::VectorXd reference_state(AdaptiveSystem& system, const Integrator& reference,
                                const std::vector<Breakpoint>& points) {
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });
  Eigen::VectorXd z = Eigen::VectorXd::Zero(system.dimension());
  reference.integrate(system, z, times,
                      [](std::size_t, const double*) { check_cancelled(); });
  return z;
}

// The values of `basis` at `points`, one row per point, kept sparse (the feature basis is zero
// but for the few features active at a point). O(points x basis size).
Eigen::SparseMatrix<double, Eigen::RowMajor> basis_matrix(const KernelBasis& basis,
                                                          std::span<const double> points) {
  const std::size_t size = basis.size();
  std::vector<double> row(size);
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::size_t m = 0; m < points.size(); ++m) {
    basis.evaluate(points[m], row.data());
    for (std::size_t f = 0; f < size; ++f)
      if (row[f] != 0.0) triplets.emplace_back(static_cast<int>(m), static_cast<int>(f), row[f]);
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> out(static_cast<Eigen::Index>(points.size()),
                                                   static_cast<Eigen::Index>(size));
  out.setFromTriplets(triplets.begin(), triplets.end());
  return out;
}

// The largest sum of |basis values| at a point: how much an error of 1 in every coefficient
// moves the estimate there.
double evaluation_scale(const Eigen::SparseMatrix<double, Eigen::RowMajor>& values) {
  double largest = 0;
  for (Eigen::Index row = 0; row < values.outerSize(); ++row) {
    double sum = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(values, row); it; ++it)
      sum += std::abs(it.value());
    largest = std::max(largest, sum);
  }
  return largest;
}
double evaluation_scale(const Eigen::MatrixXd& values) {
  return values.size() ? values.cwiseAbs().rowwise().sum().maxCoeff() : 0.0;
}

// The law refuses kernels it cannot use, before any work.
bool law_in_features(const LearningLaw& law, const AnyKernel& kernel) {
  law.require_kernel(kernel);
  return law.coordinates() == LawCoordinates::features;
}

}  // namespace

RoadTrial::RoadTrial(const AnyKernel& kernel_, const TargetFunction& target_,
                     std::span<const double> centres_, const Plant& plant_, const LearningLaw& law,
                     const Integrator& integrator_, const AdaptiveSettings& settings_,
                     std::size_t evaluation_points, const SolverOptions& solver_options_,
                     const Integrator* reference)
    : kernel(kernel_),
      target(target_),
      centres(centres_),
      plant(plant_),
      integrator(integrator_),
      settings(settings_),
      solver_options(solver_options_),
      domain(kernel.domain()),
      in_features(law_in_features(law, kernel)),
      fixed(kernel, target, centres, evaluation_points, solver_options) {
  fixed.record(out);
  gamma = law.gain();
  basis = in_features ? kernel.feature_basis() : kernel.basis(centres);
  if (!basis)
    throw std::invalid_argument(fmt::format(
        "the learning law works in feature coordinates, and kernel '{}' has no finite feature map",
        kernel.name()));
  coefficients = static_cast<Eigen::Index>(basis->size());
  // M in its cheapest exact form: Gamma^-1 as a scalar, G^+ of low rank as V diag(w) V^T. In
  // feature coordinates Gamma^-1 I (the H inner product on the range of the features).
  gram_inverse = law.uses_gram_inverse() && !in_features;
  learning_map.emplace(gram_inverse ? LearningMap::gram_inverse(fixed.solver, gamma)
                                    : LearningMap::scalar(coefficients, 1.0 / gamma));
  const Eigen::MatrixXd& A = plant.A();
  d = A.rows();
  const Eigen::MatrixXd Q = settings.q.for_dimension(d);
  P = solve_lyapunov(A, Q).P;
  set_plant_hypotheses(A, Q, P, out);

  // The road that drives the plant: f itself, or its projection Pi_n f (then f lies in H_n).
  road_basis = kernel.basis(centres);
  road_phi.resize(centres.size());
  const Eigen::Index n = fixed.n;
  if (settings.projected_road) {
    road = [this, n](double s) {
      road_basis->evaluate(s, road_phi.data());
      return Eigen::Map<const Eigen::VectorXd>(road_phi.data(), n).dot(fixed.alpha_star);
    };
    road_slope = [this, n](double s) {
      road_basis->evaluate_derivative(s, road_phi.data());
      return Eigen::Map<const Eigen::VectorXd>(road_phi.data(), n).dot(fixed.alpha_star);
    };
  } else {
    road = [&f = target](double s) { return f(s); };
    road_slope = [&f = target](double s) { return f.slope(s); };
  }

  // Feature coordinates apply their scalar map to phi itself (O(F)); a feature basis's
  // set_map would form the F x F identity.
  system.emplace(
      A, plant.B(), P, *basis, *learning_map, road, road_slope, domain, settings.speed,
      in_features ? AdaptiveSystem::LearningSignal::from_phi : learning_signal_for(kernel));
  system->set_shuttle(settings.shuttle_from, settings.shuttle_length);
  kinks = kernel.kink_points();
  if (!settings.projected_road)
    for (double kink : target.kink_points()) kinks.push_back(kink);
  m = system->dimension();
  lap_time = settings.lap_time(domain.length);
  engine = adaptive_engine_for(settings, m);
  out.engine =
      engine == AdaptiveEngine::lap_map ? AdaptiveEngine::lap_map : AdaptiveEngine::time_stepping;
  if (reference && engine != AdaptiveEngine::time_stepping)
    throw std::invalid_argument(
        "a reference integration needs time stepping (engine = \"time_stepping\")");
  set_up_grids(evaluation_points);
  z = Eigen::VectorXd::Zero(m);
}

void RoadTrial::set_up_grids(std::size_t evaluation_points) {
  // The estimate on a grid from the coefficients: the cross matrix of the sections, or the
  // features' values at the grid (sparse).
  grid = domain.uniform_points(evaluation_points);  // the rows of `cross`
  snapshot_grid = domain.uniform_points(settings.snapshot_points);
  if (in_features) {
    const auto evaluation_basis = kernel.feature_basis();
    grid_features = basis_matrix(*evaluation_basis, grid);
    if (!settings.snapshot_laps.empty())
      snapshot_features = basis_matrix(*evaluation_basis, snapshot_grid);
  } else if (!settings.snapshot_laps.empty()) {
    snapshot_cross = kernel.cross(snapshot_grid, centres);
  }
  // The coefficients of the road = "projection" in the law's coordinates: alpha*, or
  // beta* = Phi_c^T alpha* = sum_i alpha*_i psi(c_i), the representation of Pi_n f of least
  // norm (in the range of the features, where ||fhat - Pi_n f||_H = |beta - beta*|).
  coefficients_star = fixed.alpha_star;
  if (in_features) {
    const auto centre_features = basis_matrix(*kernel.feature_basis(), centres);
    coefficients_star = centre_features.transpose() * fixed.alpha_star;
  }
  out.snapshots.resize(settings.snapshot_laps.size());
  for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i)
    out.snapshots[i].lap = settings.snapshot_laps[i];
}

Eigen::VectorXd RoadTrial::on_grid(const Eigen::VectorXd& c) const {
  if (in_features) return grid_features * c;
  return fixed.cross * c;
}

// V = 1/2 e^T P e + 1/2 Gamma (c* - c)^T W (c* - c), W = G (rkhs law) or I (gradient law, and
// feature coordinates: there Gamma |beta* - beta|^2 = Gamma ||Pi_n f - fhat||_H^2).
void RoadTrial::sample(double t, const double* state) {
  out.samples.push_back(adaptive_sample(t, state, d, coefficients_star, P, gamma,
                                        gram_inverse ? &fixed.gram : nullptr, largest_state_pair));
  if (settings.initial_data_dependence && engine == AdaptiveEngine::time_stepping)
    sampled_states.emplace_back(Eigen::Map<const Eigen::VectorXd>(state, m));
}

void RoadTrial::snapshot(std::size_t index, const double* state) {
  const Eigen::Map<const Eigen::VectorXd> alpha(state + 2 * d, coefficients);
  const Eigen::VectorXd estimate = in_features ? Eigen::VectorXd(snapshot_features * alpha)
                                               : Eigen::VectorXd(snapshot_cross * alpha);
  out.snapshots[index].estimate.assign(estimate.data(), estimate.data() + estimate.size());
}

void RoadTrial::integrate(Eigen::VectorXd& state, const std::vector<Breakpoint>& points) {
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });
  auto observe = [&](std::size_t k, const double* at) {
    check_cancelled();  // every breakpoint, also for integrators from plugins
    if (points[k].roles & sample_role) sample(points[k].t, at);
    if (points[k].roles & snapshot_role) snapshot(points[k].snapshot_index, at);
  };
  const auto run = integrator.integrate(*system, state, times, observe);
  stats.steps += run.steps;
  stats.rejected_steps += run.rejected_steps;
  stats.segments += run.segments;
}

void RoadTrial::step_through_time() {
  const double final_time = settings.final_time_or_laps(domain.length);
  if (!(final_time > 0)) throw std::invalid_argument("the final time must be positive");
  integrate(z, adaptive_breakpoints(settings, domain, 0.0, final_time, kinks,
                                    integrator.restarts_at_kinks()));
}

void RoadTrial::measure_final(const Integrator* reference) {
  using M = AdaptiveMetric;
  out.road.resize(snapshot_grid.size());
  for (std::size_t k = 0; k < snapshot_grid.size(); ++k) out.road[k] = road(snapshot_grid[k]);
  Eigen::VectorXd f(static_cast<Eigen::Index>(grid.size()));
  for (std::size_t k = 0; k < grid.size(); ++k) f(static_cast<Eigen::Index>(k)) = road(grid[k]);
  const Eigen::VectorXd alpha = z.tail(coefficients);
  const Eigen::VectorXd estimate = on_grid(alpha);
  const Eigen::VectorXd residual = measure_against_limit(f, alpha, estimate);
  // Whether grid point k lies on the part of the track the path covers (all of it on laps).
  const double from = settings.shuttle_from, to = from + settings.shuttle_length;
  const auto on_path = [&](std::size_t k) {
    return !settings.shuttle() || (grid[k] >= from && grid[k] <= to);
  };
  if (settings.shuttle()) {
    // The error on and off the path's part of the track, on the grid points there (weights
    // L / M: the rectangle rule of the periodic grid, the trapezoid's interior on an interval).
    double on = 0, off = 0;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const double r = residual(static_cast<Eigen::Index>(k));
      (on_path(k) ? on : off) += r * r;
    }
    const double weight = domain.length / static_cast<double>(grid.size());
    out.metrics[M::path_l2_error] = std::sqrt(weight * on);
    out.metrics[M::off_path_l2_error] = std::sqrt(weight * off);
  }
  // Theorem 3's hypothesis (i): at constant speed the time average of k(s(t), s(t)) is its mean
  // over the part of the track the path covers (all of it on laps), so the integral over
  // [0, T] is T times that mean; its floor, the round-off of the kernel's values.
  {
    const Eigen::VectorXd diagonal = kernel.diagonal(grid);
    double sum = 0;
    std::size_t covered = 0;
    for (std::size_t k = 0; k < grid.size(); ++k)
      if (on_path(k)) {
        sum += diagonal(static_cast<Eigen::Index>(k));
        ++covered;
      }
    // In the periodic limit (laps = "limit") the horizon is infinite and so is the integral
    // whenever k(s, s) > 0: NaN, not an overflow.
    const double horizon = settings.final_time_or_laps(domain.length);
    if (covered > 0 && std::isfinite(horizon)) {
      out.metrics[M::kernel_diagonal_l1] = horizon * sum / static_cast<double>(covered);
      out.floors[M::kernel_diagonal_l1] = 4.0 * std::numeric_limits<double>::epsilon() *
                                          std::abs(out.metrics[M::kernel_diagonal_l1]);
    }
  }
  set_decay_rates();
  set_integration_floors(
      settings, engine, domain, estimate, alpha, coefficients_star, largest_state_pair, d,
      in_features ? evaluation_scale(grid_features) : evaluation_scale(fixed.cross),
      radius_uncertainty, out);
  set_lap_map_floors();
  set_cost_metrics(stats, system->rhs_evaluations() + reused_rhs_evaluations,
                   system->jacobian_evaluations() + reused_jacobian_evaluations, out);
  // After the cost metrics: the reference's evaluations are not the trial's.
  if (reference) set_integration_error(*reference, estimate);
}

Eigen::VectorXd RoadTrial::measure_against_limit(const Eigen::VectorXd& f,
                                                 const Eigen::VectorXd& alpha,
                                                 const Eigen::VectorXd& estimate) {
  // P_L2 f, the averaged (v -> 0) limit of the law, on the same grid: onto H_n, or onto H
  // itself in feature coordinates. Its E = Mbar gives the excitation of the same space.
  // Over the path's part of the track: the shuttle's time average is uniform there.
  AveragedLimitQuadrature on_path;
  on_path.range_from = settings.shuttle_from;
  on_path.range_length = settings.shuttle_length;
  const auto limit = in_features
                         ? averaged_limit_in_features(kernel, road, kinks, on_path)
                         : averaged_limit(kernel, centres, road, kinks, solver_options, on_path);
  const Eigen::VectorXd l2_projection = on_grid(limit.coefficients);
  if (!limit.quadrature_converged) out.flags.push_back("l2_projection_unconverged");
  // pe_level (rkhs/adaptive/excitation.hpp): NaN with a singular G (the trial is flagged
  // gram_singular already); flagged pe_level_unresolved when its round-off estimate exceeds 1%
  // of it (NaN when it exceeds all of it), or in feature coordinates when the smallest nonzero
  // eigenvalue of E is not separated from its zeros (NaN).
  const GramSpectrum& spectrum = fixed.solver.spectrum();
  const auto excitation = in_features ? excitation_level_on_range(limit.averaged_gram_eigenvalues)
                                      : excitation_level(limit.averaged_gram, fixed.gram, spectrum);
  // Directions a shuttle leaves unexcited (on laps around the track there are none: E is
  // positive definite with G): in H_n the pencil's eigenvalues at their round-off, NaN with a
  // singular G; in H the rank E lacks against the whole track's E.
  double unexcited = 0;
  if (settings.shuttle()) {
    if (in_features)
      unexcited = static_cast<double>(
          excitation_level_on_range(
              averaged_limit_in_features(kernel, road, kinks).averaged_gram_eigenvalues)
              .dimension -
          excitation.dimension);
    else
      unexcited = spectrum.singular ? std::numeric_limits<double>::quiet_NaN()
                                    : static_cast<double>(excitation.unexcited);
  }
  const Eigen::VectorXd projection = fixed.cross * fixed.alpha_star;
  return set_shared_metrics(
      {domain, fixed, f, estimate, projection, l2_projection, limit.solved_spectrum,
       static_cast<Eigen::Index>(limit.coefficients.size()), z, d, alpha, coefficients_star,
       settings.projected_road, excitation, unexcited, in_features || !spectrum.singular},
      out);
}

void RoadTrial::set_decay_rates() {
  // The decay of ||f~||_H against the PE level: the lap map's slowest learning mode per second,
  // and the averaged law's slowest rate H(0) pe_level / Gamma (docs/model.md section 14), the
  // rkhs law's and rkhs_embedding's (the gradient law's W = I makes its rate another pencil's).
  // The rate's error from the map's: an error delta in the radius is delta / radius in
  // ln(radius). Beyond 1% of the rate it is flagged, beyond all of it the rate is NaN.
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  const double radius = metrics[M::learning_spectral_radius];
  bool unresolved = false;
  if (std::isfinite(radius) && radius > 0 && radius < 1) {
    const double rate_per_lap = -std::log(radius);
    const double error_per_lap = radius_uncertainty / radius;
    unresolved = !(error_per_lap <= 0.01 * rate_per_lap);
    if (error_per_lap < rate_per_lap) {
      metrics[M::learning_decay_rate] = rate_per_lap / lap_time;
      out.floors[M::learning_decay_rate] = error_per_lap / lap_time;
    }
  }
  if (unresolved) out.flags.push_back("decay_rate_unresolved");
  if (gram_inverse || in_features) {
    const Eigen::MatrixXd& A = plant.A();
    const Eigen::VectorXd& B = plant.B();
    const double dc_gain = B.dot(P * A.partialPivLu().solve(-B));  // H(0) = B^T P (-A)^-1 B
    metrics[M::averaged_decay_rate] = dc_gain * metrics[M::pe_level] / gamma;
    out.floors[M::averaged_decay_rate] = std::abs(dc_gain) * out.floors[M::pe_level] / gamma;
  }
  if (metrics[M::averaged_decay_rate] > 0) {
    metrics[M::pe_decay_ratio] = metrics[M::learning_decay_rate] / metrics[M::averaged_decay_rate];
    out.floors[M::pe_decay_ratio] =
        metrics[M::pe_decay_ratio] *
        (out.floors[M::learning_decay_rate] / metrics[M::learning_decay_rate] +
         out.floors[M::averaged_decay_rate] / metrics[M::averaged_decay_rate]);
    const auto& flags = out.flags;
    if (!unresolved && std::find(flags.begin(), flags.end(), "pe_level_unresolved") != flags.end())
      out.flags.push_back("decay_rate_unresolved");
  }
}

void RoadTrial::set_lap_map_floors() {
  using M = AdaptiveMetric;
  if (lap_map_spread.size() != m) return;
  const Eigen::VectorXd estimate_spread = on_grid(lap_map_spread.tail(coefficients));
  const double l2_floor = domain.l2_norm(std::span<const double>(
      estimate_spread.data(), static_cast<std::size_t>(estimate_spread.size())));
  for (const M metric : {M::l2_error, M::gap_to_projection, M::gap_to_l2_projection,
                         M::path_l2_error, M::off_path_l2_error})
    out.floors[metric] = l2_floor;
  out.floors[M::sup_error] = estimate_spread.cwiseAbs().maxCoeff();
  out.floors[M::coefficient_error] =
      lap_map_spread.tail(coefficients).norm() / std::max(coefficients_star.norm(), 1e-300);
  out.floors[M::final_state_error] = lap_map_spread.head(2 * d).norm();
}

void RoadTrial::set_integration_error(const Integrator& reference,
                                      const Eigen::VectorXd& estimate) {
  const double final_time = settings.final_time_or_laps(domain.length);
  const auto started = std::chrono::steady_clock::now();
  const Eigen::VectorXd z_ref = reference_state(
      *system, reference,
      adaptive_breakpoints(settings, domain, 0.0, final_time, kinks, reference.restarts_at_kinks(),
                           /*snapshots=*/true));
  out.reference_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  out.metrics[AdaptiveMetric::integration_error] =
      integration_error(domain, estimate, on_grid(z_ref.tail(coefficients)));
}

AdaptiveMeasurement measure_adaptive(const AnyKernel& kernel, const TargetFunction& target,
                                     std::span<const double> centres, const Plant& plant,
                                     const LearningLaw& law, const Integrator& integrator,
                                     const AdaptiveSettings& settings,
                                     std::size_t evaluation_points,
                                     const SolverOptions& solver_options,
                                     const Integrator* reference, LapMapCache* lap_maps,
                                     const std::string& lap_map_key) {
  if (plant.state_dependent())  // f of the plant's state: no track, no lap map
    return measure_state_dependent(kernel, target, centres, plant, law, integrator, settings,
                                   evaluation_points, solver_options, reference);
  RoadTrial trial(kernel, target, centres, plant, law, integrator, settings, evaluation_points,
                  solver_options, reference);
  if (trial.engine == AdaptiveEngine::time_stepping)
    trial.step_through_time();
  else
    trial.run_lap_map(lap_maps, lap_map_key);
  trial.measure_final(reference);
  if (settings.initial_data_dependence) trial.measure_initial_data_dependence();
  return std::move(trial.out);
}

}  // namespace rkhs
