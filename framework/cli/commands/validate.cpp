// `rkhs-study validate STUDY`: the study file checked and its trials counted, nothing run.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <iostream>

#include "commands/commands.hpp"
#include "commands/common.hpp"
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
  if (const auto tiers = study_tiers(study); !study.expectations.empty() || !tiers.empty())
    std::cout << fmt::format(
        "  {} expectation{}; tiers: {}\n", study.expectations.size(),
        study.expectations.size() == 1 ? "" : "s",
        tiers.empty() ? std::string("none") : fmt::format("{}", fmt::join(tiers, ", ")));
  return exit_ok;
}

}  // namespace rkhs::cli
