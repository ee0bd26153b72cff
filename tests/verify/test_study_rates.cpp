// Rates of a finished study (rkhs/verify/study_rates.hpp) on made-up results: flagged floors, the
// asymptotic window, the reported model, and what the notes say.

#include <catch2/catch.hpp>
#include <cmath>

#include "rkhs/study/study.hpp"
#include "rkhs/verify/study_rates.hpp"

using namespace rkhs;

namespace {

const char* const study_text = R"([study]
name = "r"
metrics = ["power_function_sup", "gram_max_eigenvalue"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 100, step = 10 }
[[kernel]]
name = "gaussian"
)";

}  // namespace

TEST_CASE("compute_rates: a flagged floor, an exponential series, a pre-asymptotic head", "[rates]") {
  const auto study = parse_study(study_text, "r.toml");
  const auto trials = study.trials();
  std::vector<TrialResult> results;
  for (const auto& trial : trials) {
    TrialResult r;
    r.ok = true;
    r.metrics.assign(study.all_metrics().size(), std::nan(""));
    const double n = static_cast<double>(trial.n);
    // Exponential decay down to a flagged round-off floor from n = 70.
    r.metrics[study.metric_index("power_function_sup")] = n < 70 ? std::exp(-0.3 * n) : 6.6e-8;
    if (n >= 70) r.flags.push_back("power_function_at_floor");
    // Linear growth after a first point off the line: a pre-asymptotic head.
    r.metrics[study.metric_index("gram_max_eigenvalue")] = n == 10 ? 5.0 : 0.1 * n;
    results.push_back(std::move(r));
  }
  const auto rates = compute_rates(study, trials, results);
  REQUIRE(rates.size() == 2);

  const auto& power = rates[1];  // metrics in canonical order
  CHECK(power.metric == "power_function_sup");
  CHECK(power.analysis.reported == RateModel::exponential);
  REQUIRE(power.fit);
  CHECK(power.fit->model == RateModel::exponential);
  CHECK(power.fit->rate == Approx(-0.3).margin(1e-12));
  CHECK(power.fit->used == std::vector<std::size_t>{0, 1, 2, 3, 4, 5});
  CHECK(power.n == std::vector<double>{10, 20, 30, 40, 50, 60, 70, 80, 90, 100});
  CHECK(power.pairwise.front() == Approx(-0.3));  // the exponential model's pairwise rates
  CHECK(power.note == "floor from n = 70: 4 values flagged (power_function_at_floor)");
  CHECK(power.no_fit_reason.empty());

  const auto& eigen = rates[0];
  CHECK(eigen.analysis.reported == RateModel::power_law);
  REQUIRE(eigen.fit);
  CHECK(eigen.fit->rate == Approx(1.0).margin(1e-12));
  CHECK(eigen.analysis.power_law.window.head == std::vector<std::size_t>{0});
  CHECK_THAT(eigen.note, Catch::StartsWith("head n = 10 excluded (pairwise rate -1.32 differs "
                                           "from the bulk rate 1.00 by more than 0.1)"));
}

TEST_CASE("compute_rates: no fit when everything is flagged, with the reason", "[rates]") {
  const auto study = parse_study(study_text, "r.toml");
  const auto trials = study.trials();
  std::vector<TrialResult> results;
  for (std::size_t i = 0; i < trials.size(); ++i) {
    TrialResult r;
    r.ok = i != 3;  // one failed trial
    r.metrics.assign(study.all_metrics().size(), 1e-8);
    r.flags.push_back("power_function_at_floor");
    results.push_back(std::move(r));
  }
  const auto rates = compute_rates(study, trials, results);
  const auto& power = rates[1];
  CHECK_FALSE(power.fit);
  CHECK(power.no_fit_reason == "0 of 10 points usable after excluding 10 failed or flagged; a fit "
                               "needs at least 2");
  CHECK(power.note == "1 failed trial excluded; floor from n = 10: 9 values flagged "
                      "(power_function_at_floor); no fit: 0 usable points");
}

TEST_CASE("compute_rates: a flagged value inside the series is excluded, not a floor", "[rates]") {
  const auto study = parse_study(study_text, "r.toml");
  const auto trials = study.trials();
  std::vector<TrialResult> results;
  for (const auto& trial : trials) {
    TrialResult r;
    r.ok = true;
    r.metrics.assign(study.all_metrics().size(), std::pow(static_cast<double>(trial.n), -2.0));
    if (trial.n == 50) r.flags.push_back("power_function_at_floor");
    results.push_back(std::move(r));
  }
  const auto rates = compute_rates(study, trials, results);
  const auto& power = rates[1];
  CHECK(power.note == "1 value excluded (power_function_at_floor)");
  REQUIRE(power.fit);
  CHECK(power.fit->points == 9);
  CHECK(power.fit->rate == Approx(-2.0).margin(1e-12));
}

TEST_CASE("the flag that excludes a metric from fits comes from the metric table", "[rates]") {
  CHECK(excluding_flag(StudyKind::approximation, "gram_condition_number") == "gram_singular");
  CHECK(excluding_flag(StudyKind::approximation, "gram_min_eigenvalue") == "gram_singular");
  CHECK(excluding_flag(StudyKind::approximation, "power_function_sup") == "power_function_at_floor");
  CHECK(excluding_flag(StudyKind::approximation, "sup_error") == "sup_error_at_floor");
  CHECK(excluding_flag(StudyKind::approximation, "l2_error") == "l2_error_at_floor");
  CHECK(excluding_flag(StudyKind::approximation, "fill_distance").empty());
  CHECK(excluding_flag(StudyKind::adaptive, "gram_condition_number") == "gram_singular");
  CHECK(excluding_flag(StudyKind::adaptive, "power_function_sup") == "power_function_at_floor");
  // Marked, still fitted (rkhs/approx/metrics.hpp says why).
  CHECK(excluding_flag(StudyKind::adaptive, "interpolant_sup_error").empty());
  CHECK(excluding_flag(StudyKind::adaptive, "interpolant_l2_error").empty());
  CHECK(excluding_flag(StudyKind::adaptive, "no_such_metric").empty());
}
