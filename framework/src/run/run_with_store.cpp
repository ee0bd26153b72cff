// run_with_store (result_store.hpp): the trials a store holds are reused, the others run and
// are stored as they finish.
#include <fmt/format.h>

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "rkhs/run/result_store.hpp"
#include "rkhs/run/trial_identity.hpp"

namespace rkhs {

StoredRun run_with_store(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                         const RunOptions& options, ResultStore* store, bool fresh,
                         const TrialExecutor& execute,
                         const std::vector<std::string>& known_hashes) {
  StoredRun out;
  out.results.resize(trials.size());
  if (!known_hashes.empty() && known_hashes.size() != trials.size())
    throw std::invalid_argument("run_with_store: one known hash per trial expected");
  const auto hashes = !store                 ? std::vector<std::string>()
                      : known_hashes.empty() ? trial_hashes(study, trials)
                                             : known_hashes;
  std::vector<TrialSpec> pending;
  std::vector<std::size_t> position;  // index into `trials` of each pending trial
  std::size_t old_format = 0;
  for (std::size_t i = 0; i < trials.size(); ++i) {
    if (store && !fresh) {
      auto check = store->lookup(hashes[i], &study.all_metrics());
      if (check.result) {
        out.results[i] = std::move(*check.result);
        out.results[i].reused = true;
        ++out.reused;
        continue;
      }
      if (check.old_format)
        ++old_format;
      else if (!check.problem.empty())
        out.store_problems.push_back(fmt::format(
            "{}: trial {}: {}; run again", store->file().string(), trials[i].key, check.problem));
    }
    pending.push_back(trials[i]);
    position.push_back(i);
  }
  if (store && !fresh && !pending.empty()) {
    const auto stored_keys = store->keys_of_study(study.name);
    for (const auto& trial : pending) out.superseded += stored_keys.count(trial.key);
  }
  if (old_format)
    out.store_problems.push_back(fmt::format(
        "{}: {} stored in the old record format (no checksum): run again and stored anew",
        store->file().string(),
        old_format == 1 ? "1 trial" : fmt::format("{} trials", old_format)));
  std::map<std::size_t, std::size_t> slot;  // trial index -> position in `trials`
  for (std::size_t k = 0; k < pending.size(); ++k) slot[pending[k].index] = position[k];
  RunOptions storing = options;
  // A trial that cannot be stored (a full disk, an I/O error) stops the run: the callback runs
  // on a worker thread, where an exception would end the process (std::terminate), so the
  // first error is kept, no new trial starts, and it is thrown here once the run has returned.
  std::mutex store_error_mutex;
  std::string store_error;
  auto store_failed = std::make_shared<std::atomic<bool>>(false);
  storing.on_trial_finished = [&](const TrialSpec& trial, const TrialResult& result) {
    if (store && !store_failed->load()) {
      try {
        store->put(hashes[slot.at(trial.index)], study.name, trial.key, result,
                   study.all_metrics());
      } catch (const std::exception& e) {
        std::lock_guard lock(store_error_mutex);
        if (store_error.empty()) store_error = e.what();
        store_failed->store(true);
      }
    }
    if (options.on_trial_finished) options.on_trial_finished(trial, result);
  };
  // Copied by value: abandoned trials may still ask after this function has returned.
  storing.stop_requested = [failed = store_failed, asked = options.stop_requested] {
    return failed->load() || (asked && asked());
  };
  auto ran = execute(study, pending, storing);
  if (store_failed->load()) {
    std::lock_guard lock(store_error_mutex);
    throw std::runtime_error(store_error +
                             " (the trials stored before it are kept: run the same command again "
                             "to resume once the store can be written)");
  }
  for (std::size_t k = 0; k < pending.size(); ++k) {
    if (ran[k].skipped) {
      ++out.skipped;
      if (ran[k].stopped_while_running) ++out.stopped;
    } else {
      ++out.ran;
    }
    out.results[position[k]] = std::move(ran[k]);
  }
  return out;
}

}  // namespace rkhs
