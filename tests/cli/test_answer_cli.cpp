// `rkhs-study run` as a user reads it: the console ends with the answer (a verdict line per
// expectation, or "no expectations", then the fitted rates), the groups' tables only with
// --tables, -q keeps the verdicts; report.html starts with the counts; an adaptive study says
// whether it converged in time; a metric the engine does not define is "n/a".
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "cli_support.hpp"

namespace fs = std::filesystem;

namespace {

// The standard output of `rkhs-study ARGUMENTS` alone (stderr dropped), and its exit code.
rkhs::test::CommandOutcome stdout_of(const std::string& arguments) {
  return rkhs::test::run_command("( " + std::string(RKHS_STUDY_EXECUTABLE) + " " + arguments +
                                 " 2>/dev/null )");
}

const char* const study_with_expectations = R"([study]
name = "cli_answer"
evaluation_points = 256
metrics = ["fill_distance", "power_function_sup"]
[domain]
radius = 4
[grid]
n = [8, 16, 32, 64]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 5
[[expect]]
name = "fill distance halves"
metric = "fill_distance"
rate = -1
[[expect]]
name = "impossible"
metric = "fill_distance"
degree = 1
rate = -3
)";

// A scalar plant, one lap, stepped through time: laps_to_limit is the lap map's, so it is NaN
// (n/a) for every trial, all of them ok.
const char* const adaptive_study = R"([study]
name = "cli_answer_adaptive"
kind = "adaptive"
evaluation_points = 128
metrics = ["l2_error", "interpolant_l2_error", "gap_to_projection", "laps_to_limit"]
[domain]
radius = 4.0
[grid]
n = [4, 6, 8]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 0.1
[adaptive]
speed = 1.0
laps = 1
snapshot_laps = [1]
snapshot_points = 16
)";

}  // namespace

TEST_CASE("run ends with the fitted rates and the verdict lines, and --tables adds the tables",
          "[cli][answer]") {
  const auto dir = rkhs::test::scratch_directory("cli_answer");
  std::ofstream(dir / "study.toml") << study_with_expectations;
  const std::string run = "run " + (dir / "study.toml").string() + " --no-store --no-plots --out " +
                          (dir / "out").string();
  const auto plain = stdout_of(run);
  INFO(plain.output);
  CHECK(plain.exit_code == 0);
  // The summary line, the fitted rates, then the verdicts and their counts, last.
  const auto summary = plain.output.find("cli_answer: 8 trials, 8 ok, 0 failed in ");
  const auto pass =
      plain.output.find("\nPASS         fill distance halves [kernel=bspline degree=1");
  const auto fail = plain.output.find("\nFAIL         impossible [kernel=bspline degree=1");
  CHECK_THAT(
      plain.output,
      Catch::Contains("study.toml:13:1): rate -1 [-1, -1] against rate in [-1.10, -0.900]\n"));
  CHECK_THAT(
      plain.output,
      Catch::Contains("study.toml:17:1): rate -1 [-1, -1] against rate in [-3.10, -2.90]\n"));
  const auto counts = plain.output.find("\n2 passed, 1 failed, 0 inconclusive\n");
  const auto rates = plain.output.find("\nfitted rates:\n");
  REQUIRE(summary != std::string::npos);
  REQUIRE(pass != std::string::npos);
  REQUIRE(fail != std::string::npos);
  REQUIRE(counts != std::string::npos);
  REQUIRE(rates != std::string::npos);
  CHECK(summary < rates);
  CHECK(rates < pass);
  CHECK(fail < counts);
  CHECK_THAT(plain.output, Catch::EndsWith("\n2 passed, 1 failed, 0 inconclusive\n"));
  CHECK_THAT(plain.output.substr(rates, pass - rates), Catch::Contains("power_function_sup  "));
  // No group table without --tables (they are in rates.md).
  CHECK_THAT(plain.output, !Catch::Contains("(group "));
  CHECK_THAT(rkhs::test::read_text(dir / "out" / "rates.md"),
             Catch::Contains("## kernel=bspline degree=1"));

  const auto tables = stdout_of(run + " --tables");
  INFO(tables.output);
  CHECK_THAT(tables.output, Catch::Contains("(group ") && Catch::Contains("fitted rate: "));
  CHECK(tables.output.find("(group ") < tables.output.find("\nPASS "));

  // -q: the summary line and the verdict lines, nothing else.
  const auto quiet = stdout_of(run + " -q");
  INFO(quiet.output);
  CHECK_THAT(quiet.output, Catch::StartsWith("cli_answer: 8 trials, 8 ok, 0 failed in "));
  CHECK_THAT(quiet.output, Catch::EndsWith("\n2 passed, 1 failed, 0 inconclusive\n"));
  CHECK_THAT(quiet.output, Catch::Contains("\nFAIL         impossible"));

  // report.html: the counts and the failure right under the title.
  const auto page = rkhs::test::read_text(dir / "out" / "report.html");
  const auto title = page.find("<h1>cli_answer</h1>");
  REQUIRE(title != std::string::npos);
  const auto page_counts = page.find("2 passed, 1 failed, 0 inconclusive");
  const auto page_failure = page.find("<b>FAIL</b> impossible [kernel=bspline degree=1");
  CHECK(title < page_counts);
  CHECK(page_counts < page_failure);
  CHECK(page_failure < page.find("<h2>Provenance</h2>"));
}

TEST_CASE(
    "run on a study without expectations says so, and an adaptive study says whether it "
    "converged in time and shows a metric its engine does not define as n/a",
    "[cli][answer]") {
  const auto dir = rkhs::test::scratch_directory("cli_answer_adaptive");
  std::ofstream(dir / "study.toml") << adaptive_study;
  const auto outcome = stdout_of("run " + (dir / "study.toml").string() +
                                 " --no-store --no-plots --out " + (dir / "out").string());
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("\nconvergence in time:\n  "));
  CHECK_THAT(outcome.output, Catch::EndsWith(")\nno expectations\n"));
  CHECK_THAT(outcome.output, Catch::Contains("converged in time: gap to the projection "));
  CHECK_THAT(outcome.output, Catch::Contains("(n = 8)"));
  CHECK_THAT(outcome.output, !Catch::Contains("lap map predicts"));  // stepped: not computed
  const auto markdown = rkhs::test::read_text(dir / "out" / "rates.md");
  CHECK_THAT(markdown, Catch::Contains("## Convergence in time\n\n- "));
  CHECK_THAT(markdown, Catch::Contains("| n/a |"));
  CHECK_THAT(markdown, !Catch::Contains("failed"));
  const auto page = rkhs::test::read_text(dir / "out" / "report.html");
  CHECK_THAT(page, Catch::Contains("<td>n/a</td>"));
  CHECK_THAT(page, Catch::Contains("<p class=\"counts\">No expectations.</p>"));
  CHECK_THAT(page, Catch::Contains("converged in time: gap to the projection "));
  const auto tables = stdout_of("run " + (dir / "study.toml").string() +
                                " --no-store --no-plots --tables --out " + (dir / "out").string());
  CHECK_THAT(tables.output, Catch::Contains("n/a"));
  CHECK_THAT(tables.output, !Catch::Contains("failed  "));
}
