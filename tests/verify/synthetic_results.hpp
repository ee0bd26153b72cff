#pragma once
// A study whose results are made up from formulas, for tests of rates, verdicts and check's
// selection: every trial succeeds, each metric is value(trial, metric), and the fill and
// separation distances are those of uniform centres (or what `distances` says).

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "rkhs/study/study.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs::test {

struct SyntheticResults {
  using Value = std::function<double(const TrialSpec&, const std::string&)>;
  using Distances = std::function<std::pair<double, double>(const TrialSpec&)>;

  StudyDefinition study;
  std::vector<TrialSpec> trials;
  std::vector<TrialResult> results;
  std::vector<MetricSeries> rates;

  /// `text` is the whole study file; `distances(trial)` gives (h, q), default L / (2n) each;
  /// every trial records `seconds` of wall time.
  SyntheticResults(const std::string& text, const Value& value, const Distances& distances = {},
                   double seconds = 0.0)
      : study(parse_study(text, "s.toml")), trials(study.trials()) {
    for (const auto& trial : trials) {
      TrialResult r;
      r.ok = true;
      r.seconds = seconds;
      const double uniform = study.domain.length / (2.0 * static_cast<double>(trial.n));
      const auto [h, q] = distances ? distances(trial) : std::pair{uniform, uniform};
      for (const auto& metric : study.all_metrics()) {
        if (metric == "fill_distance")
          r.metrics.push_back(h);
        else if (metric == "separation_distance")
          r.metrics.push_back(q);
        else
          r.metrics.push_back(value(trial, metric));
      }
      results.push_back(std::move(r));
    }
    rates = compute_rates(study, trials, results);
  }
  std::vector<ExpectationOutcome> verify() const {
    return verify_expectations(study, trials, results, rates);
  }
};

/// The StudyError `text` raises as "s.toml", or "no error".
inline std::string study_error(const std::string& text) {
  try {
    parse_study(text, "s.toml");
  } catch (const StudyError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace rkhs::test
