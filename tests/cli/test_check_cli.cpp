// `rkhs-study check` as CI runs it: exit codes 0 / 1 / 2 / 3, readable verdicts, tiers, JUnit.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_support.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = rkhs::test::CommandOutcome;
using rkhs::test::rkhs_study;

fs::path scratch(const std::string& name) {
  return rkhs::test::scratch_directory("check_cli_" + name);
}

// B-splines of degree 1 and 2 (J = 8) on the paper's track, n = 10..60: power-function slopes
// about -0.5 and -1.5, condition-number slopes about 2 and 4.
const std::string small_study = R"([study]
name = "check_small"
evaluation_points = 512
metrics = ["fill_distance", "separation_distance", "gram_condition_number", "power_function_sup"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 60, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
tier = "quick"
[[kernel]]
name = "gaussian"
sigma = 1.0
)";

fs::path write_study(const fs::path& dir, const std::string& expectations) {
  const auto file = dir / "study.toml";
  std::ofstream(file) << small_study << expectations;
  return file;
}

std::string read(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("check: theory expectations that hold exit 0", "[cli][check]") {
  const auto dir = scratch("pass");
  const auto study = write_study(dir, R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
)");
  const auto outcome = rkhs_study("check " + study.string() + " --quiet");
  INFO(outcome.output);
  CHECK(outcome.exit_code == 0);
  CHECK_THAT(outcome.output,
             Catch::Contains("PASS         #1 power_function_sup, kernel=bspline degree=1 r=1"));
  CHECK_THAT(outcome.output, Catch::Contains("2 passed, 0 failed, 0 inconclusive"));
}

TEST_CASE("check: a deliberately wrong expectation exits 1 with a readable message",
          "[cli][check]") {
  const auto dir = scratch("fail");
  const auto study = write_study(dir, R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
degree = 1
rate = -1.0
)");
  const auto outcome = rkhs_study("check " + study.string() + " --quiet");
  INFO(outcome.output);
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output,
             Catch::Contains("FAIL         #1 power_function_sup, kernel=bspline degree=1 r=1 (" +
                             study.string() + ":18:1)"));
  CHECK_THAT(outcome.output,
             Catch::Contains(
                 "    expected: rate -1.00 +- 0.100 against ln n, i.e. rate in [-1.10, -0.900]\n"));
  CHECK_THAT(outcome.output, Catch::Contains("    found:    power law rate -0.4"));
  CHECK_THAT(outcome.output, Catch::Contains("on the window n = 10..60 (6 of 6 points)"));
  CHECK_THAT(outcome.output,
             Catch::Contains("    verdict:  the 95% CI lies entirely above -0.900\n"));
  CHECK_THAT(outcome.output, Catch::Contains("0 passed, 1 failed, 0 inconclusive"));
}

TEST_CASE("check: inconclusive exits 3, or 1 with --strict", "[cli][check]") {
  // A tolerance far below the scatter of the degree-2 condition numbers.
  const auto dir = scratch("inconclusive");
  const auto study = write_study(dir, R"(
[[expect]]
metric = "gram_condition_number"
kernel = "bspline"
degree = 2
theory = true
tolerance = 0.01
)");
  auto outcome = rkhs_study("check " + study.string() + " --quiet");
  INFO(outcome.output);
  CHECK(outcome.exit_code == 3);
  CHECK_THAT(outcome.output, Catch::Contains("INCONCLUSIVE #1 gram_condition_number"));
  CHECK_THAT(outcome.output, Catch::Contains("wider than the accepted interval (0.020)"));
  outcome = rkhs_study("check " + study.string() + " --quiet --strict");
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output, Catch::Contains("(--strict: inconclusive counts as failed)"));
}

