// Tests of the asymptotic analysis of a series (rkhs/rates/asymptotic.hpp): the window without head
// and floor, the choice between the power law and the exponential model, and the coverage of
// the windowed fit's confidence interval on noisy series.

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/core/random.hpp"

namespace {

constexpr double quiet_nan = std::numeric_limits<double>::quiet_NaN();

struct Series {
  std::vector<double> n, y;
  std::vector<bool> usable;
  rkhs::SeriesAnalysis analyse() const { return rkhs::analyse_series(n, n, y, usable); }
};

Series make_series(const std::vector<double>& n, double (*f)(double)) {
  Series s;
  s.n = n;
  for (double e : n) s.y.push_back(f(e));
  s.usable.assign(n.size(), true);
  return s;
}

std::vector<double> powers_of_two(int from, int to) {
  std::vector<double> n;
  for (int k = from; k <= to; ++k) n.push_back(std::ldexp(1.0, k));
  return n;
}

std::vector<double> arithmetic(double from, double to, double step) {
  std::vector<double> n;
  for (double e = from; e <= to + 1e-9; e += step) n.push_back(e);
  return n;
}

std::vector<std::size_t> range(std::size_t from, std::size_t to) {  // [from, to)
  std::vector<std::size_t> out;
  for (auto i = from; i < to; ++i) out.push_back(i);
  return out;
}

}  // namespace

TEST_CASE("an exact power law: whole window, power law preferred decisively", "[asymptotic]") {
  const auto s = make_series(arithmetic(10, 100, 10), [](double n) { return 3.0 * std::pow(n, -1.5); });
  const auto a = s.analyse();
  CHECK(a.power_law.window.points == range(0, 10));
  CHECK(a.power_law.window.head.empty());
  CHECK(a.power_law.window.floor.empty());
  CHECK(a.power_law.window.note.empty());
  REQUIRE(a.preferred);
  CHECK(*a.preferred == rkhs::RateModel::power_law);
  CHECK(a.decisive());
  CHECK(a.reported == rkhs::RateModel::power_law);
  REQUIRE(a.power_law.fit);
  CHECK(a.power_law.fit->rate == Approx(-1.5).margin(1e-12));
  CHECK(a.power_law.window.bulk_rate == Approx(-1.5).margin(1e-12));
  CHECK_THAT(a.note, Catch::StartsWith("power law preferred (ΔAIC = "));
  // The exponential model sees a power law as ever slower decay and trims a "head".
  CHECK(a.exponential.advantage < 0.0);
}

TEST_CASE("a power law with a pre-asymptotic head and a floor: both excluded", "[asymptotic]") {
  // y = n^-2 (1 + (16 / n)^2) + 1e-7: the head decays faster than n^-2, the floor stalls.
  const auto s = make_series(powers_of_two(2, 13), [](double n) {
    return std::pow(n, -2.0) * (1.0 + (16.0 / n) * (16.0 / n)) + 1e-7;
  });
  const auto a = s.analyse();
  const auto& w = a.power_law.window;
  CHECK(w.head == range(0, 3));    // n = 4, 8, 16
  CHECK(w.floor == range(9, 12));  // n = 2048, 4096, 8192
  CHECK(w.points == range(3, 9));
  CHECK_THAT(w.note, Catch::Contains("head n = 4..16 excluded (pairwise rates -3.77, -3.32, -2.68 "
                                     "differ from the bulk rate"));
  CHECK_THAT(w.note, Catch::Contains("floor from n = 2048 excluded (pairwise rates -1.64, -1.08, "
                                     "-0.474 stalled against the bulk rate"));
  REQUIRE(a.power_law.fit);
  const auto& fit = *a.power_law.fit;
  CHECK(fit.used == w.points);
  CHECK(std::fabs(fit.rate + 2.0) < 0.05);
  CHECK(fit.ci_low <= -2.0);
  CHECK(fit.ci_high >= -2.0);
  CHECK(a.reported == rkhs::RateModel::power_law);
  REQUIRE(a.preferred);
  CHECK(*a.preferred == rkhs::RateModel::power_law);

  // Without the window the same series gives a biased rate whose CI misses -2.
  std::vector<double> all_x = s.n, all_y = s.y;
  const auto plain = rkhs::fit_power_law(all_x, all_y);
  REQUIRE(plain);
  CHECK_FALSE((plain->ci_low <= -2.0 && -2.0 <= plain->ci_high && std::fabs(plain->rate + 2) < 0.05));
}

