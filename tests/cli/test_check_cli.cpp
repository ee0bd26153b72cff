// `rkhs-study check` as CI runs it: exit codes 0 / 1 / 2 / 3 / 5, readable verdicts, tiers,
// JUnit, several study files, -k, xfail, --allow inconclusive, verdicts in summary.json.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
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
             Catch::Contains("PASS         power_function_sup kernel=bspline [kernel=bspline "
                             "degree=1 r=1] ("));
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
             Catch::Contains("FAIL         power_function_sup kernel=bspline degree=1 "
                             "[kernel=bspline degree=1 r=1] (" +
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
  CHECK_THAT(outcome.output, Catch::Contains("INCONCLUSIVE gram_condition_number kernel=bspline"));
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
                                  "name=\"power_function_sup kernel=bspline degree=2 "
                                  "[kernel=bspline degree=2 r=2]\""));
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

// ---- What CI users of pytest expect: several files, -k, xfail, --allow, JUnit, summary.json ----

namespace {

// small_study under another [study] name, with `expectations` after it.
fs::path write_named_study(const fs::path& file, const std::string& name,
                           const std::string& expectations) {
  auto text = small_study;
  text.replace(text.find("check_small"), std::string("check_small").size(), name);
  std::ofstream(file) << text << expectations;
  return file;
}

// Runs Python on `script` with `argument` as sys.argv[1]; its exit status.
int python(const std::string& script, const fs::path& argument) {
  const auto file = fs::path(argument).replace_extension(".py");
  std::ofstream(file) << script;
  return std::system(("/usr/bin/python3 " + file.string() + " " + argument.string()).c_str());
}

const std::string bspline_theory = R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
)";
const std::string gaussian_theory = R"(
[[expect]]
name = "Gaussian power function"
metric = "power_function_sup"
kernel = "gaussian"
theory = true
)";
// Wrong on purpose: the degree-1 condition number grows like n^2.
const std::string wrong_condition = R"(
[[expect]]
metric = "gram_condition_number"
degree = 1
rate = 5.0
)";

}  // namespace

TEST_CASE("check a.toml b.toml -k power --junit r.xml: one suite per study, one exit code",
          "[cli][check]") {
  const auto dir = scratch("several");
  const auto a = write_named_study(dir / "a.toml", "study_a", bspline_theory + wrong_condition);
  const auto b = write_named_study(dir / "b.toml", "study_b", gaussian_theory);
  const auto store = " --store " + (dir / "store.sqlite").string();
  const auto xml = dir / "r.xml";
  auto outcome = rkhs_study("check " + a.string() + " " + b.string() + " -k power --junit " +
                            xml.string() + " --out " + (dir / "out").string() + " --quiet" + store);
  INFO(outcome.output);
  CHECK(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("study_a: 18 trials, 18 ok"));
  CHECK_THAT(outcome.output, Catch::Contains("2 passed, 0 failed, 0 inconclusive, 1 deselected\n"));
  CHECK_THAT(outcome.output, Catch::Contains("study_b: 18 trials, 18 ok"));
  CHECK_THAT(outcome.output,
             Catch::Contains("total over 2 studies: 3 passed, 0 failed, 0 inconclusive, 1 "
                             "deselected in "));
  // One JUnit file, one <testsuite> per study, real times, the deselected case left out.
  CHECK(python(R"(import sys, xml.etree.ElementTree as t
root = t.parse(sys.argv[1]).getroot()
suites = root.findall("testsuite")
assert [s.get("name") for s in suites] == ["study_a", "study_b"], suites
assert root.get("tests") == "3" and root.get("failures") == "0", root.attrib
assert [len(s.findall("testcase")) for s in suites] == [2, 1]
assert all(float(s.get("time")) > 0 and s.get("timestamp") for s in suites)
cases = root.findall("./testsuite/testcase")
assert all(float(c.get("time")) > 0 for c in cases), [c.get("time") for c in cases]
assert cases[2].get("name") == "Gaussian power function [kernel=gaussian]", cases[2].get("name")
assert cases[2].get("file").endswith("b.toml") and cases[2].get("line") == "18"
props = {p.get("name"): p.get("value") for p in suites[0].find("properties")}
assert props["keyword_expression"] == "power" and props["deselected"] == "1", props
)",
               xml) == 0);
  // --out with several studies: a directory per study, each with what `run` writes.
  for (const auto* name : {"study_a", "study_b"})
    for (const auto* file : {"trials.csv", "rates.csv", "summary.json", "report.html"})
      CHECK(fs::exists(dir / "out" / name / file));

  // Without -k the wrong expectation of a.toml fails the whole check: the worst study decides.
  outcome = rkhs_study("check " + a.string() + " " + b.string() + " --quiet" + store);
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output, Catch::Contains("total over 2 studies: 3 passed, 1 failed"));
}

