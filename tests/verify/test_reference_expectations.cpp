// reference = { ... } expectations: a metric against published values from a CSV file, n by n
// (docs/verification.md, "Reference values").
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "rkhs/core/data_root.hpp"
#include "rkhs/study/study.hpp"
#include "synthetic_results.hpp"

using namespace rkhs;
namespace fs = std::filesystem;

namespace {

const std::string header = R"([study]
name = "r"
metrics = ["gram_condition_number", "power_function_sup"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 50, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[kernel]]
name = "gaussian"
sigma = 1.0
)";

// A data root holding `published.csv`, the root of the process while it lives.
class PublishedValues {
 public:
  explicit PublishedValues(const std::string& csv)
      // One folder per process: ctest runs each test case as its own process, side by side.
      : root_(fs::temp_directory_path() / ("rkhs_reference_values_" + std::to_string(::getpid()))) {
    fs::create_directories(root_);
    std::ofstream(root_ / "published.csv") << csv;
    set_data_root(root_);
  }
  ~PublishedValues() {
    set_data_root({});
    fs::remove_all(root_);
  }

 private:
  fs::path root_;
};

// cond = 3 n^(2 p) for the B-splines, infinite for the Gaussian (a singular Gram matrix).
double condition(const TrialSpec& t, const std::string& metric) {
  const double n = static_cast<double>(t.n);
  if (metric != "gram_condition_number") return 1.0 / n;
  if (t.kernel.name != "bspline") return std::numeric_limits<double>::infinity();
  return 3.0 * std::pow(n, 2.0 * static_cast<double>(t.kernel.parameters.integer("degree")));
}

// The published table: the B-splines' 3 n^(2 p) times (1 + 0.01 n / 50) (1 % off at n = 50).
std::string table() {
  std::string csv = "# a comment line\nn,kernel,printed\n";
  for (int p : {1, 2})
    for (int n = 10; n <= 50; n += 10)
      csv += std::to_string(n) + ",order_" + std::to_string(p) + "," +
             std::to_string(3.0 * std::pow(n, 2.0 * p) * (1.0 + 0.01 * n / 50.0)) + "\n";
  for (int n = 10; n <= 50; n += 10) csv += std::to_string(n) + ",gaussian,1e16\n";
  return csv;
}

std::string expect(const std::string& selector, const std::string& where, double within) {
  return "[[expect]]\nmetric = \"gram_condition_number\"\n" + selector +
         "\nreference = { file = \"published.csv\", value = \"printed\", where = { kernel = \"" +
         where + "\" }, within = " + std::to_string(within) + " }\n";
}

}  // namespace

TEST_CASE("reference expectations: a metric against published values n by n",
          "[verification][reference]") {
  const PublishedValues files(table());
  const test::SyntheticResults study(
      header + expect("kernel = \"bspline\"\ndegree = 1", "order_1", 0.011) +
          expect("kernel = \"bspline\"\ndegree = 2", "order_2", 0.005) +
          expect("kernel = \"gaussian\"", "gaussian", 0.5),
      condition);
  const auto& spec = study.study.expectations[0].reference;
  CHECK(spec.n == std::vector<std::size_t>{10, 20, 30, 40, 50});
  CHECK(spec.lines == std::vector<unsigned>{3, 4, 5, 6, 7});
  CHECK(spec.text() == "published.csv, printed where kernel = order_1");
  const auto outcomes = study.verify();
  REQUIRE(outcomes.size() == 3);

  // Within 1.1 %: the ratios 1 / 1.002 .. 1 / 1.01 pass, and are reported.
  CHECK(outcomes[0].verdict == Verdict::pass);
  CHECK(outcomes[0].expected ==
        "gram_condition_number / reference = 1 ± 0.011 at every n of the reference "
        "(published.csv, printed where kernel = order_1)");
  CHECK_THAT(outcomes[0].found,
             Catch::StartsWith("ratio gram_condition_number / reference from 0.9901 (n = 50) to "
                               "0.998 (n = 10) at 5 of 5 n"));
  CHECK(outcomes[0].effectivity_min == Approx(1.0 / 1.01).epsilon(1e-6));
  CHECK(outcomes[0].effectivity_max == Approx(1.0 / 1.002).epsilon(1e-6));

  // Within 0.5 %: fails where the ratio is furthest from 1, naming the n, values and line.
  CHECK(outcomes[1].verdict == Verdict::fail);
  CHECK_THAT(outcomes[1].reason,
             Catch::StartsWith("at n = 50 gram_condition_number is 1.875e+07 against the "
                               "reference's 18937500 (line 12): a ratio of 0.9901"));

  // A singular Gram matrix (an infinite condition number) is no number to compare.
  CHECK(outcomes[2].verdict == Verdict::fail);
  CHECK_THAT(outcomes[2].reason,
             Catch::StartsWith("at n = 10 the measured value is inf, no number to set beside "
                               "the reference's 1e+16 (line 13)"));
}

