#pragma once
// Running a study's trials across MPI ranks (`rkhs-study run STUDY --mpi`, docs/cluster.md).
//
// Rank 0 is the coordinator: it alone opens the result store, hands trials out one at a time,
// largest estimated cost first, to whichever rank has a free thread (itself included), commits
// each result as it arrives and writes the outputs. Every rank runs its trials on oneTBB with
// its own threads. Results travel as the store's exact text records, so a distributed run gives
// bit for bit the results of a single process. A rank that dies loses only the trials it had in
// flight: everything rank 0 committed is reused by the next run.
//
// This header has no MPI types; in a build without MPI (RKHS_STUDY_MPI=OFF, or no MPI found)
// Session's constructor throws and available() is false.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "rkhs/pipeline/executor.hpp"
#include "rkhs/run/result_store.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::distributed {

/// True when this build can run with MPI.
bool available() noexcept;

/// CPUs this process may run on (its affinity mask: mpirun and srun bind ranks to cores).
int usable_cpus() noexcept;

/// The number of processes this one was started among by an MPI launcher, read from the
/// launcher's environment before MPI is initialised (OMPI_COMM_WORLD_SIZE of Open MPI's mpirun,
/// PMI_SIZE of MPICH's launchers and srun --mpi=pmi2); 1 when not started by one.
int launched_process_count() noexcept;

/// True when this process is the first of those (rank 0 by the launcher's environment,
/// OMPI_COMM_WORLD_RANK or PMI_RANK), or was not started by a launcher: the process that prints
/// a refusal before MPI is initialised.
bool launched_first() noexcept;

/// Thrown on ranks other than 0 for an error that rank 0 reports: the rank exits with `code`
/// without printing anything, so the user sees each error once.
struct QuietExit {
  int code;
};

