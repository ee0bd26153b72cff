// `rkhs-study check STUDY...`: runs each study (or one tier of it) in turn and judges its
// [[expect]] tables (docs/verification.md): the test cases `-k` selects, xfail markers, one
// combined report, one JUnit file with a suite per study, one exit code over all studies: 0 all
// pass, 1 a failure (--strict: also inconclusive or XPASS), 3 inconclusive ones besides passes
// (0 with --allow inconclusive), 5 when no test case was judged (-k selected nothing, or no
// study has an [[expect]] table).
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "commands/options.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/run_folder.hpp"
#include "rkhs/study/tiers.hpp"
#include "rkhs/verify/expectation_cases.hpp"
#include "rkhs/verify/junit.hpp"
#include "rkhs/verify/keyword_expression.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs::cli {

namespace {

// One study of the command line: loaded and restricted to the tier on every process, its test
// cases split by -k before anything runs; its outcomes on the root once it ran.
struct CheckedStudy {
  StudyDefinition study;
  std::vector<TrialSpec> trials;
  CaseSelection cases;                       ///< the test cases -k selects
  std::vector<ExpectationOutcome> outcomes;  ///< the selected cases' (root)
  double seconds = 0;
  std::string started;
};

// Two files that define studies of the same name would write the same --out directory and
// JUnit suite: refused, naming both.
void require_distinct_names(const std::deque<CheckedStudy>& studies) {
  for (std::size_t i = 0; i < studies.size(); ++i)
    for (std::size_t j = i + 1; j < studies.size(); ++j)
      if (studies[i].study.name == studies[j].study.name)
        throw std::invalid_argument(
            studies[i].study.source == studies[j].study.source
                ? fmt::format("{} is given twice", studies[i].study.source)
                : fmt::format("{} and {} both define the study '{}': their reports would be "
                              "mistaken for each other; rename one ([study] name)",
                              studies[i].study.source, studies[j].study.source,
                              studies[i].study.name));
}

// Before any trial: the folder of the --junit file is created when missing, and a file can be
// created in it; otherwise exit 2 naming the path, with nothing run (the report is written last,
// after every study, where a failure would have cost the whole check).
void prepare_junit_file(const std::filesystem::path& file) {
  namespace fs = std::filesystem;
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(
        fmt::format("cannot write the JUnit report {}: {} (choose another "
                    "with --junit FILE)",
                    file.string(), why));
  };
  std::error_code error;
  if (fs::is_directory(file, error)) fail("it is a folder");
  const auto folder = file.parent_path().empty() ? fs::path(".") : file.parent_path();
  fs::create_directories(folder, error);
  if (error) fail(fmt::format("cannot create its folder {}: {}", folder.string(), error.message()));
  if (!fs::is_directory(folder, error)) fail(fmt::format("{} is not a folder", folder.string()));
  const auto probe = folder / fmt::format(".rkhs-study-probe.{}", static_cast<long>(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0)
    fail(fmt::format("cannot create a file in {}: {}", folder.string(), std::strerror(errno)));
  ::close(fd);
  ::unlink(probe.c_str());
}

class Check {
 public:
  Check(const CheckCommand& arguments, pipeline::Executor& executor)
      : arguments_(arguments), executor_(executor) {
    policy_.strict = arguments.strict;
    policy_.allow_inconclusive = std::find(arguments.allow.begin(), arguments.allow.end(),
                                           "inconclusive") != arguments.allow.end();
    tier_text_ = arguments.tier.empty() ? std::string() : " (tier " + arguments.tier + ")";
  }

  int run() {
    collect();
    const bool root = executor_.is_root();
    if (root && !arguments_.junit_file.empty()) prepare_junit_file(arguments_.junit_file);
    for (auto& checked : studies_) {
      if (selection_ && checked.cases.selected.empty()) {
        if (root) report_not_run(checked);
        continue;
      }
      // The root reports (and may fail to write); every process then learns whether to go on,
      // so that the ranks of an MPI job leave together.
      std::optional<int> stop;
      std::exception_ptr error;
      auto judged = run_one(checked);
      if (root) {
        try {
          stop = report(checked, judged);
        } catch (...) {
          error = std::current_exception();
        }
      }
      const bool go_on = executor_.root_decision(!stop && !error);
      if (error) std::rethrow_exception(error);
      if (!go_on) {
        if (stop) return *stop;
        return stop_was_requested() ? exit_interrupted : exit_ok;
      }
    }
    return root ? finish() : exit_ok;
  }

