// Expectations ([[expect]]), theory rates, tiers and verdicts (rkhs/study/expectation.hpp,
// rkhs/rates/theory.hpp, rkhs/study/tiers.hpp, rkhs/verify/verification.hpp, rkhs/verify/junit.hpp). Verdicts are tested
// on synthetic results, so each rule is exercised with known numbers.

#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>

#include "rkhs/verify/junit.hpp"
#include "rkhs/core/random.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/rates/theory.hpp"
#include "rkhs/study/tiers.hpp"
#include "rkhs/verify/verification.hpp"
#include "verify/synthetic_results.hpp"

using namespace rkhs;

namespace {

constexpr double infinity = std::numeric_limits<double>::infinity();

// Two B-spline groups (degree 1 and 2) and a Gaussian, n = 10..100.
const std::string base = R"([study]
name = "v"
metrics = ["fill_distance", "separation_distance", "power_function_sup", "sup_error",
           "gram_condition_number", "interpolant_native_norm"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 100, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[kernel]]
name = "gaussian"
sigma = 1.0
)";

std::string error_of(const std::string& text) { return test::study_error(text); }

// Results made up from formulas on `header` (default: base) with the expectations appended.
struct Synthetic : test::SyntheticResults {
  Synthetic(const std::string& expectations, const Value& value, const Distances& distances = {},
            const std::string& header = base)
      : SyntheticResults(header + expectations, value, distances) {}
};

double degree_of(const TrialSpec& t) {
  return t.kernel.name == "bspline" ? static_cast<double>(t.kernel.parameters.integer("degree")) : 0.0;
}

// Power function like the theory says: n^-(tau - 1/2) for B-splines, exp(-0.3 n) for the
// Gaussian; the other metrics smooth and harmless.
double textbook(const TrialSpec& t, const std::string& metric) {
  const double n = static_cast<double>(t.n), tau = degree_of(t);
  if (metric == "power_function_sup")
    return t.kernel.name == "bspline" ? 2.0 * std::pow(n, -(tau - 0.5)) : std::exp(-0.3 * n);
  if (metric == "gram_condition_number")
    return t.kernel.name == "bspline" ? 3.0 * std::pow(n, 2 * tau) : std::exp(0.5 * n);
  if (metric == "sup_error") return 0.01 * textbook(t, "power_function_sup");
  return 3.0;  // interpolant_native_norm
}

}  // namespace

TEST_CASE("[[expect]] tables parse: theory, rate, interval, model, bound, tiers", "[verification]") {
  const auto study = parse_study(base + R"(
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
degree = 1
theory = true
tier = "quick"
[[expect]]
name = "degree 2 rate"
metric = "power_function_sup"
degree = [2]
rate = -1.5
tolerance = 0.2
[[expect]]
metric = "gram_condition_number"
kernel = "bspline"
rate = { min = 1.5 }
tier = ["quick", "nightly"]
[[expect]]
metric = "power_function_sup"
sigma = 1
model = "exponential"
[[expect]]
metric = "sup_error"
bound = { by = "power_function_sup", times = "interpolant_native_norm", constant = 2.0 }
)", "s.toml");
  REQUIRE(study.expectations.size() == 5);
  const auto& theory = study.expectations[0];
  CHECK(theory.number == 1);
  CHECK(theory.location == "s.toml:17:1");
  CHECK(theory.kind == ExpectationKind::theory);
  CHECK(theory.tolerance == default_rate_tolerance);
  CHECK(theory.tiers == std::vector<std::string>{"quick"});
  CHECK(theory.selector_text() == "kernel=bspline degree=1");
  const auto& rate = study.expectations[1];
  CHECK(rate.name == "degree 2 rate");
  CHECK(rate.kind == ExpectationKind::rate);
  CHECK(rate.model == RateModel::power_law);
  REQUIRE(rate.expected);
  CHECK(rate.interval.low == Approx(-1.7));
  CHECK(rate.interval.high == Approx(-1.3));
  const auto& interval = study.expectations[2];
  CHECK(interval.interval.low == 1.5);
  CHECK(interval.interval.high == infinity);
  CHECK(interval.tiers == std::vector<std::string>{"quick", "nightly"});
  CHECK(interval.in_tier("nightly"));
  CHECK_FALSE(interval.in_tier("weekly"));
  CHECK(interval.in_tier(""));
  const auto& model = study.expectations[3];
  CHECK(model.kind == ExpectationKind::model);
  CHECK(model.model == RateModel::exponential);
  const auto& bound = study.expectations[4];
  CHECK(bound.kind == ExpectationKind::bound);
  CHECK(bound.bound.by == "power_function_sup");
  CHECK(bound.bound.times == "interpolant_native_norm");
  CHECK(bound.bound.constant == 2.0);
  CHECK(bound.selector_text() == "every group");

  // Selectors compare values as printed: sigma = 1 selects the Gaussian's sigma = 1.0.
  const auto trials = study.trials();
  CHECK(std::count_if(trials.begin(), trials.end(),
                      [&](const TrialSpec& t) { return model.selects(t); }) == 10);
  CHECK(std::count_if(trials.begin(), trials.end(),
                      [&](const TrialSpec& t) { return theory.selects(t); }) == 10);
}

