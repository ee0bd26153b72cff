// The power law with a pre-asymptotic term (rkhs/rates/corrected_fit.hpp) and the windows of
// analyse_series (rkhs/rates/asymptotic.hpp): bends recognised and fitted, scatter and exact
// power laws left alone, windows set by hand taken as they are.

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "rkhs/core/random.hpp"
#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/rates/corrected_fit.hpp"

namespace {

std::vector<double> powers_of_two(int from, int to) {
  std::vector<double> n;
  for (int k = from; k <= to; ++k) n.push_back(std::ldexp(1.0, k));
  return n;
}

// y = C n^p (1 + a n^-q) at each n.
std::vector<double> bent(const std::vector<double>& n, double c, double p, double a, double q) {
  std::vector<double> y;
  for (double e : n) y.push_back(c * std::pow(e, p) * (1.0 + a * std::pow(e, -q)));
  return y;
}

double half_width(const rkhs::RateFit& fit) { return 0.5 * (fit.ci_high - fit.ci_low); }

}  // namespace

TEST_CASE("a series of the model's own form is fitted exactly", "[corrected_fit]") {
  const auto n = powers_of_two(3, 8);  // 8..256
  const auto y = bent(n, 2.0, -1.5, 3.0, 0.8);
  const auto fit = rkhs::fit_power_law_corrected(n, y, true);
  REQUIRE(fit);
  CHECK(fit->fit.rate == Approx(-1.5).margin(1e-8));
  CHECK(fit->order == Approx(0.8).margin(1e-6));
  // D is the correction's size at the finest point: 3 * 256^-0.8.
  CHECK(fit->correction == Approx(3.0 * std::pow(256.0, -0.8)).epsilon(1e-6));
  CHECK(fit->fit.intercept == Approx(std::log(2.0)).margin(1e-7));
  CHECK(fit->fit.points == 6);
  CHECK(fit->fit.ci_low <= -1.5);
  CHECK(fit->fit.ci_high >= -1.5);
  CHECK(half_width(fit->fit) < 1e-6);
  CHECK(fit->advantage > 100.0);  // the straight line misses the bend by far
}

TEST_CASE("against the fill distance the correction fades as h shrinks", "[corrected_fit]") {
  const auto n = powers_of_two(3, 9);
  std::vector<double> h, y;
  for (double e : n) {
    h.push_back(1.0 / e);
    y.push_back(0.5 * std::pow(1.0 / e, 2.5) * (1.0 - 0.7 * std::pow(1.0 / e, 1.2)));
  }
  const auto fit = rkhs::fit_power_law_corrected(h, y, false);
  REQUIRE(fit);
  CHECK(fit->fit.rate == Approx(2.5).margin(1e-8));
  CHECK(fit->order == Approx(1.2).margin(1e-6));
  // Fitted with t = n instead, the same points describe no such term.
  const auto wrong_direction = rkhs::fit_power_law_corrected(h, y, true);
  CHECK((!wrong_direction || std::fabs(wrong_direction->fit.rate - 2.5) > 1e-3));
}

TEST_CASE("the corrected fit needs six finite positive points", "[corrected_fit]") {
  const auto n = powers_of_two(3, 7);  // 5 points
  CHECK_FALSE(rkhs::fit_power_law_corrected(n, bent(n, 1.0, -2.0, 1.0, 1.0), true));
  auto n6 = powers_of_two(3, 8);
  auto y6 = bent(n6, 1.0, -2.0, 1.0, 1.0);
  CHECK(rkhs::fit_power_law_corrected(n6, y6, true));
  y6[2] = -1.0;
  CHECK_FALSE(rkhs::fit_power_law_corrected(n6, y6, true));
  CHECK_THROWS_AS(rkhs::fit_power_law_corrected(n6, std::vector<double>(5, 1.0), true),
                  std::invalid_argument);
}

TEST_CASE("a second correction term moves p by about the CI's width, not more", "[corrected_fit]") {
  // The model is the first term of an expansion; the next one is a misfit the CI sees.
  const auto n = powers_of_two(3, 8);
  std::vector<double> y;
  for (double e : n) y.push_back(std::pow(e, -1.5) * (1.0 + 3.0 * std::pow(e, -0.8) + 5.0 * std::pow(e, -1.6)));
  const auto fit = rkhs::fit_power_law_corrected(n, y, true);
  REQUIRE(fit);
  const double error = std::fabs(fit->fit.rate + 1.5);
  CHECK(error < 2.0 * half_width(fit->fit));
  CHECK(error < 0.05);
}

