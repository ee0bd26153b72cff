// The laps axis in the output files: a study whose [adaptive] laps is a list gets a laps column
// (after the plugin columns, before n) in trials.csv, rates.csv, estimates.csv and
// timeseries.csv, one rate series per lap count, and "limit" printed as such; a study with one
// lap count gets none. The results are made up (l2_error = laps-dependent constant / n), so no
// trial runs here.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "rkhs/report/output.hpp"
#include "rkhs/verify/study_rates.hpp"

using namespace rkhs;

namespace {

StudyDefinition laps_study(const std::string& laps) {
  return parse_study(R"([study]
name = "laps_columns"
kind = "adaptive"
evaluation_points = 64
metrics = ["l2_error"]
[domain]
radius = 1.0
[grid]
n = [4, 8, 16]
[[kernel]]
name = "gaussian"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
[adaptive]
speed = 0.5
snapshot_laps = [1]
snapshot_points = 2
)" + laps + "\n",
                     "laps_columns.toml");
}

// l2_error = c / n with c the lap count (1 for "limit"), one sample and one snapshot per trial.
std::vector<TrialResult> made_up_results(const StudyDefinition& study,
                                         const std::vector<TrialSpec>& trials) {
  std::vector<TrialResult> results;
  for (const auto& trial : trials) {
    TrialResult result;
    result.ok = true;
    result.metrics.assign(study.all_metrics().size(), std::numeric_limits<double>::quiet_NaN());
    const auto& laps = trial.adaptive_axes().laps;
    const double c = laps && std::isfinite(*laps) ? *laps : 1.0;
    result.metrics[study.metric_index("l2_error")] = c / static_cast<double>(trial.n);
    result.samples = {{0.0, 1.0, 1.0}};
    result.road = {0.0, 1.0};
    result.snapshots = {{1.0, {0.5, 0.25}}};
    results.push_back(std::move(result));
  }
  return results;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, ',');) out.push_back(field);
  return out;
}

// The value of `column` in each data row of a CSV text.
std::vector<std::string> column_of(const std::string& csv, const std::string& column) {
  const auto rows = lines(csv);
  const auto header = fields(rows.at(0));
  const auto at = std::find(header.begin(), header.end(), column);
  REQUIRE(at != header.end());
  std::vector<std::string> out;
  for (std::size_t r = 1; r < rows.size(); ++r)
    out.push_back(fields(rows[r]).at(static_cast<std::size_t>(at - header.begin())));
  return out;
}

}  // namespace

TEST_CASE("a laps axis is a laps column of every output file, and a rate series per lap count",
          "[output][laps]") {
  const auto study = laps_study(R"(laps = [10, 1e6, "limit"])");
  const auto trials = study.trials();
  const auto results = made_up_results(study, trials);
  const auto rates = compute_rates(study, trials, results);
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};

  const auto trials_header = fields(lines(trials_csv(record)).at(0));
  const auto laps_at = std::find(trials_header.begin(), trials_header.end(), "laps");
  REQUIRE(laps_at != trials_header.end());
  CHECK(*(laps_at + 1) == "n");  // nested just outside n
  // After the plugin columns.
  CHECK(std::find(trials_header.begin(), trials_header.end(), "integrator") < laps_at);
  CHECK(column_of(trials_csv(record), "laps") ==
        std::vector<std::string>{"10", "10", "10", "1000000", "1000000", "1000000", "limit",
                                 "limit", "limit"});
  CHECK(column_of(trials_csv(record), "n") ==
        std::vector<std::string>{"4", "8", "16", "4", "8", "16", "4", "8", "16"});

  // One series per lap count: three groups of three values of n, each with rate -1.
  REQUIRE(rates.size() == 3);
  for (const auto& series : rates) {
    CHECK(series.trials.size() == 3);
    REQUIRE(series.fit);
    CHECK(series.fit->rate == Approx(-1.0));
  }
  const auto rates_header = fields(lines(rates_csv(record)).at(0));
  CHECK(std::find(rates_header.begin(), rates_header.end(), "laps") + 1 ==
        std::find(rates_header.begin(), rates_header.end(), "metric"));
  std::vector<std::string> fitted;
  const auto rate_laps = column_of(rates_csv(record), "laps");
  const auto rate_kinds = column_of(rates_csv(record), "kind");
  for (std::size_t r = 0; r < rate_laps.size(); ++r)
    if (rate_kinds[r] == "fit") fitted.push_back(rate_laps[r]);
  CHECK(fitted == std::vector<std::string>{"10", "1000000", "limit"});

  CHECK(column_of(estimates_csv(record), "laps").front() == "10");
  CHECK(column_of(estimates_csv(record), "laps").back() == "limit");
  CHECK(column_of(timeseries_csv(record), "laps").back() == "limit");
}

TEST_CASE("one lap count, a number or \"limit\", adds no laps column", "[output][laps]") {
  for (const char* laps : {"laps = 10", "laps = \"limit\""}) {
    INFO(laps);
    const auto study = laps_study(laps);
    const auto trials = study.trials();
    const auto results = made_up_results(study, trials);
    const auto rates = compute_rates(study, trials, results);
    const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};
    for (const auto& csv : {trials_csv(record), rates_csv(record), estimates_csv(record),
                            timeseries_csv(record)}) {
      const auto header = fields(lines(csv).at(0));
      CHECK(std::find(header.begin(), header.end(), "laps") == header.end());
    }
    CHECK(rates.size() == 1);
  }
}
