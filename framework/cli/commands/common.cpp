#include "commands/common.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "commands/commands.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/report/plots.hpp"

namespace rkhs::cli {

namespace {

std::atomic<bool> interrupted{false};
// A trial busy in a call without cancellation points (a large eigendecomposition) is given this
// long after Ctrl-C, then abandoned.
constexpr double abandon_after_seconds = 1.5;

extern "C" void request_stop(int) {
  interrupted = true;
}

}  // namespace

void refuse_output_onto_input(const std::string& option, const std::string& output,
                              const std::string& what, const std::string& input) {
  std::error_code error;
  if (std::filesystem::equivalent(output, input, error) && !error)
    throw std::invalid_argument(fmt::format(
        "{} {} is {} {}: writing it would replace what this command reads; write to another file",
        option, output, what, input));
}

void remove_store_files(const std::string& file) {
  std::error_code ignored;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"})
    std::filesystem::remove(file + suffix, ignored);
}

std::string counted(std::size_t count, const char* singular, const char* plural) {
  return fmt::format("{} {}", count, count == 1 ? singular : plural);
}

std::string computed_metrics_text(const StudyDefinition& study) {
  const auto computed = study.computed_metric_names();
  const auto total = study.computable_metrics().size();
  if (computed.size() == total)
    return fmt::format("metrics computed: all {} of an {} trial", total,
                       study_kind_name(study.kind()));
  std::vector<std::string> extra;
  for (const auto& metric : computed)
    if (std::find(study.metrics.begin(), study.metrics.end(), metric) == study.metrics.end())
      extra.push_back(metric);
  const std::string why = extra.empty()
                              ? std::string()
                              : fmt::format("; {} for {}", fmt::join(extra, ", "),
                                            fmt::join(study.computed_metric_reasons(), " and "));
  return fmt::format("metrics computed: {} ({} of {}{})", fmt::join(computed, ", "),
                     computed.size(), total, why);
}

void print_warnings(const StudyDefinition& study) {
  for (const auto& warning : study.warnings) std::cerr << printable(warning, true) << "\n";
}

void stop_at_signals() {
  std::signal(SIGINT, request_stop);
  std::signal(SIGTERM, request_stop);
}

void stop_on_signals(RunOptions& options) {
  stop_at_signals();
  options.stop_requested = [] { return interrupted.load(); };
  options.abandon_after_seconds = abandon_after_seconds;
}

bool stop_was_requested() noexcept {
  return interrupted.load();
}

int report_interruption(const StoredRun& run, const pipeline::StoreOptions& store,
                        const std::string& journal) {
  const auto trials = [](std::size_t count) { return counted(count, "trial", "trials"); };
  const std::size_t not_started = run.skipped - run.stopped;
  const std::string undone =
      run.stopped
          ? fmt::format("{} stopped while running and {} not started", run.stopped, not_started)
          : fmt::format("{} not started", not_started);
  if (store.disabled) {
    std::cerr << fmt::format(
        "rkhs-study: interrupted: {} finished, {}. Nothing was stored (--no-store){}: the same "
        "command runs every trial again.\n",
        trials(run.ran), undone,
        journal.empty() || !run.ran
            ? std::string()
            : fmt::format("; the finished trials' metrics are in {}", journal));
  } else {
    std::cerr << fmt::format(
        "rkhs-study: interrupted: {} finished and stored, {} (not stored). Run the same command "
        "again to resume: stored trials are reused.\n",
        trials(run.ran), undone);
  }
  return exit_interrupted;
}

void print_run_sources(const pipeline::PipelineOutcome& outcome,
                       const pipeline::Executor& executor) {
  if (!outcome.completed && !outcome.interrupted) return;  // not the root
  const auto ranks = executor.ranks();
  if (!ranks.empty()) {
    std::string per_rank;
    for (std::size_t r = 0; r < ranks.size(); ++r)
      per_rank += fmt::format("{}rank {} ({}, {} thread{}): {}{}", r ? "; " : "", r, ranks[r].host,
                              ranks[r].threads, ranks[r].threads == 1 ? "" : "s", ranks[r].trials,
                              ranks[r].lost ? " (lost)" : "");
    std::cerr << fmt::format("  trials run per MPI rank: {}\n", per_rank);
  }
  if (outcome.completed && !outcome.store_file.empty()) {
    const auto& stored = outcome.completed->stored;
    // A trial stored under another identity was not reused: say so, and what can change it.
    const auto superseded = std::min(stored.superseded, stored.ran);
    std::cerr << fmt::format(
        "  {} reused from {}, {} run now{}\n", counted(stored.reused, "trial", "trials"),
        outcome.store_file, stored.ran,
        superseded ? fmt::format(" ({} stored before under another identity: a plugin module "
                                 "rebuilt, another rkhs-study build or other study settings)",
                                 superseded == stored.ran ? std::string("all")
                                                          : fmt::format("{} of them", superseded))
                   : std::string());
  }
}

std::size_t render_plots(const RunRecord& record, const std::string& out_dir, bool quiet) {
  try {
    // A hanging gnuplot is killed at its time limit, or at SIGINT / SIGTERM.
    const auto outcome = write_plots(record, out_dir, plot_options(stop_was_requested));
    if (!quiet) {
      std::cerr << fmt::format("  {} in {}/plots (SVG, PNG and PDF)\n",
                               counted(outcome.rendered.size(), "plot", "plots"), out_dir);
      for (const auto& note : outcome.notes) std::cerr << "  note: " << note << "\n";
    }
    for (const auto& failure : outcome.failures)
      std::cerr << "rkhs-study: warning: plot not rendered: " << printable(failure, true) << "\n";
    return outcome.rendered.size();
  } catch (const std::exception& e) {
    std::cerr << "rkhs-study: warning: no plots: " << printable(e.what(), true) << "\n";
    return 0;
  }
}

void print_store_problems(const pipeline::PipelineOutcome& outcome) {
  const StoredRun* run = outcome.completed     ? &outcome.completed->stored
                         : outcome.interrupted ? &*outcome.interrupted
                                               : nullptr;
  if (!run) return;
  for (const auto& line : run->store_problems)
    std::cerr << fmt::format("rkhs-study: warning: {}\n", line);
}

}  // namespace rkhs::cli
