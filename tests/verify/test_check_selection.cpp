// What `rkhs-study check` adds for CI around the verdicts: -k keyword expressions
// (rkhs/verify/keyword_expression.hpp), stable test-case names and keywords
// (rkhs/verify/expectation_cases.hpp), xfail markers and the exit codes they give
// (rkhs/verify/verification.hpp), JUnit suites (rkhs/verify/junit.hpp), and the verdicts in
// summary.json read back (rkhs/report/run_summary.hpp).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include "rkhs/core/random.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/run_summary.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/verify/expectation_cases.hpp"
#include "rkhs/verify/junit.hpp"
#include "rkhs/verify/keyword_expression.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/verify/verification.hpp"
#include "verify/synthetic_results.hpp"

using namespace rkhs;

namespace {

// Two B-spline groups (degree 1 and 2) and a Gaussian, n = 10..100.
const std::string base = R"([study]
name = "sel"
metrics = ["fill_distance", "separation_distance", "power_function_sup", "gram_condition_number"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 100, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
tier = "quick"
[[kernel]]
name = "gaussian"
sigma = 1.0
)";

bool selects(const std::string& expression, const std::vector<std::string>& keywords) {
  return KeywordExpression::parse(expression).matches(keywords);
}

std::string parse_error(const std::string& expression) {
  try {
    KeywordExpression::parse(expression);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

using test::study_error;

// The power function and condition number as theory says (B-splines of degree tau:
// n^-(tau - 1/2) and n^(2 tau); the Gaussian: exp(-0.3 n) and exp(0.5 n)), uniform centres,
// each trial 0.25 s.
double textbook_value(const TrialSpec& trial, const std::string& metric) {
  const double n = static_cast<double>(trial.n);
  const bool spline = trial.kernel.name == "bspline";
  const double tau = spline ? static_cast<double>(trial.kernel.parameters.integer("degree")) : 0.0;
  if (metric == "power_function_sup")
    return spline ? 2.0 * std::pow(n, -(tau - 0.5)) : std::exp(-0.3 * n);
  return spline ? 3.0 * std::pow(n, 2 * tau) : std::exp(0.5 * n);
}

struct Textbook : test::SyntheticResults {
  explicit Textbook(const std::string& expectations)
      : SyntheticResults(base + expectations, textbook_value, {}, 0.25) {}
};

}  // namespace

TEST_CASE("check -k: identifiers are case-insensitive substrings of any keyword",
          "[verification][check]") {
  const std::vector<std::string> keywords = {
      "power_function_sup kernel=bspline [kernel=bspline degree=2 r=2]", "power_function_sup",
      "gram_and_power"};
  CHECK(selects("", keywords));
  CHECK(selects("   ", keywords));
  CHECK(selects("power", keywords));
  CHECK(selects("POWER_Function", keywords));
  CHECK(selects("degree=2", keywords));
  CHECK(selects("[kernel=bspline", keywords));
  CHECK(selects("gram_and", keywords));
  CHECK_FALSE(selects("gaussian", keywords));
  CHECK_FALSE(selects("degree=1", keywords));
  CHECK(selects("not gaussian", keywords));
  CHECK(selects("power and not gaussian", keywords));
  CHECK_FALSE(selects("power and gaussian", keywords));
  CHECK(selects("gaussian or degree=2", keywords));
  CHECK_FALSE(selects("not (gaussian or degree=2)", keywords));
  CHECK(selects("not not power", keywords));
  CHECK(selects("((power))", keywords));
  // A keyword of a test case is matched alone: an identifier does not span two keywords.
  CHECK_FALSE(selects("power_function_supgram", keywords));
  CHECK_FALSE(selects("anything", {}));
  CHECK(selects("", {}));
}

TEST_CASE("check -k: precedence is not, then and, then or, as in pytest", "[verification][check]") {
  // Random flat expressions "[not] x op [not] x op ...", evaluated by the parser and by the
  // rule written out: split at `or` into `and` groups, each true when all its terms are.
  Random random(11);
  const std::vector<std::string> names = {"alpha", "beta", "gamma"};
  for (int round = 0; round < 500; ++round) {
    std::set<std::string> present;
    for (const auto& name : names)
      if (random.uniform() < 0.5) present.insert(name);
    const std::vector<std::string> keywords(present.begin(), present.end());
    const int terms = 1 + static_cast<int>(random.uniform() * 5);
    std::string text;
    bool expected = false, group = true;
    for (int t = 0; t < terms; ++t) {
      if (t > 0) {
        const bool is_or = random.uniform() < 0.5;
        text += is_or ? " or " : " and ";
        if (is_or) {
          expected = expected || group;
          group = true;
        }
      }
      const bool negated = random.uniform() < 0.3;
      const auto& name = names[static_cast<std::size_t>(random.uniform() * 3) % 3];
      text += (negated ? "not " : "") + name;
      group = group && (present.contains(name) != negated);
    }
    expected = expected || group;
    INFO(text);
    CHECK(selects(text, keywords) == expected);
  }
}

TEST_CASE("check -k: a malformed expression names the column and what was expected",
          "[verification][check]") {
  CHECK(parse_error("power and") ==
        "-k 'power and': at column 10: expected an identifier, 'not' or '(', found the end of "
        "the expression");
  CHECK(parse_error("power gaussian") ==
        "-k 'power gaussian': at column 7: expected 'and', 'or' or the end of the expression, "
        "found 'gaussian'");
  CHECK(parse_error("(power or gram") ==
        "-k '(power or gram': at column 15: expected ')', found the end of the expression");
  CHECK(parse_error("power)") ==
        "-k 'power)': at column 6: expected 'and', 'or' or the end of the expression, found ')'");
  CHECK(parse_error("and") ==
        "-k 'and': at column 1: expected an identifier, 'not' or '(', found 'and'");
  CHECK(parse_error("not") ==
        "-k 'not': at column 4: expected an identifier, 'not' or '(', found the end of the "
        "expression");
  CHECK_THAT(parse_error("power && gram"),
             Catch::StartsWith("-k 'power && gram': at column 7: unexpected character '&'"));
  CHECK_THAT(parse_error("\"power\""), Catch::Contains("at column 1: unexpected character '\"'"));
}

// Issue 50: 30,000 nested parentheses were a SIGSEGV (the recursion of the parser), and a
// chain of terms as long recursed as deep when matched.
TEST_CASE("check -k: nesting is bounded, long chains are matched without deep recursion",
          "[verification][check][hostile]") {
  const auto nested = [](const std::string& open, std::size_t depth) {
    std::string text;
    for (std::size_t i = 0; i < depth; ++i) text += open;
    text += "power";
    if (open == "(") text += std::string(depth, ')');
    return text;
  };
  const std::vector<std::string> power{"power_function_sup"};
  CHECK(KeywordExpression::parse(nested("(", KeywordExpression::max_depth)).matches(power));
  CHECK(KeywordExpression::parse(nested("not ", KeywordExpression::max_depth)).matches(power));
  const auto deep = parse_error(nested("(", 30000));
  CHECK_THAT(deep,
             Catch::StartsWith("-k '...((((") &&
                 Catch::EndsWith("...': at column 201: 'not' and '(' nested more than 200 deep"));
  CHECK(deep.size() < 250);
  CHECK_THAT(parse_error(nested("not ", 30000)),
             Catch::EndsWith(": at column 801: 'not' and '(' nested more than 200 deep"));
  // 100,000 terms: a left spine as long, walked in a loop.
  std::string chain_or, chain_and;
  for (int i = 0; i < 100000; ++i) {
    chain_or += "gram or ";
    chain_and += "power and ";
  }
  CHECK(KeywordExpression::parse(chain_or + "power").matches(power));
  CHECK_FALSE(KeywordExpression::parse(chain_or + "gram").matches(power));
  CHECK(KeywordExpression::parse(chain_and + "function").matches(power));
  CHECK_FALSE(KeywordExpression::parse(chain_and + "gram").matches(power));
  // A long expression is quoted around the column the message names.
  CHECK(parse_error(chain_or + "power )").size() < 300);
}

TEST_CASE("test cases: stable names from name, metric and selectors, not positions",
          "[verification][check]") {
  const std::string theory = R"([[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
)";
  const std::string named = R"([[expect]]
name = "Gaussian decay"
metric = "power_function_sup"
kernel = "gaussian"
theory = true
xfail = "known"
)";
  const std::string everywhere = R"([[expect]]
metric = "gram_condition_number"
model = "power_law"
tier = "quick"
)";
  const auto study = parse_study(base + theory + named + everywhere, "dir/s.toml");
  const auto cases = expectation_cases(study, study.trials());
  std::vector<std::string> names;
  for (const auto& c : cases) names.push_back(c.name);
  CHECK(names ==
        std::vector<std::string>{"power_function_sup kernel=bspline [kernel=bspline degree=1 r=1]",
                                 "power_function_sup kernel=bspline [kernel=bspline degree=2 r=2]",
                                 "Gaussian decay [kernel=gaussian]",
                                 "gram_condition_number [kernel=bspline degree=1 r=1]",
                                 "gram_condition_number [kernel=bspline degree=2 r=2]",
                                 "gram_condition_number [kernel=gaussian]"});
  CHECK(cases[2].keywords == std::vector<std::string>{"Gaussian decay [kernel=gaussian]",
                                                      "power_function_sup", "sel", "s", "theory",
                                                      "Gaussian decay", "xfail"});
  CHECK(cases[3].keywords ==
        std::vector<std::string>{"gram_condition_number [kernel=bspline degree=1 r=1]",
                                 "gram_condition_number", "sel", "s", "model", "quick"});

  // The same tables in another order: the same names for the same expectations and groups.
  const auto reordered = parse_study(base + everywhere + named + theory, "dir/s.toml");
  std::map<std::string, std::string> first, second;
  for (const auto& c : cases) first[c.name] = c.expectation->metric + " " + c.group;
  for (const auto& c : expectation_cases(reordered, reordered.trials()))
    second[c.name] = c.expectation->metric + " " + c.group;
  CHECK(first == second);
  CHECK(first.size() == 6);

  // The verdicts carry the names; each case's time is its group's trials' seconds (10 trials
  // of 0.25 s) plus the judging.
  const Textbook textbook(theory + named);
  const auto outcomes = textbook.verify();
  REQUIRE(outcomes.size() == 3);
  CHECK(outcomes[0].name == "power_function_sup kernel=bspline [kernel=bspline degree=1 r=1]");
  CHECK(outcomes[2].name == "Gaussian decay [kernel=gaussian]");
  for (const auto& o : outcomes) {
    CHECK(o.seconds >= 2.5);
    CHECK(o.seconds < 3.0);
  }
}