TEST_CASE("check: a bad file among several is exit 2 naming it, before anything runs",
          "[cli][check]") {
  const auto dir = scratch("several_bad");
  const auto good = write_named_study(dir / "good.toml", "good", bspline_theory);
  const auto bad = write_named_study(
      dir / "bad.toml", "bad", "[[expect]]\nmetric = \"power_function_sup\"\ntheory = \"yes\"\n");
  const auto xml = dir / "r.xml";
  auto outcome = rkhs_study("check " + good.string() + " " + bad.string() + " --junit " +
                            xml.string() + " --no-store --quiet");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output,
             Catch::Contains(bad.string() + ":19:10: expect.theory: expected true"));
  CHECK(outcome.output.find("trials") == std::string::npos);  // nothing ran
  CHECK_FALSE(fs::exists(xml));
  // The same study twice, or two files with one [study] name: their reports would collide.
  outcome = rkhs_study("check " + good.string() + " " + good.string() + " --no-store");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains(good.string() + " is given twice"));
  const auto twin = write_named_study(dir / "twin.toml", "good", bspline_theory);
  outcome = rkhs_study("check " + good.string() + " " + twin.string() + " --no-store");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("both define the study 'good'"));
}

TEST_CASE("check -k selects test cases by keyword expression, and none selected is exit 5",
          "[cli][check]") {
  const auto dir = scratch("keyword");
  const auto study = write_study(dir, bspline_theory + gaussian_theory + wrong_condition);
  const auto check = [&](const std::string& k) {
    return rkhs_study("check " + study.string() + " -k '" + k + "' --no-store --quiet");
  };
  auto outcome = check("power and not gaussian");
  INFO(outcome.output);
  CHECK(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("2 passed, 0 failed, 0 inconclusive, 2 deselected\n"));
  outcome = check("DEGREE=1");  // case-insensitive; the group label is part of the name
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output, Catch::Contains("1 passed, 1 failed, 0 inconclusive, 2 deselected\n"));
  outcome = check("(gaussian or gram) and not bound");
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output, Catch::Contains("1 passed, 1 failed, 0 inconclusive, 2 deselected\n"));
  // A -k that selects nothing: the study is not run, and the exit code is pytest's 5.
  outcome = check("matern");
  CHECK(outcome.exit_code == 5);
  CHECK_THAT(outcome.output,
             Catch::Contains("check_small: not run: -k selects none of its 4 test cases (4 "
                             "deselected)"));
  CHECK_THAT(outcome.output,
             Catch::Contains("no test case selected: -k 'matern' deselected all 4"));
  CHECK(outcome.output.find("18 trials") == std::string::npos);
  // A malformed expression is bad input, with the column.
  outcome = check("power and");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("-k 'power and': at column 10: expected an "
                                             "identifier, 'not' or '(', found the end"));
}