TEST_CASE("[[expect]] mistakes are errors with file:line:column", "[verification]") {
  const auto with = [](const std::string& table) { return base + "[[expect]]\n" + table; };
  CHECK_THAT(error_of(with("metrc = \"power_function_sup\"\ntheory = true\n")),
             Catch::StartsWith("s.toml:17:1: expect.metrc: unknown key") &&
                 Catch::Contains("did you mean 'metric'?"));
  CHECK_THAT(error_of(with("metric = \"power_function_supp\"\ntheory = true\n")),
             Catch::Contains("s.toml:17:10: expect.metric: unknown metric 'power_function_supp'") &&
                 Catch::Contains("did you mean 'power_function_sup'?"));
  CHECK_THAT(error_of(with("metric = \"l2_error\"\ntheory = true\n")),
             Catch::Contains("expect.metric: metric 'l2_error' is not measured by this study"));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\ndegree = 3\ntheory = true\n")),
             Catch::Contains("s.toml:16:1: expect: degree=3 selects no group of this study "
                             "(values in the study: degree: 1, 2)"));
  // Every value of a list selects something: a typo in one is not silently dropped.
  CHECK(error_of(with("metric = \"power_function_sup\"\ndegree = [1, 5]\ntheory = true\n")) ==
        "s.toml:18:14: expect.degree: degree=5 selects no group of this study (the groups it "
        "selects have degree: 1)");
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\nkernel = [\"bspline\", \"gausian\"]\n"
                           "theory = true\n")),
             Catch::Contains("s.toml:18:22: expect.kernel: kernel=gausian selects no group"));
  CHECK_NOTHROW(parse_study(with("metric = \"power_function_sup\"\ndegree = [1, 2]\ntheory = true\n"),
                            "s.toml"));
  CHECK_THAT(error_of(with("metric = \"fill_distance\"\ntheory = true\n")),
             Catch::Contains("s.toml:18:10: expect.theory:") &&
                 Catch::Contains("no theory rate for metric 'fill_distance'"));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\n")),
             Catch::Contains("expect: say what is expected"));
  CHECK_THAT(
      error_of(with("metric = \"power_function_sup\"\ntheory = true\nrate = -1\n")),
      Catch::Contains(
          "give one of theory = true, rate = ..., bound = { ... }, constant = ... or reference"));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\nrate = { min = 1, max = 0 }\n")),
             Catch::Contains("s.toml:18:8: expect.rate: min (1) is above max (0)"));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\nrate = { low = 1 }\n")),
             Catch::Contains("expect.rate.low: unknown key (known: min, max, at_least)"));
  CHECK_THAT(error_of(with("metric = \"sup_error\"\nrate = { at_least = \"power_function_sup\", "
                           "max = 0 }\n")),
             Catch::Contains("s.toml:18:8: expect.rate: at_least derives the interval") &&
                 Catch::Contains("without min or max"));
  CHECK_THAT(error_of(with("metric = \"sup_error\"\nrate = { at_least = \"sup_error\" }\n")),
             Catch::Contains("expect.rate.at_least: 'sup_error' is the expectation's own metric"));
  CHECK_THAT(error_of(with("metric = \"sup_error\"\nrate = { at_least = \"l2_error\" }\n")),
             Catch::Contains("expect.rate.at_least: metric 'l2_error' is not measured"));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\nmodel = \"exponential\"\nrate = -0.3\n")),
             Catch::Contains("give tolerance = ..."));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\nmodel = \"cubic\"\n")),
             Catch::Contains("expect.model: found \"cubic\""));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\nrate = { max = 0 }\ntolerance = 0.2\n")),
             Catch::Contains("expect.tolerance: only for theory = true, rate = <number> or rate = "
                             "{ at_least = \"metric\" }"));
  CHECK_THAT(error_of(with("metric = \"sup_error\"\nbound = { by = \"l2_error\" }\n")),
             Catch::Contains("expect.bound.by: metric 'l2_error' is not measured"));
  CHECK_THAT(error_of(with("metric = \"sup_error\"\nbound = { times = \"power_function_sup\" }\n")),
             Catch::Contains("expect.bound.by: missing"));
  CHECK_THAT(error_of(with("metric = \"sup_error\"\nbound = {}\n")),
             Catch::Contains("expect.bound: give by = \"metric\""));
  CHECK_THAT(error_of(with("metric = \"power_function_sup\"\ntheory = true\ntier = \"\"\n")),
             Catch::Contains("expect.tier: expected a tier name"));
  CHECK_THAT(error_of(base + "[[expect]]\nmetric = \"power_function_sup\"\ntheory = \"yes\"\n"),
             Catch::Contains("expect.theory: expected true"));
}

TEST_CASE("tier marks on plugin entries and --tier restriction", "[verification]") {
  std::string text = base;
  text.replace(text.find("J = 8\n"), 6, "J = 8\ntier = \"quick\"\n");
  text += R"([[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
tier = "quick"
[[expect]]
metric = "power_function_sup"
kernel = "gaussian"
theory = true
)";
  const auto study = parse_study(text, "s.toml");
  CHECK(study.kernels.at(0).tiers == std::vector<std::string>{"quick"});
  CHECK(study.kernels.at(1).tiers == std::vector<std::string>{"quick"});  // degree 2
  CHECK(study.kernels.at(2).tiers.empty());                                // the Gaussian
  CHECK(study.kernels.at(0).label() == "bspline degree=1 r=1 n0=4 J=8");  // tiers are not axes
  CHECK(study_tiers(study) == std::vector<std::string>{"quick"});

  const auto quick = restrict_to_tier(study, "quick");
  REQUIRE(quick.kernels.size() == 2);  // the B-spline entry expands to degree 1 and 2
  CHECK(quick.kernels.at(0).name == "bspline");
  CHECK(quick.targets.size() == 1);  // unmarked axes are not restricted
  REQUIRE(quick.expectations.size() == 1);
  CHECK(quick.expectations.at(0).number == 1);
  CHECK(quick.trials().size() == 20);

  CHECK_THROWS_WITH(restrict_to_tier(study, "quik"),
                    Catch::Contains("tier 'quik' is not named in this study (tiers: quick)"));
  // An expectation of the tier that selects only groups outside it is an input error.
  std::string orphan = text;
  orphan += "[[expect]]\nmetric = \"power_function_sup\"\nkernel = \"gaussian\"\ntheory = true\ntier = \"quick\"\n";
  CHECK_THROWS_WITH(restrict_to_tier(parse_study(orphan, "s.toml"), "quick"),
                    Catch::Contains("expect: in tier 'quick', kernel=gaussian selects no group the tier runs"));
  CHECK_THAT(error_of(base + "[[target]]\nname = \"sine\"\ntier = 3\n"),
             Catch::Contains("target.tier: expected a tier name"));
}

