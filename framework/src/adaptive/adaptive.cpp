#include "rkhs/adaptive/adaptive.hpp"

#include <Eigen/Sparse>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/adaptive/averaged_limit.hpp"
#include "rkhs/adaptive/breakpoints.hpp"
#include "rkhs/adaptive/excitation.hpp"
#include "rkhs/adaptive/lap_map.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/state_dependent.hpp"

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

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

bool whole(double laps) { return laps >= 1 && laps == std::floor(laps) && laps < 9.2e18; }

}  // namespace

std::vector<double> path_kink_times(const AdaptiveSettings& settings, const Domain& domain,
                                    const std::vector<double>& kinks) {
  std::vector<double> out;
  const double v = settings.speed;
  if (!settings.shuttle()) {
    for (double kink : kinks) out.push_back(kink / v);
  } else {
    // Out at (k - from) / v and back at (2l - (k - from)) / v; the turning point l / v, where
    // s'(t) jumps, is one too (t = 0 starts every lap anyway).
    const double from = settings.shuttle_from, l = settings.shuttle_length;
    out.push_back(l / v);
    for (double kink : kinks) {
      for (double shift : {0.0, domain.length, -domain.length}) {  // a periodic track's images
        const double u = kink + shift - from;
        if (u > 0 && u < l) {
          out.push_back(u / v);
          out.push_back((2 * l - u) / v);
        }
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<Breakpoint> adaptive_breakpoints(const AdaptiveSettings& settings,
                                             const Domain& domain, double start, double end,
                                             const std::vector<double>& kinks,
                                             bool restart_at_kinks, bool snapshots) {
  std::vector<Breakpoint> points{{start, sample_role, 0}};
  const double lap_time = settings.lap_time(domain.length);
  const double laps_total = (end - start) / lap_time;
  const double sample_count =
      std::max(1.0, std::ceil(laps_total * static_cast<double>(settings.samples_per_lap)));
  const auto in_lap =
      restart_at_kinks ? path_kink_times(settings, domain, kinks) : std::vector<double>{};
  const double kink_count = std::ceil(laps_total) * static_cast<double>(in_lap.size());
  if (!(sample_count + kink_count <= static_cast<double>(max_breakpoints)))
    throw std::length_error(fmt::format(
        "{:.6g} laps stepped through time need {:.3g} breakpoints ({} output samples per lap{}), "
        "more than the {} the time-stepping engine holds; the lap map, whose cost does not "
        "grow with the horizon, takes a whole number of laps below 9.2e18 or laps = \"limit\" "
        "(without final_time)",
        laps_total, sample_count + kink_count, settings.samples_per_lap,
        in_lap.empty() ? "" : fmt::format(" and {} kinks", in_lap.size()), max_breakpoints));
  const auto samples = static_cast<std::size_t>(sample_count);
  for (std::size_t k = 1; k <= samples; ++k) {
    if (k % 65536 == 0) check_cancelled();
    points.push_back(
        {start + (end - start) * static_cast<double>(k) / static_cast<double>(samples),
         sample_role, 0});
  }
  if (snapshots)
    for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i) {
      const double t = settings.snapshot_laps[i] * lap_time;
      if (t <= end * (1 + 1e-12)) points.push_back({std::min(t, end), snapshot_role, i});
    }
  if (restart_at_kinks) {
    for (double lap = std::floor(start / lap_time); lap * lap_time < end; ++lap)
      for (double kink_time : in_lap) {
        const double t = lap * lap_time + kink_time;
        if (t > start && t < end) points.push_back({t, 0, 0});
      }
  }
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  std::vector<Breakpoint> merged;
  const double tolerance = 1e-12 * end;
  for (const auto& p : points) {
    if (!merged.empty() && p.t - merged.back().t <= tolerance) {
      merged.back().roles |= p.roles;
      if (p.roles & snapshot_role) merged.back().snapshot_index = p.snapshot_index;
    } else {
      merged.push_back(p);
    }
  }
  return merged;
}

AdaptiveEngine adaptive_engine_for(const AdaptiveSettings& settings, Eigen::Index dimension) {
  const bool applies = settings.final_time <= 0 &&
                       (settings.limit() || whole(settings.laps)) &&
                       std::all_of(settings.snapshot_laps.begin(), settings.snapshot_laps.end(),
                                   [](double lap) { return whole(lap); });
  switch (settings.engine) {
    case AdaptiveEngine::time_stepping:
      if (settings.limit())
        throw std::invalid_argument("laps = \"limit\" needs the lap map (engine = \"time_stepping\")");
      return AdaptiveEngine::time_stepping;
    case AdaptiveEngine::lap_map:
      if (!applies)
        throw std::invalid_argument(
            "the lap map needs a whole number of laps (or \"limit\"), no final_time and whole "
            "snapshot laps");
      return AdaptiveEngine::lap_map;
    case AdaptiveEngine::automatic:
      break;
  }
  if (settings.limit() && !applies)
    throw std::invalid_argument(
        "laps = \"limit\" needs the lap map: no final_time and whole snapshot laps");
  return applies && (settings.limit() || settings.laps > static_cast<double>(dimension + 1))
             ? AdaptiveEngine::lap_map
             : AdaptiveEngine::time_stepping;
}

namespace {

// The smallest N >= 0 with distance(N) <= fraction distance(0), found by doubling and then
// bisection (it assumes distance(N) stays below the fraction once it is there, as it does
// for the contracting learning dynamics). Empty when not reached by `cap` laps (or 2^62).
template <class Distance>
std::optional<std::uint64_t> laps_within(Distance&& distance, double fraction, std::uint64_t cap) {
  const double target = fraction * distance(0);
  if (!(target > 0)) return 0;
  std::uint64_t high = 1;
  while (distance(high) > target) {
    if (high >= cap || high >= (std::uint64_t{1} << 62)) return std::nullopt;
    high *= 2;
  }
  std::uint64_t low = high / 2;  // distance(low) > target, or low = 0
  while (high - low > 1) {
    const std::uint64_t middle = low + (high - low) / 2;
    (distance(middle) > target ? low : high) = middle;
  }
  return high;
}

// The most laps whose powers of the lap map still say something about the limit: 50 time
// constants of its slowest excited mode (e^-50 = 2e-22 of what it had), and at least 2 m laps
// (a nilpotent part of an m x m map is gone after m). Beyond them what is left of
// fhat - fhat(limit) is the map's own error along its unexcited directions (eigenvalues 1 up
// to lap_map_rtol) raised to the power of the lap count, which overflows: persistence of
// excitation's unexcited paths gave 2.9e17 laps and a sampled state error of +inf. 2^62 for a
// map that does not contract (no finite time constant).
std::uint64_t meaningful_laps(double slowest_time_constant_laps, Eigen::Index dimension) {
  constexpr auto most = std::uint64_t{1} << 62;
  if (!std::isfinite(slowest_time_constant_laps)) return most;
  const double laps =
      std::max(50.0 * slowest_time_constant_laps, 2.0 * static_cast<double>(dimension));
  return laps >= static_cast<double>(most) ? most : static_cast<std::uint64_t>(std::ceil(laps));
}

// Lap numbers 2 .. laps - 2 at which the lap map's state is sampled: every lap up to 200 laps,
// beyond that about 50 per decade (rounded to whole laps).
std::vector<std::uint64_t> lap_boundaries(std::uint64_t laps) {
  std::vector<std::uint64_t> out;
  if (laps < 4) return out;
  const std::uint64_t last = laps - 2;
  if (last <= 200) {
    for (std::uint64_t k = 2; k <= last; ++k) out.push_back(k);
    return out;
  }
  for (double x = std::log10(2.0); x <= std::log10(static_cast<double>(last)); x += 0.02) {
    const auto k = static_cast<std::uint64_t>(std::llround(std::pow(10.0, x)));
    if (out.empty() || k > out.back()) out.push_back(std::min(k, last));
  }
  if (out.back() != last) out.push_back(last);
  return out;
}

}  // namespace

namespace {

// The state at the last breakpoint, integrated from z = 0 with `reference` through `points`
// (what the trial's time stepping lands on, with the reference's own kink restarts): the
// reference solution integration_error compares with. Observes nothing but cancellation.
Eigen::VectorXd reference_state(AdaptiveSystem& system, const Integrator& reference,
                                const std::vector<Breakpoint>& points) {
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });
  Eigen::VectorXd z = Eigen::VectorXd::Zero(system.dimension());
  reference.integrate(system, z, times,
                      [](std::size_t, const double*) { check_cancelled(); });
  return z;
}

}  // namespace

namespace {

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


}  // namespace

void set_integration_floors(const AdaptiveSettings& settings, AdaptiveEngine engine,
                            const Domain& domain, const Eigen::VectorXd& estimate,
                            const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star,
                            double largest_state_pair, Eigen::Index d, double basis_scale,
                            double radius_uncertainty, AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  auto& floors = out.floors;
  const double radius = metrics[M::learning_spectral_radius];
  if (engine == AdaptiveEngine::lap_map && radius > 0 && radius < 1) {
    floors[M::learning_spectral_radius] = radius_uncertainty;
    const double log_radius = std::log(radius);
    floors[M::slowest_time_constant_laps] = radius_uncertainty / (radius * log_radius * log_radius);
    floors[M::laps_to_limit] =
        metrics[M::laps_to_limit] * radius_uncertainty / (radius * std::abs(log_radius));
  }
  // The lap map's state comes from its powers or limit, whose floors the caller measures
  // (measure_adaptive); the integrator's tolerances give the samples' (max_state_error, V).
  const double rtol = settings.integrator_rtol, atol = settings.integrator_atol;
  if (!(rtol > 0 && atol >= 0 && std::isfinite(rtol) && std::isfinite(atol))) return;
  const auto l2 = [&](const Eigen::VectorXd& v) {
    return domain.l2_norm(std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
  };
  const double l2_floor = rtol * l2(estimate) + atol * basis_scale * std::sqrt(domain.volume());
  for (const M metric : {M::l2_error, M::gap_to_projection, M::gap_to_l2_projection,
                         M::path_l2_error, M::off_path_l2_error})
    floors[metric] = l2_floor;
  floors[M::sup_error] =
      rtol * (estimate.size() ? estimate.cwiseAbs().maxCoeff() : 0.0) + atol * basis_scale;
  floors[M::coefficient_error] =
      (rtol * alpha.norm() + atol * std::sqrt(static_cast<double>(alpha.size()))) /
      std::max(alpha_star.norm(), 1e-300);
  const double state_floor = rtol * largest_state_pair + atol * std::sqrt(2.0 * static_cast<double>(d));
  floors[M::final_state_error] = state_floor;
  floors[M::max_state_error] = state_floor;
  if (!out.samples.empty() && out.samples.front().lyapunov > 0) {
    double largest = 0;
    for (const auto& sample : out.samples) largest = std::max(largest, sample.lyapunov);
    // V is quadratic in the state: twice its relative tolerance.
    const double lyapunov_floor = 2 * rtol * largest / out.samples.front().lyapunov;
    floors[M::lyapunov_ratio] = lyapunov_floor;
    floors[M::lyapunov_max_increase] = lyapunov_floor;
  }
  floors[M::lap_map_residual] = rtol;
}

void set_static_floors(const ApproximationMeasurement& approximation, const GramSpectrum& spectrum,
                       Eigen::Index n, double l2_projection_l2, double l2_projection_sup,
                       AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  using Static = ApproximationMetric;
  for (auto [adaptive, static_metric] :
       {std::pair{M::gram_condition_number, Static::gram_condition_number},
        {M::power_function_sup, Static::power_function_sup},
        {M::interpolant_l2_error, Static::l2_error},
        {M::interpolant_sup_error, Static::sup_error}})
    out.floors[adaptive] = approximation.floors[static_metric];
  const double relative = solve_round_off(spectrum, n);
  out.floors[M::l2_projection_l2_error] = relative * l2_projection_l2;
  out.floors[M::l2_projection_sup_error] = relative * l2_projection_sup;
}

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
                                     const SolverOptions& solver_options,
                                     const Integrator* reference, LapMapCache* lap_maps,
                                     const std::string& lap_map_key) {
  if (plant.state_dependent())  // f of the plant's state: no track, no lap map
    return measure_state_dependent(kernel, target, centres, plant, law, integrator, settings,
                                   evaluation_points, solver_options, reference);
  law.require_kernel(kernel);  // before any work: the law refuses kernels it cannot use
  const Domain& domain = kernel.domain();
  const auto n = static_cast<Eigen::Index>(centres.size());
  // The law's coordinates: alpha over the n sections at the centres, or beta over the kernel's
  // F features (rkhs_embedding: H itself; the centres then define only the static part, Pi_n f
  // and the road = "projection").
  const bool in_features = law.coordinates() == LawCoordinates::features;
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
  // The estimator's basis: the sections k(c_i, .) (n), or the features psi_f (F).
  const auto basis = in_features ? kernel.feature_basis() : kernel.basis(centres);
  if (!basis)
    throw std::invalid_argument(fmt::format(
        "the learning law works in feature coordinates, and kernel '{}' has no finite feature map",
        kernel.name()));
  const auto coefficients = static_cast<Eigen::Index>(basis->size());  // n, or F
  // M in its cheapest exact form: Gamma^-1 as a scalar, G^+ of low rank as V diag(w) V^T. In
  // feature coordinates Gamma^-1 I (the H inner product on the range of the features).
  const bool gram_inverse = law.uses_gram_inverse() && !in_features;
  const LearningMap learning_map = gram_inverse ? LearningMap::gram_inverse(solver, gamma)
                                                : LearningMap::scalar(coefficients, 1.0 / gamma);
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
  const auto road_basis = kernel.basis(centres);
  std::vector<double> road_phi(centres.size());
  const std::function<double(double)> road =
      settings.projected_road ? std::function<double(double)>([&](double s) {
        road_basis->evaluate(s, road_phi.data());
        return Eigen::Map<const Eigen::VectorXd>(road_phi.data(), n).dot(alpha_star);
      })
                              : std::function<double(double)>([&](double s) { return target(s); });
  const std::function<double(double)> road_slope =
      settings.projected_road ? std::function<double(double)>([&](double s) {
        road_basis->evaluate_derivative(s, road_phi.data());
        return Eigen::Map<const Eigen::VectorXd>(road_phi.data(), n).dot(alpha_star);
      })
                              : std::function<double(double)>(
                                    [&](double s) { return target.slope(s); });

  // Feature coordinates apply their scalar map to phi itself (O(F)); a feature basis's
  // set_map would form the F x F identity.
  AdaptiveSystem system(
      A, B, P, *basis, learning_map, road, road_slope, domain, settings.speed,
      in_features ? AdaptiveSystem::LearningSignal::from_phi : learning_signal_for(kernel));
  system.set_shuttle(settings.shuttle_from, settings.shuttle_length);
  auto kinks = kernel.kink_points();  // of phi(s), and of f (a sampled road)
  if (!settings.projected_road)
    for (double kink : target.kink_points()) kinks.push_back(kink);
  const Eigen::Index m = system.dimension();
  const double lap_time = settings.lap_time(domain.length);
  const AdaptiveEngine engine = adaptive_engine_for(settings, m);
  double radius_uncertainty = std::numeric_limits<double>::quiet_NaN();  // lap map only
  out.engine = engine == AdaptiveEngine::lap_map ? "lap_map" : "time_stepping";
  if (reference && engine != AdaptiveEngine::time_stepping)
    throw std::invalid_argument(
        "a reference integration needs time stepping (engine = \"time_stepping\")");

  // The estimate on a grid from the coefficients: the cross matrix of the sections, or the
  // features' values at the grid (sparse).
  const auto grid = domain.uniform_points(evaluation_points);  // the rows of `cross`
  const auto snapshot_grid = domain.uniform_points(settings.snapshot_points);
  Eigen::SparseMatrix<double, Eigen::RowMajor> grid_features, snapshot_features;
  Eigen::MatrixXd snapshot_cross;
  if (in_features) {
    const auto evaluation_basis = kernel.feature_basis();
    grid_features = basis_matrix(*evaluation_basis, grid);
    if (!settings.snapshot_laps.empty())
      snapshot_features = basis_matrix(*evaluation_basis, snapshot_grid);
  } else if (!settings.snapshot_laps.empty()) {
    snapshot_cross = kernel.cross(snapshot_grid, centres);
  }
  auto on_grid = [&](const Eigen::VectorXd& c) -> Eigen::VectorXd {
    if (in_features) return grid_features * c;
    return cross * c;
  };
  // The coefficients of the road = "projection" in the law's coordinates: alpha*, or
  // beta* = Phi_c^T alpha* = sum_i alpha*_i psi(c_i), the representation of Pi_n f of least
  // norm (in the range of the features, where ||fhat - Pi_n f||_H = |beta - beta*|).
  Eigen::VectorXd coefficients_star = alpha_star;
  if (in_features) {
    const auto centre_features = basis_matrix(*kernel.feature_basis(), centres);
    coefficients_star = centre_features.transpose() * alpha_star;
  }

  // V = 1/2 e^T P e + 1/2 Gamma (c* - c)^T W (c* - c), W = G (rkhs law) or I (gradient law, and
  // feature coordinates: there Gamma |beta* - beta|^2 = Gamma ||Pi_n f - fhat||_H^2).
  double largest_state_pair = 0;  // max over the samples of |x| + |xhat| (the floors' scale)
  out.snapshots.resize(settings.snapshot_laps.size());
  for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i)
    out.snapshots[i].lap = settings.snapshot_laps[i];
  auto sample = [&](double t, const double* z) {
    const Eigen::Map<const Eigen::VectorXd> x(z, d), xhat(z + d, d), alpha(z + 2 * d, coefficients);
    const Eigen::VectorXd e = x - xhat;
    const Eigen::VectorXd coefficient_gap = coefficients_star - alpha;
    const double weighted =
        gram_inverse ? coefficient_gap.dot(gram * coefficient_gap) : coefficient_gap.squaredNorm();
    out.samples.push_back({t, e.norm(), 0.5 * e.dot(P * e) + 0.5 * gamma * weighted});
    largest_state_pair = std::max(largest_state_pair, x.norm() + xhat.norm());
  };
  auto snapshot = [&](std::size_t index, const double* z) {
    const Eigen::Map<const Eigen::VectorXd> alpha(z + 2 * d, coefficients);
    const Eigen::VectorXd estimate = in_features ? Eigen::VectorXd(snapshot_features * alpha)
                                                 : Eigen::VectorXd(snapshot_cross * alpha);
    out.snapshots[index].estimate.assign(estimate.data(), estimate.data() + estimate.size());
  };
  // Integrates from z at t = start through `points` (times from start on) with the study's
  // integrator, sampling and taking snapshots where the points say.
  IntegrationStats stats;
  auto integrate = [&](Eigen::VectorXd& z, const std::vector<Breakpoint>& points) {
    std::vector<double> times(points.size());
    std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });
    auto observe = [&](std::size_t k, const double* state) {
      check_cancelled();  // every breakpoint, also for integrators from plugins
      if (points[k].roles & sample_role) sample(points[k].t, state);
      if (points[k].roles & snapshot_role) snapshot(points[k].snapshot_index, state);
    };
    const auto run = integrator.integrate(system, z, times, observe);
    stats.steps += run.steps;
    stats.rejected_steps += run.rejected_steps;
    stats.segments += run.segments;
  };

  Eigen::VectorXd z = Eigen::VectorXd::Zero(m);
  Eigen::VectorXd lap_map_spread;  // lap map: z from the perturbed map minus z (the floors)
  std::shared_ptr<const LapMap> lap_map;
  std::size_t reused_rhs_evaluations = 0, reused_jacobian_evaluations = 0;
  if (engine == AdaptiveEngine::time_stepping) {
    const double final_time = settings.final_time_or_laps(domain.length);
    if (!(final_time > 0)) throw std::invalid_argument("the final time must be positive");
    integrate(z, adaptive_breakpoints(settings, domain, 0.0, final_time, kinks,
                             integrator.restarts_at_kinks()));
  } else {
    // One lap as an affine map, then N laps (or the limit) through its powers. Samples: the
    // first lap and, for N laps, the last lap integrated with the study's integrator from the
    // state the map gives (the last lap's end checks the map: lap_map_residual), and the lap
    // boundaries in between from the map.
    const auto kink_times = path_kink_times(settings, domain, kinks);
    auto compute = [&] {
      return compute_lap_map(system, lap_time, kink_times, settings.lap_map_atol,
                             settings.lap_map_rtol, std::numeric_limits<std::int64_t>::max());
    };
    bool computed_here = true;
    if (lap_maps) {
      auto found = lap_maps->find_or_compute(lap_map_key, compute);
      lap_map = std::move(found.map);
      computed_here = found.computed_here;
    } else {
      lap_map = std::make_shared<const LapMap>(compute());
    }
    // A map computed by another trial: its cost is this trial's too (deterministic counts).
    if (!computed_here) {
      reused_rhs_evaluations = lap_map->rhs_evaluations;
      reused_jacobian_evaluations = lap_map->jacobian_evaluations;
    }
    stats.steps += lap_map->stats.steps;
    stats.rejected_steps += lap_map->stats.rejected_steps;
    stats.segments += lap_map->stats.segments;
    check_cancelled();
    const LapPowers powers(*lap_map);
    const Eigen::VectorXd z0 = z;
    const auto limit = periodic_limit(*lap_map, z0, d, 100 * settings.lap_map_rtol,
                                      settings.lap_map_rtol);
    metrics[M::learning_spectral_radius] = limit.spectral_radius;
    radius_uncertainty = limit.spectral_radius_uncertainty;
    metrics[M::slowest_time_constant_laps] = limit.slowest_time_constant_laps;
    metrics[M::unexcited_directions] = static_cast<double>(limit.unexcited_directions);
    for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i)
      if (settings.limit() || settings.snapshot_laps[i] <= settings.laps)  // the ones reached
        snapshot(i,
                 powers.advance(z0, static_cast<std::uint64_t>(settings.snapshot_laps[i])).data());
    // Laps until fhat is within 1% (in L2 on the evaluation grid) of its limit.
    auto distance_to_limit = [&](std::uint64_t laps) {
      const Eigen::VectorXd state = powers.advance(z0, laps);
      const Eigen::VectorXd gap =
          on_grid(state.tail(coefficients) - limit.state.tail(coefficients));
      return domain.l2_norm(
          std::span<const double>(gap.data(), static_cast<std::size_t>(gap.size())));
    };
    const std::uint64_t laps_cap = meaningful_laps(limit.slowest_time_constant_laps, m);
    const auto laps_to_limit = laps_within(distance_to_limit, 0.01, laps_cap);
    if (laps_to_limit)
      metrics[M::laps_to_limit] = static_cast<double>(*laps_to_limit);
    else
      out.flags.push_back("laps_to_limit_unresolved");

    Eigen::VectorXd first = z0;
    integrate(first, adaptive_breakpoints(settings, domain, 0.0, lap_time, kinks,
                                 integrator.restarts_at_kinks(), /*snapshots=*/false));
    const std::uint64_t laps = settings.limit()
                                   ? std::max<std::uint64_t>(2, laps_to_limit.value_or(laps_cap))
                                   : static_cast<std::uint64_t>(settings.laps);
    for (std::uint64_t k : lap_boundaries(laps))
      sample(static_cast<double>(k) * lap_time, powers.advance(z0, k).data());
    if (settings.limit()) {
      z = limit.state;
    } else {
      z = powers.advance(z0, laps);
      if (laps >= 2) {
        // The system is periodic: the last lap is integrated over [0, T] (at t near N T the
        // spacing of doubles would be coarser than the plant's transients need) and its samples
        // are shifted to where they belong.
        Eigen::VectorXd last = powers.advance(z0, laps - 1);
        const double start = static_cast<double>(laps - 1) * lap_time;
        const std::size_t first_sample = out.samples.size();
        integrate(last, adaptive_breakpoints(settings, domain, 0.0, lap_time, kinks,
                                    integrator.restarts_at_kinks(), /*snapshots=*/false));
        for (std::size_t k = first_sample; k < out.samples.size(); ++k) out.samples[k].t += start;
        metrics[M::lap_map_residual] = (last - z).norm() / std::max(z.norm(), 1e-300);
      } else {
        metrics[M::lap_map_residual] = (first - z).norm() / std::max(z.norm(), 1e-300);
      }
    }
    std::sort(out.samples.begin(), out.samples.end(),
              [](const auto& a, const auto& b) { return a.t < b.t; });
    // The floor of what the map's powers or limit give: the same state from the map perturbed
    // by its tolerance, entry by entry with alternating signs (the spread under a perturbation
    // of its inputs, a sample rather than a bound; 1 / (1 - rho) times the tolerance bounds it
    // but is orders of magnitude too pessimistic along the slow learning mode).
    LapMap perturbed = *lap_map;
    for (Eigen::Index j = 0; j < perturbed.monodromy.cols(); ++j)
      for (Eigen::Index i = 0; i < perturbed.monodromy.rows(); ++i)
        perturbed.monodromy(i, j) *= 1.0 + ((i + j) % 2 ? -1.0 : 1.0) * settings.lap_map_rtol;
    for (Eigen::Index i = 0; i < perturbed.offset.size(); ++i)
      perturbed.offset(i) *= 1.0 + (i % 2 ? -1.0 : 1.0) * settings.lap_map_rtol;
    Eigen::VectorXd z_perturbed;
    if (settings.limit()) {
      z_perturbed =
          periodic_limit(perturbed, z0, d, 100 * settings.lap_map_rtol, settings.lap_map_rtol)
              .state;
    } else {
      // N laps by squaring, one power at a time (no table of powers: no more memory than the
      // map itself).
      z_perturbed = z0;
      Eigen::MatrixXd power = perturbed.monodromy;
      Eigen::VectorXd shift = perturbed.offset;  // z -> power z + shift is the map to the 2^k
      for (std::uint64_t left = laps; left != 0; left >>= 1) {
        if (left & 1u) z_perturbed = (power * z_perturbed + shift).eval();
        if (left > 1) {
          shift = (power * shift + shift).eval();
          power = (power * power).eval();
        }
      }
    }
    lap_map_spread = z_perturbed - z;
  }
  out.road.resize(snapshot_grid.size());
  for (std::size_t k = 0; k < snapshot_grid.size(); ++k) out.road[k] = road(snapshot_grid[k]);

  // Errors at T on the M-point grid.
  Eigen::VectorXd f(static_cast<Eigen::Index>(grid.size()));
  for (std::size_t k = 0; k < grid.size(); ++k) f(static_cast<Eigen::Index>(k)) = road(grid[k]);
  const Eigen::VectorXd alpha = z.tail(coefficients);
  const Eigen::VectorXd estimate = on_grid(alpha), projection = cross * alpha_star;
  auto l2 = [&](const Eigen::VectorXd& v) {
    return domain.l2_norm(std::span<const double>(v.data(), static_cast<std::size_t>(v.size())));
  };
  const Eigen::VectorXd interpolant_residual = f - projection, residual = f - estimate;
  metrics[M::interpolant_l2_error] = l2(interpolant_residual);
  metrics[M::interpolant_sup_error] = interpolant_residual.cwiseAbs().maxCoeff();
  metrics[M::l2_error] = l2(residual);
  metrics[M::sup_error] = residual.cwiseAbs().maxCoeff();
  metrics[M::gap_to_projection] = l2(estimate - projection);
  if (settings.shuttle()) {
    // The error on and off the path's part of the track, on the grid points there (weights
    // L / M: the rectangle rule of the periodic grid, the trapezoid's interior on an interval).
    const double from = settings.shuttle_from, to = from + settings.shuttle_length;
    double on = 0, off = 0;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const double r = residual(static_cast<Eigen::Index>(k));
      (grid[k] >= from && grid[k] <= to ? on : off) += r * r;
    }
    const double weight = domain.length / static_cast<double>(grid.size());
    metrics[M::path_l2_error] = std::sqrt(weight * on);
    metrics[M::off_path_l2_error] = std::sqrt(weight * off);
  }
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
        (alpha - coefficients_star).norm() / std::max(coefficients_star.norm(), 1e-300);
    metrics[M::lyapunov_max_increase] = v0 > 0 ? max_increase / v0 : max_increase;
    metrics[M::lyapunov_ratio] = v0 > 0 ? out.samples.back().lyapunov / v0 : nan;
  }
  std::pair<double, double> l2_projection_scale{nan, nan};  // ||P_L2 f|| in L2 and on the grid
  {  // P_L2 f, the averaged (v -> 0) limit of the law, on the same grid: onto H_n, or onto H
     // itself in feature coordinates. Its E = Mbar gives the excitation of the same space.
    // Over the path's part of the track: the shuttle's time average is uniform there.
    AveragedLimitQuadrature on_path;
    on_path.range_from = settings.shuttle_from;
    on_path.range_length = settings.shuttle_length;
    const auto limit =
        in_features ? averaged_limit_in_features(kernel, road, kinks, on_path)
                    : averaged_limit(kernel, centres, road, kinks, solver_options, on_path);
    const Eigen::VectorXd l2_projection = on_grid(limit.coefficients);
    const Eigen::VectorXd l2_projection_residual = f - l2_projection;
    metrics[M::l2_projection_l2_error] = l2(l2_projection_residual);
    metrics[M::l2_projection_sup_error] = l2_projection_residual.cwiseAbs().maxCoeff();
    metrics[M::gap_to_l2_projection] = l2(estimate - l2_projection);
    l2_projection_scale = {l2(l2_projection), l2_projection.cwiseAbs().maxCoeff()};
    if (!limit.quadrature_converged) out.flags.push_back("l2_projection_unconverged");
    // pe_level (rkhs/adaptive/excitation.hpp): NaN with a singular G (the trial is flagged
    // gram_singular already); flagged pe_level_unresolved when its round-off estimate exceeds 1%
    // of it (NaN when it exceeds all of it), or in feature coordinates when the smallest nonzero
    // eigenvalue of E is not separated from its zeros (NaN).
    const auto excitation = in_features
                                ? excitation_level_on_range(limit.averaged_gram_eigenvalues)
                                : excitation_level(limit.averaged_gram, gram, solver.spectrum());
    metrics[M::pe_level] = excitation.value;
    out.floors[M::pe_level] = excitation.error_bound;
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
        unexcited = solver.spectrum().singular ? nan : static_cast<double>(excitation.unexcited);
    }
    metrics[M::unexcited_dimension] = unexcited;
    if (unexcited > 0) {
      // Def. 3.1 fails: the infimum over the space is 0 to working precision.
      metrics[M::pe_level] = 0.0;
      out.flags.push_back("not_persistently_excited");
    } else if (!excitation.resolved && (in_features || !solver.spectrum().singular)) {
      out.flags.push_back("pe_level_unresolved");
    }
  }
  // The decay of ||f~||_H against the PE level: the lap map's slowest learning mode per second,
  // and the averaged law's slowest rate H(0) pe_level / Gamma (docs/model.md section 14), the
  // rkhs law's and rkhs_embedding's (the gradient law's W = I makes its rate another pencil's).
  // The rate's error from the map's: an error delta in the radius is delta / radius in
  // ln(radius). Beyond 1% of the rate it is flagged, beyond all of it the rate is NaN.
  {
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
      if (!unresolved &&
          std::find(flags.begin(), flags.end(), "pe_level_unresolved") != flags.end())
        out.flags.push_back("decay_rate_unresolved");
    }
  }
  set_integration_floors(settings, engine, domain, estimate, alpha, coefficients_star,
                         largest_state_pair, d, in_features ? evaluation_scale(grid_features)
                                                            : evaluation_scale(cross),
                         radius_uncertainty, out);
  if (lap_map_spread.size() == m) {
    const Eigen::VectorXd estimate_spread = on_grid(lap_map_spread.tail(coefficients));
    const double l2_floor = l2(estimate_spread);
    for (const M metric : {M::l2_error, M::gap_to_projection, M::gap_to_l2_projection,
                           M::path_l2_error, M::off_path_l2_error})
      out.floors[metric] = l2_floor;
    out.floors[M::sup_error] = estimate_spread.cwiseAbs().maxCoeff();
    out.floors[M::coefficient_error] =
        lap_map_spread.tail(coefficients).norm() / std::max(coefficients_star.norm(), 1e-300);
    out.floors[M::final_state_error] = lap_map_spread.head(2 * d).norm();
  }
  set_static_floors(approximation, solver.spectrum(), n, l2_projection_scale.first,
                    l2_projection_scale.second, out);
  metrics[M::steps] = static_cast<double>(stats.steps);
  metrics[M::rejected_steps] = static_cast<double>(stats.rejected_steps);
  metrics[M::segments] = static_cast<double>(stats.segments);
  metrics[M::rhs_evaluations] =
      static_cast<double>(system.rhs_evaluations() + reused_rhs_evaluations);
  metrics[M::jacobian_evaluations] =
      static_cast<double>(system.jacobian_evaluations() + reused_jacobian_evaluations);
  if (reference) {  // after the cost metrics: the reference's evaluations are not the trial's
    const double final_time = settings.final_time_or_laps(domain.length);
    const auto started = std::chrono::steady_clock::now();
    const Eigen::VectorXd z_ref = reference_state(
        system, *reference,
        adaptive_breakpoints(settings, domain, 0.0, final_time, kinks, reference->restarts_at_kinks(),
                    /*snapshots=*/true));
    out.reference_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const Eigen::VectorXd estimate_ref = on_grid(z_ref.tail(coefficients));
    const double norm_ref = l2(estimate_ref);
    metrics[M::integration_error] = l2(estimate - estimate_ref) / std::max(norm_ref, 1e-300);
  }
  return out;
}

}  // namespace rkhs