TEST_CASE("check: xfail makes a known deviation XFAIL and an unexpected pass XPASS",
          "[cli][check]") {
  const auto dir = scratch("xfail");
  const auto study = write_study(dir, wrong_condition + "xfail = \"condition grows like n^2\"\n" +
                                          bspline_theory + "xfail = \"believed wrong\"\n");
  const auto xml = dir / "r.xml";
  auto outcome =
      rkhs_study("check " + study.string() + " --no-store --quiet --junit " + xml.string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("XFAIL        gram_condition_number degree=1 "
                                             "[kernel=bspline degree=1 r=1]"));
  CHECK_THAT(outcome.output, Catch::Contains("    xfail:    condition grows like n^2\n"));
  CHECK_THAT(outcome.output, Catch::Contains("XPASS        power_function_sup kernel=bspline "
                                             "[kernel=bspline degree=2 r=2]"));
  CHECK_THAT(outcome.output,
             Catch::Contains("0 passed, 0 failed, 0 inconclusive, 1 xfailed, 2 xpassed\n"));
  auto junit = read(xml);
  CHECK_THAT(junit, Catch::Contains("tests=\"3\" failures=\"0\" errors=\"0\" skipped=\"1\""));
  CHECK_THAT(junit, Catch::Contains("<skipped type=\"xfail\" message=\"XFAIL: condition grows "
                                    "like n^2. FAIL: "));
  // --strict: an unexpected pass fails the check (pytest's xfail_strict), an XFAIL still not.
  outcome = rkhs_study("check " + study.string() + " --no-store --quiet --strict --junit " +
                       xml.string());
  CHECK(outcome.exit_code == 1);
  CHECK_THAT(outcome.output, Catch::Contains("(--strict: XPASS counts as failed)"));
  junit = read(xml);
  CHECK_THAT(junit, Catch::Contains("tests=\"3\" failures=\"2\" errors=\"0\" skipped=\"1\""));
  CHECK_THAT(junit, Catch::Contains("<failure type=\"xpass\" message=\"XPASS(strict): believed "
                                    "wrong. PASS: "));
  // An xfail without a reason is refused where it is written.
  const auto bad = write_study(dir, bspline_theory + "xfail = \"\"\n");
  outcome = rkhs_study("check " + bad.string() + " --no-store");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("study.toml:22:9: expect.xfail: expected the reason"));
}

TEST_CASE("check --allow inconclusive exits 0 for inconclusive verdicts", "[cli][check]") {
  const auto dir = scratch("allow");
  const auto study = write_study(dir, bspline_theory + R"(
[[expect]]
metric = "gram_condition_number"
kernel = "bspline"
degree = 2
theory = true
tolerance = 0.01
)");
  const auto check = [&](const std::string& options) {
    return rkhs_study("check " + study.string() + " --no-store --quiet " + options);
  };
  auto outcome = check("");
  INFO(outcome.output);
  CHECK(outcome.exit_code == 3);
  outcome = check("--allow inconclusive");
  CHECK(outcome.exit_code == 0);
  CHECK_THAT(outcome.output,
             Catch::Contains("2 passed, 0 failed, 1 inconclusive (--allow inconclusive: "
                             "inconclusive does not fail the check)"));
  // A failure still fails.
  const auto failing = write_study(dir, wrong_condition + R"(
[[expect]]
metric = "gram_condition_number"
kernel = "bspline"
degree = 2
theory = true
tolerance = 0.01
)");
  CHECK(rkhs_study("check " + failing.string() + " --no-store --quiet --allow inconclusive")
            .exit_code == 1);
  // --allow and --strict contradict each other; an unknown verdict name is refused.
  outcome = check("--allow inconclusive --strict");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("excludes"));
  outcome = check("--allow failed");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("failed not in {inconclusive}"));
}

TEST_CASE("check --junit: test names stay when [[expect]] tables are reordered", "[cli][check]") {
  const auto dir = scratch("junit_stable");
  const auto names_and_times = [&](const std::string& expectations) {
    const auto study = write_study(dir, expectations);
    const auto xml = dir / "r.xml";
    const auto outcome = rkhs_study("check " + study.string() + " --quiet --junit " + xml.string() +
                                    " --store " + (dir / "s.sqlite").string());
    CHECK(outcome.exit_code == 1);
    const auto text = read(xml);
    std::set<std::string> names;
    const std::regex testcase(
        "<testcase classname=\"([^\"]*)\" name=\"([^\"]*)\" "
        "file=\"[^\"]*\" line=\"[0-9]+\" time=\"([0-9.]+)\"");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), testcase);
         it != std::sregex_iterator(); ++it) {
      names.insert((*it)[1].str() + " :: " + (*it)[2].str());
      CHECK(std::stod((*it)[3].str()) > 0);
    }
    return names;
  };
  const auto in_order = names_and_times(bspline_theory + gaussian_theory + wrong_condition);
  const auto reordered = names_and_times(wrong_condition + bspline_theory + gaussian_theory);
  CHECK(in_order.size() == 4);
  CHECK(in_order == reordered);
  CHECK(in_order.contains(
      "check_small.gram_condition_number :: gram_condition_number degree=1 [kernel=bspline "
      "degree=1 r=1]"));
  CHECK(in_order.contains(
      "check_small.power_function_sup :: Gaussian power function [kernel=gaussian]"));
}

