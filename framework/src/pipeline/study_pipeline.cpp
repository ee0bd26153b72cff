#include "rkhs/pipeline/study_pipeline.hpp"

#include <fmt/format.h>

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

OpenedStore open_store(const Executor& executor, const StudyDefinition& study,
                       const std::vector<TrialSpec>& trials, const StoreOptions& options) {
  OpenedStore opened;
  executor.on_every_process([&] {
    if (options.disabled || !executor.is_root()) return;
    const std::filesystem::path file = options.file;
    std::error_code ignored;
    opened.created = !std::filesystem::exists(file, ignored);
    // How many of `trials` the read-only store lacks a verified record of.
    const auto missing = [&](const ResultStore& store) {
      const auto hashes = trial_hashes(study, trials);
      return static_cast<std::size_t>(std::count_if(
          hashes.begin(), hashes.end(),
          [&](const auto& hash) { return !store.lookup(hash, &study.all_metrics()).sound(); }));
    };
    if (options.read_only_when_complete && !options.fresh && !opened.created) {
      auto store = std::make_unique<ResultStore>(file, StoreAccess::read_only);
      if (missing(*store) == 0) {
        opened.store = std::move(store);
        return;
      }
    }
    try {
      opened.store = std::make_unique<ResultStore>(file);
    } catch (const ReadOnlyStore& e) {
      // A store this run cannot write serves a run that only reads it.
      if (opened.created) throw;
      if (options.fresh)
        throw ReadOnlyStore(fmt::format(
            "{}; --fresh runs every trial again and stores it: give a store that can be "
            "written",
            e.what()));
      auto store = std::make_unique<ResultStore>(file, StoreAccess::read_only);
      if (const auto lacking = missing(*store))
        throw ReadOnlyStore(fmt::format(
            "{}: {} of the {} trials are not stored in it, and their results could not be "
            "stored; run with a store that can be written (a copy: `rkhs-study merge "
            "COPY.sqlite {}`, then --store COPY.sqlite) or with --no-store",
            e.what(), lacking, trials.size(), file.string()));
      opened.store = std::move(store);
    }
  });
  return opened;
}

PipelineOutcome run_study(Executor& executor, const StudyDefinition& study,
                          const std::vector<TrialSpec>& trials, RunOptions options,
                          const StoreOptions& store_options, Rates fit) {
  return run_study(executor, study, trials, std::move(options), store_options,
                   open_store(executor, study, trials, store_options), fit);
}

PipelineOutcome run_study(Executor& executor, const StudyDefinition& study,
                          const std::vector<TrialSpec>& trials, RunOptions options,
                          const StoreOptions& store_options, OpenedStore opened, Rates fit) {
  auto& store = opened.store;
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

JudgedRun run_and_judge(Executor& executor, const StudyDefinition& study,
                        const std::vector<TrialSpec>& trials, RunOptions options,
                        const StoreOptions& store, OpenedStore opened,
                        const CaseSelection* selection) {
  // CompletedRun holds references: built in place, never assigned.
  JudgedRun judged{run_study(executor, study, trials, std::move(options), store, std::move(opened)),
                   {}};
  if (const auto& run = judged.outcome.completed) {
    judged.verdicts = verify_expectations(study, trials, run->stored.results, run->rates);
    if (selection) keep_selected(judged.verdicts, *selection);
  }
  return judged;
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
