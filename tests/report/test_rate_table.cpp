// Tests of the rate-table model (rkhs/report/rate_table.hpp) and of the writers that render it:
// console, Markdown, LaTeX and HTML show the same axis, rates and fit, read from the model, and
// the HTML page shows the verdicts its caller judged.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/rate_table.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/verify/verification.hpp"

using namespace rkhs;

namespace {

// The golden study of test_document_tables.cpp (metrics exact functions of n), fitted against
// the fill distance h, with one expectation on it.
StudyDefinition h_study() {
  return parse_study(R"([study]
name = "golden_h"
abscissa = "h"
evaluation_points = 64
metrics = ["fill_distance", "separation_distance"]
[domain]
length = 10.0
[grid]
n = [4, 8, 16, 32]
[[kernel]]
name = "bspline"
degree = 1
J = 2
[[expect]]
metric = "fill_distance"
rate = 1.0
)",
                     "golden_h.toml");
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("rate tables: one model of axis, rows, pairwise rates and fit per metric and group",
          "[output][rate_table]") {
  const auto study = h_study();
  const auto trials = study.trials();
  const auto results = run_trials(study, trials, {1});
  const auto rates = compute_rates(study, trials, results);
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};
  const auto tables = rate_tables(record);
  REQUIRE(tables.size() == 2);
  CHECK(tables[0].metric == "fill_distance");
  CHECK(tables[1].metric == "separation_distance");
  for (const auto& table : tables) {
    const auto& series = rates[table.series];
    CHECK(table.axis == "h");
    CHECK_FALSE(table.axis_is_n());
    REQUIRE(table.rows.size() == 4);
    CHECK(std::isnan(table.rows[0].rate));
    for (std::size_t k = 0; k < table.rows.size(); ++k) {
      CHECK(table.rows[k].abscissa == series.abscissa[k]);
      CHECK(table.rows[k].n == trials[series.trials[k]].n);
      if (k > 0) CHECK(table.rows[k].rate == series.pairwise[k - 1]);
    }
    REQUIRE(table.fit);
    CHECK(table.fit->rate == Approx(1.0));
    CHECK(document_abscissa(table, table.rows[0]) == "1.25");
    CHECK(document_fit(table).starts_with("1 ± "));
    CHECK(window_text(table) == "n = 4..32, 4 of 4 points");
  }
}

TEST_CASE("every rate-table writer renders the model: axis h, the fit's rate and its level",
          "[output][rate_table]") {
  const auto study = h_study();
  const auto trials = study.trials();
  const auto results = run_trials(study, trials, {1});
  auto rates = compute_rates(study, trials, results);
  // A fit at another confidence level, with a rate no writer could recompute from the rows:
  // every writer must show these numbers, so none of them fits or chooses a level itself.
  for (auto& series : rates) {
    REQUIRE(series.fit);
    series.fit->confidence = 0.9;
    series.fit->rate = 1.23456;
    series.fit->std_error = 0.01;
    series.fit->ci_low = 1.2;
    series.fit->ci_high = 1.27;
  }
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};

  const auto console = console_tables(record);
  CHECK(contains(console, "\n  n       h  fill_distance"));
  CHECK(contains(console, "fill_distance, fitted rate: 1.23 ± 0.01 (90% CI [1.20, 1.27]"));
  CHECK_FALSE(contains(console, "95% CI"));

  const auto markdown = markdown_tables(record);
  CHECK(contains(markdown, "| n | h | fill_distance | rate | separation_distance | rate |"));
  CHECK(contains(markdown, "| 4 | 1.25 | 1.25 | - | 1.25 | - |"));
  CHECK(contains(markdown, "- fill_distance: 1.23 ± 0.01 (90% CI [1.2, 1.27]"));
  CHECK(contains(markdown, "| kernel=bspline | 1.235 [1.200, 1.270] | 1.235 [1.200, 1.270] |"));
  CHECK_FALSE(contains(markdown, "95% CI"));

  const auto latex = latex_tables(record);
  CHECK(contains(latex, "{$n$} & {$h$} & {value} & {rate} & {value} & {rate}"));
  CHECK(contains(latex, "fill\\_distance: fitted rate \\num{1.23} $\\pm$ \\num{0.01} "
                        "(90\\,\\% CI [\\num{1.2}, \\num{1.27}]"));
  CHECK(contains(latex, "\\num{1.235} [\\num{1.200}, \\num{1.270}]"));

  const auto html = html_report(record, {});
  CHECK(contains(html, "<tr><th rowspan=\"2\">n</th><th rowspan=\"2\">h</th><th "
                       "colspan=\"2\">fill_distance</th>"));
  CHECK(contains(html, "<tr><td>4</td><td>1.25</td><td>1.25</td>"));  // h of n = 4, length 10
  CHECK(contains(html, "fitted rate 1.23 &plusmn; 0.01 (90% CI [1.2, 1.27]"));
  CHECK(contains(html, "<td>1.235 [1.200, 1.270]</td>"));  // the fitted-rates table
  CHECK_FALSE(contains(html, "95% CI"));
}

TEST_CASE("the HTML page shows the verdicts its caller judged and judges none itself",
          "[output][rate_table]") {
  const auto study = h_study();
  const auto trials = study.trials();
  const auto results = run_trials(study, trials, {1});
  const auto rates = compute_rates(study, trials, results);
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};

  const auto verdicts = verify_expectations(study, trials, results, rates);
  REQUIRE(verdicts.size() == 1);
  const auto judged = html_report(record, {}, &verdicts);
  CHECK(contains(judged, "<h2>Expectations</h2>"));
  CHECK(contains(judged, "1 passed, 0 failed, 0 inconclusive"));

  // Verdicts the caller changed are shown as given: the page does not recompute them.
  auto altered = verdicts;
  altered[0].verdict = Verdict::fail;
  CHECK(contains(html_report(record, {}, &altered), "0 passed, 1 failed, 0 inconclusive"));

  const auto unjudged = html_report(record, {});
  CHECK(contains(unjudged, "<h2>Expectations</h2>"));
  CHECK(contains(unjudged, "Not judged in this report"));
  CHECK_FALSE(contains(unjudged, "passed,"));
}