TEST_CASE("test cases: names that would be shared say what they expect and where",
          "[verification][check]") {
  const auto study = parse_study(base + R"([[expect]]
metric = "power_function_sup"
degree = 1
theory = true
[[expect]]
metric = "power_function_sup"
degree = 1
rate = { max = -0.3 }
[[expect]]
metric = "power_function_sup"
degree = 1
rate = { max = -0.3 }
last = 4
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
rate = -0.5
tolerance = 0.2
model = "power_law"
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
rate = -0.5
tolerance = 0.2
)",
                                 "s.toml");
  std::vector<std::string> names;
  for (const auto& c : expectation_cases(study, study.trials())) names.push_back(c.name);
  CHECK(names ==
        std::vector<std::string>{
            "power_function_sup degree=1 (theory = true) [kernel=bspline degree=1 r=1]",
            "power_function_sup degree=1 (rate = { max = -0.3 }) [kernel=bspline degree=1 r=1]",
            "power_function_sup degree=1 (rate = { max = -0.3 }, last = 4) [kernel=bspline "
            "degree=1 r=1]",
            "power_function_sup kernel=bspline (rate = -0.5, tolerance = 0.2) [kernel=bspline "
            "degree=1 r=1] #1",
            "power_function_sup kernel=bspline (rate = -0.5, tolerance = 0.2) [kernel=bspline "
            "degree=2 r=2] #1",
            "power_function_sup kernel=bspline (rate = -0.5, tolerance = 0.2) [kernel=bspline "
            "degree=1 r=1] #2",
            "power_function_sup kernel=bspline (rate = -0.5, tolerance = 0.2) [kernel=bspline "
            "degree=2 r=2] #2"});
  CHECK(std::set<std::string>(names.begin(), names.end()).size() == names.size());
}

