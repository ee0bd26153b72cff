#pragma once
// The study pipeline every command that runs trials shares (run, check, report): load the
// study on every process, open the result store, run the trials the store does not hold,
// compute the rates, and hand back one RunRecord for the writers. Commands add only what is
// theirs (outputs, plots, verdicts, messages).

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rkhs/pipeline/executor.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/run/result_store.hpp"
#include "rkhs/verify/expectation_cases.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs::pipeline {

/// Where finished trials are committed (docs/results.md): shared by every study run from here.
struct StoreOptions {
  std::string file = "results/rkhs-study.sqlite";
  bool fresh = false;     ///< run every trial again (results are still stored)
  bool disabled = false;  ///< no store at all
  /// Open the store read-only (StoreAccess::read_only) when it holds a verified record of
  /// every trial, read-write only when some trial has to run (and be stored): `report`.
  bool read_only_when_complete = false;
};

/// The study `load` returns, loaded on every process (each must succeed; see
/// Executor::on_every_process).
StudyDefinition load_everywhere(const Executor& executor,
                                const std::function<StudyDefinition()>& load);

/// A run whose every trial has a result, with what the commands report about it.
struct CompletedRun {
  const StudyDefinition& study;
  const std::vector<TrialSpec>& trials;
  StoredRun stored;                 ///< results in trial order; reused / ran counts
  std::vector<MetricSeries> rates;  ///< compute_rates of the results (empty: Rates::not_fitted)
  std::size_t failed = 0;           ///< trials whose status is failed
  int threads = 1;                  ///< worker threads of the root process
  double seconds = 0;               ///< wall time of the run
  std::string started;              ///< ISO 8601 UTC time the run started
  std::vector<RankRecord> ranks;    ///< MPI ranks (empty: one process)

  /// The record the output writers take (it refers to this object: keep it alive).
  RunRecord record() const;
};

/// What run_study did.
struct PipelineOutcome {
  /// Every trial has a result (root only).
  std::optional<CompletedRun> completed;
  /// The run was interrupted: what finished, was stored and was not (root only).
  std::optional<StoredRun> interrupted;
  /// The store the root used ("" with StoreOptions::disabled).
  std::string store_file;
};

/// Whether run_study fits rates: for the study's whole grid (study.trials()), not for a subset
/// of it (a shard), whose results do not cover the grid positions rates are read at.
enum class Rates { fitted, not_fitted };

/// The result store a run uses, opened before the run writes anything else (its outputs, its
/// journal): a store that is refused leaves nothing behind.
struct OpenedStore {
  std::unique_ptr<ResultStore> store;  ///< nullptr with StoreOptions::disabled, and off the root
  bool created = false;                ///< no file was there: this run creates it
};

/// Opens the store of `options` on the root (on every process the same success or failure,
/// Executor::on_every_process). Read-write, but read-only (StoreAccess::read_only) where it
/// cannot be written (ReadOnlyStore: a read-only file system, a file or folder this user may
/// not write) or with StoreOptions::read_only_when_complete, when it holds a verified record
/// of every one of `trials`: such a run only reads it. A read-only store that lacks some trial
/// (or with --fresh) throws ReadOnlyStore naming the store, why and how many trials it lacks.
OpenedStore open_store(const Executor& executor, const StudyDefinition& study,
                       const std::vector<TrialSpec>& trials, const StoreOptions& options);

/// Runs `trials` of `study` through the store on `executor` with `options` (threads 0: the
/// executor's default), freezing the registries first. Non-root processes get an empty
/// outcome once the job is done. `opened`: the store open_store opened for these trials.
PipelineOutcome run_study(Executor& executor, const StudyDefinition& study,
                          const std::vector<TrialSpec>& trials, RunOptions options,
                          const StoreOptions& store, OpenedStore opened,
                          Rates rates = Rates::fitted);
/// The same, opening the store first (open_store).
PipelineOutcome run_study(Executor& executor, const StudyDefinition& study,
                          const std::vector<TrialSpec>& trials, RunOptions options,
                          const StoreOptions& store, Rates rates = Rates::fitted);

/// A run and its expectations' verdicts: what `run`, `check` and the Python module
/// (python/src/module.cpp) judge once the store is open.
struct JudgedRun {
  PipelineOutcome outcome;
  /// verify_expectations of the completed run, of the cases `selection` keeps; empty when the
  /// run was interrupted and off the root. They point into the study: keep it alive.
  std::vector<ExpectationOutcome> verdicts;
};

/// run_study with the store `opened` (open_store), then, when every trial has a result, the
/// study's expectations judged on the results and rates (verify_expectations), keeping those
/// of the cases in `selection` (`check -k`; null: every case).
JudgedRun run_and_judge(Executor& executor, const StudyDefinition& study,
                        const std::vector<TrialSpec>& trials, RunOptions options,
                        const StoreOptions& store, OpenedStore opened,
                        const CaseSelection* selection = nullptr);

/// The current UTC time, ISO 8601 ("2026-12-02T01:30:00Z").
std::string utc_now();

}  // namespace rkhs::pipeline
