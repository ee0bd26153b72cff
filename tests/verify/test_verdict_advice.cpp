// The advice of a FAIL or INCONCLUSIVE verdict (verdict_advice, rkhs/verify/verification.hpp):
// each situation is built by hand (pairwise rates still moving, a fill distance that is not
// n^(-1/d), too few points in the window) and its line checked; and the verdict lines `run`
// prints (format_verdict_lines) on a synthetic study.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "rkhs/verify/verification.hpp"
#include "verify/synthetic_results.hpp"

using namespace rkhs;

namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

// A series at `n` with the pairwise rates `pairwise` (one fewer than n).
MetricSeries series_with(std::vector<double> n, std::vector<double> pairwise) {
  MetricSeries series;
  series.metric = "power_function_sup";
  series.n = std::move(n);
  series.abscissa = series.n;
  series.pairwise = std::move(pairwise);
  return series;
}

}  // namespace

TEST_CASE("advice: pairwise rates still moving one way say to extend n", "[verification][advice]") {
  const auto climbing = series_with({36, 64, 144, 256, 576}, {0.5, 0.90, 1.2, 1.46});
  CHECK(verdict_advice(climbing, 5, Abscissa::fill_distance, std::nullopt) ==
        "pairwise rates still climb 0.90 -> 1.46: extend n beyond 576");
  const auto falling = series_with({10, 20, 40, 80}, {-0.5, -0.8, -1.1});
  CHECK(verdict_advice(falling, 4, Abscissa::n, std::nullopt) ==
        "pairwise rates still fall -0.50 -> -1.10: extend n beyond 80");
  // Settled (not monotone, or moving by 0.05 or less): nothing to say.
  CHECK(verdict_advice(series_with({10, 20, 40, 80}, {-1.0, -1.2, -1.1}), 4, Abscissa::n,
                       std::nullopt)
            .empty());
  CHECK(verdict_advice(series_with({10, 20, 40, 80}, {-1.0, -1.01, -1.02}), 4, Abscissa::n,
                       std::nullopt)
            .empty());
  // An undefined last rate leaves fewer than 2 trailing rates.
  CHECK(
      verdict_advice(series_with({10, 20, 40}, {-0.5, not_a_number}), 3, Abscissa::n, std::nullopt)
          .empty());
}

TEST_CASE("advice: a fill distance that is not n^(-1/d) says to fit against h",
          "[verification][advice]") {
  const auto series = series_with({16, 64, 256}, {-1.0, -1.0});  // steady rates
  CHECK(verdict_advice(series, 3, Abscissa::n, FillDistanceScaling{-0.57, 0.01, 2}) ==
        "h ~ n^-0.57, not n^-0.50: fit against h (abscissa = \"h\")");
  // Within 10% of 1/d, or within its own uncertainty, or already against h: no advice.
  CHECK(verdict_advice(series, 3, Abscissa::n, FillDistanceScaling{-0.52, 0.01, 2}).empty());
  CHECK(verdict_advice(series, 3, Abscissa::n, FillDistanceScaling{-0.57, 0.2, 2}).empty());
  CHECK(verdict_advice(series, 3, Abscissa::fill_distance, FillDistanceScaling{-0.57, 0.01, 2})
            .empty());
}

TEST_CASE("advice: too few points in the window say how many there are and are needed",
          "[verification][advice]") {
  const auto series = series_with({64, 128}, {-1.0});
  CHECK(verdict_advice(series, 2, Abscissa::n, std::nullopt) ==
        "the fit window has 2 points and a verdict needs at least 3: add n beyond 128");
  CHECK(verdict_advice(series_with({64}, {}), 1, Abscissa::n, std::nullopt) ==
        "the fit window has 1 point and a verdict needs at least 3: add n beyond 64");
}

TEST_CASE(
    "run's verdict lines: one per expectation with the rate against the bound, advice "
    "under a failure, the counts last",
    "[verification][advice]") {
  const std::string study = R"([study]
name = "v"
metrics = ["power_function_sup"]
[domain]
radius = 4.0
[grid]
n = [10, 20, 40, 80, 160]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[expect]]
name = "steady"
metric = "power_function_sup"
rate = { min = -3, max = -1 }
[[expect]]
name = "too slow"
metric = "power_function_sup"
rate = -3
)";
  // Pairwise rates that fall from 1.2 to -0.73 (ln y = -ln n - 30 / n): far from -3, so the
  // second expectation fails, and its advice says the rates still move.
  const test::SyntheticResults results(study, [](const TrialSpec& t, const std::string&) {
    const double n = static_cast<double>(t.n);
    return std::pow(n, -1.0) * std::exp(-30.0 / n);
  });
  const auto outcomes = results.verify();
  REQUIRE(outcomes.size() == 2);
  const auto text = format_verdict_lines(outcomes);
  INFO(text);
  CHECK_THAT(text, Catch::Contains("FAIL         too slow [kernel=gaussian] (s.toml:15:1): rate "));
  CHECK_THAT(text, Catch::Contains("] against rate in ["));
  CHECK_THAT(text, Catch::Contains("\n    advice: pairwise rates still fall "));
  CHECK_THAT(text, Catch::Contains(": extend n beyond 160\n"));
  CHECK_THAT(text, Catch::EndsWith("failed, 0 inconclusive\n"));
  // check prints the same heading and the advice among its lines.
  const auto report = format_verification(outcomes);
  CHECK_THAT(report, Catch::Contains(verdict_heading(outcomes[1]) + "\n    expected: "));
  CHECK_THAT(report, Catch::Contains("\n    advice:   pairwise rates still fall "));
  CHECK(format_verdict_lines({}) == "no expectations\n");
}
