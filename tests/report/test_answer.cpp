// The answer first: the verdict lines and fitted rates `run` ends with (console_answer), the
// counts and failures at the top of report.html, an adaptive study's convergence in time in
// words (time_convergence) in the console, rates.md and report.html, and "n/a" for a metric a
// trial's engine does not define. The results are made up, so no trial runs here.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "rkhs/report/convergence_in_time.hpp"
#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "verify/synthetic_results.hpp"

using namespace rkhs;

namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

StudyDefinition adaptive_study(const std::string& metrics) {
  return parse_study(R"([study]
name = "answer"
kind = "adaptive"
evaluation_points = 64
metrics = )" + metrics + R"(
[domain]
radius = 1.0
[grid]
n = [4, 8, 16]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
[adaptive]
speed = 0.5
laps = 10
)",
                     "answer.toml");
}

// Every metric NaN (as an engine leaves what it does not define) except `values`' own.
using Values = std::function<double(const TrialSpec&, const std::string&)>;
std::vector<TrialResult> made_up(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                                 const Values& values) {
  std::vector<TrialResult> results;
  for (const auto& trial : trials) {
    TrialResult result;
    result.ok = true;
    for (const auto& metric : study.all_metrics()) result.metrics.push_back(values(trial, metric));
    results.push_back(std::move(result));
  }
  return results;
}

double sigma_of(const TrialSpec& trial) {
  return trial.kernel.parameters.real("sigma");
}

}  // namespace

TEST_CASE("an adaptive study says per group whether the estimate has converged in time",
          "[report][answer]") {
  // sigma = 0.5 has converged (gap 3.1e-5 against 1.5e-2); sigma = 1 has not (gap 0.8 against
  // 0.3), and the lap map predicts 1200 laps to the limit.
  const auto study =
      adaptive_study(R"(["interpolant_l2_error", "gap_to_projection", "laps_to_limit"])");
  const auto trials = study.trials();
  const auto results = made_up(study, trials, [](const TrialSpec& t, const std::string& metric) {
    const bool converged = sigma_of(t) == 0.5;
    if (metric == "interpolant_l2_error")
      return (converged ? 1.5e-2 : 0.3) * 16.0 / static_cast<double>(t.n);
    if (metric == "gap_to_projection")
      return (converged ? 3.1e-5 : 0.8) * 16.0 / static_cast<double>(t.n);
    if (metric == "laps_to_limit") return converged ? not_a_number : 1200.0;
    return not_a_number;
  });
  const auto rates = compute_rates(study, trials, results);
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};
  const auto groups = time_convergence(record);
  REQUIRE(groups.size() == 2);
  CHECK(groups[0].label == "kernel=gaussian sigma=0.5");
  CHECK(groups[0].sentence ==
        "converged in time: gap to the projection 3.1e-05 is 0.21% of the projection's own "
        "error 0.015 (n = 16)");
  CHECK(groups[1].sentence ==
        "not converged in time: gap to the projection 0.8 exceeds the projection's own error 0.3 "
        "(n = 16); the lap map predicts 1200 laps to within 1% of the limit (ran 10)");
  const std::string expected_lines = "  kernel=gaussian sigma=1: " + groups[1].sentence + "\n";
  const auto console = console_answer(record, {}, false);
  // The fitted rates, the convergence in time, then (last) the verdicts: here none.
  CHECK_THAT(console, Catch::StartsWith("fitted rates:\n"));
  CHECK_THAT(console, Catch::Contains("\nconvergence in time:\n  kernel=gaussian sigma=0.5: "));
  CHECK_THAT(console, Catch::EndsWith(expected_lines + "no expectations\n"));
  CHECK(console_answer(record, {}, true) == "no expectations\n");  // -q
  CHECK_THAT(markdown_tables(record),
             Catch::Contains(
                 "## Convergence in time\n\n- kernel=gaussian sigma=0.5: converged in time: "));
  CHECK_THAT(html_report(record, {}, nullptr),
             Catch::Contains(
                 "<li>kernel=gaussian sigma=1: not converged in time: gap to the projection 0.8"));

  // Not asked for: nothing is said (and nothing computed).
  const auto without = adaptive_study(R"(["l2_error", "gap_to_projection"])");
  const auto without_trials = without.trials();
  const auto without_results =
      made_up(without, without_trials, [](const TrialSpec&, const std::string&) { return 0.1; });
  const auto without_rates = compute_rates(without, without_trials, without_results);
  const RunRecord without_record{without, without_trials, without_results, without_rates, 1, 0.0,
                                 ""};
  CHECK(time_convergence(without_record).empty());
  CHECK_THAT(markdown_tables(without_record), !Catch::Contains("Convergence in time"));
}