TEST_CASE("xfail: a known deviation, parsed with its reason", "[verification][check]") {
  const auto with = [](const std::string& value) {
    return base + "[[expect]]\nmetric = \"power_function_sup\"\ntheory = true\nxfail = " + value +
           "\n";
  };
  const auto study = parse_study(with("\"the floor sets in early\""), "s.toml");
  CHECK(study.expectations.at(0).xfail == "the floor sets in early");
  CHECK(parse_study(base + "[[expect]]\nmetric = \"power_function_sup\"\ntheory = true\n", "s.toml")
            .expectations.at(0)
            .xfail.empty());
  CHECK(study_error(with("\"\"")) ==
        "s.toml:19:9: expect.xfail: expected the reason the expectation is known not to hold (a "
        "non-empty string, e.g. xfail = \"the floor sets in before n = 50\"), found ''");
  CHECK_THAT(study_error(with("\"  \"")), Catch::StartsWith("s.toml:19:9: expect.xfail:"));
  CHECK_THAT(study_error(with("true")),
             Catch::StartsWith("s.toml:19:9: expect.xfail: expected the reason") &&
                 Catch::EndsWith("found true"));
  CHECK_THAT(
      study_error(base +
                  "[[expect]]\nmetric = \"power_function_sup\"\ntheory = true\nxfial = \"x\"\n"),
      Catch::Contains("expect.xfial: unknown key") && Catch::Contains("did you mean 'xfail'?"));
}