TEST_CASE("an exponential series selects the exponential model", "[asymptotic]") {
  const auto s = make_series(arithmetic(4, 40, 4), [](double n) { return 2.5 * std::exp(-0.3 * n); });
  const auto a = s.analyse();
  REQUIRE(a.preferred);
  CHECK(*a.preferred == rkhs::RateModel::exponential);
  CHECK(a.decisive());
  CHECK(a.reported == rkhs::RateModel::exponential);
  CHECK(&a.reported_analysis() == &a.exponential);
  REQUIRE(a.exponential.fit);
  CHECK(a.exponential.fit->model == rkhs::RateModel::exponential);
  CHECK(a.exponential.fit->rate == Approx(-0.3).margin(1e-12));
  CHECK(a.exponential.window.points == range(0, 10));
  CHECK(a.exponential.pairwise.size() == 9);
  for (double r : a.exponential.pairwise) CHECK(r == Approx(-0.3).margin(1e-12));
  CHECK_THAT(a.note, Catch::StartsWith("exponential model preferred (ΔAIC = "));
}

TEST_CASE("three points can prefer a model but never decide", "[asymptotic]") {
  const auto s = make_series(arithmetic(10, 30, 10), [](double n) { return std::exp(-1.2 * n); });
  const auto a = s.analyse();
  REQUIRE(a.preferred);
  CHECK(*a.preferred == rkhs::RateModel::exponential);
  CHECK(a.evidence > 2.0);
  CHECK(a.evidence_points == 3);
  CHECK_FALSE(a.decisive());
  CHECK(a.reported == rkhs::RateModel::power_law);
  CHECK_THAT(a.note, Catch::EndsWith(", not decisive (a decision needs 4 points)"));
}

TEST_CASE("an exponential series with an unflagged floor: floor detected, model kept", "[asymptotic]") {
  const auto s = make_series(arithmetic(4, 40, 4),
                             [](double n) { return 2.5 * std::exp(-0.3 * n) + 1e-4; });
  const auto a = s.analyse();
  CHECK(a.reported == rkhs::RateModel::exponential);
  const auto& w = a.exponential.window;
  CHECK(w.head.empty());
  REQUIRE_FALSE(w.floor.empty());
  CHECK(s.n[w.floor.front()] >= 28);
  REQUIRE(a.exponential.fit);
  CHECK(a.exponential.fit->rate == Approx(-0.3).margin(0.01));
  CHECK_THAT(w.note, Catch::StartsWith("floor from n = "));
}

TEST_CASE("the Gaussian's power function without flags: its floor found from the pairwise rates",
          "[asymptotic]") {
  // gram_and_power's values: exp(-c n^2) decay, then round-off from n = 70 (which study_rates
  // excludes by its flag first; here the pairwise rates alone must find the floor).
  Series s;
  s.n = arithmetic(10, 100, 10);
  s.y = {7.771e-01, 1.947e-01, 2.340e-02, 1.337e-03, 3.595e-05,
         4.522e-07, 6.829e-08, 6.495e-08, 6.664e-08, 6.580e-08};
  s.usable.assign(10, true);
  const auto a = s.analyse();
  CHECK(a.exponential.window.floor == range(7, 10));  // n = 80, 90, 100
  CHECK(a.power_law.window.floor == range(7, 10));
  CHECK_THAT(a.exponential.window.note,
             Catch::StartsWith("floor from n = 80 excluded (pairwise rates -0.00501, 0.00257, "
                               "-0.00127 stalled against the bulk rate -0.189: below 10 % of it)"));
  REQUIRE(a.preferred);
  CHECK(*a.preferred == rkhs::RateModel::exponential);
  CHECK(a.reported == rkhs::RateModel::exponential);
}

TEST_CASE("a NaN trial and unusable points are left out: the rest is fitted", "[asymptotic]") {
  auto s = make_series(arithmetic(10, 100, 10), [](double n) { return std::pow(n, -1.5); });
  s.y[3] = quiet_nan;      // a failed trial
  s.usable[7] = false;     // a flagged value
  s.y[7] = 1e300;          // whose value would wreck the fit
  const auto a = s.analyse();
  CHECK(a.power_law.window.points == std::vector<std::size_t>{0, 1, 2, 4, 5, 6, 8, 9});
  REQUIRE(a.power_law.fit);
  CHECK(a.power_law.fit->rate == Approx(-1.5).margin(1e-12));
  CHECK(a.power_law.fit->points == 8);
  CHECK(a.power_law.window.note.empty());
  CHECK(std::isnan(a.power_law.pairwise[2]));  // pairwise rates keep the gap visible
  CHECK(std::isnan(a.power_law.pairwise[3]));
}

