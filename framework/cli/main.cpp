// The rkhs-study command: run study definitions, list plugins, validate study files, check a
// study's expectations.
// Exit codes: 0 success; 1 the study ran but some trials failed (their reasons are recorded),
// or (check) an expectation failed; 2 bad input (command line, study file) or a broken plugin
// registration; 3 (check) no expectation failed but some are inconclusive.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <optional>
#include <thread>

#include "progress.hpp"
#include "rkhs/adaptive.hpp"
#include "rkhs/approximation.hpp"
#include "rkhs/build_info.hpp"
#include "rkhs/centres.hpp"
#include "rkhs/data_root.hpp"
#include "rkhs/distributed.hpp"
#include "rkhs/html_report.hpp"
#include "rkhs/junit.hpp"
#include "rkhs/kernel.hpp"
#include "rkhs/output.hpp"
#include "rkhs/plant.hpp"
#include "rkhs/plots.hpp"
#include "rkhs/plugin_loader.hpp"
#include "rkhs/plugin_verification.hpp"
#include "rkhs/plugins.hpp"
#include "rkhs/result_store.hpp"
#include "rkhs/run.hpp"
#include "rkhs/study.hpp"
#include "rkhs/study_rates.hpp"
#include "rkhs/target.hpp"
#include "rkhs/tiers.hpp"
#include "rkhs/verification.hpp"

