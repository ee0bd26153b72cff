// Tests of the ConvergenceTable view (rkhs/report/rate_table.hpp group_tables, and its console,
// Markdown, LaTeX and HTML renderings): every metric of a group side by side with its rate, the
// fitted rates of all groups in one table, columns wrapped to a width, LaTeX for booktabs and
// siunitx, and the verdicts of report.html as a table coloured by outcome.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "../verify/synthetic_results.hpp"
#include "rkhs/report/convergence_table.hpp"
#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/rate_table.hpp"

using namespace rkhs;

namespace {

// Two groups (B-spline degrees 1 and 2), three metrics with known rates: l2_error ~ n^-(p+1),
// power_function_sup ~ n^-(p - 1/2), and a minimum eigenvalue that turns negative (round-off)
// at the largest n.
const char* study_text = R"([study]
name = "side_by_side"
evaluation_points = 512
metrics = ["l2_error", "power_function_sup", "gram_min_eigenvalue"]
[domain]
length = 1.0
[grid]
n = [8, 16, 32, 64]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[expect]]
metric = "l2_error"
rate = -2.0
)";

double made_up(const TrialSpec& trial, const std::string& metric) {
  const double n = static_cast<double>(trial.n);
  const double p = trial.kernel.parameters.real("degree");
  if (metric == "l2_error") return 3.0 * std::pow(n, -(p + 1.0));
  if (metric == "power_function_sup") return 0.5 * std::pow(n, -(p - 0.5));
  if (metric == "gram_min_eigenvalue") return trial.n == 64 ? -1e-17 : std::pow(n, -2.0 * p);
  return 1.0;
}

struct Fixture {
  test::SyntheticResults made{study_text, made_up};
  RunRecord record{made.study, made.trials, made.results,          made.rates,
                   1,          0.0,         "2026-01-01T00:00:00Z"};
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::size_t count(const std::string& text, const std::string& part) {
  std::size_t found = 0;
  for (auto p = text.find(part); p != std::string::npos; p = text.find(part, p + part.size()))
    ++found;
  return found;
}

}  // namespace

TEST_CASE("group tables: one per group, its metrics as columns, rows the union of n",
          "[output][group_table]") {
  Fixture f;
  auto tables = rate_tables(f.record);
  REQUIRE(tables.size() == 6);  // 3 metrics x 2 groups
  const auto groups = group_tables(f.record, tables);
  REQUIRE(groups.size() == 2);
  CHECK(groups[0].label == "kernel=bspline degree=1 r=1");
  CHECK(groups[1].label == "kernel=bspline degree=2 r=2");
  for (const auto& group : groups) {
    CHECK(group.n == std::vector<std::size_t>{8, 16, 32, 64});
    CHECK_FALSE(group.shows_h());
    REQUIRE(group.columns.size() == 3);
    for (std::size_t c = 0; c < 3; ++c) {
      CHECK(tables[group.columns[c]].group == group.group);
      CHECK(tables[group.columns[c]].metric == f.made.study.metrics[c]);
    }
  }
  // A metric without a trial at some n: the group still has the row, the metric has no cell.
  auto& l2 = tables[groups[0].columns[2]];  // the study's order: l2_error last
  REQUIRE(l2.metric == "l2_error");
  l2.rows.erase(l2.rows.begin() + 1);  // n = 16
  CHECK(row_at(l2, 16) == nullptr);
  REQUIRE(row_at(l2, 32) != nullptr);
  CHECK(row_at(l2, 32)->value == Approx(3.0 * std::pow(32.0, -2.0)));
  const auto again = group_tables(f.record, tables);
  CHECK(again[0].n == std::vector<std::size_t>{8, 16, 32, 64});
  const auto text = format_group_table(again[0], tables);
  bool blank_cell = false;
  for (const auto& line : lines_of(text))
    if (line.starts_with(" 16  ")) blank_cell = line.find("e-") > 10;  // no l2 value after n
  CHECK(blank_cell);
}

TEST_CASE("the console group table: every metric's value and rate, the fitted rates at the foot",
          "[output][group_table]") {
  Fixture f;
  const auto tables = rate_tables(f.record);
  const auto groups = group_tables(f.record, tables);
  const auto text = format_group_table(groups[1], tables);  // degree 2
  const auto lines = lines_of(text);
  REQUIRE(lines.size() >= 8);
  CHECK(lines[0] == "kernel=bspline degree=2 r=2");
  CHECK(lines[1] == "(group " + groups[1].group + ")");
  // The study's metric order (its canonical order, not the file's).
  const auto& metrics = f.made.study.metrics;
  REQUIRE(metrics.size() == 3);
  CHECK(lines[2].starts_with("  n  "));
  CHECK(lines[2].find(metrics[0]) < lines[2].find(metrics[1]));
  CHECK(lines[2].find(metrics[1]) < lines[2].find(metrics[2]));
  // Pairwise rates of the made-up power laws: -3 for l2_error, -1.5 for the power function.
  CHECK(contains(lines[4], "-3.00"));
  CHECK(contains(lines[4], "-1.50"));
  // The foot holds each metric's fitted rate, in the rate column's format.
  std::string foot;
  for (const auto& line : lines)
    if (line.starts_with("fit")) foot = line;
  for (auto t : groups[1].columns)
    if (tables[t].fit) CHECK(contains(foot, fmt::format("{:.2f}", tables[t].fit->rate)));
  CHECK(contains(foot, "-3.00"));
  CHECK(contains(foot, "-1.50"));
  // One fit line per metric, named.
  for (const auto* metric :
       {"  l2_error, fitted rate: -3.00", "  power_function_sup, fitted rate: -1.50"})
    CHECK(contains(text, metric));
  // The negative eigenvalue: no rate into it, and the fit says what it left out.
  CHECK(contains(text, "-1.000e-17"));
}

