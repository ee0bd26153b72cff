// Trials across MPI ranks: the study-level layer of rkhs/mpi/distributed.hpp over distribute().

#include <fmt/format.h>

#include <cstdlib>
#include <exception>
#include <map>
#include <string_view>

#include "rkhs/core/sha256.hpp"
#include "rkhs/mpi/distributed.hpp"
#include "rkhs/run/trial_cost.hpp"

namespace rkhs::distributed {

namespace {

// Trial ids on the wire are grid indices; every rank maps them back to its own TrialSpec.
std::map<std::uint64_t, const TrialSpec*> trials_by_index(const std::vector<TrialSpec>& trials) {
  std::map<std::uint64_t, const TrialSpec*> out;
  for (const auto& trial : trials)
    if (!out.emplace(trial.index, &trial).second)
      throw std::logic_error(fmt::format("two trials with grid index {}", trial.index));
  return out;
}

}  // namespace

AgreedTrials require_same_trials(const Session& session, const StudyDefinition& study,
                                 const std::vector<TrialSpec>& trials) {
  AgreedTrials agreed;
  std::string mine;
  try {
    agreed.hashes = trial_hashes(study, trials);
    Sha256 digest;
    for (const auto& hash : agreed.hashes) digest.update(hash);
    mine = "ok " + digest.hex_digest();
  } catch (const std::exception& e) {
    mine = std::string("error ") + e.what();
  }
  std::string verdict;
  const auto all = session.gather(mine + " " + std::to_string(trials.size()));
  if (session.is_root()) {
    for (std::size_t r = 0; r < all.size(); ++r) {
      if (all[r].rfind("error ", 0) == 0)
        verdict += fmt::format("\n  rank {}: {}", r, all[r].substr(6, all[r].rfind(' ') - 6));
      else if (all[r] != all[0] && all[0].rfind("ok ", 0) == 0)
        verdict += fmt::format(
            "\n  rank {} sees other trials than rank 0 ({} trials; a different study file, data "
            "file, plugin or rkhs-study build on its node)",
            r, all[r].substr(all[r].rfind(' ') + 1));
    }
    if (!verdict.empty())
      verdict =
          fmt::format("{}: the MPI ranks do not agree on the study's trials, nothing was run:{}",
                      study.name, verdict);
  }
  verdict = session.broadcast(verdict);
  if (!verdict.empty()) {
    if (session.is_root()) throw std::runtime_error(verdict);
    throw QuietExit{2};
  }
  return agreed;
}

void require_no_errors(const Session& session, const std::string& error) {
  const auto errors = session.gather(error);
  std::string verdict;
  if (session.is_root()) {
    std::size_t failing = 0;
    bool alike = true;  // every failing rank failed as rank 0 did
    for (const auto& e : errors) {
      failing += e.empty() ? 0 : 1;
      alike = alike && (e.empty() || e == errors[0]);
    }
    if (failing > 0 && alike) {
      verdict = errors[0];  // said once (the same study file on every rank, typically)
    } else if (failing > 0) {
      verdict = fmt::format("{} of {} MPI ranks cannot go on:", failing, errors.size());
      for (std::size_t r = 0; r < errors.size(); ++r)
        if (!errors[r].empty()) verdict += fmt::format("\n  rank {}: {}", r, errors[r]);
    }
  }
  verdict = session.broadcast(verdict);
  if (verdict.empty()) return;
  if (session.is_root()) throw std::runtime_error(verdict);
  throw QuietExit{2};
}

int launched_process_count() noexcept {
  // Open MPI's mpirun, then PMI (MPICH's launchers, srun --mpi=pmi2). Not SLURM_NTASKS: a batch
  // script of a many-task job has it while it runs as one process.
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}) {
    if (const char* value = std::getenv(name)) {
      char* end = nullptr;
      const long size = std::strtol(value, &end, 10);
      if (end != value && size >= 1 && size < 1 << 24) return static_cast<int>(size);
    }
  }
  return 1;
}

