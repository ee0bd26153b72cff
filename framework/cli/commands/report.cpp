// `rkhs-study report DIR`: the tables of the run in DIR again, from the study file its
// summary.json names (restricted to its tier, if it ran one) and the result store (trials not
// stored are run).
#include <iostream>
#include <limits>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/run_summary.hpp"
#include "rkhs/study/tiers.hpp"

namespace rkhs::cli {

int command_report(const std::string& directory, const std::string& format,
                   const pipeline::StoreOptions& store) {
  const auto summary = read_run_summary(std::filesystem::path(directory) / "summary.json");
  // A run of one tier (`check --tier quick --out DIR`) is reported as it ran.
  auto study = load_study(summary.source);
  if (!summary.tier.empty()) study = restrict_to_tier(std::move(study), summary.tier);
  const auto trials = study.trials();
  pipeline::LocalExecutor executor;
  RunOptions options;
  stop_on_signals(options);
  // Only reading when the store holds every trial: then it is opened read-only.
  auto reading = store;
  reading.read_only_when_complete = true;
  auto outcome = pipeline::run_study(executor, study, trials, options, reading);
  print_store_problems(outcome);
  if (outcome.interrupted) return report_interruption(*outcome.interrupted, store);
  auto& run = *outcome.completed;
  // The tables describe the stored results, not this process: one thread, no wall time.
  run.threads = 1;
  run.seconds = 0.0;
  const auto record = run.record();
  if (format == "text") {
    std::cout << console_tables(record, std::numeric_limits<std::size_t>::max());
  } else if (format == "md") {
    std::cout << markdown_tables(record);
  } else if (format == "tex") {
    std::cout << latex_tables(record);
  } else {
    const auto file = std::filesystem::path(directory) / "report.html";
    // The page shows the expectations' verdicts, judged once here.
    std::optional<std::vector<ExpectationOutcome>> verdicts;
    if (!study.expectations.empty())
      verdicts = verify_expectations(study, record.trials, record.results, record.rates);
    write_file_atomically(file, html_report(record, std::filesystem::path(directory) / "plots",
                                            verdicts ? &*verdicts : nullptr));
    std::cout << "wrote " << file.string() << "\n";
  }
  return exit_ok;
}

}  // namespace rkhs::cli
