// A program that embeds rkhs-study through its public headers: it parses a study, runs its
// trials and reads their results (tests/plugin/install_and_build_plugin.sh builds and runs it
// against the installed package). Prints "embedded study: N trials ok" and exits 0, or names the
// trial that failed and exits 1.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace {

constexpr const char* kStudy = R"(
[study]
name = "embedded"
description = "the Gaussian on the closed track, run by a program linked against rkhs_study"
evaluation_points = 256
metrics = ["power_function_sup", "sup_error"]

[domain]
radius = 4.0

[grid]
n = [8, 16]

[[kernel]]
name = "gaussian"
sigma = 1.0
)";

}  // namespace

int main() {
  const rkhs::StudyDefinition study = rkhs::parse_study(kStudy, "embedded.toml");
  const std::vector<rkhs::TrialSpec> trials = study.trials();
  rkhs::RunOptions options;
  options.threads = 2;
  const std::vector<rkhs::TrialResult> results = rkhs::run_trials(study, trials, options);
  if (trials.empty() || results.size() != trials.size()) {
    std::printf("embedded study: %zu trials, %zu results\n", trials.size(), results.size());
    return 1;
  }
  // The metrics the study asks for, by their position in all_metrics() (the others are NaN).
  const std::vector<std::string>& names = study.all_metrics();
  std::vector<std::size_t> asked;
  for (const char* name : {"power_function_sup", "sup_error"}) {
    const auto at = std::find(names.begin(), names.end(), name);
    if (at == names.end()) {
      std::printf("embedded study: no metric %s\n", name);
      return 1;
    }
    asked.push_back(static_cast<std::size_t>(at - names.begin()));
  }
  for (std::size_t i = 0; i < results.size(); ++i) {
    const rkhs::TrialResult& result = results[i];
    bool finite = result.metrics.size() == names.size();
    for (std::size_t at : asked) finite = finite && std::isfinite(result.metrics[at]);
    if (!result.ok || !finite) {
      std::printf("embedded study: trial %zu %s: %s; metrics", i, result.ok ? "ok" : "failed",
                  result.reason.c_str());
      for (double value : result.metrics) std::printf(" %g", value);
      std::printf("\n");
      return 1;
    }
  }
  std::printf("embedded study: %zu trials ok\n", results.size());
  return 0;
}