TEST_CASE("a tier of some values of n: grid.tier_n", "[verification]") {
  std::string text = base;
  const std::string n_line = "n = { from = 10, to = 100, step = 10 }\n";
  text.replace(text.find(n_line), n_line.size(),
               n_line + "tier_n = { quick = { from = 10, to = 40, step = 10 }, slow = [100] }\n");
  const auto study = parse_study(text, "s.toml");
  CHECK(study_tiers(study) == std::vector<std::string>{"quick", "slow"});
  const auto quick = restrict_to_tier(study, "quick");
  CHECK(quick.n_values == std::vector<std::size_t>{10, 20, 30, 40});
  CHECK(quick.kernels.size() == study.kernels.size());  // no axis is restricted
  CHECK(quick.trials().size() == 4 * study.kernels.size());
  CHECK(restrict_to_tier(study, "slow").n_values == std::vector<std::size_t>{100});
  // A trial's key does not depend on the tier.
  CHECK(quick.trials().front().key == study.trials().front().key);

  std::string outside = base;
  outside.replace(outside.find(n_line), n_line.size(), n_line + "tier_n = { quick = [10, 15] }\n");
  CHECK_THAT(error_of(outside), Catch::Contains("grid.tier_n.quick: n = 15 is not one of grid.n"));
  std::string not_table = base;
  not_table.replace(not_table.find(n_line), n_line.size(), n_line + "tier_n = [10]\n");
  CHECK_THAT(error_of(not_table), Catch::Contains("grid.tier_n: expected a table of tiers"));
}

TEST_CASE("theory rates from kernel metadata, converted to the fitted abscissa", "[verification]") {
  KernelProperties sobolev;
  sobolev.sobolev_order = 2.0;
  auto pf = theory_rate("power_function_sup", sobolev);
  REQUIRE(pf);
  CHECK(pf->model == RateModel::power_law);
  CHECK(pf->h_exponent == 1.5);
  CHECK(pf->sharp);
  double slope = 0;
  auto band = theory_interval(*pf, Abscissa::n, 0.1, &slope);
  CHECK(slope == -1.5);
  CHECK(band.low == Approx(-1.6));
  CHECK(band.high == Approx(-1.4));
  band = theory_interval(*pf, Abscissa::fill_distance, 0.1, &slope);
  CHECK(slope == 1.5);
  CHECK(band.low == Approx(1.4));

  const auto l2 = theory_rate("l2_error", sobolev);
  REQUIRE(l2);
  CHECK_FALSE(l2->sharp);  // an upper bound: faster convergence is allowed
  band = theory_interval(*l2, Abscissa::n, 0.1);
  CHECK(band.low == -infinity);
  CHECK(band.high == Approx(-1.9));
  band = theory_interval(*l2, Abscissa::fill_distance, 0.1);
  CHECK(band.low == Approx(1.9));
  CHECK(band.high == infinity);

  // cond ~ n q^-(2 tau - d) = h^-2 tau; lambda_min ~ q^(2 tau - d).
  const auto cond = theory_rate("gram_condition_number", sobolev);
  REQUIRE(cond);
  theory_interval(*cond, Abscissa::n, 0.1, &slope);
  CHECK(slope == 4.0);
  const auto lambda = theory_rate("gram_min_eigenvalue", sobolev);
  REQUIRE(lambda);
  theory_interval(*lambda, Abscissa::n, 0.1, &slope);
  CHECK(slope == -3.0);

  KernelProperties analytic;
  analytic.analytic = true;
  const auto gaussian = theory_rate("gram_condition_number", analytic);
  REQUIRE(gaussian);
  CHECK(gaussian->model == RateModel::exponential);
  CHECK(gaussian->direction == +1);
  CHECK(theory_rate("power_function_sup", analytic)->direction == -1);

  std::string why;
  CHECK_FALSE(theory_rate("power_function_sup", KernelProperties{}, &why));
  CHECK_THAT(why, Catch::Contains("neither analytic nor Sobolev-equivalent"));
  CHECK_FALSE(theory_rate("fill_distance", sobolev, &why));
  // d comes from the kernel's properties: tau = 2 in d = 2 gives h^(tau - d/2) = h^1 for the
  // power function, n^-1/2 against n (h ~ n^-1/d).
  KernelProperties plane = sobolev;
  plane.sobolev_order = 2.0;
  plane.dimension = 2;
  const auto pf2 = theory_rate("power_function_sup", plane);
  REQUIRE(pf2);
  CHECK(pf2->dimension == 2);
  CHECK(pf2->h_exponent == Approx(1.0));
  theory_interval(*pf2, Abscissa::n, 0.1, &slope);
  CHECK(slope == Approx(-0.5));
}

