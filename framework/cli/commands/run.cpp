// `rkhs-study run STUDY`: every trial, then trials.csv, rates.csv, summary.json, rates.md,
// rates.tex, plots and report.html (docs/results.md); `--shard K/N` runs a subset into the
// store only. The console ends with the answer (console_answer): the fitted rates, the
// convergence in time of an adaptive study and, last, a verdict line per expectation; the groups'
// convergence tables only with --tables.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "commands/options.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/pipeline/journal.hpp"
#include "rkhs/pipeline/progress.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/run_folder.hpp"

namespace rkhs::cli {

namespace {

// "K/N" -> (K, N): two whole numbers of digits only (at most 4294967295) around one '/', with
// 1 <= K <= N, nothing before or after. Throws std::invalid_argument naming what was found and
// what is allowed otherwise.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text) {
  constexpr std::uint64_t most = 4294967295;
  const auto refuse = [&](const std::string& why) {
    throw std::invalid_argument(
        fmt::format("--shard '{}': {}; --shard takes K/N, two whole numbers (digits only) with 1 "
                    "<= K <= N, e.g. 2/4",
                    printable(text), why));
  };
  const auto slash = text.find('/');
  if (slash == std::string::npos) refuse("no '/'");
  if (text.find('/', slash + 1) != std::string::npos) refuse("more than one '/'");
  const auto number = [&](std::string_view digits, const char* name) -> std::size_t {
    if (digits.empty()) refuse(fmt::format("{} is empty", name));
    if (digits.find_first_not_of("0123456789") != std::string_view::npos)
      refuse(fmt::format("{} is '{}', not a whole number of digits", name, printable(digits)));
    std::uint64_t value = 0;
    for (const char c : digits) {
      value = value * 10 + static_cast<std::uint64_t>(c - '0');
      if (value > most) refuse(fmt::format("{} is larger than {}", name, most));
    }
    return static_cast<std::size_t>(value);
  };
  const auto k = number(std::string_view(text).substr(0, slash), "K");
  const auto n = number(std::string_view(text).substr(slash + 1), "N");
  if (n == 0) refuse("N is 0");
  if (k == 0) refuse("K is 0 (shards count from 1)");
  if (k > n) refuse(fmt::format("K = {} is greater than N = {}", k, n));
  return {k, n};
}

// A shard runs the trials whose grid index is K - 1 modulo N into its own store; `merge`
// combines the stores and a run over the merged store writes the outputs.
int run_shard(const RunCommand& arguments, const StudyDefinition& study,
              const std::vector<TrialSpec>& trials, pipeline::Executor& executor) {
  const auto [k, n] = parse_shard(arguments.shard);  // checked before the study was read
  if (arguments.store.disabled)
    throw std::invalid_argument("--shard needs a result store (not --no-store)");
  std::vector<TrialSpec> mine;
  for (const auto& trial : trials)
    if (trial.index % n == k - 1) mine.push_back(trial);
  RunOptions options;
  options.threads = arguments.threads;
  stop_on_signals(options);
  const auto outcome = pipeline::run_study(executor, study, mine, options, arguments.store,
                                           pipeline::Rates::not_fitted);
  print_store_problems(outcome);
  if (!arguments.quiet) print_run_sources(outcome, executor);
  if (outcome.interrupted) return report_interruption(*outcome.interrupted, arguments.store);
  const auto& stored = outcome.completed->stored;
  std::cout << fmt::format(
      "{}: shard {}/{}: {} of {} trials ({} reused, {} run) in {}; combine "
      "the shards' stores with `rkhs-study merge`\n",
      study.name, k, n, mine.size(), trials.size(), stored.reused, stored.ran,
      arguments.store.file);
  return exit_ok;
}

}  // namespace