/// MPI for the lifetime of the object: MPI_Init_thread (MPI_THREAD_FUNNELED: only the thread
/// that made the Session calls MPI) in the constructor, MPI_Finalize in the destructor.
class Session {
 public:
  /// Throws std::runtime_error when the build has no MPI or MPI cannot be initialised.
  Session(int& argc, char**& argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  int rank() const noexcept { return rank_; }
  int size() const noexcept { return size_; }
  bool is_root() const noexcept { return rank_ == 0; }
  /// Ranks on this rank's node (MPI_COMM_TYPE_SHARED).
  int ranks_on_node() const noexcept { return ranks_on_node_; }
  /// This node's name (MPI_Get_processor_name).
  const std::string& host() const noexcept { return host_; }
  /// Worker threads a rank uses by default: the node's hardware threads shared by its ranks,
  /// at most the CPUs the rank is bound to.
  int default_threads() const noexcept;

  /// Collective: every rank's `text`, indexed by rank, on rank 0 (empty on the others).
  std::vector<std::string> gather(const std::string& text) const;
  /// Collective: rank 0's `value` on every rank.
  std::string broadcast(const std::string& value) const;
  /// Ends every rank of the job at once (MPI_Abort) after printing `why` on this one.
  [[noreturn]] void abort(const std::string& why, int code) const;
  /// Rank 0 took a rank as lost (under mpirun --enable-recovery). MPI_Finalize synchronises
  /// with every rank of the job, the lost one included, and then can wait for it for ever (seen
  /// with Open MPI 4.1 in about 1 of 10 runs); the destructor then leaves without it, and mpirun
  /// reaps the process like the lost one.
  void mark_rank_lost() const noexcept { rank_lost_ = true; }

 private:
  int rank_ = 0, size_ = 1, ranks_on_node_ = 1;
  std::string host_;
  mutable bool rank_lost_ = false;
};

/// Collective: every rank passes its error ("" if none). When any rank has one, rank 0 throws
/// std::runtime_error with it (rank 0's own when every failing rank failed alike, else each
/// rank's, named) and the others throw QuietExit{2}: a rank that cannot go on must not leave
/// the others waiting.
void require_no_errors(const Session& session, const std::string& error);

/// The content hashes of a study's trials (trial_hashes()), known to be the same on every rank.
struct AgreedTrials {
  std::vector<std::string> hashes;
};

/// Collective: every rank computes the content hashes of `trials` (key, study settings, data,
/// build); rank 0 names each rank whose hashes differ from its own or that could not compute
/// them, and then throws std::runtime_error (the others QuietExit{2}). Call it before creating
/// anything, so that a refused run leaves nothing behind; run_with_store() takes its result.
AgreedTrials require_same_trials(const Session& session, const StudyDefinition& study,
                                 const std::vector<TrialSpec>& trials);

/// A task as it comes back to rank 0.
struct TaskReport {
  std::uint64_t id = 0;
  bool skipped = false;  ///< not run: stop was requested before it started
  std::string payload;   ///< what `run` returned (empty when skipped)
  int rank = 0;          ///< the rank that ran it
};

/// A set of tasks to spread over the ranks. Every rank calls distribute() with its own Job.
struct Job {
  /// The ids of the tasks in hand-out order (read on rank 0 only).
  std::vector<std::uint64_t> order;
  /// Runs one task on this rank and returns its result, or std::nullopt when the task was
  /// stopped by a stop request while it ran (reported as skipped); called concurrently from
  /// this rank's worker threads. It must not throw (an exception aborts the MPI job).
  std::function<std::optional<std::string>(std::uint64_t)> run;
  /// Rank 0: called for each task that finished or was skipped, in arrival order, from the
  /// thread that called distribute(). An exception thrown here aborts the MPI job.
  std::function<void(const TaskReport&)> on_report;
  /// Asked before a task starts, on every rank: once true on rank 0, no task is handed out any
  /// more and the rest are reported as skipped; on any rank, tasks it has not started are
  /// skipped. Tasks in flight finish normally.
  std::function<bool()> stop_requested;
  int threads = 1;  ///< worker threads on this rank (oneTBB)
  /// A worker that sends nothing (not even the heartbeat every timeout / 5, at most 5 s) for
  /// this long is taken as lost by rank 0, and its tasks in flight are run elsewhere; a worker
  /// that hears nothing from rank 0 for this long ends with an error. 0: wait for ever.
  double rank_timeout_seconds = 60;
};

/// How a job was spread, per rank (complete on rank 0 only).
struct JobStatistics {
  std::vector<RankRecord> ranks;  ///< host, threads and tasks of each rank
};

/// Collective: runs the job's tasks on every rank's threads; returns when every task is reported
/// (rank 0) or when rank 0 ends the job (others), so jobs can follow one another. A lost rank
/// is marked in the statistics (RankRecord::lost) and its tasks are run by the others.
JobStatistics distribute(const Session& session, const Job& job);

/// Collective: runs `trials` of `study`, which every rank has `agreed` on, across the ranks
/// through the result store (only rank 0 touches `store`, which may be null there and is
/// ignored elsewhere). Rank 0 gets every result, the
/// others std::nullopt once they are done. `options.threads` is this rank's thread count;
/// `options.on_start` and `options.on_trial_finished` are called on rank 0 only, from the
/// calling thread. `statistics`, when given, receives the spread (rank 0).
std::optional<StoredRun> run_with_store(const Session& session, const StudyDefinition& study,
                                        const std::vector<TrialSpec>& trials,
                                        const AgreedTrials& agreed, const RunOptions& options,
                                        ResultStore* store, bool fresh,
                                        JobStatistics* statistics = nullptr,
                                        double rank_timeout_seconds = 60);

/// The study pipeline's executor over the ranks of an MPI job (rkhs/pipeline/executor.hpp):
/// agree_on() is require_same_trials, run() is run_with_store above, on_every_process() is
/// require_no_errors around the action. Every rank makes the same calls in the same order.
class MpiExecutor final : public pipeline::Executor {
 public:
  MpiExecutor(const Session& session, double rank_timeout_seconds)
      : session_(session), rank_timeout_seconds_(rank_timeout_seconds) {}
  bool is_root() const override { return session_.is_root(); }
  void on_every_process(const std::function<void()>& action) const override;
  int default_threads() const override { return session_.default_threads(); }
  void agree_on(const StudyDefinition& study, const std::vector<TrialSpec>& trials) override;
  std::optional<StoredRun> run(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                               RunOptions options, ResultStore* store, bool fresh) override;
  bool root_decision(bool decision) const override {
    return session_.broadcast(decision ? "1" : "0") == "1";
  }
  std::vector<RankRecord> ranks() const override { return statistics_.ranks; }
  std::string where() const override;

 private:
  const Session& session_;
  double rank_timeout_seconds_;
  std::optional<AgreedTrials> agreed_;
  JobStatistics statistics_;
};

}  // namespace rkhs::distributed