TEST_CASE("verdicts: theory passes, a wrong rate fails, scatter is inconclusive", "[verification]") {
  const Synthetic exact(R"([[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
[[expect]]
metric = "power_function_sup"
kernel = "gaussian"
theory = true
[[expect]]
metric = "gram_condition_number"
theory = true
[[expect]]
metric = "power_function_sup"
degree = 1
rate = -1.0
[[expect]]
metric = "power_function_sup"
degree = 2
rate = { max = -1.0 }
)", textbook);
  const auto outcomes = exact.verify();
  REQUIRE(outcomes.size() == 8);  // 2 + 1 + 3 + 1 + 1
  for (std::size_t i : {0, 1, 2, 3, 4, 5, 7}) {
    INFO(i << ": " << outcomes[i].expected << " / " << outcomes[i].found << " / " << outcomes[i].reason);
    CHECK(outcomes[i].verdict == Verdict::pass);
  }
  CHECK(outcomes[0].group_label == "kernel=bspline degree=1 r=1");
  CHECK(outcomes[0].rate == Approx(-0.5));
  CHECK(outcomes[0].accepted_low == Approx(-0.6));
  CHECK(outcomes[0].window_from == 10);
  CHECK(outcomes[0].window_to == 100);
  CHECK(outcomes[0].window_points == 10);
  CHECK_THAT(outcomes[0].expected, Catch::Contains("h^0.5 (tau = 1, d = 1)"));
  CHECK_THAT(outcomes[2].found, Catch::StartsWith("exponential model rate -0.300 per unit n"));
  CHECK_THAT(outcomes[2].reason, Catch::Contains("its 95% CI [-0.300, -0.300] lies below 0"));
  CHECK_THAT(outcomes[5].reason, Catch::Contains("lies above 0"));  // Gaussian condition grows

  const auto& wrong = outcomes[6];
  CHECK(wrong.verdict == Verdict::fail);
  CHECK(wrong.reason == "the 95% CI lies entirely above -0.900");
  CHECK_THAT(wrong.expected, Catch::StartsWith("rate -1.00 +- 0.100 against ln n"));
  CHECK_THAT(wrong.found, Catch::StartsWith("power law rate -0.500 (95% CI [-0.500, -0.500]) on "
                                            "the window n = 10..100 (10 of 10 points)"));

  const auto counts = count_verdicts(outcomes);
  CHECK(counts.passed == 7);
  CHECK(counts.failed == 1);
  CHECK(check_exit_code(counts) == 1);
  const auto report = format_verification(outcomes);
  CHECK_THAT(report, Catch::Contains("FAIL         power_function_sup degree=1 "
                                     "[kernel=bspline degree=1 r=1] (s.toml:"));
  CHECK_THAT(report, Catch::EndsWith("7 passed, 1 failed, 0 inconclusive\n"));

  // The Gaussian's theory fails when its series is algebraic.
  const Synthetic algebraic("[[expect]]\nmetric = \"power_function_sup\"\nkernel = \"gaussian\"\ntheory = true\n",
                            [](const TrialSpec& t, const std::string& m) {
                              return m == "power_function_sup" ? std::pow(static_cast<double>(t.n), -3.0) : 1.0;
                            });
  const auto algebraic_outcome = algebraic.verify();
  REQUIRE(algebraic_outcome.size() == 1);
  CHECK(algebraic_outcome[0].verdict == Verdict::fail);
  CHECK_THAT(algebraic_outcome[0].reason,
             Catch::StartsWith("the power law fits better, not the exponential model"));
}

// A multilevel study (Wendland phi_{2,1}, nested grids of m = 4 2^j + 1 points per side, levels
// j = 0..4), its reduction factor made up from the finest level's fill distance.
const std::string multilevel = R"toml([study]
name = "ml"
abscissa = "h"
evaluation_points = 16641
metrics = ["fill_distance", "separation_distance", "level_reduction_factor"]
[domain]
lengths = [1.0, 1.0]
periodic = false
[grid]
n = [25, 81, 289, 1089, 4225]
[[kernel]]
name = "wendland"
k = 1
radius = 1.0
[[target]]
name = "expression"
f = "exp(x1) * cos(x2)"
[[projection]]
name = "multilevel"
[[expect]]
metric = "level_reduction_factor"
theory = true
)toml";

// A tensor grid of n = m^2 points on the unit square: h = spacing / sqrt(2), q = spacing / 2.
std::pair<double, double> tensor_grid(const TrialSpec& t) {
  const double spacing = 1.0 / (std::sqrt(static_cast<double>(t.n)) - 1.0);
  return {spacing / std::sqrt(2.0), spacing / 2.0};
}

TEST_CASE("theory of multiscale interpolation: a reduction factor below 1 bounded away from it",
          "[verification]") {
  KernelProperties sobolev;
  sobolev.sobolev_order = 2.5;
  sobolev.dimension = 2;
  const auto law = theory_rate("level_reduction_factor", sobolev);
  REQUIRE(law);
  CHECK_FALSE(law->sharp);
  CHECK(law->h_exponent == 0.0);
  REQUIRE(law->values_below);
  CHECK(*law->values_below == 1.0);
  const auto band = theory_interval(*law, Abscissa::fill_distance, 0.1);
  CHECK(band.low == Approx(-0.1));
  CHECK(band.high == infinity);
  KernelProperties analytic;
  analytic.analytic = true;
  std::string why;
  CHECK_FALSE(theory_rate("level_reduction_factor", analytic, &why));
  CHECK_THAT(why, Catch::Contains("finite smoothness") && Catch::Contains("is analytic"));

  auto outcome_of = [](double (*factor)(double h)) {
    const Synthetic made(
        "", [&](const TrialSpec& t, const std::string&) { return factor(tensor_grid(t).first); },
        tensor_grid, multilevel);
    const auto outcomes = made.verify();
    REQUIRE(outcomes.size() == 1);
    INFO(outcomes[0].expected << " / " << outcomes[0].found << " / " << outcomes[0].reason);
    return outcomes[0];
  };
  // A factor of about 0.2 at every level, falling slowly: the theorem's picture.
  const auto holds = outcome_of([](double h) { return 0.2 * std::pow(h / 0.177, 0.05); });
  CHECK(holds.verdict == Verdict::pass);
  CHECK_THAT(holds.expected, Catch::Contains("<= alpha < 1 at every level") &&
                                 Catch::Contains("tau = 2.5, d = 2") &&
                                 Catch::Contains("every value below 1") &&
                                 Catch::Contains("quasi-uniform nested centre sets"));
  CHECK_THAT(holds.reason, Catch::Contains("every usable value lies below 1 (largest 0.200"));
  // Below 1 at every level but creeping towards it as h falls (h^-0.3): the slope fails.
  const auto creeps = outcome_of([](double h) { return 0.3 * std::pow(h / 0.177, -0.3); });
  CHECK(creeps.verdict == Verdict::fail);
  CHECK(creeps.rate == Approx(-0.3));
  CHECK_THAT(creeps.reason, Catch::Contains("every usable value lies below 1"));
  // Constant but at 1.05: no reduction, the values fail.
  const auto stalls = outcome_of([](double) { return 1.05; });
  CHECK(stalls.verdict == Verdict::fail);
  CHECK_THAT(stalls.reason, Catch::Contains("5 of 5 values at or above 1 beyond their floors"));

  // The fixed-kernel theory of the errors does not describe a kernel scaled with the level.
  std::string errors = multilevel;
  errors.replace(errors.find("\"level_reduction_factor\"]"), 25, "\"l2_error\"]");
  errors.replace(errors.find("metric = \"level_reduction_factor\""), 33, "metric = \"l2_error\"");
  CHECK_THAT(error_of(errors),
             Catch::Contains("expect.theory: projection 'multilevel' scales its kernel with the "
                             "level (rho_j = nu h_j), so the theory of a fixed kernel for "
                             "l2_error does not describe it"));
}

