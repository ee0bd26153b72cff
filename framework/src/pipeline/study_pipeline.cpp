#include "rkhs/pipeline/study_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>

#include "rkhs/plugin/builtins.hpp"

namespace rkhs::pipeline {

StudyDefinition load_everywhere(const Executor& executor,
                                const std::function<StudyDefinition()>& load) {
  std::optional<StudyDefinition> study;
  executor.on_every_process([&] { study.emplace(load()); });
  return std::move(*study);
}

RunRecord CompletedRun::record() const {
  return RunRecord{study, trials, stored.results, rates, threads, seconds, started, ranks};
}

PipelineOutcome run_study(Executor& executor, const StudyDefinition& study,
                          const std::vector<TrialSpec>& trials, RunOptions options,
                          const StoreOptions& store_options, Rates fit) {
  std::optional<ResultStore> store;
  executor.on_every_process([&] {
    if (store_options.disabled || !executor.is_root()) return;
    if (store_options.read_only_when_complete && !store_options.fresh &&
        std::filesystem::exists(store_options.file)) {
      store.emplace(store_options.file, StoreAccess::read_only);
      const auto hashes = trial_hashes(study, trials);
      const bool complete = std::all_of(hashes.begin(), hashes.end(), [&](const auto& hash) {
        return store->lookup(hash, &study.all_metrics()).sound();
      });
      if (complete) return;
      store.reset();
    }
    store.emplace(store_options.file);
  });
  if (options.threads <= 0) options.threads = executor.default_threads();
  freeze_registries();
  const std::string started = utc_now();
  const auto start = std::chrono::steady_clock::now();
  auto stored =
      executor.run(study, trials, options, store ? &*store : nullptr, store_options.fresh);
  // The database file alone then holds every trial (a copy without its -wal file is whole).
  if (store) store->checkpoint();
  PipelineOutcome outcome;
  if (!stored) return outcome;
  outcome.store_file = store ? store->file().string() : std::string();
  if (stored->skipped) {
    outcome.interrupted = std::move(*stored);
    return outcome;
  }
  std::size_t failed = 0;
  for (const auto& result : stored->results) failed += result.ok ? 0 : 1;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  auto rates = fit == Rates::fitted ? compute_rates(study, trials, stored->results)
                                    : std::vector<MetricSeries>{};
  outcome.completed.emplace(CompletedRun{study, trials, std::move(*stored), std::move(rates),
                                         failed, options.threads, seconds, started,
                                         executor.ranks()});
  return outcome;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

}  // namespace rkhs::pipeline
