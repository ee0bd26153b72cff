#pragma once
// Where the trials of a study run: in this process (LocalExecutor), or over the ranks of an MPI
// job (rkhs::distributed::MpiExecutor in framework/mpi/, the layer above this one). The study
// pipeline (study_pipeline.hpp) is written against this interface only, so every command runs
// a study the same way with and without MPI.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rkhs/run/result_store.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::pipeline {

class Executor {
 public:
  virtual ~Executor() = default;

  /// True on the process that opens the result store and writes the outputs (MPI rank 0, or
  /// the only process).
  virtual bool is_root() const = 0;

  /// Runs `action` on this process. With several processes every one must succeed before any
  /// goes on (one that cannot must not leave the others waiting): the root then throws the
  /// error (its own exception when every failing process failed alike), the others end
  /// quietly (distributed::QuietExit).
  virtual void on_every_process(const std::function<void()>& action) const = 0;

  /// Checks that every process sees the same `trials` (a job whose ranks read different study
  /// or data files is refused); call it before creating anything, so that a refused run leaves
  /// nothing behind. One process: nothing to check.
  virtual void agree_on(const StudyDefinition& study, const std::vector<TrialSpec>& trials) {
    (void)study;
    (void)trials;
  }

  /// Worker threads of this process when none were asked for: all cores, shared by the ranks
  /// of a node.
  virtual int default_threads() const = 0;

  /// Runs the trials `store` does not hold (all when `fresh` or `store` is null), committing
  /// each as it finishes; every result on the root, std::nullopt on other processes. `store`
  /// is null on every process but the root.
  virtual std::optional<StoredRun> run(const StudyDefinition& study,
                                       const std::vector<TrialSpec>& trials, RunOptions options,
                                       ResultStore* store, bool fresh) = 0;

  /// Collective: the root's `decision` on every process (one process: `decision` itself), so
  /// that the processes of a job leave a sequence of runs together, e.g. after an interrupted
  /// one or an error on the root.
  virtual bool root_decision(bool decision) const { return decision; }

  /// After run(): each process with its host, threads and the trials it ran (empty for one
  /// process).
  virtual std::vector<RankRecord> ranks() const { return {}; }

  /// Where the trials run, for the start line: "" in this process, " on rank 0 of 4 MPI
  /// ranks" in a job.
  virtual std::string where() const { return {}; }
};

/// The trials on this process's threads (run_with_store with run_trials).
class LocalExecutor final : public Executor {
 public:
  bool is_root() const override { return true; }
  void on_every_process(const std::function<void()>& action) const override { action(); }
  int default_threads() const override;
  std::optional<StoredRun> run(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                               RunOptions options, ResultStore* store, bool fresh) override;
};

}  // namespace rkhs::pipeline