TEST_CASE("verdicts: inconclusive when the CI is too wide or the window too short", "[verification]") {
  // Scatter of 30 % in the degree-2 power function: the CI is wider than +-0.1.
  Random random(7);
  std::map<std::size_t, double> noise;
  for (std::size_t n = 10; n <= 100; n += 10) noise[n] = std::exp(0.3 * random.normal());
  const Synthetic noisy("[[expect]]\nmetric = \"power_function_sup\"\ndegree = 2\ntheory = true\n",
                        [&](const TrialSpec& t, const std::string& m) {
                          return textbook(t, m) * (m == "power_function_sup" ? noise[t.n] : 1.0);
                        });
  const auto outcome = noisy.verify();
  REQUIRE(outcome.size() == 1);
  CHECK(outcome[0].verdict == Verdict::inconclusive);
  CHECK_THAT(outcome[0].reason, Catch::Contains("wider than the accepted interval (0.200)"));
  CHECK(check_exit_code(count_verdicts(outcome)) == 3);
  CHECK(check_exit_code(count_verdicts(outcome), {.strict = true}) == 1);
  CHECK(check_exit_code(count_verdicts(outcome), {.allow_inconclusive = true}) == 0);

  // Only two unflagged points: no verdict.
  const Synthetic short_series("[[expect]]\nmetric = \"power_function_sup\"\ndegree = 1\ntheory = true\n",
                               [](const TrialSpec& t, const std::string& m) {
                                 return t.n <= 20 ? textbook(t, m) : std::nan("");
                               });
  const auto two = short_series.verify();
  REQUIRE(two.size() == 1);
  CHECK(two[0].verdict == Verdict::inconclusive);
  CHECK(two[0].reason == "only 2 points in the window: a verdict needs at least 3");

  CHECK(check_exit_code({}) == 5);  // no expectations: nothing verified
  CHECK(format_verification({}) == "no expectations to check (nothing verified)\n");
}

TEST_CASE("verdicts: bounds report effectivities and fail when exceeded", "[verification]") {
  const Synthetic holds(R"([[expect]]
metric = "sup_error"
bound = { by = "power_function_sup", times = "interpolant_native_norm" }
[[expect]]
metric = "sup_error"
kernel = "gaussian"
bound = { by = "power_function_sup", constant = 0.001 }
[[expect]]
metric = "interpolant_native_norm"
degree = 1
bound = { constant = 3.0 }
)", textbook);
  const auto outcomes = holds.verify();
  REQUIRE(outcomes.size() == 5);
  CHECK(outcomes[4].verdict == Verdict::pass);  // 3 <= 3: a constant bound
  CHECK(outcomes[4].expected == "interpolant_native_norm <= 3 at every n");
  CHECK(outcomes[4].effectivity_max == Approx(1.0));
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(outcomes[i].verdict == Verdict::pass);
    CHECK(outcomes[i].effectivity_max == Approx(0.01 / 3.0));
    CHECK(outcomes[i].effectivity_min == Approx(0.01 / 3.0));
  }
  CHECK(outcomes[3].verdict == Verdict::fail);  // 0.01 pf > 0.001 pf
  CHECK(outcomes[3].effectivity_max == Approx(10.0));
  CHECK_THAT(outcomes[3].reason, Catch::StartsWith("the bound is exceeded by a factor 10 at n = "));
  CHECK_THAT(outcomes[0].found, Catch::StartsWith("effectivity sup_error / bound from 0.00333 to 0.00333"));
}

TEST_CASE("verdicts: bound = { ..., at_least } brackets the metric from both sides",
          "[verification]") {
  // sup_error / (power_function_sup * interpolant_native_norm) = 0.01 / 3 in the textbook series.
  const auto bracket = [](const std::string& at_least) {
    return Synthetic("[[expect]]\nmetric = \"sup_error\"\ndegree = 1\nbound = { by = "
                     "\"power_function_sup\", times = \"interpolant_native_norm\", constant = "
                     "0.004, at_least = " + at_least + " }\n",
                     textbook)
        .verify();
  };
  const auto holds = bracket("0.003");
  REQUIRE(holds.size() == 1);  // the B-spline of degree 1
  for (const auto& o : holds) {
    CHECK(o.verdict == Verdict::pass);
    CHECK(o.expected == "0.003 * power_function_sup * interpolant_native_norm <= sup_error <= "
                        "0.004 * power_function_sup * interpolant_native_norm at every n");
    CHECK(o.effectivity_min == Approx(0.01 / 3.0 / 0.004));
  }
  const auto below = bracket("0.0035");
  REQUIRE(below.size() == 1);
  for (const auto& o : below) {
    CHECK(o.verdict == Verdict::fail);
    CHECK_THAT(o.reason, Catch::StartsWith("below the lower bound at n = ") &&
                             Catch::Contains(": sup_error is 0.952 times it"));
  }
  // The lower constant must lie in [0, constant).
  CHECK_THROWS_WITH(bracket("0.004"),
                    Catch::Contains("expect.bound.at_least: must be >= 0 and below constant = "
                                    "0.004, found 0.004"));
  CHECK_THROWS_WITH(bracket("-1.0"), Catch::Contains("expect.bound.at_least: must be >= 0"));
  CHECK_THROWS_WITH(bracket("\"a\""), Catch::Contains("expect.bound.at_least:"));
}

