// `rkhs-study validate STUDY`: the study file checked and its trials counted, nothing run.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <memory>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "commands/options.hpp"
#include "rkhs/run/trial_cost.hpp"
#include "rkhs/study/tiers.hpp"

namespace rkhs::cli {

int command_validate(const std::string& study_file) {
  const auto study = load_study(study_file);
  print_warnings(study);
  // Counted from the axes: a valid grid may still be large, and nothing here needs its trials.
  std::vector<std::string> factors;
  std::size_t trials = 1;
  for (const auto& axis : study.grid_axes()) {
    factors.push_back(counted(axis.count, axis.singular, axis.plural));
    trials *= axis.count;
  }
  std::cout << fmt::format("{}: valid; {} = {}\n", study_file, fmt::join(factors, " x "),
                           counted(trials, "trial", "trials"));
  std::cout << "  " << computed_metrics_text(study) << "\n";
  // [limits] matrix_megabytes from the predicted footprints (run fails such trials before it
  // builds anything): the largest names how far beyond the limit the grid goes. Dense trials'
  // footprints depend on n alone, so a dense study is checked from its n axis (one with
  // [[projection]] entries trial by trial: a matrix-free projection predicts its own).
  std::size_t refused = 0, first_too_large = 0, last_too_large = 0;
  TrialFootprint largest;
  std::size_t largest_n = 0;
  const auto check = [&](std::size_t n, const TrialFootprint& footprint, std::size_t count) {
    if (footprint.megabytes <= study.limits.matrix_megabytes) return;
    if (refused == 0 || n < first_too_large) first_too_large = n;
    last_too_large = std::max(last_too_large, n);
    refused += count;
    if (footprint.megabytes > largest.megabytes) {
      largest = footprint;
      largest_n = n;
    }
  };
  if (study.kind() != StudyKind::approximation ||
      (study.solver.algebra == GramAlgebra::dense && study.projections.empty()))
    for (const std::size_t n : study.n_values)
      check(n, {trial_matrix_megabytes(n, study.evaluation_points)},
            trials / study.n_values.size());
  else
    for (const auto& trial : study.trials()) check(trial.n, trial_footprint(study, trial), 1);
  int status = exit_ok;
  if (refused > 0) {
    std::cerr << fmt::format(
        "  limits: {} of n = {}{} {} more than limits.matrix_megabytes = {} MB of "
        "matrices (the largest, n = {} with {} evaluation points, {}: {:.0f} MB); run fails {} "
        "before building anything: {}\n",
        counted(refused, "trial", "trials"), first_too_large,
        last_too_large > first_too_large ? " and above" : "", refused == 1 ? "needs" : "need",
        format_real(study.limits.matrix_megabytes), largest_n, study.evaluation_points,
        largest.describe(), largest.megabytes, refused == 1 ? "it" : "them",
        "raise the limit or lower n");
    status = exit_failed_trials;
  }
  if (const auto tiers = study_tiers(study); !study.expectations.empty() || !tiers.empty())
    std::cout << fmt::format(
        "  {} expectation{}; tiers: {}\n", study.expectations.size(),
        study.expectations.size() == 1 ? "" : "s",
        tiers.empty() ? std::string("none") : fmt::format("{}", fmt::join(tiers, ", ")));
  return status;
}

Command add_validate_command(CLI::App& app, SessionOptions& session) {
  auto study_file = std::make_shared<std::string>();
  auto* validate = app.add_subcommand("validate", "check a study file and count its trials");
  validate->add_option("study", *study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  add_plugin_option(*validate, session);
  add_data_dir_option(*validate, session);
  return {
      validate, {}, [study_file](pipeline::Executor&) { return command_validate(*study_file); }};
}

}  // namespace rkhs::cli