TEST_CASE("xfail: a fail is XFAIL and a pass XPASS, inconclusive stays", "[verification][check]") {
  const Textbook textbook(R"([[expect]]
metric = "power_function_sup"
degree = 1
rate = -2.0
xfail = "wrong on purpose"
[[expect]]
metric = "power_function_sup"
degree = 2
theory = true
xfail = "believed wrong"
[[expect]]
metric = "power_function_sup"
degree = 2
rate = -1.0
)");
  const auto outcomes = textbook.verify();
  REQUIRE(outcomes.size() == 3);
  CHECK(outcomes[0].verdict == Verdict::fail);
  CHECK(case_outcome(outcomes[0]) == CaseOutcome::xfailed);
  CHECK(outcomes[1].verdict == Verdict::pass);
  CHECK(case_outcome(outcomes[1]) == CaseOutcome::xpassed);
  CHECK(case_outcome(outcomes[2]) == CaseOutcome::failed);
  const auto counts = count_verdicts(outcomes);
  CHECK(counts.xfailed == 1);
  CHECK(counts.xpassed == 1);
  CHECK(counts.failed == 1);
  CHECK(counts.passed == 0);
  const auto report = format_verification(outcomes);
  CHECK_THAT(report, Catch::Contains("XFAIL        power_function_sup degree=1 [kernel=bspline "
                                     "degree=1 r=1] (s.toml:16:1)\n"));
  CHECK_THAT(report, Catch::Contains("    xfail:    wrong on purpose\n"));
  // Two expectations on degree 2: each name says what it expects.
  CHECK_THAT(report, Catch::Contains("XPASS        power_function_sup degree=2 (theory = true) "
                                     "[kernel=bspline degree=2 r=2] (s.toml:21:1)\n"));
  CHECK_THAT(report, Catch::Contains("FAIL         power_function_sup degree=2 (rate = -1) "
                                     "[kernel=bspline degree=2 r=2] (s.toml:26:1)\n"));
  CHECK_THAT(report, Catch::EndsWith("0 passed, 1 failed, 0 inconclusive, 1 xfailed, 1 xpassed\n"));
  CHECK_THAT(format_verification(outcomes, {.strict = true}, 4),
             Catch::EndsWith("0 passed, 1 failed, 0 inconclusive, 1 xfailed, 1 xpassed, 4 "
                             "deselected (--strict: XPASS counts as failed)\n"));

  // An inconclusive verdict of a marked expectation stays inconclusive.
  ExpectationOutcome inconclusive = outcomes[0];
  inconclusive.verdict = Verdict::inconclusive;
  CHECK(case_outcome(inconclusive) == CaseOutcome::inconclusive);
  CHECK(case_outcome_name(CaseOutcome::xfailed) == "XFAIL");
  CHECK(case_outcome_id(CaseOutcome::xpassed) == "xpassed");
}