TEST_CASE("verdicts: rate = { at_least = metric } derives the interval from that metric's fit",
          "[verification]") {
  // B-splines: power_function_sup ~ n^-(p - 1/2). sup_error decays like it (degree 1), faster
  // (degree 2: n^-3) or, with `slow`, at n^-0.2 against degree 1's n^-0.5.
  const std::string expectation = R"([[expect]]
metric = "sup_error"
kernel = "bspline"
rate = { at_least = "power_function_sup" }
)";
  const auto made_up = [](bool slow) {
    return [slow](const TrialSpec& t, const std::string& m) {
      const double n = static_cast<double>(t.n);
      if (m == "sup_error" && t.kernel.name == "bspline")
        return degree_of(t) == 1 ? (slow ? std::pow(n, -0.2) : 0.01 * std::pow(n, -0.5))
                                 : std::pow(n, -3.0);
      return textbook(t, m);
    };
  };
  const auto holds = Synthetic(expectation, made_up(false)).verify();
  REQUIRE(holds.size() == 2);
  for (const auto& o : holds) {
    INFO(o.expected << " / " << o.found << " / " << o.reason);
    CHECK(o.verdict == Verdict::pass);
  }
  // The accepted interval: at or below the reference's CI upper end plus the tolerance 0.1.
  CHECK(holds[0].accepted_high == Approx(-0.5 + 0.1).margin(1e-9));
  CHECK(std::isinf(holds[0].accepted_low));
  CHECK_THAT(holds[0].expected,
             Catch::StartsWith("at least as fast as power_function_sup against ln n "
                               "(power_function_sup decreases at -0.500"));
  CHECK(holds[1].accepted_high == Approx(-1.5 + 0.1).margin(1e-9));

  const auto slow = Synthetic(expectation, made_up(true)).verify();
  REQUIRE(slow.size() == 2);
  CHECK(slow[0].verdict == Verdict::fail);
  CHECK_THAT(slow[0].reason, Catch::Contains("CI lies entirely above -0.4"));
  CHECK(slow[1].verdict == Verdict::pass);

  // A reference without a usable fit (NaN everywhere): inconclusive, saying why.
  const auto no_reference =
      Synthetic(expectation, [](const TrialSpec& t, const std::string& m) {
        return m == "power_function_sup" ? std::nan("") : textbook(t, m);
      }).verify();
  REQUIRE(no_reference.size() == 2);
  CHECK(no_reference[0].verdict == Verdict::inconclusive);
  CHECK_THAT(no_reference[0].reason, Catch::Contains("power_function_sup has no rate"));
}

TEST_CASE("JUnit XML: one test case per outcome, failures and skips with messages", "[verification]") {
  Random random(7);
  const Synthetic mixed(R"([[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
[[expect]]
metric = "power_function_sup"
kernel = "gaussian"
rate = { min = 0 }
name = "a <wrong> & \"quoted\" one"
)", textbook);
  const auto outcomes = mixed.verify();
  REQUIRE(outcomes.size() == 3);
  const auto xml =
      junit_xml({{{&mixed.study, &outcomes, 1.5, "quick", "2024-01-01T00:00:00Z"}}, {}, {}});
  CHECK_THAT(xml, Catch::StartsWith("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\"rkhs-study check\" tests=\"3\" failures=\"1\" errors=\"0\" skipped=\"0\" time=\"1.500\">"));
  CHECK_THAT(xml,
             Catch::Contains(
                 "<testcase classname=\"v.power_function_sup\" name=\"power_function_sup "
                 "kernel=bspline [kernel=bspline degree=1 r=1]\" file=\"s.toml\" line=\"16\""));
  CHECK_THAT(xml, Catch::Contains(
                      "name=\"a &lt;wrong&gt; &amp; &quot;quoted&quot; one [kernel=gaussian]\""));
  CHECK_THAT(xml, Catch::Contains("<failure type=\"fail\" message=\"FAIL: the 95% CI"));
  CHECK_THAT(xml, Catch::Contains("<property name=\"tier\" value=\"quick\"/>"));
  CHECK(xml_escape("a\nb\x01<") == "a&#10;b&lt;");
  CHECK(xml_escape("a\nb", false) == "a\nb");
}

TEST_CASE("fit windows: [[expect]] and [rates] set the points judged", "[verification]") {
  // A metric that changes its rate at n = 50, continuously: 2500 n^-3 below, n^-1 from there.
  const auto kink = [](const TrialSpec& t, const std::string& m) {
    const double n = static_cast<double>(t.n);
    if (m == "sup_error") return n < 50 ? 2500.0 * std::pow(n, -3.0) : 1.0 / n;
    return textbook(t, m);
  };
  const std::string expectations = R"([[expect]]
metric = "sup_error"
degree = 1
rate = -1.0
n_from = 50
[[expect]]
metric = "sup_error"
degree = 1
rate = -1.0
last = 3
[[expect]]
metric = "sup_error"
degree = 1
rate = -3.0
n_to = 40
[[expect]]
metric = "sup_error"
degree = 1
bound = { constant = 0.021 }
n_from = 50
[[expect]]
metric = "sup_error"
degree = 1
bound = { constant = 0.021 }
)";
  const Synthetic s(expectations, kink);
  const auto outcomes = s.verify();
  REQUIRE(outcomes.size() == 5);
  for (std::size_t i : {0, 1, 2, 3}) {
    INFO(i << ": " << outcomes[i].found << " / " << outcomes[i].reason);
    CHECK(outcomes[i].verdict == Verdict::pass);
  }
  CHECK(outcomes[0].window_from == 50);
  CHECK(outcomes[0].window_to == 100);
  CHECK(outcomes[0].window_points == 6);
  CHECK_THAT(outcomes[0].found, Catch::Contains("window set by n_from = 50: n = 50..100"));
  CHECK(outcomes[1].window_from == 80);
  CHECK(outcomes[1].window_points == 3);
  CHECK(outcomes[2].window_to == 40);
  CHECK(outcomes[2].rate == Approx(-3.0));
  CHECK_THAT(outcomes[3].found, Catch::Contains("at 6 of 10 n (window set by n_from = 50)"));
  // Without its window the bound fails below n = 50 (2500 / 10^3 = 2.5 > 0.021).
  CHECK(outcomes[4].verdict == Verdict::fail);
  CHECK_THAT(outcomes[4].reason, Catch::Contains("at n = 10"));

  // [rates] sets the window of every series (rates.csv, tables and verdicts without their own).
  const Synthetic study_wide("[rates]\nn_from = 50\n[[expect]]\nmetric = \"sup_error\"\ndegree = 1\n"
                             "rate = -1.0\n",
                             kink);
  const auto& series = study_wide.rates;
  const auto found = std::find_if(series.begin(), series.end(), [&](const MetricSeries& m) {
    return m.metric == "sup_error" && m.group == 0;
  });
  REQUIRE(found != series.end());
  REQUIRE(found->fit);
  CHECK(found->fit->rate == Approx(-1.0));
  CHECK(found->fit->points == 6);
  CHECK_THAT(found->note, Catch::Contains("window set by n_from = 50: n = 50..100"));
  CHECK(study_wide.verify().at(0).verdict == Verdict::pass);
}

