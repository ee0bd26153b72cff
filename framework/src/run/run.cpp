#include "rkhs/run/run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "rkhs/adaptive/finite_to_infinite.hpp"
#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/reference_resolution.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/metrics.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/run/trial_cost.hpp"
#include "rkhs/run/trial_kinds.hpp"

namespace rkhs {

namespace {

// The two results of a trial that did not run to its end: never started, or stopped while it ran
// (neither is reported as finished, so neither is stored).
TrialResult not_started() {
  TrialResult result;
  result.skipped = true;
  result.reason = "not run: the run was interrupted";
  return result;
}

TrialResult stopped_while_running() {
  TrialResult result = not_started();
  result.stopped_while_running = true;
  result.reason = "not run: the run was interrupted while the trial ran";
  return result;
}

// Whether an infinite value of `metric` means something: only where the trial raised the
// metric's own flag (a singular Gram matrix's condition number is +inf, flagged gram_singular).
// Any other infinity is an overflow of the trial's arithmetic.
bool infinity_is_documented(const MetricInfo& metric, const std::vector<std::string>& flags) {
  return !metric.flag.empty() && std::find(flags.begin(), flags.end(), metric.flag) != flags.end();
}

// The floor of a count N of the integrator's work (FloorRule::step_controller):
// 0.02 N + 3 sqrt(N), a drift of the path plus three standard deviations of a random walk of
// accept/reject decisions that flip. Across processors and glibc's code paths the counts of the
// shipped studies moved by up to 0.84 % (2511 against 2532 steps) and, few as they are, the
// rejected steps by 14 (28 against 42).
double step_controller_floor(double count) {
  return 0.02 * std::abs(count) + 3 * std::sqrt(std::abs(count));
}

// Completes a measured trial's floors by their rules (MetricInfo::floor): none for an exact
// metric or a NaN value, step_controller_floor for the step controller's counts, and flags
// every value at or below its floor with floor_flag (once). Every metric the trial computed is
// flagged, reported or not: what a trial computes is its identity, what it reports is not
// (trials.csv writes the flags of the reported metrics, rkhs/report/output.hpp).
void apply_floors(const std::vector<MetricInfo>& rows, TrialResult& result) {
  result.floors.resize(result.metrics.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < rows.size() && i < result.metrics.size(); ++i) {
    const auto& row = rows[i];
    const double value = result.metrics[i];
    double& floor = result.floors[i];
    if (row.floor == FloorRule::exact || std::isnan(value)) {
      floor = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    if (row.floor == FloorRule::step_controller) {
      floor = step_controller_floor(value);
      continue;  // a measure of work: never "at its floor"
    }
    if (!(floor > 0 && std::abs(value) <= floor)) continue;
    const auto flag = floor_flag(row);
    if (std::find(result.flags.begin(), result.flags.end(), flag) == result.flags.end())
      result.flags.push_back(flag);
  }
}

// The deadline `seconds` (> 0) after `start`, or none when it lies beyond what the clock can
// represent: a limit of 1e10 s or 1e300 s is no limit, never a time point that overflowed
// into the past (every trial then "exceeded" it at 0.0 s).
std::optional<std::chrono::steady_clock::time_point> deadline_after(
    std::chrono::steady_clock::time_point start, double seconds) {
  using clock = std::chrono::steady_clock;
  const double room = std::chrono::duration<double>(clock::time_point::max() - start).count();
  if (!(seconds < 0.5 * room)) return std::nullopt;
  return start +
         std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace

TrialResult run_trial(const StudyDefinition& study, const TrialSpec& trial,
                      const std::function<bool()>& stop_requested, LapMapCache* lap_maps) {
  // Everything the trial computes on this thread counts here, its own result's storage too; a
  // part of it run on another thread installs the same counters there.
  WorkCounters counters;
  const WorkCounterScope counting(&counters);
  TrialResult result;
  result.metrics.assign(study.all_metrics().size(),
                        std::numeric_limits<double>::quiet_NaN());
  const MetricSelection computed = study.computed_metrics();
  double reference_seconds = 0;  // the reference integration's share (adaptive, with one)
  const auto start = std::chrono::steady_clock::now();
  std::optional<std::chrono::steady_clock::time_point> deadline;
  if (study.limits.trial_seconds > 0) deadline = deadline_after(start, study.limits.trial_seconds);
  const auto time_limit_reason = [&](double seconds) {
    return fmt::format("exceeded limits.trial_seconds = {} ({:.1f} s)",
                       format_real(study.limits.trial_seconds), seconds);
  };
  try {
    const CancellationScope cancellation(stop_requested, deadline);
    if (const auto footprint = trial_footprint(study, trial);
        footprint.megabytes > study.limits.matrix_megabytes)
      throw std::runtime_error(
          fmt::format("needs {:.0f} MB of matrices ({}), above limits.matrix_megabytes = {:.0f}",
                      footprint.megabytes, footprint.describe(), study.limits.matrix_megabytes));
    const auto kernel = make_kernel(trial.kernel.name, trial.kernel.parameters, study.domain);
    const auto target =
        target_registry().find(trial.target.name)->factory(trial.target.parameters, study.domain);
    result.data_provenance = target->data_provenance();
    const auto placement = centre_registry().find(trial.centres.name)->factory(trial.centres.parameters);
    const auto centres = placement->place(trial.n, study.domain, trial.seed);
    check_cancelled();
    const TrialInputs inputs{study, trial, computed, *kernel, *target, centres, lap_maps};
    reference_seconds = trial_kind(study.kind()).measure(inputs, result);
    const auto& catalogue = study.kind_descriptor().metrics();
    apply_floors(catalogue, result);
    check_cancelled();
    // Metrics that are undefined by design in some trials (MetricInfo::may_be_nan: a single
    // centre has no separation; coefficient and Lyapunov metrics need a road in H_n).
    // A value that overflowed is no measurement either: the trial fails rather than report it
    // ok. Every metric the trial computed is judged, reported or not, so that its status does
    // not depend on which of them a study prints.
    for (std::size_t i = 0; i < catalogue.size(); ++i) {
      if (!computed[i]) continue;
      const double value = result.metrics[i];
      if (std::isnan(value) && !catalogue[i].may_be_nan)
        throw std::runtime_error(fmt::format("{} is NaN", catalogue[i].name));
      if (std::isinf(value) && !infinity_is_documented(catalogue[i], result.flags))
        throw std::runtime_error(fmt::format(
            "{} overflowed to {}: the trial's values exceed the range of a double (1.8e308)",
            catalogue[i].name, value > 0 ? "+inf" : "-inf"));
    }
    result.ok = true;
  } catch (const TrialCancelled&) {
    result = stopped_while_running();
  } catch (const TrialTimeLimitExceeded& e) {
    result.ok = false;
    result.reason = time_limit_reason(e.elapsed_seconds);
  } catch (const std::exception& e) {
    result.ok = false;
    result.reason = e.what();
  } catch (...) {
    result.ok = false;
    result.reason = "unknown exception";
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (result.skipped) return result;
  result.work = snapshot(counters);
  if (result.ok && study.limits.trial_seconds > 0 && result.seconds > study.limits.trial_seconds) {
    result.ok = false;
    result.reason = time_limit_reason(result.seconds);
  }
  // The limit counts everything the trial ran; its recorded wall time is its own integrator's
  // (with the static part), the measure of work a work-precision plot needs.
  result.seconds -= reference_seconds;
  if (!result.ok) {
    std::fill(result.metrics.begin(), result.metrics.end(), std::numeric_limits<double>::quiet_NaN());
    result.floors.assign(result.metrics.size(), std::numeric_limits<double>::quiet_NaN());
  }
  return result;
}

namespace {

std::atomic<bool> abandoned_any{false};

// What the worker threads of one run_trials call share. When trials are abandoned it outlives
// the call (the workers hold it), so it owns copies of everything they read.
struct RunState {
  StudyDefinition study;
  std::vector<TrialSpec> trials;
  RunOptions options;
  std::vector<TrialResult> results;
  enum Phase : char { waiting, running, done };
  std::vector<Phase> phase;   // by position in `trials`
  std::mutex mutex;           // guards results, phase, finished, abandoned and the callbacks
  std::condition_variable changed;
  std::size_t finished = 0;   // trials done, skipped or not (the whole run ends at trials.size())
  bool abandoned = false;     // run_trials has returned: no more writes, no more callbacks
  LapMapCache lap_maps;       // shared by trials that differ only in their lap count
};

// One scheduled task per trial (run_concurrently, core/concurrency.hpp). A task does not run
// the trial of its own index: it claims the next trial of `order` (largest first) when it
// starts, under the mutex that also calls on_trial_started, so trials start in exactly that
// order whatever the thread count, the scheduling backend and whichever task a thread happens to
// take (a oneTBB thread that steals takes the far end of a range, which here would be the
// cheapest trials). With limits.memory_megabytes, a task claims the first trial of `order` left
// whose predicted matrices fit beside those of the trials running, or waits for one to finish;
// a trial runs alone whatever its size. The results do not depend on it, only the order in
// which trials start.
void run_in_arena(RunState& state) {
  const auto order = largest_first_order(state.study, state.trials);
  const auto& options = state.options;
  const int threads = options.threads > 0 ? options.threads : default_concurrency();
  const double budget = state.study.limits.memory_megabytes;
  std::vector<double> megabytes(order.size(), 0.0);  // by position in `order`
  if (budget > 0)
    for (std::size_t k = 0; k < order.size(); ++k)
      megabytes[k] = trial_footprint(state.study, state.trials[order[k]]).megabytes;
  std::vector<bool> claimed(order.size(), false);  // guarded by state.mutex
  std::size_t first_left = 0;                      // claimed[k] for every k < first_left
  double in_use = 0;                               // MB of the trials running
  std::size_t running = 0;
  run_concurrently(order.size(), threads, [&](std::size_t) {
    const bool stop = options.stop_requested && options.stop_requested();
    std::size_t k = 0;
    {
      std::unique_lock lock(state.mutex);
      for (;;) {
        if (state.abandoned) return;
        k = first_left;
        if (budget > 0 && !stop)
          while (k < order.size() &&
                 (claimed[k] || (running > 0 && in_use + megabytes[k] > budget)))
            ++k;
        if (k < order.size()) break;
        state.changed.wait(lock);  // every trial that would fit waits for room
      }
      claimed[k] = true;
      while (first_left < order.size() && claimed[first_left]) ++first_left;
      if (!stop) {
        in_use += megabytes[k];
        ++running;
        state.phase[order[k]] = RunState::running;
        if (options.on_trial_started) options.on_trial_started(state.trials[order[k]]);
      }
    }
    const std::size_t i = order[k];
    TrialResult result =
        stop ? not_started()
             : run_trial(state.study, state.trials[i], options.stop_requested, &state.lap_maps);
    std::lock_guard lock(state.mutex);
    if (!stop) {
      in_use -= megabytes[k];
      --running;
    }
    state.changed.notify_all();
    if (state.abandoned) return;
    state.phase[i] = RunState::done;
    state.results[i] = std::move(result);
    if (!state.results[i].skipped && options.on_trial_finished)
      options.on_trial_finished(state.trials[i], state.results[i]);
    ++state.finished;
  });
}

}  // namespace

bool trials_abandoned() noexcept {
  return abandoned_any.load();
}

std::vector<TrialResult> run_trials(const StudyDefinition& study,
                                    const std::vector<TrialSpec>& trials,
                                    const RunOptions& options) {
  if (options.on_start) options.on_start(trials.size());
  auto state = std::make_shared<RunState>();
  state->study = study;
  state->trials = trials;
  state->options = options;
  state->results.resize(trials.size());
  state->phase.assign(trials.size(), RunState::waiting);
  if (options.abandon_after_seconds < 0 || trials.empty()) {
    run_in_arena(*state);
    return std::move(state->results);
  }
  // The trials run on a thread of their own, so that this one can give up waiting.
  std::thread runner([state] { run_in_arena(*state); });
  std::unique_lock lock(state->mutex);
  std::optional<std::chrono::steady_clock::time_point> stop_seen;
  const auto grace = std::chrono::duration<double>(options.abandon_after_seconds);
  while (state->finished < trials.size()) {
    state->changed.wait_for(lock, std::chrono::milliseconds(50));
    if (state->finished == trials.size()) break;
    if (!stop_seen && options.stop_requested && options.stop_requested())
      stop_seen = std::chrono::steady_clock::now();
    if (stop_seen && std::chrono::steady_clock::now() - *stop_seen >= grace) {
      // Trials still running are abandoned; trials not reached yet are skipped.
      state->abandoned = true;
      abandoned_any = true;
      for (std::size_t i = 0; i < trials.size(); ++i) {
        if (state->phase[i] == RunState::running)
          state->results[i] = stopped_while_running();
        else if (state->phase[i] == RunState::waiting)
          state->results[i] = not_started();
      }
      auto results = state->results;
      lock.unlock();
      runner.detach();
      return results;
    }
  }
  lock.unlock();
  runner.join();
  return std::move(state->results);
}

}  // namespace rkhs
