#include "rkhs/run/trial_cost.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <exception>
#include <numeric>
#include <set>
#include <string>
#include <string_view>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/run/trial_kinds.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs {

namespace {

// Steps an integrator takes per lap (the same for every integrator: see the header).
constexpr double steps_per_lap = 1e3;

// The dimension of the trial's plant; 1 when it cannot be made (the trial fails at once then).
std::size_t plant_dimension(const PluginChoice& plant) {
  const auto* entry = plant_registry().find(plant.name);
  if (!entry) return 1;
  try {
    const auto made = entry->factory(plant.parameters);
    return made ? static_cast<std::size_t>(std::max<Eigen::Index>(made->A().rows(), 1)) : 1;
  } catch (const std::exception&) {
    return 1;
  }
}

// What the trial's integrator declares it does per step (Integrator::properties()); the dearer
// default (implicit, dense) when it cannot be made (the trial fails at once then).
IntegratorProperties integrator_properties(const PluginChoice& integrator) {
  const auto* entry = integrator_registry().find(integrator.name);
  if (!entry) return {};
  try {
    const auto made = entry->factory(integrator.parameters);
    return made ? made->properties() : IntegratorProperties{};
  } catch (const std::exception&) {
    return {};
  }
}

// Laps of the coupled system the engine integrates: the horizon when it steps through time, one
// lap of the state and of its 2d + n sensitivities with the lap map.
double integrated_laps(const AdaptiveTrialShape& shape) noexcept {
  if (shape.lap_map) return static_cast<double>(2 * shape.plant_dimension + shape.n);
  return shape.laps;
}

}  // namespace

double trial_matrix_megabytes(std::size_t n, std::size_t evaluation_points) noexcept {
  const auto m = static_cast<double>(n);
  return 8.0 * (3 * m * m + 2 * m * static_cast<double>(evaluation_points)) / 1048576.0;
}

double sparse_trial_megabytes(double gram_nonzeros, double factor_nonzeros, std::size_t n,
                              std::size_t evaluation_points) noexcept {
  // Bytes: a stored nonzero of G or of the cross matrix takes 12 (value, row index). G is
  // assembled from triplets of its upper triangle (8 a nonzero of G, reserved, and 12 for the
  // compressed upper triangle with setFromTriplets' transposed copy), then mirrored (6 for the
  // upper triangle beside the 12 of G): at most 20 a nonzero. CHOLMOD keeps a permuted copy of
  // G's upper triangle (6); its supernodal factor stores L's nonzeros with about a quarter more
  // for the supernodes' dense blocks (10). The cross matrix is built by chunks of evaluation
  // points of at most about 2^23 entries (measure_sparse_approximation), one chunk at a time,
  // from triplets (16 an entry, 32 while the vector grows, and 12 for the transposed copy); the
  // solves take blocks of at most 32 MB on each of two threads.
  const double per_point = gram_nonzeros / std::max(1.0, static_cast<double>(n));
  const double cross = std::min(per_point * static_cast<double>(evaluation_points),
                                std::ldexp(1.0, 23) + 512.0 * per_point);
  const double gram_phase = std::max(
      20.0 * gram_nonzeros, 12.0 * gram_nonzeros + 6.0 * gram_nonzeros + 10.0 * factor_nonzeros);
  return (gram_phase + 56.0 * cross) / 1048576.0 + 64.0;
}

std::string TrialFootprint::describe() const {
  if (sparse)
    return fmt::format("sparse: {:.2g} nonzeros in G, {:.2g} in its Cholesky factor (predicted)",
                       gram_nonzeros, factor_nonzeros);
  return "dense: the n x n Gram matrix three times and two n x E matrices";
}

TrialFootprint trial_footprint(const StudyDefinition& study, const TrialSpec& trial) {
  return trial_kind(study.kind()).footprint(study, trial);
}

double approximation_trial_cost(std::size_t n, std::size_t evaluation_points) noexcept {
  const auto m = static_cast<double>(n);
  return m * m * m + m * m * static_cast<double>(evaluation_points);
}

double adaptive_trial_cost(const AdaptiveTrialShape& shape, std::size_t evaluation_points) noexcept {
  const auto size = static_cast<double>(2 * shape.plant_dimension + shape.n);  // N = 2d + n
  // A right-hand side costs O(N^2) at most (psi = M phi with a dense M); a dense implicit step
  // adds an O(N^3) factorisation, a structured one O(N).
  const double step = shape.implicit_integrator && !shape.structured_solves
                          ? size * size * size + size * size
                          : size * size;
  return approximation_trial_cost(shape.n, evaluation_points) +
         integrated_laps(shape) * steps_per_lap * step;
}

AdaptiveTrialShape adaptive_trial_shape(const StudyDefinition& study, const TrialSpec& trial) {
  AdaptiveTrialShape shape;
  shape.n = trial.n;
  const auto& own = trial.adaptive_axes();
  shape.plant_dimension = plant_dimension(own.plant);
  const auto settings = trial_adaptive_settings(study, trial);
  const auto integrator = integrator_properties(own.integrator);
  shape.implicit_integrator = integrator.implicit();
  shape.structured_solves = integrator.structured_stage_solves;
  try {
    shape.lap_map = adaptive_engine_for(settings, static_cast<Eigen::Index>(
                                                      2 * shape.plant_dimension + shape.n)) ==
                    AdaptiveEngine::lap_map;
  } catch (const std::exception&) {
    shape.lap_map = false;  // the trial fails at once
  }
  shape.laps = settings.limit() ? 0.0
                                : settings.final_time_or_laps(study.domain.length) /
                                      settings.lap_time(study.domain.length);
  return shape;
}

double estimated_trial_cost(const StudyDefinition& study, const TrialSpec& trial) {
  return trial_kind(study.kind()).cost(study, trial, nullptr);
}

std::string lap_map_key(const TrialSpec& trial) {
  std::string key;
  std::size_t start = 0;
  while (start <= trial.key.size()) {
    const auto stop = std::min(trial.key.find(" | ", start), trial.key.size());
    const auto part = trial.key.substr(start, stop - start);
    if (!part.starts_with("laps=")) key += (key.empty() ? "" : " | ") + part;
    start = stop + 3;
  }
  return key;
}

std::vector<std::size_t> largest_first_order(const StudyDefinition& study,
                                             const std::vector<TrialSpec>& trials) {
  std::vector<double> cost(trials.size());
  std::set<std::string> shared;  // work shared by several trials, already counted (lap maps)
  const auto& kind = trial_kind(study.kind());
  for (std::size_t i = 0; i < trials.size(); ++i) cost[i] = kind.cost(study, trials[i], &shared);
  std::vector<std::size_t> order(trials.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
  return order;
}

}  // namespace rkhs