TEST_CASE("check exit codes: fail, strict, --allow inconclusive, nothing selected",
          "[verification][check]") {
  const auto counts = [](std::size_t passed, std::size_t failed, std::size_t inconclusive,
                         std::size_t xfailed, std::size_t xpassed, std::size_t deselected) {
    VerdictCounts c;
    c.passed = passed;
    c.failed = failed;
    c.inconclusive = inconclusive;
    c.xfailed = xfailed;
    c.xpassed = xpassed;
    c.deselected = deselected;
    return c;
  };
  const CheckPolicy plain, strict{.strict = true}, allow{.allow_inconclusive = true};
  CHECK(check_exit_code(counts(2, 0, 0, 0, 0, 0), plain) == 0);
  CHECK(check_exit_code(counts(0, 0, 0, 0, 0, 0), plain) == 5);  // nothing to check
  CHECK(check_exit_code(counts(2, 1, 1, 0, 0, 0), allow) == 1);
  CHECK(check_exit_code(counts(2, 0, 0, 3, 0, 0), plain) == 0);  // XFAIL does not fail
  CHECK(check_exit_code(counts(2, 0, 0, 3, 0, 0), strict) == 0);
  CHECK(check_exit_code(counts(2, 0, 0, 0, 1, 0), plain) == 0);  // XPASS is reported only
  CHECK(check_exit_code(counts(2, 0, 0, 0, 1, 0), strict) == 1);
  CHECK(check_exit_code(counts(2, 0, 1, 0, 0, 0), plain) == 3);
  CHECK(check_exit_code(counts(2, 0, 1, 0, 0, 0), allow) == 0);
  CHECK(check_exit_code(counts(2, 0, 1, 0, 0, 0), strict) == 1);
  CHECK(check_exit_code(counts(0, 0, 0, 0, 0, 4), plain) == 5);  // -k selected nothing
  CHECK(check_exit_code(counts(1, 0, 0, 0, 0, 4), plain) == 0);
  CHECK(check_exit_code(counts(0, 1, 0, 0, 0, 4), plain) == 1);
  // Counts of several studies add up: the worst study decides.
  auto total = counts(2, 0, 1, 0, 0, 1);
  total += counts(0, 1, 0, 1, 1, 2);
  CHECK(total.selected() == 6);
  CHECK(total.deselected == 3);
  CHECK(check_exit_code(total, allow) == 1);
  CHECK(format_counts(total) ==
        "2 passed, 1 failed, 1 inconclusive, 1 xfailed, 1 xpassed, 3 deselected");
  CHECK(format_counts(counts(1, 0, 1, 0, 0, 0), allow) ==
        "1 passed, 0 failed, 1 inconclusive (--allow inconclusive: inconclusive does not fail "
        "the check)");
}