namespace {

constexpr int exit_ok = 0, exit_failed_trials = 1, exit_bad_input = 2, exit_interrupted = 130;

// "1 trial", "3 trials".
std::string counted(std::size_t count, const char* singular, const char* plural) {
  return fmt::format("{} {}", count, count == 1 ? singular : plural);
}

// A study file's warnings (valid but doubtful settings), one line each.
void print_warnings(const rkhs::StudyDefinition& study) {
  for (const auto& warning : study.warnings) std::cerr << warning << "\n";
}

// Where finished trials are committed (docs/results.md): shared by every study run from here.
struct StoreOptions {
  std::string file = "results/rkhs-study.sqlite";
  bool fresh = false;     ///< run every trial again (results are still stored)
  bool disabled = false;  ///< no store at all
};

// --rank-timeout: an MPI rank silent this long is taken as lost (docs/cluster.md).
double rank_timeout_seconds = 60;

// SIGINT / SIGTERM: no new trial starts, and trials in flight stop at their next cancellation
// point (rkhs/cancellation.hpp) or are abandoned `abandon_after_seconds` later; neither kind is
// stored. The run then exits 130 with the resume message.
std::atomic<bool> interrupted{false};
constexpr double abandon_after_seconds = 2.0;
extern "C" void request_stop(int) {
  interrupted = true;
}

void install_stop_handlers() {
  std::signal(SIGINT, request_stop);
  std::signal(SIGTERM, request_stop);
}

using rkhs::distributed::Session;

// Runs `action` on this rank. With MPI every rank must succeed before any goes on (a rank
// that cannot must not leave the others waiting in a collective call): rank 0 reports the
// errors, as its own exception when every failing rank failed alike, and the other ranks
// leave quietly.
template <class Action>
void on_every_rank(const Session* mpi, const Action& action) {
  if (!mpi) return action();
  std::string error;
  std::exception_ptr own_error;
  try {
    action();
  } catch (const std::exception& e) {
    error = e.what();
    own_error = std::current_exception();
  }
  try {
    rkhs::distributed::require_no_errors(*mpi, error);
  } catch (const std::runtime_error& verdict) {
    if (own_error && verdict.what() == error) std::rethrow_exception(own_error);
    throw;
  }
}

// A command's part in a distributed run: the session, the trials every rank agreed on and,
// once they ran, how they were spread over the ranks.
struct Distributed {
  const Session& session;
  rkhs::distributed::AgreedTrials agreed;
  std::vector<rkhs::RankRecord> ranks = {};
};

// With --mpi: checks that every rank sees the same trials (before anything is created).
std::optional<Distributed> distribute_over(const Session* mpi, const rkhs::StudyDefinition& study,
                                           const std::vector<rkhs::TrialSpec>& trials) {
  if (!mpi) return std::nullopt;
  return Distributed{*mpi, rkhs::distributed::require_same_trials(*mpi, study, trials)};
}

// Runs the trials through the store; prints how to resume when interrupted. With MPI
// (`distributed` not null) the trials are spread over the ranks: rank 0 alone opens the store
// and gets the results; the other ranks get std::nullopt when they are done.
std::optional<rkhs::StoredRun> run_trials_stored(const rkhs::StudyDefinition& study,
                                                 const std::vector<rkhs::TrialSpec>& trials,
                                                 rkhs::RunOptions options,
                                                 const StoreOptions& store_options, bool quiet,
                                                 Distributed* distributed = nullptr) {
  const Session* mpi = distributed ? &distributed->session : nullptr;
  std::optional<rkhs::ResultStore> store;
  on_every_rank(mpi, [&] {
    if (!store_options.disabled && (!mpi || mpi->is_root())) store.emplace(store_options.file);
  });
  install_stop_handlers();
  options.stop_requested = [] { return interrupted.load(); };
  rkhs::freeze_registries();
  std::optional<rkhs::StoredRun> run;
  if (distributed) {
    rkhs::distributed::JobStatistics spread;
    run = rkhs::distributed::run_with_store(*mpi, study, trials, distributed->agreed, options,
                                            store ? &*store : nullptr, store_options.fresh, &spread,
                                            rank_timeout_seconds);
    distributed->ranks = spread.ranks;
    if (run && !quiet) {
      std::string per_rank;
      for (std::size_t r = 0; r < spread.ranks.size(); ++r)
        per_rank +=
            fmt::format("{}rank {} ({}, {} thread{}): {}{}", r ? "; " : "", r, spread.ranks[r].host,
                        spread.ranks[r].threads, spread.ranks[r].threads == 1 ? "" : "s",
                        spread.ranks[r].trials, spread.ranks[r].lost ? " (lost)" : "");
      std::cerr << fmt::format("  trials run per MPI rank: {}\n", per_rank);
    }
  } else {
    // A trial busy in a call without cancellation points (a large eigendecomposition) is
    // given this long after Ctrl-C, then abandoned; main() then ends the process at once.
    options.abandon_after_seconds = abandon_after_seconds;
    run = rkhs::run_with_store(study, trials, options, store ? &*store : nullptr,
                               store_options.fresh);
  }
  if (run && !run->skipped && !quiet && store)
    std::cerr << fmt::format("  {} reused from {}, {} run now\n",
                             counted(run->reused, "trial", "trials"), store->file().string(),
                             run->ran);
  return run;
}

// Loads the study (`load` reads it) on every rank; rank 0 prints its warnings.
template <class Load>
rkhs::StudyDefinition load_on_every_rank(const Load& load, const Session* mpi) {
  std::optional<rkhs::StudyDefinition> study;
  on_every_rank(mpi, [&] { study.emplace(load()); });
  if (!mpi || mpi->is_root()) print_warnings(*study);
  return std::move(*study);
}

// What an interrupted run did and kept, in words that are true with and without a store.
// `journal`: where `run` kept the finished trials' metrics (empty for other commands).
int report_interruption(const rkhs::StoredRun& run, const StoreOptions& store_options,
                        const std::filesystem::path& journal = {}) {
  const auto trials = [](std::size_t count) { return counted(count, "trial", "trials"); };
  const std::size_t not_started = run.skipped - run.stopped;
  const std::string undone =
      run.stopped
          ? fmt::format("{} stopped while running and {} not started", run.stopped, not_started)
          : fmt::format("{} not started", not_started);
  if (store_options.disabled) {
    std::cerr << fmt::format(
        "rkhs-study: interrupted: {} finished, {}. Nothing was stored (--no-store){}: the same "
        "command runs every trial again.\n",
        trials(run.ran), undone,
        journal.empty() || !run.ran
            ? std::string()
            : fmt::format("; the finished trials' metrics are in {}", journal.string()));
  } else {
    std::cerr << fmt::format(
        "rkhs-study: interrupted: {} finished and stored, {} (not stored). Run the same command "
        "again to resume: stored trials are reused.\n",
        trials(run.ran), undone);
  }
  return exit_interrupted;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

std::string describe_parameter(const rkhs::ParameterSpec& spec) {
  std::string detail =
      "default " +
      (spec.default_doc.empty() ? rkhs::format_value(spec.default_value) : spec.default_doc);
  if (spec.type == rkhs::ParameterType::choice)
    detail += fmt::format("; one of {}", fmt::join(spec.choices, ", "));
  else if (spec.type == rkhs::ParameterType::real || spec.type == rkhs::ParameterType::integer)
    if (const auto range = rkhs::describe_range(spec); range != "any number")
      detail += "; " + range;
  return fmt::format("    {:<14} {} ({})", spec.name, spec.doc, detail);
}

template <class RegistryType>
void list_registry(const RegistryType& registry, std::ostream& out) {
  out << registry.kind() << " plugins:\n";
  for (const auto& name : registry.names()) {
    const auto& info = registry.find(name)->info;
    out << fmt::format("  {:<10} {}\n", name, info.doc);
    for (const auto& spec : info.parameters) out << describe_parameter(spec) << "\n";
    for (const auto& [key, value] : info.traits) out << fmt::format("    [{}] {}\n", key, value);
  }
  out << "\n";
}

int command_list(const std::string& kind) {
  const bool all = kind.empty();
  if (all || kind == "kernel" || kind == "kernels")
    list_registry(rkhs::kernel_registry(), std::cout);
  if (all || kind == "centres") list_registry(rkhs::centre_registry(), std::cout);
  if (all || kind == "target" || kind == "targets")
    list_registry(rkhs::target_registry(), std::cout);
  if (all || kind == "plant" || kind == "plants") list_registry(rkhs::plant_registry(), std::cout);
  if (all || kind == "law" || kind == "laws") list_registry(rkhs::law_registry(), std::cout);
  if (all || kind == "integrator" || kind == "integrators")
    list_registry(rkhs::integrator_registry(), std::cout);
  if (all || kind == "metric" || kind == "metrics") {
    for (const char* study_kind : {"approximation", "adaptive"}) {
      std::cout << "metrics (" << study_kind << " trials):\n";
      for (const auto& name : rkhs::metric_names(study_kind)) std::cout << "  " << name << "\n";
    }
  }
  if (const auto plugins = rkhs::loaded_plugins(); all && !plugins.empty()) {
    std::cout << "\nplugin modules:\n";
    for (const auto& p : plugins)
      std::cout << fmt::format("  {:<10} {} (built against rkhs-study {})\n", p.name,
                               p.file.string(), p.rkhs_study_version);
  }
  return exit_ok;
}

// Exit 0 when every check passed, 1 when some failed (the report says which).
int command_verify_plugin(const std::string& file) {
  const auto verification = rkhs::verify_plugin(file);
  std::cout << rkhs::format_verification(verification);
  return verification.passed() ? exit_ok : exit_failed_trials;
}

// Appends each finished trial to a journal, flushed at once, so an interrupted run keeps what
// it computed; removed once the outputs are complete.
class Journal {
 public:
  Journal(const std::filesystem::path& file, const std::vector<std::string>& metrics)
      : file_(file) {
    out_.open(file, std::ios::trunc);
    out_ << "index,key,status,reason";
    for (const auto& m : metrics) out_ << "," << m;
    out_ << "\n" << std::flush;
  }
  void record(const rkhs::StudyDefinition& study, const rkhs::TrialSpec& trial,
              const rkhs::TrialResult& result) {
    out_ << trial.index << "," << rkhs::csv_field(trial.key) << "," << (result.ok ? "ok" : "failed")
         << "," << rkhs::csv_field(result.reason);
    for (const auto& m : study.metrics)
      out_ << "," << rkhs::csv_number(result.metrics[study.metric_index(m)]);
    out_ << "\n" << std::flush;
  }
  void remove() {
    out_.close();
    std::filesystem::remove(file_);
  }
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  std::ofstream out_;
};

// Threads of this process: --threads, else all cores (shared by the MPI ranks on a node).
int default_thread_count(int threads, const Session* mpi) {
  if (threads > 0) return threads;
  if (mpi) return mpi->default_threads();
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// An MPI rank other than 0: runs the trials rank 0 hands it; writes nothing.
int serve_trials(const rkhs::StudyDefinition& study, const std::vector<rkhs::TrialSpec>& trials,
                 int threads, const StoreOptions& store_options, Distributed& distributed) {
  rkhs::RunOptions options;
  options.threads = default_thread_count(threads, &distributed.session);
  run_trials_stored(study, trials, options, store_options, true, &distributed);
  return interrupted ? exit_interrupted : exit_ok;
}

// "K/N" -> (K, N) with 1 <= K <= N; throws CLI::ValidationError otherwise.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::size_t k = 0, n = 0;
  try {
    if (slash != std::string::npos) {
      k = std::stoul(text.substr(0, slash));
      n = std::stoul(text.substr(slash + 1));
    }
  } catch (const std::exception&) {
  }
  if (n == 0 || k == 0 || k > n)
    throw std::invalid_argument("--shard must be K/N with 1 <= K <= N, found '" + text + "'");
  return {k, n};
}

int command_run(const std::string& study_file, std::string out_dir, int threads, bool quiet,
                const StoreOptions& store_options, bool plots, const std::string& shard,
                const Session* mpi) {
  const auto study = load_on_every_rank([&] { return rkhs::load_study(study_file); }, mpi);
  if (out_dir.empty()) out_dir = (std::filesystem::path("results") / study.name).string();
  auto trials = study.trials();
  auto distributed = distribute_over(mpi, study, trials);
  if (mpi && !mpi->is_root())
    return serve_trials(study, trials, threads, store_options, *distributed);
  if (!shard.empty()) {
    // A shard runs the trials whose grid index is K - 1 modulo N into its own store; `merge`
    // combines the stores and a run over the merged store writes the outputs.
    const auto [k, n] = parse_shard(shard);
    if (store_options.disabled)
      throw std::invalid_argument("--shard needs a result store (not --no-store)");
    std::vector<rkhs::TrialSpec> mine;
    for (const auto& trial : trials)
      if (trial.index % n == k - 1) mine.push_back(trial);
    rkhs::RunOptions options;
    options.threads = threads;
    const auto stored = *run_trials_stored(study, mine, options, store_options, quiet);
    if (stored.skipped) return report_interruption(stored, store_options);
    std::cout << fmt::format(
        "{}: shard {}/{}: {} of {} trials ({} reused, {} run) in {}; combine "
        "the shards' stores with `rkhs-study merge`\n",
        study.name, k, n, mine.size(), trials.size(), stored.reused, stored.ran,
        store_options.file);
    return exit_ok;
  }
  const int thread_count = default_thread_count(threads, mpi);
  std::filesystem::create_directories(out_dir);
  Journal journal(std::filesystem::path(out_dir) / "journal.csv", study.metrics);

  if (!quiet)
    std::cerr << fmt::format(
        "rkhs-study: {} ({}, {}{}) -> {}\n", study.name, counted(trials.size(), "trial", "trials"),
        counted(thread_count, "thread", "threads"),
        mpi ? fmt::format(" on rank 0 of {} MPI ranks", mpi->size()) : "", out_dir);
  const std::string started = utc_now();
  const auto start = std::chrono::steady_clock::now();
  std::size_t failed = 0;
  std::optional<rkhs::cli::Progress> progress;
  if (!quiet) progress.emplace(std::cerr, isatty(STDERR_FILENO) != 0);
  rkhs::RunOptions options;
  options.threads = thread_count;
  options.on_start = [&](std::size_t count) {
    if (progress) progress->start(count);  // the trials the store does not hold
  };
  options.on_trial_started = [&](const rkhs::TrialSpec& trial) {
    if (progress) progress->trial_started(trial.index);
  };
  options.on_trial_finished = [&](const rkhs::TrialSpec& trial, const rkhs::TrialResult& result) {
    journal.record(study, trial, result);
    if (!progress) return;
    if (!result.ok)
      progress->message(fmt::format("  trial failed: {}: {}", trial.key, result.reason));
    progress->trial_finished(trial.index, result.ok);
  };
  const auto stored = *run_trials_stored(study, trials, options, store_options, quiet,
                                         distributed ? &*distributed : nullptr);
  if (progress) progress->stop();
  if (stored.skipped) return report_interruption(stored, store_options, journal.file());
  const auto& results = stored.results;
  for (const auto& result : results) failed += result.ok ? 0 : 1;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto rates = rkhs::compute_rates(study, trials, results);
  const rkhs::RunRecord record{
      study,        trials,
      results,      rates,
      thread_count, seconds,
      started,      distributed ? distributed->ranks : std::vector<rkhs::RankRecord>{}};
  rkhs::write_outputs(record, out_dir);
  journal.remove();
  std::size_t plot_count = 0;
  if (plots) {
    try {
      const auto outcome = rkhs::write_plots(record, out_dir);
      plot_count = outcome.rendered.size();
      if (!quiet) {
        std::cerr << fmt::format("  {} in {}/plots (SVG and PNG)\n",
                                 counted(plot_count, "plot", "plots"), out_dir);
        for (const auto& note : outcome.notes) std::cerr << "  note: " << note << "\n";
      }
      for (const auto& failure : outcome.failures)
        std::cerr << "rkhs-study: warning: plot not rendered: " << failure << "\n";
    } catch (const std::exception& e) {
      std::cerr << "rkhs-study: warning: no plots: " << e.what() << "\n";
    }
  }
  // Without plots this run, the page embeds none (not those an earlier run left in plots/).
  rkhs::write_file_atomically(
      std::filesystem::path(out_dir) / "report.html",
      rkhs::html_report(
          record, plots ? std::filesystem::path(out_dir) / "plots" : std::filesystem::path()));

  if (!quiet) std::cout << rkhs::console_tables(record);
  std::cout << fmt::format(
      "{}: {}, {} ok, {} failed in {:.2f} s; wrote {}/trials.csv, rates.csv, summary.json, "
      "rates.md, rates.tex, report.html{}\n",
      study.name, counted(trials.size(), "trial", "trials"), trials.size() - failed, failed,
      seconds, out_dir, plot_count ? fmt::format(", plots/ ({} plots)", plot_count) : "");
  return failed ? exit_failed_trials : exit_ok;
}

// `check`: runs the study (or one tier of it) and judges its [[expect]] tables
// (docs/verification.md). The exit code is the verdicts': 0 all pass, 1 a failure, 3 only
// inconclusive ones besides passes (1 with --strict).
struct CheckArguments {
  std::string study_file, tier, junit_file, out_dir;
  bool strict = false;
};

int command_check(const CheckArguments& arguments, int threads, bool quiet,
                  const StoreOptions& store_options, const Session* mpi) {
  const auto study = load_on_every_rank(
      [&] {
        auto loaded = rkhs::load_study(arguments.study_file);
        if (!arguments.tier.empty())
          loaded = rkhs::restrict_to_tier(std::move(loaded), arguments.tier);
        return loaded;
      },
      mpi);
  const auto trials = study.trials();
  auto distributed = distribute_over(mpi, study, trials);
  if (mpi && !mpi->is_root())
    return serve_trials(study, trials, threads, store_options, *distributed);
  const int thread_count = default_thread_count(threads, mpi);
  const auto tier_text = arguments.tier.empty() ? std::string() : " (tier " + arguments.tier + ")";
  if (!quiet)
    std::cerr << fmt::format("rkhs-study check: {}{}: {}, {}\n", study.name, tier_text,
                             counted(trials.size(), "trial", "trials"),
                             counted(thread_count, "thread", "threads"));
  const std::string started = utc_now();
  const auto start = std::chrono::steady_clock::now();
  rkhs::RunOptions options;
  options.threads = thread_count;
  const auto stored = *run_trials_stored(study, trials, options, store_options, quiet,
                                         distributed ? &*distributed : nullptr);
  if (stored.skipped) return report_interruption(stored, store_options);
  const auto& results = stored.results;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto rates = rkhs::compute_rates(study, trials, results);
  std::size_t failed = 0;
  for (const auto& result : results) failed += result.ok ? 0 : 1;
  if (!arguments.out_dir.empty()) {
    const rkhs::RunRecord record{
        study,        trials,
        results,      rates,
        thread_count, seconds,
        started,      distributed ? distributed->ranks : std::vector<rkhs::RankRecord>{}};
    rkhs::write_outputs(record, arguments.out_dir);
  }
  const auto outcomes = rkhs::verify_expectations(study, trials, results, rates);
  std::cout << fmt::format("{}{}: {}, {} ok, {} failed in {:.2f} s\n", study.name, tier_text,
                           counted(trials.size(), "trial", "trials"), trials.size() - failed,
                           failed, seconds);
  if (failed)
    std::cout << fmt::format(
        "note: {} trial{} failed; their reasons are in trials.csv (--out DIR)\n", failed,
        failed > 1 ? "s" : "");
  std::cout << rkhs::format_verification(outcomes, arguments.strict);
  if (!arguments.junit_file.empty())
    rkhs::write_file_atomically(
        arguments.junit_file,
        rkhs::junit_xml({study, outcomes, arguments.strict, seconds, arguments.tier, started}));
  return rkhs::check_exit_code(rkhs::count_verdicts(outcomes), arguments.strict);
}

// `report DIR`: the tables of the run in DIR again, from the study file it names (summary.json)
// and the result store (trials not stored are run).
int command_report(const std::string& directory, const std::string& format,
                   const StoreOptions& store_options) {
  const auto summary = std::filesystem::path(directory) / "summary.json";
  std::ifstream in(summary);
  if (!in)
    throw std::runtime_error(summary.string() + ": cannot open (is it a results directory?)");
  std::string line, source;
  while (std::getline(in, line))
    if (const auto at = line.find("\"source\": \""); at != std::string::npos) {
      source = line.substr(at + 11);
      source = source.substr(0, source.find('"'));
      break;
    }
  if (source.empty())
    throw std::runtime_error(summary.string() + ": no \"source\" study file recorded");
  const auto study = rkhs::load_study(source);
  const auto trials = study.trials();
  rkhs::RunOptions options;
  const auto stored = *run_trials_stored(study, trials, options, store_options, true);
  if (stored.skipped) return report_interruption(stored, store_options);
  const auto rates = rkhs::compute_rates(study, trials, stored.results);
  const rkhs::RunRecord record{study, trials, stored.results, rates, 1, 0.0, utc_now()};
  if (format == "md")
    std::cout << rkhs::markdown_tables(record);
  else if (format == "tex")
    std::cout << rkhs::latex_tables(record);
  else {
    const auto file = std::filesystem::path(directory) / "report.html";
    rkhs::write_file_atomically(
        file, rkhs::html_report(record, std::filesystem::path(directory) / "plots"));
    std::cout << "wrote " << file.string() << "\n";
  }
  return exit_ok;
}

int command_validate(const std::string& study_file) {
  const auto study = rkhs::load_study(study_file);
  print_warnings(study);
  const auto trials = study.trials();
  std::vector<std::string> factors;
  for (const auto& axis : study.grid_axes())
    factors.push_back(counted(axis.count, axis.singular, axis.plural));
  std::cout << fmt::format("{}: valid; {} = {}\n", study_file, fmt::join(factors, " x "),
                           counted(trials.size(), "trial", "trials"));
  if (const auto tiers = rkhs::study_tiers(study); !study.expectations.empty() || !tiers.empty())
    std::cout << fmt::format(
        "  {} expectation{}; tiers: {}\n", study.expectations.size(),
        study.expectations.size() == 1 ? "" : "s",
        tiers.empty() ? std::string("none") : fmt::format("{}", fmt::join(tiers, ", ")));
  return exit_ok;
}

int rkhs_study_main(int argc, char** argv) {
  CLI::App app{
      "rkhs-study: convergence studies of kernel approximation and adaptive estimation "
      "in reproducing kernel Hilbert spaces"};
  app.require_subcommand(1);
  app.set_version_flag(
      "--version",
      fmt::format("rkhs-study {} (commit {}; {}; MPI runner: {})", rkhs::build_info().version,
                  rkhs::build_info().git_commit, rkhs::build_info().build_type,
                  rkhs::distributed::available() ? "yes" : "no, see docs/cluster.md"));

  std::string study_file, out_dir, kind;
  int threads = 0;
  bool quiet = false;
  auto* run =
      app.add_subcommand("run", "run a study: trials, rates, trials.csv, rates.csv, summary.json");
  run->add_option("study", study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("--out", out_dir, "output directory (default: results/<study name>)");
  run->add_option("--threads", threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  run->add_flag("--quiet,-q", quiet, "print only the final summary line");
  StoreOptions store_options;
  auto add_store_options = [&](CLI::App* command) {
    command->add_option(
        "--store", store_options.file,
        "result store (SQLite) shared by studies (default: results/rkhs-study.sqlite)");
    command->add_flag("--fresh", store_options.fresh,
                      "run every trial again, ignoring stored results");
    command->add_flag("--no-store", store_options.disabled,
                      "neither read nor write a result store");
  };
  add_store_options(run);
  std::string shard;
  run->add_option("--shard", shard,
                  "K/N: run only the K-th of N deterministic subsets into the store (job arrays)");
  std::string merge_into;
  std::vector<std::string> merge_from;
  auto* merge = app.add_subcommand("merge", "combine result stores (e.g. of shards) into one");
  merge->add_option("into", merge_into, "the store to merge into (created if needed)")->required();
  merge->add_option("from", merge_from, "stores to copy from")
      ->required()
      ->check(CLI::ExistingFile);
  bool use_mpi = false;
  run->add_flag("--mpi", use_mpi,
                "spread the trials over MPI ranks (under mpirun or srun; rank 0 writes)");
  const auto add_rank_timeout = [&](CLI::App* command) {
    command
        ->add_option("--rank-timeout", rank_timeout_seconds,
                     "with --mpi: seconds of silence after which a rank is taken as lost and its "
                     "trials run elsewhere (0: never; default 60)")
        ->check(CLI::Range(0.0, 1e9));
  };
  add_rank_timeout(run);
  bool no_plots = false;
  run->add_flag("--no-plots", no_plots, "do not render plots (gnuplot) into <out>/plots");

  auto* list = app.add_subcommand(
      "list", "list plugins (kernel, centres, target, plant, law, integrator) or metrics");
  list->add_option("kind", kind,
                   "kernel, centres, target, plant, law, integrator or metrics (default: all)")
      ->check(CLI::IsMember({"kernel", "kernels", "centres", "target", "targets", "plant", "plants",
                             "law", "laws", "integrator", "integrators", "metric", "metrics"}));

  std::string report_dir, report_format = "html";
  auto* report = app.add_subcommand(
      "report", "the rate tables of a run again: Markdown, LaTeX or report.html");
  report->add_option("directory", report_dir, "a results directory (with summary.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  report
      ->add_option("--format", report_format,
                   "md, tex or html (default html: writes DIR/report.html)")
      ->check(CLI::IsMember({"md", "tex", "html"}));
  add_store_options(report);

  auto* validate = app.add_subcommand("validate", "check a study file and count its trials");
  validate->add_option("study", study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingFile);

  CheckArguments check_arguments;
  auto* check = app.add_subcommand(
      "check",
      "run a study and judge its [[expect]] tables: exit 0 all pass, 1 a failure, "
      "3 inconclusive, 2 bad input");
  check->add_option("study", check_arguments.study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  check->add_option("--tier", check_arguments.tier,
                    "run only the entries and expectations of this tier (e.g. quick)");
  check->add_flag("--strict", check_arguments.strict, "count inconclusive verdicts as failures");
  check->add_option("--junit", check_arguments.junit_file,
                    "write JUnit XML: one test case per expectation and group");
  check->add_option("--out", check_arguments.out_dir,
                    "also write trials.csv, rates.csv and summary.json here (default: none)");
  check->add_option("--threads", threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  check->add_flag("--quiet,-q", quiet, "no progress line");
  add_store_options(check);
  check->add_flag("--mpi", use_mpi,
                  "spread the trials over MPI ranks (under mpirun or srun; rank 0 writes)");
  add_rank_timeout(check);

  // Plugin modules: --plugin (repeatable) here, RKHS_STUDY_PLUGIN_PATH, `plugins = [...]`.
  std::vector<std::string> plugin_files;
  std::string plugin_to_verify;
  for (auto* command : {run, list, validate, check})
    command->add_option("--plugin", plugin_files, "load a plugin module (.so); repeatable")
        ->allow_extra_args(false);
  // The data root that data files in study files are relative to (rkhs/data_root.hpp).
  std::string data_dir;
  for (auto* command : {run, validate, check})
    command
        ->add_option("--data-dir", data_dir,
                     "data files named in the study are relative to DIR (default: "
                     "RKHS_STUDY_DATA, else studies/data/)")
        ->check(CLI::ExistingDirectory);
  auto* verify =
      app.add_subcommand("verify-plugin",
                         "load a plugin module and check its kernels: the kernel contract, and the "
                         "declared smoothness against the measured power-function rate");
  verify->add_option("plugin", plugin_to_verify, "plugin module (.so)")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? exit_ok : exit_bad_input;
  }

  if (const auto errors = rkhs::registration_errors(); !errors.empty()) {
    for (const auto& e : errors)
      std::cerr << "rkhs-study: plugin registration error: " << e << "\n";
    return exit_bad_input;
  }
  if (const auto missing = rkhs::missing_builtin_plugins(); !missing.empty()) {
    for (const auto& m : missing) std::cerr << "rkhs-study: built-in plugin missing: " << m << "\n";
    return exit_bad_input;
  }

  // MPI for the whole command when --mpi is given; a command started as several MPI processes
  // without it would run the whole study once per process.
  std::optional<Session> mpi;
  if ((*run || *check) && !use_mpi && rkhs::distributed::launched_process_count() > 1) {
    if (const char* rank = std::getenv("OMPI_COMM_WORLD_RANK"); !rank || std::string(rank) == "0")
      std::cerr << fmt::format(
          "rkhs-study: started as {} MPI processes without --mpi: each would run "
          "the whole study and write the same files; add --mpi\n",
          rkhs::distributed::launched_process_count());
    return exit_bad_input;
  }
  if (use_mpi) {
    if (!shard.empty()) {
      std::cerr << "rkhs-study: --mpi and --shard exclude each other (--shard is for schedulers "
                   "without MPI)\n";
      return exit_bad_input;
    }
    try {
      mpi.emplace(argc, argv);
    } catch (const std::exception& e) {
      std::cerr << "rkhs-study: " << e.what() << "\n";
      return exit_bad_input;
    }
  }
  const Session* mpi_session = mpi ? &*mpi : nullptr;

  try {
    const auto load_plugins = [&] {
      rkhs::load_plugins_from_environment();
      for (const auto& file : plugin_files) rkhs::load_plugin(file);
      if (!data_dir.empty()) rkhs::set_data_root(data_dir);
    };
    on_every_rank(mpi_session, load_plugins);
    if (*verify) return command_verify_plugin(plugin_to_verify);
    if (*run)
      return command_run(study_file, out_dir, threads, quiet || (mpi && !mpi->is_root()),
                         store_options, !no_plots, shard, mpi_session);
    if (*merge) {
      rkhs::ResultStore into(merge_into);
      for (const auto& from : merge_from) {
        const auto count = into.merge_from(from);
        std::cout << fmt::format("merged {} from {}\n", counted(count, "trial", "trials"), from);
      }
      std::cout << fmt::format("{} holds {}\n", merge_into,
                               counted(into.size(), "trial", "trials"));
      return exit_ok;
    }
    if (*list) return command_list(kind);
    if (*report) return command_report(report_dir, report_format, store_options);
    if (*validate) return command_validate(study_file);
    if (*check) return command_check(check_arguments, threads, quiet, store_options, mpi_session);
  } catch (const rkhs::distributed::QuietExit& e) {
    return e.code;
  } catch (const rkhs::StudyError& e) {
    std::cerr << e.what() << "\n";
    return exit_bad_input;
  } catch (const std::exception& e) {
    std::cerr << "rkhs-study: " << e.what() << "\n";
    return exit_bad_input;
  }
  return exit_ok;
}

}  // namespace

int main(int argc, char** argv) {
  const int code = rkhs_study_main(argc, argv);
  if (rkhs::trials_abandoned()) {
    // Abandoned trials still compute on their threads: end now, without static destructors.
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    std::_Exit(code);
  }
  return code;
}
