// Theorem 1 of the paper (Lipschitz dependence on the initial data; docs/theorems.md) as
// metrics of an adaptive trial: embedding_constant, lipschitz_constant, initial_data_lipschitz
// and lipschitz_exponent, against closed forms on a scalar plant.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "rkhs/adaptive/metrics.hpp"
#include "study_support.hpp"

using namespace rkhs;

namespace {

// Box features of one level (degree 0, J = 0, n0 = 4 cells; r weighs levels j > 0 only): at every s
// exactly one feature is nonzero, so |w(s)|^2 = k(s, s) is the same everywhere. The rkhs_embedding
// law works in those features (W = I).
std::string boxes_study(double a, double b, double gamma, const std::string& adaptive) {
  return R"([study]
name = "theorem1"
kind = "adaptive"
evaluation_points = 1024
metrics = ["embedding_constant", "lipschitz_constant", "initial_data_lipschitz",
           "lipschitz_exponent"]
[domain]
radius = 4.0
[grid]
n = [4]
[[kernel]]
name = "bspline"
degree = 0
r = 1
n0 = 4
J = 0
[[plant]]
name = "linear"
A = ")" + std::to_string(-a) + R"("
B = ")" + std::to_string(b) + R"("
[[law]]
name = "rkhs_embedding"
gamma = )" + std::to_string(gamma) +
                                  R"(
[[integrator]]
name = "radau5"
rtol = 1e-10
atol = 1e-12
[adaptive]
)" + adaptive;
}

test::StudyOutcome run_boxes(double a, double b, double gamma, const std::string& adaptive) {
  return test::run_study_text(boxes_study(a, b, gamma, adaptive), "theorem1.toml");
}

// ||[[-a, b c], [-c b P / gamma, 0]]||_2 with P = 1 / (2 a) (A^T P + P A = -1): the larger
// root of s^2 - S s + det^2, S the sum of the squared entries.
double generator_norm(double a, double b, double c, double gamma) {
  const double p = 1.0 / (2.0 * a), upper = b * c, lower = c * b * p / gamma;
  const double sum = a * a + upper * upper + lower * lower, det = upper * lower;
  return std::sqrt((sum + std::sqrt(sum * sum - 4.0 * det * det)) / 2.0);
}

}  // namespace

TEST_CASE("Theorem 1's constants on one level of boxes", "[adaptive][theorem1]") {
  const double a = 1.0, b = 8.0, gamma = 0.5;
  const auto trial =
      run_boxes(a, b, gamma, "speed = 1.0\nfinal_time = 2.0\nengine = \"time_stepping\"\n");
  // One box of height 1 at every s: k(s, s) = 1.
  const double c = trial.metric(0, "embedding_constant");
  CHECK(c == Approx(1.0).epsilon(1e-14));
  CHECK(trial.metric(0, "lipschitz_constant") ==
        Approx(generator_norm(a, b, c, gamma)).epsilon(1e-12));
}

TEST_CASE("Theorem 1's dependence on the initial data: a closed form", "[adaptive][theorem1]") {
  // With gamma = 1e12 the coefficients do not move (to 1e-12): the perturbation dc of the four
  // coefficients (each |dc| / 2, |dc| = the size s of the perturbation) enters e' as the constant
  // -b phi(s)^T dc = -b s / 2, and de(0) = s. So de(t) = s g(t), g = e^-at - beta (1 - e^-at),
  // beta = b / (2 a), and the distance over the initial one is r(t) = sqrt(g^2 + 1) / sqrt(2).
  const double a = 1.0, b = 8.0, beta = b / (2.0 * a), horizon = 20.0;
  const auto trial = run_boxes(a, b, 1e12,
                               "speed = 1.0\nfinal_time = 20.0\nsamples_per_lap = 40\n"
                               "engine = \"time_stepping\"\n");
  const auto r = [&](double t) {
    const double g = std::exp(-a * t) - beta * (1.0 - std::exp(-a * t));
    return std::sqrt(g * g + 1.0) / std::sqrt(2.0);
  };
  // r falls from 1, then grows to its largest at T (g -> -beta).
  CHECK(trial.metric(0, "initial_data_lipschitz") == Approx(r(horizon)).epsilon(1e-7));
  // The exponent is ln r(t) / t at a sample: at most its largest over [0, T], at least its
  // value at T (a sample).
  double largest = 0;
  for (int k = 1; k <= 200000; ++k) {
    const double t = horizon * k / 200000.0;
    largest = std::max(largest, std::log(r(t)) / t);
  }
  const double exponent = trial.metric(0, "lipschitz_exponent");
  CHECK(exponent <= largest * (1.0 + 1e-7));
  CHECK(exponent >= std::log(r(horizon)) / horizon * (1.0 - 1e-7));
  // Gronwall: at most the Lipschitz constant.
  CHECK(exponent <= trial.metric(0, "lipschitz_constant"));
}

TEST_CASE("Theorem 1's measured dependence needs time stepping", "[adaptive][theorem1]") {
  // The lap map samples no trajectory to compare: the measured metrics are NaN, the constants
  // are computed.
  const auto trial = run_boxes(1.0, 8.0, 0.5, "speed = 1.0\nlaps = 3\nengine = \"lap_map\"\n");
  CHECK(std::isnan(trial.metric(0, "initial_data_lipschitz")));
  CHECK(std::isnan(trial.metric(0, "lipschitz_exponent")));
  CHECK(trial.metric(0, "lipschitz_constant") > 0);
}

TEST_CASE("Theorem 1's metrics turn the initial data dependence on, the others do not",
          "[adaptive][theorem1]") {
  // The setting follows the metric table: the rows that need adaptive_work_initial_data.
  auto study =
      parse_study(boxes_study(1.0, 8.0, 0.5, "speed = 1.0\nfinal_time = 2.0\n"), "theorem1.toml");
  const auto trial = study.trials().front();
  std::vector<std::string> needing, others;
  for (const auto& row : MetricTable<AdaptiveMetric>::rows) {
    INFO(row.name);
    const bool needs = (row.needs & adaptive_work_initial_data) != 0;
    (needs ? needing : others).emplace_back(row.name);
    study.metrics = {std::string(row.name)};
    CHECK(trial_adaptive_settings(study, trial).initial_data_dependence == needs);
    study.metrics = {"l2_error", std::string(row.name)};
    CHECK(trial_adaptive_settings(study, trial).initial_data_dependence == needs);
  }
  CHECK(needing == std::vector<std::string>{"embedding_constant", "lipschitz_constant",
                                            "initial_data_lipschitz", "lipschitz_exponent"});
  study.metrics = others;
  CHECK_FALSE(trial_adaptive_settings(study, trial).initial_data_dependence);
  study.metrics = metric_table_names<AdaptiveMetric>();
  CHECK(trial_adaptive_settings(study, trial).initial_data_dependence);
}