TEST_CASE("fit windows: mistakes are errors with file:line:column", "[verification]") {
  const auto with = [](const std::string& table) {
    return base + "[[expect]]\nmetric = \"power_function_sup\"\ntheory = true\n" + table;
  };
  CHECK_THAT(error_of(with("n_from = 200\n")),
             Catch::Contains("s.toml:19:10: expect.n_from: the window n = 200.. holds 0 of the "
                             "grid's n (10..100); a fit needs at least 2"));
  CHECK_THAT(error_of(with("n_from = 50\nn_to = 20\n")),
             Catch::Contains("expect.n_to: n_to = 20 is below n_from = 50: the window is empty"));
  CHECK_THAT(error_of(with("last = 1\n")),
             Catch::Contains("s.toml:19:8: expect.last: expected a whole number of points >= 2"));
  CHECK_THAT(error_of(with("last = 11\n")),
             Catch::Contains("expect.last: last = 11 but the grid has 10 values of n"));
  CHECK_THAT(error_of(with("h_from = 0.1\n")),
             Catch::Contains("expect.h_from: a window in h needs study.abscissa = \"h\""));
  CHECK_THAT(error_of(with("n_from = \"ten\"\n")),
             Catch::Contains("expect.n_from: expected a positive number, found 'ten'"));
  CHECK_THAT(error_of(base + "[rates]\nn_frm = 20\n"),
             Catch::Contains("s.toml:17:1: rates.n_frm: unknown key") &&
                 Catch::Contains("did you mean 'n_from'?"));
  CHECK_NOTHROW(parse_study(with("n_from = 50\nn_to = 100\nlast = 3\n"), "s.toml"));
}

TEST_CASE("theory against h: bounds in the fill distance hold for any centres", "[verification]") {
  // Scattered centres: h ~ n^-0.8 with scatter, q ~ n^-2 (the mesh ratio grows like n^1.2).
  // The power function and the L2 error follow h as theory says for any point set; the
  // condition number is a statement in q and needs quasi-uniform centres.
  std::string header = base;
  header.replace(header.find("name = \"v\"\n"), 11, "name = \"v\"\nabscissa = \"h\"\n");
  const auto fill = [](const TrialSpec& t) {
    const double n = static_cast<double>(t.n);
    return 3.0 * std::pow(n, -0.8) * (1.0 + 0.2 * std::sin(7.0 * n));
  };
  const auto distances = [&](const TrialSpec& t) {
    return std::pair{fill(t), 5.0 * std::pow(static_cast<double>(t.n), -2.0)};
  };
  const auto values = [&](const TrialSpec& t, const std::string& m) {
    const double h = fill(t), tau = degree_of(t);
    if (m == "power_function_sup") return 0.7 * std::pow(h, tau - 0.5);
    if (m == "l2_error") return 0.01 * std::pow(h, tau + 1.0);  // smoother than H^tau: faster
    if (m == "gram_condition_number") return std::pow(h, -2.0 * tau);
    return textbook(t, m);
  };
  header.replace(header.find("\"interpolant_native_norm\"]"), 26,
                 "\"interpolant_native_norm\", \"l2_error\"]");
  const Synthetic scattered(R"([[expect]]
metric = "power_function_sup"
kernel = "bspline"
theory = true
[[expect]]
metric = "l2_error"
kernel = "bspline"
theory = true
[[expect]]
metric = "gram_condition_number"
kernel = "bspline"
theory = true
)",
                            values, distances, header);
  const auto outcomes = scattered.verify();
  REQUIRE(outcomes.size() == 6);
  for (std::size_t i : {0, 1, 2, 3}) {
    INFO(i << ": " << outcomes[i].expected << " / " << outcomes[i].found << " / " << outcomes[i].reason);
    CHECK(outcomes[i].verdict == Verdict::pass);
    CHECK_THAT(outcomes[i].expected, Catch::Contains("against ln h, for any centres"));
  }
  for (std::size_t i : {4, 5}) {
    CHECK(outcomes[i].verdict == Verdict::inconclusive);
    CHECK_THAT(outcomes[i].reason, Catch::StartsWith("the centres are not quasi-uniform"));
    CHECK_THAT(outcomes[i].expected, Catch::Contains("stated in the separation distance q"));
  }
}