TEST_CASE("JUnit: a suite per study, XFAIL skipped, XPASS a failure only when strict",
          "[verification][check]") {
  const Textbook first(R"([[expect]]
metric = "power_function_sup"
degree = 1
rate = -2.0
xfail = "wrong & known"
[[expect]]
metric = "power_function_sup"
degree = 2
theory = true
xfail = "believed wrong"
)");
  const Textbook second(
      "[[expect]]\nmetric = \"power_function_sup\"\nkernel = \"gaussian\"\ntheory = true\n");
  const auto a = first.verify(), b = second.verify();
  REQUIRE(a.size() == 2);
  REQUIRE(b.size() == 1);
  JUnitReport report{
      {{&first.study, &a, 2.0, "", "2024-01-01T00:00:00Z", 0}, {&second.study, &b, 0.5, "", "", 3}},
      {},
      "power"};
  auto xml = junit_xml(report);
  CHECK_THAT(xml,
             Catch::Contains("<testsuites name=\"rkhs-study check\" tests=\"3\" failures=\"0\" "
                             "errors=\"0\" skipped=\"1\" time=\"2.500\">"));
  CHECK_THAT(xml,
             Catch::Contains("<testsuite name=\"sel\" tests=\"2\" failures=\"0\" errors=\"0\" "
                             "skipped=\"1\" time=\"2.000\" timestamp=\"2024-01-01T00:00:00Z\""));
  CHECK_THAT(xml, Catch::Contains("<testsuite name=\"sel\" tests=\"1\" failures=\"0\" errors=\"0\" "
                                  "skipped=\"0\" time=\"0.500\" file=\"s.toml\">"));
  CHECK_THAT(xml,
             Catch::Contains("<skipped type=\"xfail\" message=\"XFAIL: wrong &amp; known. FAIL: "));
  CHECK_THAT(xml, Catch::Contains("<property name=\"keyword_expression\" value=\"power\"/>"));
  CHECK_THAT(xml, Catch::Contains("<property name=\"deselected\" value=\"3\"/>"));
  CHECK_THAT(xml,
             Catch::Contains("name=\"power_function_sup degree=2 [kernel=bspline degree=2 r=2]\" "
                             "file=\"s.toml\" line=\"21\" time=\"2.5"));
  CHECK(xml.find("time=\"0.000\"") == std::string::npos);
  CHECK(xml.find("<failure") == std::string::npos);
  report.policy.strict = true;
  xml = junit_xml(report);
  CHECK_THAT(xml, Catch::Contains("tests=\"3\" failures=\"1\" errors=\"0\" skipped=\"1\""));
  CHECK_THAT(xml, Catch::Contains(
                      "<failure type=\"xpass\" message=\"XPASS(strict): believed wrong. PASS: "));
}

TEST_CASE("summary.json: the tier is read back for `report`", "[verification][check]") {
  const Textbook textbook(
      "[[expect]]\nmetric = \"power_function_sup\"\ntheory = true\ntier = \"quick\"\n");
  const auto outcomes = textbook.verify();
  RunRecord record{textbook.study, textbook.trials, textbook.results, textbook.rates, 1, 0.0, ""};
  record.tier = "quick";
  record.verdicts = &outcomes;
  record.deselected = 2;
  const auto json = summary_json(record);
  CHECK_THAT(json, Catch::Contains("\"tier\": \"quick\""));
  CHECK_THAT(json,
             Catch::Contains("\"counts\": {\"passed\": 3, \"failed\": 0, \"inconclusive\": 0, "
                             "\"xfailed\": 0, \"xpassed\": 0, \"deselected\": 2}"));
  const auto file = std::filesystem::temp_directory_path() / "rkhs_check_selection_summary.json";
  std::ofstream(file) << json;
  const auto summary = read_run_summary(file);
  CHECK(summary.tier == "quick");
  CHECK(summary.source == "s.toml");
  record.tier.clear();
  record.verdicts = nullptr;
  std::ofstream(file) << summary_json(record);
  CHECK(read_run_summary(file).tier.empty());
  CHECK(summary_json(record).find("\"expectations\"") == std::string::npos);
  std::filesystem::remove(file);
}

