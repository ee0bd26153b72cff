#pragma once
// Running trials: each trial is one oneTBB task; a trial that throws, produces NaN or exceeds
// its limits is recorded as failed with its reason, and the others go on. Trials start largest
// first (largest_first_order, rkhs/run/trial_cost.hpp), so that a long trial does not end a run
// alone. Results are stored by trial index and every trial is computed sequentially inside its
// task, so they are bit-identical for any thread count and in the order of the trials given.
//
// Stopping (SIGINT, SIGTERM): once RunOptions::stop_requested returns true no trial starts, and
// trials in flight stop at their next cancellation point (rkhs/core/cancellation.hpp); both are
// recorded as not run (`skipped`), never as failed. A trial busy inside a call that has no such
// point (a dense eigendecomposition) is abandoned after RunOptions::abandon_after_seconds.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rkhs/core/work_counters.hpp"
#include "rkhs/run/trial_cost.hpp"
#include "rkhs/adaptive/lap_map.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs {

struct TrialResult {
  bool ok = false;
  std::string reason;             ///< why the trial failed (empty when ok)
  std::vector<double> metrics;    ///< aligned with study.all_metrics(); NaN if not measured
  /// The floor of each metric, aligned with `metrics` (MetricInfo::floor, docs/metrics.md
  /// "Floors"); NaN for an exact metric or one whose floor the trial did not estimate. Empty for
  /// a result stored before floors were recorded.
  std::vector<double> floors;
  std::string solve_method;       ///< how the Gram matrix was solved
  /// Adaptive trials: the engine it ran with (lap_map or time_stepping), written by name
  /// (adaptive_engine_name); std::nullopt for approximation trials.
  std::optional<AdaptiveEngine> engine;
  std::vector<std::string> flags; ///< numerically doubtful values (gram_singular, ..._at_floor)
  double seconds = 0;             ///< wall time (not part of the deterministic results),
                                  ///< without the reference integration of integration_error
  std::string data_provenance;    ///< the target's external data ("sha256:..."), empty if none
  bool skipped = false;           ///< not run: the run was interrupted before it ended
  bool stopped_while_running = false;  ///< skipped after it had started (else never started)
  /// What the trial computed (rkhs/core/work_counters.hpp), counted while it ran; empty when it
  /// did not run in this process and its record holds none (a record stored without them).
  std::optional<WorkCounts> work;
  bool reused = false;  ///< taken from the result store by this run, not run (run_with_store)
  // Adaptive trials only:
  std::vector<TimeSample> samples;  ///< |x - xhat| and V at the output samples
  std::vector<double> road;         ///< f on the snapshot grid
  std::vector<Snapshot> snapshots;  ///< fhat on the snapshot grid at the chosen laps
};

/// The name of the engine `result` ran with (adaptive_engine_name), "" for a trial without
/// one: how trials.csv, summary.json and the store's exports write it.
inline std::string_view engine_text(const TrialResult& result) noexcept {
  return result.engine ? adaptive_engine_name(*result.engine) : std::string_view();
}

struct RunOptions {
  int threads = 0;  ///< worker threads; 0: all hardware threads
  /// Called after each trial, from the worker thread that ran it, serialised by a mutex.
  std::function<void(const TrialSpec&, const TrialResult&)> on_trial_finished = {};
  /// Asked before each trial starts; when it returns true the trial is skipped (`skipped`,
  /// not reported to on_trial_finished) and trials in flight finish normally.
  std::function<bool()> stop_requested = {};
  /// Called once, before any trial starts, with the number of trials about to run.
  std::function<void(std::size_t)> on_start = {};
  /// Called as each trial starts, from its worker thread, serialised by the same mutex as
  /// on_trial_finished: in largest_first_order, exactly, for any thread count (trials skipped
  /// because of a stop request are not reported).
  std::function<void(const TrialSpec&)> on_trial_started = {};
  /// Once stop_requested has returned true, trials still running this many seconds later are
  /// abandoned: recorded as stopped while running, and run_trials returns without waiting for
  /// them. Their threads go on computing in the background (on copies of the study and trials,
  /// never calling back), so the process must then end with std::_Exit, without returning from
  /// main (see trials_abandoned()). Negative: wait for every trial (the default; a library
  /// caller that cannot end its process must keep it so).
  double abandon_after_seconds = -1;
};

/// Runs one trial; never throws (failures are returned as results). `stop_requested` is its
/// cancellation predicate (rkhs/core/cancellation.hpp): a trial stopped by it is returned `skipped`.
/// limits.trial_seconds is enforced at the trial's cancellation points as it runs.
/// `lap_maps`, when given, is shared by the trials of one run: trials that differ only in their
/// lap count compute their lap map once (rkhs/adaptive/lap_map.hpp; results are unchanged).
TrialResult run_trial(const StudyDefinition& study, const TrialSpec& trial,
                      const std::function<bool()>& stop_requested = {},
                      LapMapCache* lap_maps = nullptr);

/// True once run_trials abandoned a trial in this process: its thread still runs, so the
/// process must end with std::_Exit (after flushing its output), not by returning from main.
bool trials_abandoned() noexcept;

/// Runs `trials` concurrently, started in largest_first_order(study, trials); results in the
/// order of `trials`.
std::vector<TrialResult> run_trials(const StudyDefinition& study,
                                    const std::vector<TrialSpec>& trials,
                                    const RunOptions& options);

/// One MPI rank of a distributed run.
struct RankRecord {
  std::string host;
  int threads = 0;
  std::size_t trials = 0;  ///< trials it ran in this run
  bool lost = false;       ///< stopped answering during the run; its trials ran elsewhere
};

}  // namespace rkhs