TEST_CASE("check: bad input exits 2 and says where", "[cli][check]") {
  const auto dir = scratch("bad");
  auto study =
      write_study(dir, "[[expect]]\nmetric = \"power_function_sup\"\ndegre = 1\ntheory = true\n");
  auto outcome = rkhs_study("check " + study.string());
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("study.toml:19:1: expect.degre: unknown key"));
  CHECK_THAT(outcome.output, Catch::Contains("did you mean 'degree'?"));

  study = write_study(
      dir, "[[expect]]\nmetric = \"power_function_sup\"\nkernel = \"matern\"\ntheory = true\n");
  outcome = rkhs_study("check " + study.string());
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("kernel=matern selects no group of this study "
                                             "(values in the study: kernel: bspline, gaussian)"));

  study = write_study(
      dir, "[[expect]]\nmetric = \"power_function_sup\"\ntheory = true\ntier = \"quick\"\n");
  outcome = rkhs_study("check " + study.string() + " --tier nightly");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output,
             Catch::Contains("tier 'nightly' is not named in this study (tiers: quick)"));
  CHECK(rkhs_study("check").exit_code == 2);
  CHECK(rkhs_study("check " + (dir / "missing.toml").string()).exit_code == 2);
}

TEST_CASE("check --tier runs the tier's entries and expectations only", "[cli][check]") {
  const auto dir = scratch("tier");
  const auto study = write_study(dir, R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
tier = "quick"
[[expect]]
metric = "power_function_sup"
kernel = "gaussian"
rate = 5.0
)");
  // The whole study: the deliberately wrong Gaussian expectation fails.
  auto outcome = rkhs_study("check " + study.string() + " --quiet");
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output, Catch::Contains("check_small: 18 trials"));
  // The quick tier: B-splines only (the Gaussian entry is not in it), one expectation.
  outcome = rkhs_study("check " + study.string() + " --quiet --tier quick --out " +
                       (dir / "out").string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("check_small (tier quick): 12 trials, 12 ok"));
  CHECK_THAT(outcome.output, Catch::Contains("2 passed, 0 failed, 0 inconclusive"));
  CHECK(fs::exists(dir / "out" / "rates.csv"));
  CHECK_FALSE(fs::exists(dir / "out" / "journal.csv"));
  // summary.json reports each fit's model, asymptotic window and the other model's fit.
  const int json_ok = std::system(
      ("/usr/bin/python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); "
       "r = [x for x in d[\"rates\"] if x[\"metric\"] == \"power_function_sup\"][0]; "
       "assert r[\"model\"] == \"power_law\" and r[\"window\"] == [10, 20, 30, 40, 50, 60], r; "
       "assert r[\"preferred\"] == \"power_law\" and r[\"decisive\"], r; "
       "assert r[\"alternative\"][\"model\"] == \"exponential\" and r[\"head\"] == [], r' " +
       (dir / "out" / "summary.json").string())
          .c_str());
  CHECK(json_ok == 0);
}

TEST_CASE("check --junit writes one test case per expectation and group", "[cli][check]") {
  const auto dir = scratch("junit");
  const auto study = write_study(dir, R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
degree = 2
rate = -3.0
)");
  const auto xml_file = dir / "report.xml";
  const auto outcome =
      rkhs_study("check " + study.string() + " --quiet --junit " + xml_file.string());
  CHECK(outcome.exit_code == 1);
  const auto xml = read(xml_file);
  CHECK_THAT(xml, Catch::Contains("tests=\"3\" failures=\"1\" errors=\"0\" skipped=\"0\""));
  CHECK_THAT(xml, Catch::Contains("<testcase classname=\"check_small.power_function_sup\" "
                                  "name=\"#2 kernel=bspline degree=2 r=2\""));
  CHECK_THAT(xml,
             Catch::Contains(
                 "<failure type=\"fail\" message=\"FAIL: the 95% CI lies entirely above -2.90."));
  // Well-formed, by a real XML parser (Python's standard library).
  const int parsed = std::system(("/usr/bin/python3 -c 'import sys, xml.etree.ElementTree as t; "
                                  "r = t.parse(sys.argv[1]).getroot(); "
                                  "assert len(r.findall(\"./testsuite/testcase\")) == 3' " +
                                  xml_file.string())
                                     .c_str());
  CHECK(parsed == 0);
}

TEST_CASE("the project's studies pass their quick tier", "[cli][check]") {
  for (const auto& entry : fs::directory_iterator(fs::path(RKHS_STUDY_SOURCE_DIR) / "studies")) {
    if (entry.path().extension() != ".toml") continue;
    if (read(entry.path()).find("tier = \"quick\"") == std::string::npos) continue;
    const auto outcome =
        rkhs_study("check --tier quick --quiet --threads 2 " + entry.path().string());
    INFO(outcome.output);
    CHECK(outcome.exit_code == 0);
  }
}
