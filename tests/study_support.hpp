#pragma once
// Running a study given as TOML text, in process, for tests that look at its trials' results.

#include <catch2/catch.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::test {

struct StudyOutcome {
  StudyDefinition study;
  std::vector<TrialSpec> trials;
  std::vector<TrialResult> results;  ///< in the order of `trials`

  /// A metric of one trial, by name.
  double metric(std::size_t trial, std::string_view name) const {
    return results.at(trial).metrics.at(study.metric_index(name));
  }
};

/// The TOML of the small adaptive trials of tests: the sine road of amplitude 2, the scalar
/// plant x' = -x + f (time constant 1 s) and radau5 at the tolerances given ("1e-11").
inline std::string scalar_plant_sections(const std::string& rtol, const std::string& atol) {
  return "[[target]]\nname = \"sine\"\namplitude = 2.0\n"
         "[[plant]]\nname = \"linear\"\nA = \"-1\"\nB = \"1\"\n"
         "[[integrator]]\nname = \"radau5\"\nrtol = " + rtol + "\natol = " + atol + "\n";
}

/// Parses `text` (named `source` in error messages) and runs every trial on 2 threads; each
/// trial must succeed (its reason is shown when one does not).
inline StudyOutcome run_study_text(const std::string& text,
                                   const std::string& source = "test.toml") {
  StudyOutcome out{parse_study(text, source), {}, {}};
  out.trials = out.study.trials();
  RunOptions options;
  options.threads = 2;
  out.results = run_trials(out.study, out.trials, options);
  for (std::size_t i = 0; i < out.results.size(); ++i) {
    INFO(out.trials[i].key);
    REQUIRE(out.results[i].reason == "");
    REQUIRE(out.results[i].ok);
  }
  return out;
}

}  // namespace rkhs::test