TEST_CASE("a window never has fewer than 3 points: short series are not trimmed", "[asymptotic]") {
  // Every pairwise rate differs from the next: the rule would trim all but it keeps 3.
  const std::vector<double> n{10, 20, 40, 80, 160};
  const std::vector<double> y{1.0, 0.9, 0.5, 0.1, 0.001};
  const auto a = rkhs::analyse_series(n, n, y, std::vector<bool>(5, true));
  CHECK(a.power_law.window.points.size() >= 3);
  CHECK(a.exponential.window.points.size() >= 3);

  const std::vector<double> n3{10, 20, 40}, y3{1.0, 0.1, 0.09};
  const auto b = rkhs::analyse_series(n3, n3, y3, std::vector<bool>(3, true));
  CHECK(b.power_law.window.points == range(0, 3));
  CHECK(b.power_law.window.note.empty());

  // Two points: a fit without statistics, models not compared.
  const std::vector<double> n2{10, 20}, y2{1.0, 0.25};
  const auto c = rkhs::analyse_series(n2, n2, y2, std::vector<bool>(2, true));
  REQUIRE(c.power_law.fit);
  CHECK(c.power_law.fit->rate == Approx(-2.0));
  CHECK_FALSE(c.preferred);
  CHECK(c.note == "models not compared (fewer than 3 points in a window)");
  CHECK(c.reported == rkhs::RateModel::power_law);
}

TEST_CASE("a constant series prefers no model and reports the power law", "[asymptotic]") {
  const auto s = make_series(arithmetic(10, 60, 10), [](double) { return 4.5; });
  const auto a = s.analyse();
  CHECK_FALSE(a.preferred);
  CHECK(a.reported == rkhs::RateModel::power_law);
  REQUIRE(a.power_law.fit);
  CHECK(a.power_law.fit->rate == 0.0);
  CHECK(a.power_law.window.floor.empty());  // no bulk rate to stall against
}

TEST_CASE("an abscissa that is not monotone disables window detection", "[asymptotic]") {
  const std::vector<double> u{1, 2, 1.5, 3, 4}, v{0, -1, -0.7, -2, -3}, labels{1, 2, 3, 4, 5};
  const auto w = rkhs::detect_asymptotic_window(u, v, labels);
  CHECK(w.points == range(0, 5));
  CHECK(w.note == "abscissa not strictly monotone in n: no asymptotic window detected");
  CHECK_THROWS_AS(rkhs::detect_asymptotic_window(u, v, std::vector<double>{1}), std::invalid_argument);
}

TEST_CASE("noisy power laws: the windowed fit keeps the CI's coverage and rarely trims",
          "[asymptotic]") {
  // y = 2 n^-1.5 exp(0.2 z): i.i.d. normal noise in ln y. Trimming decided by chance would
  // bias the slope and shrink the CI below its level.
  rkhs::Random random(20240917);
  const auto n = arithmetic(10, 100, 10);
  constexpr int replicates = 2000;
  int covered = 0, trimmed = 0, power_preferred = 0;
  std::vector<double> y(n.size());
  for (int rep = 0; rep < replicates; ++rep) {
    for (std::size_t k = 0; k < n.size(); ++k)
      y[k] = 2.0 * std::pow(n[k], -1.5) * std::exp(0.2 * random.normal());
    const auto a = rkhs::analyse_series(n, n, y, std::vector<bool>(n.size(), true));
    REQUIRE(a.power_law.fit);
    covered += a.power_law.fit->ci_low <= -1.5 && -1.5 <= a.power_law.fit->ci_high;
    trimmed += a.power_law.window.points.size() < n.size();
    power_preferred += a.preferred == rkhs::RateModel::power_law;
  }
  const double r = replicates;
  CHECK(covered / r >= 0.93);  // 0.95 nominal; Binomial sd 0.005
  CHECK(covered / r <= 0.97);
  CHECK(trimmed / r < 0.04);
  CHECK(power_preferred / r > 0.8);
}

TEST_CASE("pairwise exponential rates and label ranges", "[asymptotic]") {
  const std::vector<double> n{10, 20, 30, 30}, y{1.0, std::exp(-2.0), 0.0, 1.0};
  const auto rates = rkhs::pairwise_exponential_rates(n, y);
  REQUIRE(rates.size() == 3);
  CHECK(rates[0] == Approx(-0.2));
  CHECK(std::isnan(rates[1]));
  CHECK(std::isnan(rates[2]));
  CHECK(rkhs::label_range(n, {}) == "");
  CHECK(rkhs::label_range(n, {1}) == "20");
  CHECK(rkhs::label_range(n, {0, 1, 2}) == "10..30");
}