 private:
  // Every study loaded, restricted to the tier and split by -k before any trial runs: a bad file
  // or expression is exit 2, naming it, with nothing run.
  void collect() {
    // --junit onto a study file would replace the study with its report.
    if (!arguments_.junit_file.empty())
      for (const auto& file : arguments_.study_files)
        refuse_output_onto_input("--junit", arguments_.junit_file, "the study file", file);
    executor_.on_every_process([&] {
      if (!arguments_.keyword_expression.empty())
        selection_ = KeywordExpression::parse(arguments_.keyword_expression);
    });
    for (const auto& file : arguments_.study_files) {
      auto study = pipeline::load_everywhere(executor_, [&] {
        auto loaded = load_study(file);
        if (!arguments_.tier.empty()) loaded = restrict_to_tier(std::move(loaded), arguments_.tier);
        return loaded;
      });
      studies_.push_back(CheckedStudy{std::move(study), {}, {}, {}, 0, {}});
    }
    executor_.on_every_process([&] { require_distinct_names(studies_); });
    for (auto& checked : studies_) {
      if (executor_.is_root()) print_warnings(checked.study);
      checked.trials = checked.study.trials();
      checked.cases =
          select_cases(checked.study, checked.trials, selection_ ? &*selection_ : nullptr);
    }
  }

  pipeline::JudgedRun run_one(const CheckedStudy& checked) {
    executor_.agree_on(checked.study, checked.trials);
    // The store first: one that is refused leaves the output folder as it was.
    auto opened = pipeline::open_store(executor_, checked.study, checked.trials, arguments_.store);
    // Before any trial: an output folder that cannot be written is exit 2, naming it (and a
    // store this check created is removed again).
    if (executor_.is_root() && !arguments_.out_dir.empty()) {
      try {
        prepare_output_directory(output_directory(checked));
        if (arguments_.plots) prepare_output_directory(output_directory(checked) / "plots");
      } catch (...) {
        if (opened.created && opened.store) {
          opened.store.reset();
          remove_store_files(arguments_.store.file);
        }
        throw;
      }
    }
    const int threads = arguments_.threads > 0 ? arguments_.threads : executor_.default_threads();
    if (!quiet())
      std::cerr << fmt::format("rkhs-study check: {}{}: {}, {}\n", checked.study.name, tier_text_,
                               counted(checked.trials.size(), "trial", "trials"),
                               counted(threads, "thread", "threads"))
                << "  " << computed_metrics_text(checked.study) << "\n";
    RunOptions options;
    options.threads = threads;
    stop_on_signals(options);
    return pipeline::run_and_judge(executor_, checked.study, checked.trials, options,
                                   arguments_.store, std::move(opened), &checked.cases);
  }

  bool quiet() const { return arguments_.quiet || !executor_.is_root(); }

  // The study's verdicts, outputs and report on the root; the exit code when the check must
  // stop (an interrupted run), nothing otherwise.
  std::optional<int> report(CheckedStudy& checked, pipeline::JudgedRun& judged) {
    const auto& outcome = judged.outcome;
    print_store_problems(outcome);
    if (!quiet()) print_run_sources(outcome, executor_);
    if (outcome.interrupted) return report_interruption(*outcome.interrupted, arguments_.store);

    const auto& run = *outcome.completed;
    const auto& study = checked.study;
    checked.outcomes = std::move(judged.verdicts);
    checked.seconds = run.seconds;
    checked.started = run.started;
    if (!arguments_.out_dir.empty()) write_outputs_of(checked, run);
    if (stop_was_requested()) {  // while the plots were rendered: gnuplot was killed
      std::cerr << "rkhs-study: interrupted while rendering plots; every other output is "
                   "complete\n";
      return exit_interrupted;
    }
    std::cout << fmt::format("{}{}: {}, {} ok, {} failed in {:.2f} s\n", study.name, tier_text_,
                             counted(checked.trials.size(), "trial", "trials"),
                             checked.trials.size() - run.failed, run.failed, run.seconds);
    if (run.failed)
      std::cout << fmt::format(
          "note: {} trial{} failed; their reasons are in trials.csv (--out DIR)\n", run.failed,
          run.failed > 1 ? "s" : "");
    std::cout << format_verification(checked.outcomes, policy_, checked.cases.deselected);
    return std::nullopt;
  }

  // What `run --out` writes, with the verdicts in summary.json and report.html: into --out,
  // or --out/<study name> when several studies are checked.
  std::filesystem::path output_directory(const CheckedStudy& checked) const {
    return studies_.size() > 1 ? std::filesystem::path(arguments_.out_dir) / checked.study.name
                               : std::filesystem::path(arguments_.out_dir);
  }

  void write_outputs_of(const CheckedStudy& checked, const pipeline::CompletedRun& run) const {
    const auto directory = output_directory(checked);
    auto record = run.record();
    record.tier = arguments_.tier;
    record.verdicts = &checked.outcomes;
    record.deselected = checked.cases.deselected;
    std::size_t plots = 0;
    write_run_folder(record, directory, arguments_.plots, [&] {
      plots = arguments_.plots ? render_plots(record, directory, quiet()) : 0;
    });
    if (!quiet())
      std::cerr << fmt::format("  wrote {}/trials.csv, rates.csv, summary.json, report.html{}\n",
                               directory.string(),
                               plots ? fmt::format(", plots/ ({} plots)", plots) : "");
  }