TEST_CASE("summary.json: the outcome table's fields in its order, read back the same by `report`",
          "[verification][check]") {
  const Textbook textbook(R"([[expect]]
metric = "power_function_sup"
name = "named"
theory = true
[[expect]]
metric = "power_function_sup"
degree = 1
rate = -2.0
xfail = "wrong & known"
)");
  const auto outcomes = textbook.verify();
  REQUIRE(outcomes.size() == 4);
  RunRecord record{textbook.study, textbook.trials, textbook.results, textbook.rates, 1, 0.0, ""};
  record.verdicts = &outcomes;
  const auto json = summary_json(record);
  // Each outcome's keys: the table's summary.json fields, in its order, nothing between them.
  std::vector<std::string> keys;
  for (const auto& field : outcome_fields)
    if (field.in(OutcomeField::in_summary_json)) keys.push_back('"' + std::string(field.key) + '"');
  auto at = json.find("\"outcomes\": [");
  REQUIRE(at != std::string::npos);
  for (std::size_t k = 0; k < outcomes.size(); ++k) {
    at = json.find("\n      {", at);
    REQUIRE(at != std::string::npos);
    const auto line = json.substr(at + 8, json.find('\n', at + 1) - at - 8);
    // Between keys: a value, then ", " (a JSON string holds no unescaped '"'; the window's
    // object is skipped whole).
    std::size_t from = 0;
    for (const auto& key : keys) {
      INFO(line << "\n" << key);
      REQUIRE(line.compare(from, key.size(), key) == 0);
      from = line.find(", \"", key == "\"window\"" ? line.find('}', from) : from) + 2;
    }
    CHECK(from == 1);  // no key after the last (npos + 2)
    ++at;
  }
  const auto dir = std::filesystem::temp_directory_path() / "rkhs_outcome_fields";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "summary.json") << json;
  const auto folder = read_results_folder(dir);
  std::filesystem::remove_all(dir);
  REQUIRE(folder.verdicts.size() == outcomes.size());
  for (std::size_t k = 0; k < outcomes.size(); ++k) {
    const auto &a = outcomes[k], &b = folder.verdicts[k];
    for (const auto& field : outcome_fields) {
      INFO(k << ": " << field.key);
      switch (field.type) {
        case OutcomeFieldType::text:
        case OutcomeFieldType::optional_text:
          CHECK(field.text(b) == field.text(a));
          break;
        case OutcomeFieldType::number:
          CHECK((a.*field.number == b.*field.number ||
                 (std::isnan(a.*field.number) && std::isnan(b.*field.number))));
          break;
        case OutcomeFieldType::seconds:
          CHECK(b.*field.number == Approx(a.*field.number).margin(1e-4));
          break;
        case OutcomeFieldType::verdict:
          CHECK(b.verdict == a.verdict);
          break;
        case OutcomeFieldType::kind:
          CHECK(b.expectation->kind == a.expectation->kind);
          break;
        case OutcomeFieldType::window:
          CHECK(b.window_from == a.window_from);
          CHECK(b.window_to == a.window_to);
          CHECK(b.window_points == a.window_points);
          break;
        case OutcomeFieldType::outcome:
          CHECK(case_outcome(b) == case_outcome(a));
          break;
        case OutcomeFieldType::summary:
          CHECK(verdict_numbers(b) == verdict_numbers(a));
          break;
      }
    }
  }
  CHECK(outcomes[0].expectation->name == "named");
  CHECK(outcomes[3].expectation->xfail == "wrong & known");
  // The verdicts read back write the same "expectations" again.
  const auto expectations = [](const std::string& text) {
    return text.substr(text.find("  \"expectations\": {"));
  };
  CHECK(expectations(summary_json(folder.record())) == expectations(json));
}