TEST_CASE("verdicts: constant series and constant expectations", "[verification][constant]") {
  // interpolant_native_norm is 3 everywhere in the textbook series: constant, not a rate.
  const Synthetic study(R"([[expect]]
metric = "interpolant_native_norm"
constant = { value = 3.0 }
[[expect]]
metric = "interpolant_native_norm"
constant = { value = 3.1, within = 0.05 }
[[expect]]
metric = "interpolant_native_norm"
constant = true
[[expect]]
metric = "power_function_sup"
constant = true
[[expect]]
metric = "interpolant_native_norm"
rate = 0.0
[[expect]]
metric = "interpolant_native_norm"
rate = -1.0
[[expect]]
metric = "interpolant_native_norm"
model = "exponential"
)",
                        textbook);
  for (const auto& series : study.rates) {
    if (series.metric != "interpolant_native_norm") continue;
    REQUIRE(series.constant());
    CHECK_FALSE(series.fit);
    CHECK(series.no_fit_reason == "constant 3 ± 0 on n = 10..100: not a rate");
  }
  const auto outcomes = study.verify();
  REQUIRE(outcomes.size() == 21);  // 7 expectations x 3 groups
  auto of = [&](std::size_t expectation) {
    std::vector<const ExpectationOutcome*> out;
    for (const auto& o : outcomes)
      if (o.expectation->number == expectation) out.push_back(&o);
    REQUIRE(out.size() == 3);
    return out;
  };
  for (const auto* o : of(1)) {
    CHECK(o->verdict == Verdict::pass);
    CHECK(o->expected == "interpolant_native_norm = 3 within each value's floor at every n");
    CHECK(o->reason == "every usable value lies within the band");
  }
  for (const auto* o : of(2)) {
    CHECK(o->verdict == Verdict::fail);
    CHECK(o->reason == "it deviates from 3.1 by 0.1 at n = 10, 0.05 beyond the band");
  }
  for (const auto* o : of(3)) CHECK(o->verdict == Verdict::pass);
  for (const auto* o : of(4)) {
    // The B-splines' power function decays; the Gaussian's too.
    CHECK(o->verdict == Verdict::fail);
    CHECK(o->reason == "it varies with n beyond its floors and the relative band");
  }
  for (const auto* o : of(5)) {
    CHECK(o->verdict == Verdict::pass);
    CHECK_THAT(o->reason, Catch::StartsWith("the series is constant: the rates its band allows"));
    CHECK_THAT(o->found, Catch::StartsWith("constant 3 ± 0 on n = 10..100 (10 of 10 points"));
    CHECK(o->rate == 0.0);
  }
  for (const auto* o : of(6)) {
    CHECK(o->verdict == Verdict::fail);
    CHECK_THAT(o->reason, Catch::Contains("lie entirely above -0.900"));
  }
  for (const auto* o : of(7)) {
    CHECK(o->verdict == Verdict::fail);
    CHECK_THAT(o->reason, Catch::StartsWith("the series is constant"));
  }
}

TEST_CASE("constant expectations: mistakes are errors with file:line:column",
          "[verification][constant]") {
  auto with = [](const std::string& expectation) {
    return error_of(base + "[[expect]]\nmetric = \"interpolant_native_norm\"\n" + expectation);
  };
  CHECK_THAT(with("constant = false\n"),
             Catch::Contains("expect.constant: constant = false expects nothing"));
  CHECK_THAT(with("constant = { within = 1 }\n"),
             Catch::Contains("expect.constant.value: missing"));
  CHECK_THAT(with("constant = { value = 1, within = -1 }\n"),
             Catch::Contains("expect.constant.within: must be >= 0"));
  CHECK_THAT(with("constant = { value = 1, band = 1 }\n"),
             Catch::Contains("expect.constant.band: unknown key (known: value, within)"));
  CHECK_THAT(with("constant = 1\n"),
             Catch::Contains("expect.constant: expected true or { value = 1, within = 1e-12 }"));
  CHECK_THAT(with("constant = true\nrate = 0\n"), Catch::Contains("give one of theory = true"));
  CHECK_THAT(with("constant = true\nmodel = \"exponential\"\n"),
             Catch::Contains("a constant has no rate model"));
  CHECK_THAT(
      error_of(base + "[rates]\nconstant_within = 1.5\n"),
      Catch::Contains("rates.constant_within: expected a relative band in [0, 1), found 1.5"));
  CHECK(parse_study(base + "[rates]\nconstant_within = 0\n", "s.toml").constant_within == 0.0);
}

TEST_CASE("verdicts: a bound's extremes and its verdict are decided beyond the floors",
          "[verification][floors]") {
  // sup_error / power_function_sup is 1 within 1e-12 at every n, each with a floor of 1e-10:
  // the largest effectivity is named at the first n, whichever n holds the last bits' maximum,
  // and 1 + 1e-12 is not known to exceed the bound 1.
  auto wobble = [](const TrialSpec& t, const std::string& metric) {
    if (metric == "power_function_sup") return 0.1;
    if (metric == "sup_error") return 0.1 * (1.0 + (t.n % 20 == 0 ? 1e-12 : -1e-12));
    return textbook(t, metric);
  };
  Synthetic study(
      "[[expect]]\nmetric = \"sup_error\"\ndegree = 1\nbound = { by = "
      "\"power_function_sup\" }\n",
      wobble);
  auto outcomes = study.verify();
  REQUIRE(outcomes.size() == 1);
  CHECK(outcomes[0].verdict == Verdict::fail);  // no floors: exceeded by 1e-12
  for (auto& r : study.results) r.floors.assign(r.metrics.size(), 1e-11);
  outcomes = study.verify();
  REQUIRE(outcomes.size() == 1);
  CHECK(outcomes[0].verdict == Verdict::pass);
  CHECK_THAT(outcomes[0].found, Catch::Contains("(largest at n = 10)"));
}

TEST_CASE("verdicts: a bound never passes over a value that is not finite", "[verification]") {
  auto overflowing = [](const TrialSpec& t, const std::string& metric) {
    if (metric == "sup_error" && t.n == 50) return std::numeric_limits<double>::infinity();
    return textbook(t, metric);
  };
  const auto outcomes = Synthetic(
                            "[[expect]]\nmetric = \"sup_error\"\ndegree = 1\nbound = { by = "
                            "\"power_function_sup\" }\n",
                            overflowing)
                            .verify();
  REQUIRE(outcomes.size() == 1);
  CHECK(outcomes[0].verdict == Verdict::inconclusive);
  CHECK_THAT(outcomes[0].reason, Catch::StartsWith("1 value of sup_error or its bound not finite"));
}
