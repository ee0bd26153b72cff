// `rkhs-study check STUDY`: runs the study (or one tier of it) and judges its [[expect]] tables
// (docs/verification.md). The exit code is the verdicts': 0 all pass, 1 a failure, 3 only
// inconclusive ones besides passes (1 with --strict).
#include <fmt/format.h>

#include <iostream>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/study/tiers.hpp"
#include "rkhs/verify/junit.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs::cli {

int command_check(const CheckCommand& arguments, pipeline::Executor& executor) {
  const auto study = pipeline::load_everywhere(executor, [&] {
    auto loaded = load_study(arguments.study_file);
    if (!arguments.tier.empty()) loaded = restrict_to_tier(std::move(loaded), arguments.tier);
    return loaded;
  });
  if (executor.is_root()) print_warnings(study);
  const auto trials = study.trials();
  executor.agree_on(study, trials);
  const bool root = executor.is_root();
  const bool quiet = arguments.quiet || !root;
  const int thread_count = arguments.threads > 0 ? arguments.threads : executor.default_threads();
  const auto tier_text = arguments.tier.empty() ? std::string() : " (tier " + arguments.tier + ")";
  if (!quiet)
    std::cerr << fmt::format("rkhs-study check: {}{}: {}, {}\n", study.name, tier_text,
                             counted(trials.size(), "trial", "trials"),
                             counted(thread_count, "thread", "threads"));
  RunOptions options;
  options.threads = thread_count;
  stop_on_signals(options);
  const auto outcome = pipeline::run_study(executor, study, trials, options, arguments.store);
  if (!root) return stop_was_requested() ? exit_interrupted : exit_ok;
  print_store_problems(outcome);
  if (!quiet) print_run_sources(outcome, executor);
  if (outcome.interrupted) return report_interruption(*outcome.interrupted, arguments.store);

  const auto& run = *outcome.completed;
  if (!arguments.out_dir.empty()) write_outputs(run.record(), arguments.out_dir);
  const auto outcomes = verify_expectations(study, trials, run.stored.results, run.rates);
  std::cout << fmt::format("{}{}: {}, {} ok, {} failed in {:.2f} s\n", study.name, tier_text,
                           counted(trials.size(), "trial", "trials"), trials.size() - run.failed,
                           run.failed, run.seconds);
  if (run.failed)
    std::cout << fmt::format(
        "note: {} trial{} failed; their reasons are in trials.csv (--out DIR)\n", run.failed,
        run.failed > 1 ? "s" : "");
  std::cout << format_verification(outcomes, arguments.strict);
  if (!arguments.junit_file.empty())
    write_file_atomically(arguments.junit_file,
                          junit_xml({study, outcomes, arguments.strict, run.seconds,
                                     arguments.tier, run.started}));
  return check_exit_code(count_verdicts(outcomes), arguments.strict);
}

}  // namespace rkhs::cli