int command_run(const RunCommand& arguments, pipeline::Executor& executor) {
  if (!arguments.shard.empty()) parse_shard(arguments.shard);  // a bad --shard reads nothing
  const auto study =
      pipeline::load_everywhere(executor, [&] { return load_study(arguments.study_file); });
  if (executor.is_root()) print_warnings(study);
  const std::string out_dir = arguments.out_dir.empty()
                                  ? (std::filesystem::path("results") / study.name).string()
                                  : arguments.out_dir;
  const auto trials = study.trials();
  executor.agree_on(study, trials);
  if (!arguments.shard.empty()) return run_shard(arguments, study, trials, executor);
  const bool root = executor.is_root();
  const bool quiet = arguments.quiet || !root;
  const int thread_count = arguments.threads > 0 ? arguments.threads : executor.default_threads();

  // The store first: one that is refused (not a store, damaged, a directory, read-only and
  // lacking trials) leaves the output folder as it was, without a journal.csv.
  auto opened = pipeline::open_store(executor, study, trials, arguments.store);
  std::optional<pipeline::Journal> journal;
  if (root) {
    // Before any trial: an output folder that cannot be written is exit 2, naming it (and a
    // store this run created is removed again).
    try {
      prepare_output_directory(out_dir);
      if (arguments.plots) prepare_output_directory(std::filesystem::path(out_dir) / "plots");
      journal.emplace(std::filesystem::path(out_dir) / "journal.csv", study);
    } catch (...) {
      if (opened.created && opened.store) {
        opened.store.reset();
        remove_store_files(arguments.store.file);
      }
      throw;
    }
  }
  if (!quiet)
    std::cerr << fmt::format("rkhs-study: {} ({}, {}{}) -> {}\n", study.name,
                             counted(trials.size(), "trial", "trials"),
                             counted(thread_count, "thread", "threads"), executor.where(), out_dir)
              << "  " << computed_metrics_text(study) << "\n";
  std::optional<pipeline::Progress> progress;
  if (!quiet) progress.emplace(std::cerr, isatty(STDERR_FILENO) != 0);
  RunOptions options;
  options.threads = thread_count;
  stop_on_signals(options);
  options.on_start = [&](std::size_t count) {
    if (progress) progress->start(count);  // the trials the store does not hold
  };
  options.on_trial_started = [&](const TrialSpec& trial) {
    if (progress) progress->trial_started(trial.index);
  };
  options.on_trial_finished = [&](const TrialSpec& trial, const TrialResult& result) {
    if (journal) journal->record(trial, result);
    if (!progress) return;
    if (!result.ok)
      progress->message(
          fmt::format("  trial failed: {}: {}", printable(trial.key), printable(result.reason)));
    progress->trial_finished(trial.index, result.ok);
  };
  const auto judged =
      pipeline::run_and_judge(executor, study, trials, options, arguments.store, std::move(opened));
  const auto& outcome = judged.outcome;
  if (!root) return stop_was_requested() ? exit_interrupted : exit_ok;
  if (!quiet) print_run_sources(outcome, executor);
  if (progress) progress->stop();
  print_store_problems(outcome);
  if (outcome.interrupted)
    // A journal whose writing failed is not offered as holding the finished trials.
    return report_interruption(*outcome.interrupted, arguments.store,
                               journal && journal->complete() ? journal->file().string() : "");

  const auto& run = *outcome.completed;
  // The expectations' verdicts, judged once with the run, go into summary.json and report.html.
  const auto& verdicts = judged.verdicts;
  auto record = run.record();
  record.verdicts = &verdicts;
  std::size_t plot_count = 0;
  write_run_folder(record, out_dir, arguments.plots, [&] {
    journal->remove();
    plot_count = arguments.plots ? render_plots(record, out_dir, quiet) : 0;
  });
  if (stop_was_requested()) {  // while the plots were rendered: gnuplot was killed
    std::cerr << fmt::format(
        "rkhs-study: interrupted while rendering plots; every other output in {} is complete\n",
        out_dir);
    return exit_interrupted;
  }

  if (!quiet && arguments.tables) std::cout << console_tables(record);
  std::cout << fmt::format(
      "{}: {}, {} ok, {} failed in {:.2f} s; wrote {}/trials.csv, rates.csv, summary.json, "
      "rates.md, rates.tex, report.html{}\n",
      study.name, counted(trials.size(), "trial", "trials"), trials.size() - run.failed, run.failed,
      run.seconds, out_dir, plot_count ? fmt::format(", plots/ ({} plots)", plot_count) : "");
  // The answer last, where the terminal shows it: the fitted rates, the convergence in time and
  // the verdicts (these also with -q).
  std::cout << console_answer(record, verdicts, quiet);
  return run.failed ? exit_failed_trials : exit_ok;
}

Command add_run_command(CLI::App& app, SessionOptions& session) {
  auto arguments = std::make_shared<RunCommand>();
  auto no_plots = std::make_shared<bool>(false);
  auto* run =
      app.add_subcommand("run", "run a study: trials, rates, trials.csv, rates.csv, summary.json");
  run->add_option("study", arguments->study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  run->add_option("--out", arguments->out_dir, "output directory (default: results/<study name>)");
  run->add_option("--threads", arguments->threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  run->add_flag("--quiet,-q", arguments->quiet,
                "print only the summary line and the verdict lines");
  add_store_options(*run, arguments->store);
  run->add_option("--shard", arguments->shard,
                  "K/N (digits only, 1 <= K <= N): run only the K-th of N deterministic subsets "
                  "into the store (job arrays)");
  add_mpi_options(*run, session);
  run->add_flag("--no-plots", *no_plots, "do not render plots (gnuplot) into <out>/plots");
  run->add_flag("--tables", arguments->tables,
                "also print each group's convergence table (they are in rates.md, rates.tex and "
                "report.html either way)");
  add_plugin_option(*run, session);
  add_data_dir_option(*run, session);
  return {run,
          [arguments, no_plots](SessionOptions& options) {
            options.runs_trials = true;
            options.shard = !arguments->shard.empty();
            arguments->plots = !*no_plots;
          },
          [arguments](pipeline::Executor& executor) { return command_run(*arguments, executor); }};
}

}  // namespace rkhs::cli