TEST_CASE("the console group table wraps its metrics at the width and repeats n in each part",
          "[output][group_table]") {
  Fixture f;
  const auto tables = rate_tables(f.record);
  const auto groups = group_tables(f.record, tables);
  const auto wide = format_group_table(groups[0], tables, 200);
  const auto narrow = format_group_table(groups[0], tables, 40);
  // Wide: one part, header once. Narrow: one metric per part (n and a metric's value and rate
  // take 26 to 33 bytes; two of them more than 40), so three headers, each starting with n.
  std::size_t wide_headers = 0, narrow_headers = 0;
  for (const auto& line : lines_of(wide)) wide_headers += line.starts_with("  n  ");
  for (const auto& line : lines_of(narrow)) {
    narrow_headers += line.starts_with("  n  ");
    if (line.starts_with("  n  ") || line.starts_with("fit") ||
        (!line.empty() && std::isdigit(static_cast<unsigned char>(line[1]))))
      CHECK(line.size() <= 40);
  }
  CHECK(wide_headers == 1);
  CHECK(narrow_headers == 3);
  for (const auto& metric : f.made.study.metrics) {
    CHECK(count(wide, metric + "  ") + count(wide, metric + "\n") >= 1);
    CHECK(count(narrow, " " + metric) == count(wide, " " + metric));
  }
}

TEST_CASE("the fitted rates of every group and metric in one table", "[output][group_table]") {
  Fixture f;
  const auto tables = rate_tables(f.record);
  const auto groups = group_tables(f.record, tables);
  const auto text = format_fitted_rates(groups, tables);
  CHECK(text.starts_with("fitted rates with 95% confidence intervals"));
  const auto lines = lines_of(text);
  REQUIRE(lines.size() == 4);
  for (std::size_t g = 0; g < 2; ++g) {
    CHECK(lines[g + 2].starts_with(groups[g].label));
    for (auto t : groups[g].columns) CHECK(contains(lines[g + 2], fit_cell(tables[t])));
  }
  // The made-up l2_error of degree 1 is exactly 3 n^-2: rate -2 and a zero-width interval.
  const auto& l2 = tables[groups[0].columns[2]];
  REQUIRE(l2.metric == "l2_error");
  REQUIRE(l2.fit);
  CHECK(fit_cell(l2) == "-2.000 [-2.000, -2.000]");
  // The console shows the fitted rates first when there are several groups.
  const auto console = console_tables(f.record);
  CHECK(console.starts_with(text));
  CHECK(contains(console, "kernel=bspline degree=1 r=1\n(group "));
}

TEST_CASE("fit cells are rounded to their confidence interval", "[output][group_table]") {
  RateTable table;
  CHECK(fit_cell(table) == "no fit");
  CHECK_FALSE(fit_cell_parts(table));
  const auto with = [&](double rate, double low, double high, double std_error,
                        RateModel model = RateModel::power_law) {
    RateFit fit;
    fit.rate = rate;
    fit.ci_low = low;
    fit.ci_high = high;
    fit.std_error = std_error;
    fit.model = model;
    table.fit = fit;
    return fit_cell(table);
  };
  // Half-width 0.215: two significant digits of it need 2 decimals.
  CHECK(with(3.9376, 3.7226, 4.1526, 0.09) == "3.94 [3.72, 4.15]");
  // Half-width 81: no decimal.
  CHECK(with(-20.7, -102.3, 60.9, 35) == "-21 [-102, 61]");
  // A rate at round-off with an interval of the same size is zero to 3 decimals, without "-0".
  CHECK(with(-9.9e-16, -5.7e-16, 2.6e-15, 1e-15) == "0.000 [0.000, 0.000]");
  CHECK(with(-0.287, -0.363, -0.211, 0.03, RateModel::exponential) ==
        "-0.287 [-0.363, -0.211] exp");
  // Without a standard error: 3 significant digits, at most 3 decimals.
  CHECK(with(-1.4712, NAN, NAN, NAN) == "-1.47");
  CHECK(with(0.004123, NAN, NAN, NAN) == "0.004");
  const auto parts = fit_cell_parts(table);
  REQUIRE(parts);
  CHECK(parts->low.empty());
  CHECK_FALSE(parts->exponential);
}