TEST_CASE("reference expectations: mistakes name the study file and the CSV's line and column",
          "[verification][reference]") {
  const PublishedValues files(table() + "60,order_1,5\n");
  auto error = [](const std::string& reference) {
    return test::study_error(header +
                             "[[expect]]\nmetric = \"gram_condition_number\"\n"
                             "reference = " +
                             reference + "\n");
  };
  const std::string ok = "file = \"published.csv\", value = \"printed\", within = 0.1";
  CHECK_THAT(error("{ file = \"published.csv\", value = \"printed\" }"),
             Catch::Contains("expect.reference.within: missing"));
  CHECK_THAT(error("{ " + ok + ", tolerance = 1 }"),
             Catch::Contains("expect.reference.tolerance: unknown key (known: file, value, "
                             "where, within)"));
  CHECK_THAT(error("{ file = \"published.csv\", value = \"printed\", within = -1 }"),
             Catch::Contains("expect.reference.within: must be >= 0"));
  CHECK_THAT(error("{ file = \"published.csv\", value = \"printd\", within = 0.1 }"),
             Catch::Contains("published.csv:2:1: no column 'printd' (reference.value); the "
                             "columns are n, kernel, printed"));
  CHECK_THAT(error("{ " + ok + ", where = { kernel = \"order_3\" } }"),
             Catch::Contains("reference.where selects no row (the file has kernel: gaussian, "
                             "order_1, order_2)"));
  // Without `where` every row is read: n = 10 repeats on the second order's first row.
  CHECK_THAT(error("{ " + ok + " }"),
             Catch::Contains("published.csv:8:1: n = 10 again (line 3 has it)"));
  // n = 60 is a row of the file the study does not run.
  CHECK_THAT(error("{ " + ok + ", where = { kernel = \"order_1\" } }"),
             Catch::Contains("published.csv (line 18) gives n = 60, which this study does not "
                             "run (n: 10, 20, 30, 40, 50)"));
  CHECK_THAT(error("{ file = \"missing.csv\", value = \"printed\", within = 0.1 }"),
             Catch::Contains("expect.reference.file: ") && Catch::Contains("missing.csv"));
  CHECK_THAT(error("{ " + ok + ", where = { kernel = \"order_1\" } }\nmodel = \"exponential\""),
             Catch::Contains("reference values have no rate model"));
}

TEST_CASE("reference expectations: a value that is not a number is an error at its column",
          "[verification][reference]") {
  const PublishedValues files("n,printed\n10,1.5\n20,abc\n");
  CHECK_THAT(
      test::study_error(header + "[[expect]]\nmetric = \"gram_condition_number\"\nreference = { "
                                 "file = \"published.csv\", value = \"printed\", within = 0.1 }\n"),
      Catch::Contains("published.csv:3:4: printed: 'abc' is not a finite nonzero number"));
}

TEST_CASE("reference expectations: control characters from the file or the study are escaped",
          "[verification][reference]") {
  // A header with an escape sequence and a where value with a carriage return: the messages
  // quote both, escaped, and no raw control character reaches the terminal.
  const PublishedValues files("n,kind\x1b[31m,printed\n10,a,1.5\n");
  const auto message =
      test::study_error(header +
                        "[[expect]]\nmetric = \"gram_condition_number\"\nreference = { file = "
                        "\"published.csv\", value = \"printed\", where = { \"kind\\r\" = \"a\" }, "
                        "within = 0.1 }\n");
  CHECK_THAT(message, Catch::Contains("no column 'kind\\x0d' (reference.where); the columns "
                                      "are n, kind\\x1b[31m, printed"));
  CHECK(message.find('\x1b') == std::string::npos);
  CHECK(message.find('\r') == std::string::npos);
}