  void report_not_run(const CheckedStudy& checked) const {
    const std::size_t cases = checked.cases.deselected;
    std::cout << fmt::format("{}{}: not run: {}\n", checked.study.name, tier_text_,
                             cases ? fmt::format("-k selects none of its {} ({} deselected)",
                                                 counted(cases, "test case", "test cases"), cases)
                                   : std::string("it has no expectations to judge"));
  }

  // The combined counts, the JUnit file and the exit code, on the root.
  int finish() const {
    VerdictCounts total;
    double seconds = 0;
    for (const auto& checked : studies_) {
      auto counts = count_verdicts(checked.outcomes);
      counts.deselected = checked.cases.deselected;
      total += counts;
      seconds += checked.seconds;
    }
    if (!arguments_.junit_file.empty()) {
      JUnitReport junit{{}, policy_, arguments_.keyword_expression};
      for (const auto& checked : studies_)
        junit.suites.push_back({&checked.study, &checked.outcomes, checked.seconds, arguments_.tier,
                                checked.started, checked.cases.deselected});
      write_file_atomically(arguments_.junit_file, junit_xml(junit));
    }
    if (studies_.size() > 1)
      std::cout << fmt::format("total over {} studies: {} in {:.2f} s\n", studies_.size(),
                               format_counts(total, policy_), seconds);
    // -k that selects nothing is pytest's "no tests collected" (5), also when the studies
    // have no expectations at all.
    if (selection_ && total.selected() == 0) {
      std::cout << (total.deselected
                        ? fmt::format("no test case selected: -k '{}' deselected all {}\n",
                                      selection_->text(), total.deselected)
                        : std::string("no test case selected: no expectations to judge\n"));
      return check_none_selected;
    }
    return check_exit_code(total, policy_);
  }

  const CheckCommand& arguments_;
  pipeline::Executor& executor_;
  CheckPolicy policy_;
  std::string tier_text_;
  std::optional<KeywordExpression> selection_;
  std::deque<CheckedStudy> studies_;  // a deque: outcomes point into each study, never moved
};

}  // namespace

int command_check(const CheckCommand& arguments, pipeline::Executor& executor) {
  return Check(arguments, executor).run();
}

Command add_check_command(CLI::App& app, SessionOptions& session) {
  auto arguments = std::make_shared<CheckCommand>();
  auto no_plots = std::make_shared<bool>(false);
  auto* check = app.add_subcommand(
      "check",
      "run studies and judge their [[expect]] tables: exit 0 all pass, 1 a failure, 2 bad "
      "input, 3 inconclusive, 5 -k selected nothing");
  check
      ->add_option("studies", arguments->study_files,
                   "study definitions (TOML), run and judged in turn")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  check->add_option("--tier", arguments->tier,
                    "run only the entries and expectations of this tier (e.g. quick)");
  check
      ->add_option("-k", arguments->keyword_expression,
                   "judge only the test cases whose names match EXPR: case-insensitive "
                   "substrings with and, or, not and parentheses, as pytest's -k (e.g. \"power "
                   "and not gaussian\"); a study with none selected is not run")
      ->type_name("EXPR");
  auto* strict = check->add_flag("--strict", arguments->strict,
                                 "count inconclusive verdicts and XPASS as failures");
  check
      ->add_option("--allow", arguments->allow,
                   "verdicts that do not fail the check: inconclusive (exit 0, not 3)")
      ->check(CLI::IsMember({"inconclusive"}))
      ->delimiter(',')
      ->allow_extra_args(false)
      ->excludes(strict);
  check->add_option("--junit", arguments->junit_file,
                    "write JUnit XML: one suite per study, one test case per expectation and "
                    "group");
  check->add_option("--out", arguments->out_dir,
                    "also write what `run` writes (trials.csv, rates.csv, summary.json with the "
                    "verdicts, report.html, plots) here; DIR/<study name> for several studies");
  check->add_flag("--no-plots", *no_plots, "with --out: do not render plots");
  check->add_option("--threads", arguments->threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  check->add_flag("--quiet,-q", arguments->quiet, "no progress line");
  add_store_options(*check, arguments->store);
  add_mpi_options(*check, session);
  add_plugin_option(*check, session);
  add_data_dir_option(*check, session);
  return {
      check,
      [arguments, no_plots](SessionOptions& options) {
        options.runs_trials = true;
        arguments->plots = !*no_plots;
      },
      [arguments](pipeline::Executor& executor) { return command_check(*arguments, executor); }};
}

}  // namespace rkhs::cli