TEST_CASE("analyse_series fits a monotone bend and judges its rate", "[corrected_fit][asymptotic]") {
  // Pairwise rates 4.42, 4.21, 4.11, 4.07, 4.04 approaching 4: the straight line misses it.
  const auto n = powers_of_two(3, 8);
  const auto y = bent(n, 1.0, 4.0, -2.0, 0.7);
  const auto a = rkhs::analyse_series(n, n, y, std::vector<bool>(n.size(), true));
  REQUIRE(a.corrected);
  CHECK(a.bends());
  CHECK(a.corrected_points.size() == 6);
  const auto* judged = a.power_law_rate_fit();
  REQUIRE(judged == &a.corrected->fit);
  CHECK(judged->rate == Approx(4.0).margin(1e-6));
  REQUIRE(a.power_law.fit);
  CHECK(std::fabs(a.power_law.fit->rate - 4.0) > 0.05);  // the line is pulled off
  CHECK(a.set_window.empty());

  // A bend towards a wrong rate is fitted as such: a theory of 4 would fail on it.
  const auto wrong = rkhs::analyse_series(n, n, bent(n, 1.0, 3.5, -2.0, 0.7),
                                          std::vector<bool>(n.size(), true));
  REQUIRE(wrong.bends());
  CHECK(wrong.power_law_rate_fit()->rate == Approx(3.5).margin(1e-6));
  CHECK(wrong.power_law_rate_fit()->ci_high < 3.9);
}

TEST_CASE("scatter and exact power laws are not bends", "[corrected_fit][asymptotic]") {
  const auto n = powers_of_two(3, 10);
  std::vector<double> exact, noisy;
  rkhs::Random random(7);
  for (double e : n) {
    exact.push_back(3.0 * std::pow(e, -2.0));
    noisy.push_back(3.0 * std::pow(e, -2.0) * std::exp(0.05 * random.normal()));
  }
  const std::vector<bool> all(n.size(), true);
  const auto a = rkhs::analyse_series(n, n, exact, all);
  CHECK_FALSE(a.bends());
  REQUIRE(a.power_law_rate_fit() == &*a.power_law.fit);
  const auto b = rkhs::analyse_series(n, n, noisy, all);
  CHECK_FALSE(b.corrected);
  CHECK_FALSE(b.bends());
}

TEST_CASE("a window set by hand is taken as it is", "[asymptotic]") {
  const auto n = powers_of_two(3, 8);  // 8..256
  const auto y = bent(n, 1.0, 4.0, -0.9, 0.9);
  std::vector<bool> usable(n.size(), true);
  usable[5] = false;  // n = 256 flagged

  rkhs::FitWindow from32;
  from32.n_from = 32;
  const auto a = rkhs::analyse_series(n, n, y, usable, 0.95, from32);
  CHECK(a.power_law.window.points == std::vector<std::size_t>{2, 3, 4});
  CHECK(a.power_law.window.head.empty());
  CHECK(a.power_law.window.floor.empty());
  CHECK_FALSE(a.corrected);
  CHECK(a.set_window == "n_from = 32");
  REQUIRE(a.power_law.fit);
  CHECK(a.power_law.fit->used == std::vector<std::size_t>{2, 3, 4});

  rkhs::FitWindow last3;
  last3.last = 3;
  const auto b = rkhs::analyse_series(n, n, y, usable, 0.95, last3);
  CHECK(b.power_law.window.points == std::vector<std::size_t>{2, 3, 4});  // usable ones only
  CHECK(b.set_window == "last = 3");

  rkhs::FitWindow range;
  range.n_from = 16;
  range.n_to = 64;
  range.last = 2;
  const auto c = rkhs::analyse_series(n, n, y, usable, 0.95, range);
  CHECK(c.power_law.window.points == std::vector<std::size_t>{2, 3});
  CHECK(range.text() == "n_from = 16, n_to = 64, last = 2");

  rkhs::FitWindow in_h;  // h_from / h_to select on the power law's abscissa
  in_h.h_to = 1.0 / 32;
  std::vector<double> h;
  for (double e : n) h.push_back(1.0 / e);
  const auto d = rkhs::analyse_series(h, n, y, std::vector<bool>(n.size(), true), 0.95, in_h);
  CHECK(d.power_law.window.points == std::vector<std::size_t>{2, 3, 4, 5});
}