std::optional<StoredRun> run_with_store(const Session& session, const StudyDefinition& study,
                                        const std::vector<TrialSpec>& trials,
                                        const AgreedTrials& agreed, const RunOptions& options,
                                        ResultStore* store, bool fresh, JobStatistics* statistics,
                                        double rank_timeout_seconds) {
  const auto by_index = trials_by_index(trials);
  Job job;
  job.threads = options.threads > 0 ? options.threads : session.default_threads();
  job.stop_requested = options.stop_requested;
  job.rank_timeout_seconds = rank_timeout_seconds;
  LapMapCache lap_maps;  // this rank's: trials differing only in laps share their lap map
  job.run = [&](std::uint64_t id) -> std::optional<std::string> {
    const auto result = run_trial(study, *by_index.at(id), options.stop_requested, &lap_maps);
    if (result.skipped) return std::nullopt;  // stopped while it ran: not stored, run again later
    return serialize_result(result);
  };
  if (!session.is_root()) {
    distribute(session, job);
    return std::nullopt;
  }
  // Rank 0: the trials the store lacks are handed out, largest first (largest_first_order, as
  // in a run without MPI); each result is committed
  // (through `storing`) as it arrives.
  const TrialExecutor coordinate = [&](const StudyDefinition&,
                                       const std::vector<TrialSpec>& pending,
                                       const RunOptions& storing) {
    if (storing.on_start) storing.on_start(pending.size());
    // Also true once a result could not be stored (a full disk): no trial is handed out then.
    job.stop_requested = storing.stop_requested;
    std::vector<TrialResult> results(pending.size());
    std::map<std::uint64_t, std::size_t> slot;
    for (std::size_t k = 0; k < pending.size(); ++k) slot[pending[k].index] = k;
    for (const auto k : largest_first_order(study, pending)) job.order.push_back(pending[k].index);
    job.on_report = [&](const TaskReport& report) {
      const std::size_t k = slot.at(report.id);
      if (report.skipped) {
        results[k].skipped = true;
        results[k].reason = "not run: the run was interrupted";
        return;
      }
      results[k] = deserialize_result(report.payload);
      if (storing.on_trial_finished) storing.on_trial_finished(pending[k], results[k]);
    };
    auto spread = distribute(session, job);
    if (statistics) *statistics = std::move(spread);
    return results;
  };
  return rkhs::run_with_store(study, trials, options, store, fresh, coordinate, agreed.hashes);
}

bool launched_first() noexcept {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMI_RANK"})
    if (const char* value = std::getenv(name)) return std::string_view(value) == "0";
  return true;
}

void MpiExecutor::on_every_process(const std::function<void()>& action) const {
  std::string error;
  std::exception_ptr own_error;
  try {
    action();
  } catch (const std::exception& e) {
    error = e.what();
    own_error = std::current_exception();
  }
  try {
    require_no_errors(session_, error);
  } catch (const std::runtime_error& verdict) {
    if (own_error && verdict.what() == error) std::rethrow_exception(own_error);
    throw;
  }
}

void MpiExecutor::agree_on(const StudyDefinition& study, const std::vector<TrialSpec>& trials) {
  agreed_ = require_same_trials(session_, study, trials);
}

std::optional<StoredRun> MpiExecutor::run(const StudyDefinition& study,
                                          const std::vector<TrialSpec>& trials, RunOptions options,
                                          ResultStore* store, bool fresh) {
  if (!agreed_) agree_on(study, trials);
  // A rank's trials in flight finish: the coordinator reports them (no abandoning).
  options.abandon_after_seconds = -1;
  return run_with_store(session_, study, trials, *agreed_, options, store, fresh, &statistics_,
                        rank_timeout_seconds_);
}

std::string MpiExecutor::where() const {
  return fmt::format(" on rank 0 of {} MPI ranks", session_.size());
}

}  // namespace rkhs::distributed