TEST_CASE("a metric the trial's engine does not define is n/a, a failed trial's value failed",
          "[report][answer]") {
  const auto study = adaptive_study(R"(["l2_error", "laps_to_limit"])");
  const auto trials = study.trials();
  auto results = made_up(study, trials, [](const TrialSpec& t, const std::string& metric) {
    return metric == "l2_error" ? 1.0 / static_cast<double>(t.n)
                                : not_a_number;  // laps_to_limit: lap map only
  });
  results.back().ok = false;  // one failed trial: its values are "failed"
  results.back().reason = "made up";
  for (auto& value : results.back().metrics) value = not_a_number;
  const auto rates = compute_rates(study, trials, results);
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};
  for (const auto& [name, text] :
       {std::pair{std::string("console"), console_tables(record)},
        std::pair{std::string("rates.md"), markdown_tables(record)},
        std::pair{std::string("rates.tex"), latex_tables(record)},
        std::pair{std::string("report.html"), html_report(record, {}, nullptr)}}) {
    INFO(name << ":\n" << text);
    CHECK_THAT(text, Catch::Contains("n/a"));
    CHECK_THAT(text, Catch::Contains("failed"));
  }
  // Only the failed trial's cells say "failed": two metrics, one trial.
  const auto markdown = markdown_tables(record);
  std::size_t failed_cells = 0;
  for (auto p = markdown.find("| failed |"); p != std::string::npos;
       p = markdown.find("| failed |", p + 1))
    ++failed_cells;
  CHECK(failed_cells == 2);
}

TEST_CASE(
    "report.html starts with the verdict counts and the failures, run's answer with the "
    "verdict lines",
    "[report][answer]") {
  const test::SyntheticResults results(
      R"([study]
name = "counts"
metrics = ["power_function_sup"]
[domain]
radius = 4.0
[grid]
n = [10, 20, 40, 80]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[expect]]
name = "first order"
metric = "power_function_sup"
rate = -1
[[expect]]
name = "second order"
metric = "power_function_sup"
rate = -2
)",
      [](const TrialSpec& t, const std::string&) { return 1.0 / static_cast<double>(t.n); });
  const auto verdicts = results.verify();
  REQUIRE(verdicts.size() == 2);
  RunRecord record{results.study, results.trials, results.results, results.rates, 1, 0.0, ""};
  record.verdicts = &verdicts;
  const auto page = html_report(record, {}, &verdicts);
  const auto title = page.find("<h1>counts</h1>\n");
  const auto counts = page.find("1 passed, 1 failed, 0 inconclusive");
  const auto failure = page.find("<b>FAIL</b> second order [kernel=gaussian]");
  REQUIRE(title != std::string::npos);
  REQUIRE(counts != std::string::npos);
  REQUIRE(failure != std::string::npos);
  CHECK(page.substr(title + 16, 26) == "<div class=\"answer\">\n<p cl");
  CHECK(counts < failure);
  CHECK(failure < page.find("<h2>Provenance</h2>"));
  CHECK(page.find("<b>PASS</b>") == std::string::npos);  // passes are only counted up top
  CHECK(failure < page.find("<h2>Expectations</h2>"));

  const auto console = console_answer(record, verdicts, false);
  // The fitted rates first, the verdicts and their counts last.
  CHECK_THAT(console, Catch::StartsWith("fitted rates:\n"));
  CHECK_THAT(console, Catch::Contains("power_function_sup  -1"));
  CHECK(console.find("power_function_sup  -1") <
        console.find("\nPASS         first order [kernel=gaussian] (s.toml:11:1): rate -1 ["));
  CHECK_THAT(
      console,
      Catch::Contains("\nFAIL         second order [kernel=gaussian] (s.toml:15:1): rate -1 ["));
  CHECK_THAT(console, Catch::EndsWith("\n1 passed, 1 failed, 0 inconclusive\n"));
  CHECK(console_answer(record, verdicts, true) == format_verdict_lines(verdicts));
}