TEST_CASE("LaTeX: siunitx S columns sized to their numbers, real minus signs, booktabs rules",
          "[output][group_table]") {
  Fixture f;
  const auto latex = latex_tables(f.record);
  CHECK(
      latex.starts_with("% side\\_by\\_side: convergence tables (needs \\usepackage{booktabs} and "
                        "\\usepackage{siunitx})"));
  // The fitted rates, then one table per group with three metrics: exactly three tables.
  CHECK(count(latex, "\\begin{table}") == 3);
  CHECK(count(latex, "\\toprule") == count(latex, "\\bottomrule"));
  CHECK(contains(latex, "\\caption{side\\_by\\_side: kernel=bspline degree=1 r=1}"));
  CHECK(contains(latex, "\\label{tab:side-by-side-group2}"));
  // Values are positive except the minimum eigenvalue (first in the study's order) at n = 64,
  // whose column has a sign slot; rates are -d.dd.
  CHECK(contains(latex,
                 "\\begin{tabular}{r S[table-format=-1.3e-2] S[table-format=-1.2] "
                 "S[table-format=1.3e-2] S[table-format=-1.2] S[table-format=1.3e-2] "
                 "S[table-format=-1.2]}"));
  CHECK(contains(latex, "-1.000e-17"));
  // No hyphen as a minus outside S columns and \num: every fitted rate in the text is \num.
  CHECK(contains(latex, "l2\\_error: fitted rate \\num{-2}"));
  CHECK(contains(latex, "& \\num{-2.000} [\\num{-2.000}, \\num{-2.000}]"));
  CHECK_FALSE(contains(latex, "rate -"));
  CHECK_FALSE(contains(latex, "[-"));
  CHECK(contains(latex, "{--}"));  // no rate in the first row: text in braces, not a number
}

TEST_CASE("LaTeX splits a group with many metrics into continued tables", "[output][group_table]") {
  std::string text = study_text;
  const std::string metrics =
      R"(metrics = ["l2_error", "power_function_sup", "gram_min_eigenvalue"])";
  text.replace(
      text.find(metrics), metrics.size(),
      R"(metrics = ["l2_error", "sup_error", "power_function_sup", "gram_min_eigenvalue"])");
  const test::SyntheticResults made{text, made_up};
  const RunRecord record{made.study, made.trials, made.results, made.rates, 1, 0.0, ""};
  const auto latex = latex_tables(record);
  // Four metrics: three in a group's first table, one in its continuation; two groups.
  CHECK(count(latex, "\\begin{table}") == 1 + 2 * 2);
  CHECK(count(latex, " (continued)}") == 2);
  CHECK(contains(latex, "\\label{tab:side-by-side-group1-2}"));
}

TEST_CASE("report.html shows the verdicts as a table coloured by outcome",
          "[output][group_table]") {
  Fixture f;
  auto verdicts = f.made.verify();
  REQUIRE(verdicts.size() == 2);  // rate = -2 on both groups: degree 1 passes, degree 2 fails
  REQUIRE(verdicts[0].verdict == Verdict::pass);
  REQUIRE(verdicts[1].verdict == Verdict::fail);
  const auto html = html_report(f.record, {}, &verdicts);
  CHECK(contains(html, "<table class=\"verdicts\">"));
  CHECK(count(html, "<tr class=\"passed\"><td class=\"outcome\">PASS</td>") == 1);
  CHECK(count(html, "<tr class=\"failed\"><td class=\"outcome\">FAIL</td>") == 1);
  CHECK(contains(html, "tr.failed td.outcome {"));  // the colour is in the page's own style
  // The fitted rate, its CI and window of each case are cells of its row.
  for (const auto& o : verdicts) {
    const auto row = html.substr(html.find("<b>" + o.name + "</b>"));
    const auto end = row.find("</tr>");
    CHECK(row.find(fmt::format("<td>{:.3g}</td>", o.rate)) < end);
    CHECK(row.find(fmt::format("<td>[{:.3g}, {:.3g}]</td>", o.ci_low, o.ci_high)) < end);
    CHECK(row.find(fmt::format("n = {}..{} ({} points)", o.window_from, o.window_to,
                               o.window_points)) < end);
  }
  CHECK(contains(html, "1 passed, 1 failed, 0 inconclusive"));
  // The fitted-rates table links each group to its convergence table.
  CHECK(contains(html, "<a href=\"#group2\">kernel=bspline degree=2 r=2</a>"));
  CHECK(contains(html, "<h3 id=\"group2\">kernel=bspline degree=2 r=2</h3>"));
  CHECK(count(html, "<table class=\"rates\">") == 2);
}
