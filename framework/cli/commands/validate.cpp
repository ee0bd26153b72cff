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
  const auto trials = study.trials();
  std::vector<std::string> factors;
  for (const auto& axis : study.grid_axes())
    factors.push_back(counted(axis.count, axis.singular, axis.plural));
  std::cout << fmt::format("{}: valid; {} = {}\n", study_file, fmt::join(factors, " x "),
                           counted(trials.size(), "trial", "trials"));
  if (const auto tiers = study_tiers(study); !study.expectations.empty() || !tiers.empty())
    std::cout << fmt::format(
        "  {} expectation{}; tiers: {}\n", study.expectations.size(),
        study.expectations.size() == 1 ? "" : "s",
        tiers.empty() ? std::string("none") : fmt::format("{}", fmt::join(tiers, ", ")));
  return exit_ok;
}

}  // namespace rkhs::cli