TEST_CASE("constant series: within the floors, within a relative band, or not at all",
          "[asymptotic][constant]") {
  const std::vector<double> n{10, 20, 30, 40, 50, 60};
  const std::vector<bool> all(n.size(), true);
  // Exactly constant: band 0, within the floors (none given: 4 ulps).
  const std::vector<double> one(n.size(), 1.0);
  auto exact = rkhs::analyse_series(n, n, one, all);
  REQUIRE(exact.constant);
  CHECK(exact.constant->value == 1.0);
  CHECK(exact.constant->band == 0.0);
  CHECK(exact.constant->within_floors);
  CHECK(exact.constant->points.size() == n.size());
  CHECK(exact.constant->text(n) == "1 ± 0 on n = 10..60");

  // Round-off about 1 within floors of 1e-11: constant with the relative band 0 too.
  const std::vector<double> noisy{1.0, 1.0 + 3e-12, 1.0 - 2e-12, 1.0 + 8e-12, 1.0, 1.0 - 5e-12};
  const std::vector<double> floors(n.size(), 1e-11);
  auto round_off = rkhs::analyse_series(n, n, noisy, all, 0.95, {}, floors, 0.0);
  REQUIRE(round_off.constant);
  CHECK(round_off.constant->within_floors);
  CHECK(round_off.constant->value == Approx(1.0 + 1.5e-12).epsilon(1e-15));
  CHECK(round_off.constant->band == Approx(6.5e-12).epsilon(1e-3));
  CHECK_THAT(round_off.constant->text(n),
             Catch::Contains("(within the values' floors) on n = 10..60"));
  // Without floors and without a band the same values vary.
  CHECK_FALSE(rkhs::analyse_series(n, n, noisy, all, 0.95, {}, {}, 0.0).constant);

  // A limit approached within 0.75 % (an interpolant's native norm): constant at the default 1 %,
  // not at 0.1 %.
  const std::vector<double> settling{3.741, 3.762, 3.765, 3.767, 3.768, 3.769};
  auto settled = rkhs::analyse_series(n, n, settling, all);
  REQUIRE(settled.constant);
  CHECK_FALSE(settled.constant->within_floors);
  CHECK(settled.constant->value == Approx(3.755));
  CHECK(settled.constant->band == Approx(0.014));
  CHECK(settled.constant->relative_band() == Approx(0.014 / 3.755));
  CHECK(settled.constant->text(n) == "3.755 ± 0.014 (0.37 %) on n = 10..60");
  // At 0.1 % only after its head; at 0.001 % not at all.
  const auto tighter = rkhs::analyse_series(n, n, settling, all, 0.95, {}, {}, 0.001);
  CHECK((!tighter.constant || !tighter.constant->head.empty()));
  CHECK_FALSE(rkhs::analyse_series(n, n, settling, all, 0.95, {}, {}, 1e-5).constant);

  // A power law is never constant; nor are fewer than 3 usable points.
  std::vector<double> decaying;
  for (double e : n) decaying.push_back(std::pow(e, -0.5));
  CHECK_FALSE(rkhs::analyse_series(n, n, decaying, all).constant);
  std::vector<bool> two(n.size(), false);
  two[0] = two[1] = true;
  CHECK_FALSE(rkhs::analyse_series(n, n, one, two).constant);

  // Zeros and negative values count (no logarithm is taken).
  const std::vector<double> zeros(n.size(), 0.0);
  auto zero = rkhs::analyse_series(n, n, zeros, all);
  REQUIRE(zero.constant);
  CHECK(zero.constant->value == 0.0);
  CHECK(zero.constant->relative_band() == 0.0);
}

TEST_CASE("constant series: a pre-asymptotic head is left out", "[asymptotic][constant]") {
  // A B-spline interpolant's native norm: a head at n = 10 1.2 % below, then within 0.3 %.
  const std::vector<double> n{10, 20, 30, 40, 50, 60, 70, 80, 90, 100};
  const std::vector<double> y{2.8813, 2.9345, 2.9401, 2.9488, 2.9471,
                              2.9510, 2.9503, 2.9529, 2.9523, 2.9528};
  const auto a = rkhs::analyse_series(n, n, y, std::vector<bool>(n.size(), true));
  REQUIRE(a.constant);
  REQUIRE(a.constant->head == std::vector<std::size_t>{0});
  CHECK(a.constant->points.front() == 1);
  CHECK(a.constant->band < 0.01 * a.constant->value);
  // With a set window there is no automatic head: the whole window must be constant.
  rkhs::FitWindow window;
  window.n_from = 10;
  CHECK_FALSE(
      rkhs::analyse_series(n, n, y, std::vector<bool>(n.size(), true), 0.95, window).constant);
  window.n_from = 20;
  const auto windowed =
      rkhs::analyse_series(n, n, y, std::vector<bool>(n.size(), true), 0.95, window);
  REQUIRE(windowed.constant);
  CHECK(windowed.constant->head.empty());
}
