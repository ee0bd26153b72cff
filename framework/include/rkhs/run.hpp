#pragma once
// Running trials: each trial is one oneTBB task; a trial that throws, produces NaN or exceeds
// its limits is recorded as failed with its reason, and the others go on. Results are stored by
// trial index and every trial is computed sequentially inside its task, so they are
// bit-identical for any thread count.

#include <functional>
#include <string>
#include <vector>

#include "rkhs/study.hpp"

namespace rkhs {

struct TrialResult {
  bool ok = false;
  std::string reason;             ///< why the trial failed (empty when ok)
  std::vector<double> metrics;    ///< aligned with study.all_metrics(); NaN if not measured
  std::string solve_method;       ///< how the Gram matrix was solved
  std::vector<std::string> flags; ///< numerically doubtful values (gram_singular, ..._at_floor)
  double seconds = 0;             ///< wall time (not part of the deterministic results)
  std::string data_provenance;    ///< the target's external data ("sha256:..."), empty if none
  bool skipped = false;           ///< not run: the run was interrupted before it started
  // Adaptive trials only:
  std::vector<TimeSample> samples;  ///< |x - xhat| and V at the output samples
  std::vector<double> road;         ///< f on the snapshot grid
  std::vector<Snapshot> snapshots;  ///< fhat on the snapshot grid at the chosen laps
};

struct RunOptions {
  int threads = 0;  ///< worker threads; 0: all hardware threads
  /// Called after each trial, from the worker thread that ran it, serialised by a mutex.
  std::function<void(const TrialSpec&, const TrialResult&)> on_trial_finished = {};
  /// Asked before each trial starts; when it returns true the trial is skipped (`skipped`,
  /// not reported to on_trial_finished) and trials in flight finish normally.
  std::function<bool()> stop_requested = {};
  /// Called once, before any trial starts, with the number of trials about to run.
  std::function<void(std::size_t)> on_start = {};
};

/// Runs one trial; never throws (failures are returned as results).
TrialResult run_trial(const StudyDefinition& study, const TrialSpec& trial);

/// The positions of `trials` ordered by estimated cost, largest first (ties keep grid order):
/// the order in which trials are started, so that long trials do not end a run alone.
std::vector<std::size_t> largest_first_order(const StudyDefinition& study,
                                             const std::vector<TrialSpec>& trials);

/// Runs `trials` concurrently, largest first; results in the order of `trials`.
std::vector<TrialResult> run_trials(const StudyDefinition& study,
                                    const std::vector<TrialSpec>& trials,
                                    const RunOptions& options);

}  // namespace rkhs
