#include "rkhs/run.hpp"

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <numeric>

#include "rkhs/approximation.hpp"
#include "rkhs/centres.hpp"
#include "rkhs/kernel.hpp"
#include "rkhs/plant.hpp"
#include "rkhs/target.hpp"

namespace rkhs {

namespace {

double estimated_cost(const StudyDefinition& study, const TrialSpec& trial) {
  const auto n = static_cast<double>(trial.n);
  const double static_cost = n * n * n + n * n * static_cast<double>(study.evaluation_points);
  if (study.kind != "adaptive") return static_cost;
  // One dense LU of the (2d + n) system per step, steps growing with the horizon in laps.
  const double laps = study.adaptive.final_time_or_laps(study.domain.length) * study.adaptive.speed /
                      study.domain.length;
  return static_cost + laps * (n + 8) * (n + 8) * (n + 8) * 1e3;
}

// Dense matrices of a trial: Gram (twice, with its eigenvectors) and the cross matrix.
double matrix_megabytes(const StudyDefinition& study, const TrialSpec& trial) {
  const auto n = static_cast<double>(trial.n);
  return 8.0 * (3 * n * n + 2 * n * static_cast<double>(study.evaluation_points)) / 1048576.0;
}

}  // namespace

TrialResult run_trial(const StudyDefinition& study, const TrialSpec& trial) {
  TrialResult result;
  result.metrics.assign(study.all_metrics().size(),
                        std::numeric_limits<double>::quiet_NaN());
  const auto start = std::chrono::steady_clock::now();
  try {
    if (const double mb = matrix_megabytes(study, trial); mb > study.limits.matrix_megabytes)
      throw std::runtime_error(fmt::format(
          "needs {:.0f} MB of matrices, above limits.matrix_megabytes = {:.0f}", mb,
          study.limits.matrix_megabytes));
    const auto kernel = make_kernel(trial.kernel.name, trial.kernel.parameters, study.domain);
    const auto target =
        target_registry().find(trial.target.name)->factory(trial.target.parameters, study.domain);
    result.data_provenance = target->data_provenance();
    const auto placement = centre_registry().find(trial.centres.name)->factory(trial.centres.parameters);
    const auto centres = placement->place(trial.n, study.domain, trial.seed);
    if (study.kind == "adaptive") {
      const auto plant = plant_registry().find(trial.plant.name)->factory(trial.plant.parameters);
      const auto law = law_registry().find(trial.law.name)->factory(trial.law.parameters);
      const auto integrator =
          integrator_registry().find(trial.integrator.name)->factory(trial.integrator.parameters);
      auto measured = measure_adaptive(*kernel, *target, centres, *plant, *law, *integrator,
                                       study.adaptive, study.evaluation_points, study.solver);
      result.metrics = std::move(measured.metrics);
      result.solve_method = std::move(measured.solve_method);
      result.flags = std::move(measured.flags);
      result.samples = std::move(measured.samples);
      result.road = std::move(measured.road);
      result.snapshots = std::move(measured.snapshots);
    } else {
      auto measured =
          measure_approximation(*kernel, *target, centres, study.evaluation_points, study.solver);
      result.metrics = std::move(measured.metrics);
      result.solve_method = std::move(measured.solve_method);
      result.flags = std::move(measured.flags);
    }
    // Metrics that are undefined by design in some trials: a single centre has no separation;
    // coefficient and Lyapunov metrics need a road in H_n.
    static const std::vector<std::string> may_be_undefined{
        "separation_distance", "coefficient_error", "lyapunov_max_increase", "lyapunov_ratio"};
    const auto& names = study.all_metrics();
    for (std::size_t i = 0; i < names.size(); ++i)
      if (std::isnan(result.metrics[i]) &&
          std::find(may_be_undefined.begin(), may_be_undefined.end(), names[i]) == may_be_undefined.end())
        throw std::runtime_error(fmt::format("{} is NaN", names[i]));
    result.ok = true;
  } catch (const std::exception& e) {
    result.ok = false;
    result.reason = e.what();
  } catch (...) {
    result.ok = false;
    result.reason = "unknown exception";
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (result.ok && study.limits.trial_seconds > 0 && result.seconds > study.limits.trial_seconds) {
    result.ok = false;
    result.reason = fmt::format("exceeded limits.trial_seconds = {} ({:.1f} s)",
                                format_real(study.limits.trial_seconds), result.seconds);
  }
  if (!result.ok)
    std::fill(result.metrics.begin(), result.metrics.end(), std::numeric_limits<double>::quiet_NaN());
  return result;
}

std::vector<std::size_t> largest_first_order(const StudyDefinition& study,
                                             const std::vector<TrialSpec>& trials) {
  std::vector<double> cost(trials.size());
  for (std::size_t i = 0; i < trials.size(); ++i) cost[i] = estimated_cost(study, trials[i]);
  std::vector<std::size_t> order(trials.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
  return order;
}

std::vector<TrialResult> run_trials(const StudyDefinition& study,
                                    const std::vector<TrialSpec>& trials,
                                    const RunOptions& options) {
  if (options.on_start) options.on_start(trials.size());
  std::vector<TrialResult> results(trials.size());
  const auto order = largest_first_order(study, trials);
  std::mutex report_mutex;
  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  // Raise TBB's worker limit to the requested count (it defaults to the hardware threads).
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<std::size_t>(threads));
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, order.size(), 1),
        [&](const tbb::blocked_range<std::size_t>& range) {
          for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const std::size_t i = order[k];
            if (options.stop_requested && options.stop_requested()) {
              results[i].skipped = true;
              results[i].reason = "not run: the run was interrupted";
              continue;
            }
            results[i] = run_trial(study, trials[i]);
            if (options.on_trial_finished) {
              std::lock_guard lock(report_mutex);
              options.on_trial_finished(trials[i], results[i]);
            }
          }
        },
        tbb::simple_partitioner());
  });
  return results;
}

}  // namespace rkhs