TEST_CASE("check --out: summary.json carries the verdicts", "[cli][check]") {
  const auto dir = scratch("summary_verdicts");
  const auto quick = std::string("tier = \"quick\"\n");
  const auto study =
      write_study(dir, bspline_theory + quick + wrong_condition + quick +
                           "xfail = \"condition grows like n^2\"\n" + gaussian_theory);
  const auto out = dir / "out";
  const auto outcome = rkhs_study("check " + study.string() +
                                  " -k 'not degree=2' --tier quick "
                                  "--no-plots --no-store --quiet --out " +
                                  out.string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 0);
  CHECK(python(R"(import json, sys
d = json.load(open(sys.argv[1]))
assert d["tier"] == "quick", d["tier"]
e = d["expectations"]
assert e["counts"] == {"passed": 1, "failed": 0, "inconclusive": 0, "xfailed": 1,
                       "xpassed": 0, "deselected": 1}, e["counts"]
o = e["outcomes"]
assert [x["name"] for x in o] == [
    "power_function_sup kernel=bspline [kernel=bspline degree=1 r=1]",
    "gram_condition_number degree=1 [kernel=bspline degree=1 r=1]"], o
p, x = o
assert p["verdict"] == "pass" and p["outcome"] == "passed" and p["xfail"] is None, p
assert p["metric"] == "power_function_sup" and p["kind"] == "theory", p
assert p["group_label"] == "kernel=bspline degree=1 r=1" and p["group"].startswith("kernel=bspline"), p
close = lambda a, b: abs(a - b) < 1e-12
assert close(p["accepted_low"], -0.6) and close(p["accepted_high"], -0.4), p
assert p["accepted_low"] <= p["ci_low"] <= p["rate"] <= p["ci_high"] <= p["accepted_high"], p
assert p["window"] == {"from": 10, "to": 60, "points": 6}, p["window"]
assert p["reason"] == "the 95% CI lies within the accepted interval", p["reason"]
assert p["location"].endswith("study.toml:18:1") and p["seconds"] > 0, p
assert x["verdict"] == "fail" and x["outcome"] == "xfailed", x
assert x["xfail"] == "condition grows like n^2" and x["expectation_name"] is None, x
assert close(x["accepted_low"], 4.9) and close(x["accepted_high"], 5.1), x
assert x["reason"].startswith("the 95% CI lies entirely below 4.90"), x["reason"]
)",
               out / "summary.json") == 0);
  // `report` on the directory reports what the folder holds: the quick tier's 12 trials, not the
  // study's 18.
  const auto report = rkhs_study("report " + out.string() + " --format md");
  INFO(report.output);
  CHECK(report.exit_code == 0);
  CHECK(report.output.find("gaussian") == std::string::npos);
}

TEST_CASE("check --junit into a missing folder creates it, one that cannot be is exit 2 up front",
          "[cli][check]") {
  const auto dir = scratch("junit_folder");
  const auto study = write_study(dir, R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
)");
  const auto xml = dir / "missing" / "dir" / "r.xml";
  auto outcome =
      rkhs_study("check " + study.string() + " --no-store --quiet --junit " + xml.string());
  INFO(outcome.output);
  CHECK(outcome.exit_code != 2);
  CHECK(fs::is_regular_file(xml));
  // A folder that cannot be made (a file is in the way): exit 2 naming the path, no trial run.
  std::ofstream(dir / "a_file") << "x";
  const auto blocked = dir / "a_file" / "r.xml";
  outcome =
      rkhs_study("check " + study.string() + " --no-store --quiet --junit " + blocked.string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("cannot write the JUnit report " + blocked.string()));
  CHECK_THAT(outcome.output, !Catch::Contains("trials,"));
  CHECK_THAT(outcome.output, !Catch::Contains("PASS"));
}

TEST_CASE("check on a study without [[expect]] exits 5, like -k selecting nothing",
          "[cli][check]") {
  const auto dir = scratch("no_expectations");
  const auto study = write_study(dir, "");
  const auto outcome =
      rkhs_study("check " + study.string() + " --no-store --quiet --out " + (dir / "out").string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 5);
  CHECK_THAT(outcome.output, Catch::Contains("no expectations to check (nothing verified)"));
  // Its trials ran and its outputs were written all the same.
  CHECK(fs::is_regular_file(dir / "out" / "trials.csv"));
}
