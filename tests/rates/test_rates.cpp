// Tests of the convergence-rate fitter (rkhs/rates/rates.hpp): exact series, statistical calibration
// of the standard error and confidence interval on noisy series, exclusions and edge cases.

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "rkhs/rates/rates.hpp"

namespace {

constexpr double quiet_nan = std::numeric_limits<double>::quiet_NaN();
constexpr double infinity = std::numeric_limits<double>::infinity();

std::vector<double> power_series(const std::vector<double>& x, double c, double p) {
  std::vector<double> y;
  for (double e : x) y.push_back(c * std::pow(e, p));
  return y;
}

// Standard normal deviates from mt19937_64 (whose output the standard fixes) via Box-Muller
// on our own uniforms, so the noisy tests give the same numbers with every standard library.
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : engine_(seed) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(engine_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = static_cast<double>(engine_() >> 11) * 0x1.0p-53;          // [0, 1)
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 6.283185307179586 * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace

TEST_CASE("pairwise rates of an exact power law are its exponent", "[rates]") {
  const std::vector<double> x{8, 16, 32, 64, 100, 1000};
  const auto rates = rkhs::pairwise_rates(x, power_series(x, 3.0, -1.5));
  REQUIRE(rates.size() == x.size() - 1);
  for (double r : rates) CHECK(r == Approx(-1.5).margin(1e-12));
}

TEST_CASE("pairwise rates follow changing local slopes", "[rates]") {
  // Slope -1 from x = 1 to 4, then -2 up to 16, then -0.5 from 16 to 64 (non-uniform step).
  const std::vector<double> x{1, 2, 4, 8, 16, 64};
  const std::vector<double> y{1.0, 0.5, 0.25, 0.0625, 0.015625, 0.0078125};
  const auto rates = rkhs::pairwise_rates(x, y);
  REQUIRE(rates.size() == 5);
  CHECK(rates[0] == Approx(-1.0).margin(1e-14));
  CHECK(rates[1] == Approx(-1.0).margin(1e-14));
  CHECK(rates[2] == Approx(-2.0).margin(1e-14));
  CHECK(rates[3] == Approx(-2.0).margin(1e-14));
  CHECK(rates[4] == Approx(-0.5).margin(1e-14));
}

TEST_CASE("pairwise rates are NaN where undefined, empty for fewer than two points", "[rates]") {
  const std::vector<double> x{1, 2, 3, 3, 4, 5, 6};
  const std::vector<double> y{1, 0, 1, 2, quiet_nan, 0.5, 0.25};
  const auto rates = rkhs::pairwise_rates(x, y);
  REQUIRE(rates.size() == 6);
  CHECK(std::isnan(rates[0]));  // y = 0
  CHECK(std::isnan(rates[1]));  // y = 0
  CHECK(std::isnan(rates[2]));  // equal abscissae (a finite slope would be +-inf)
  CHECK(std::isnan(rates[3]));  // y = NaN
  CHECK(std::isnan(rates[4]));  // y = NaN
  CHECK(rates[5] == Approx(std::log(0.5) / std::log(6.0 / 5.0)));

  CHECK(rkhs::pairwise_rates(std::vector<double>{1.0}, std::vector<double>{1.0}).empty());
  CHECK(rkhs::pairwise_rates({}, {}).empty());
  CHECK_THROWS_AS(rkhs::pairwise_rates(std::vector<double>{1, 2}, std::vector<double>{1}),
                  std::invalid_argument);
}

TEST_CASE("an exact power law is fitted exactly", "[rates]") {
  const std::vector<double> x{16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192};
  const auto fit = rkhs::fit_power_law(x, power_series(x, 7.0, -1.5));
  REQUIRE(fit);
  CHECK(fit->model == rkhs::RateModel::power_law);
  CHECK(fit->rate == Approx(-1.5).margin(1e-12));
  CHECK(fit->intercept == Approx(std::log(7.0)).margin(1e-11));
  CHECK(fit->r_squared == Approx(1.0).margin(1e-14));
  CHECK(fit->std_error < 1e-13);
  CHECK(fit->residual_std < 1e-13);
  CHECK(fit->ci_low <= fit->rate);
  CHECK(fit->ci_high >= fit->rate);
  CHECK(fit->ci_high - fit->ci_low < 1e-12);
  CHECK(fit->points == 10);
  CHECK(fit->used.size() == 10);
  CHECK(fit->note.empty());
  CHECK(fit->confidence == 0.95);
}

TEST_CASE("a fill-distance abscissa gives a positive rate", "[rates]") {
  // error ~ h^2 with h = 1/n: rate +2 against h.
  const std::vector<double> h{0.1, 0.05, 0.025, 0.0125};
  const auto fit = rkhs::fit_power_law(h, power_series(h, 0.3, 2.0));
  REQUIRE(fit);
  CHECK(fit->rate == Approx(2.0).margin(1e-12));
}

TEST_CASE("the confidence interval uses the Student t quantile with points - 2 dof", "[rates]") {
  // Deterministic wiggle around slope -1; 10 points, so t_{0.975, 8} = 2.306004135.
  std::vector<double> x, y;
  for (int k = 0; k < 10; ++k) {
    x.push_back(10.0 * std::pow(1.5, k));
    y.push_back(std::pow(x.back(), -1.0) * std::exp(0.1 * ((k % 3) - 1)));
  }
  const auto fit = rkhs::fit_power_law(x, y);
  REQUIRE(fit);
  REQUIRE(fit->std_error > 0.0);
  CHECK((fit->ci_high - fit->rate) / fit->std_error == Approx(2.306004135).epsilon(1e-8));
  CHECK((fit->rate - fit->ci_low) / fit->std_error == Approx(2.306004135).epsilon(1e-8));
  const auto fit99 = rkhs::fit_power_law(x, y, 0.99);  // t_{0.995, 8} = 3.355387331
  REQUIRE(fit99);
  CHECK(fit99->confidence == 0.99);
  CHECK((fit99->ci_high - fit99->rate) / fit99->std_error == Approx(3.355387331).epsilon(1e-8));
  // Reference values from an independent two-pass computation of the same formulas.
  CHECK(fit->rate == Approx(-0.9955158118865886).epsilon(1e-12));
  CHECK(fit->intercept == Approx(-0.028507042885939526).epsilon(1e-10));
  CHECK(fit->residual_std == Approx(0.09268715709799888).epsilon(1e-10));
  CHECK(fit->std_error == Approx(0.025167443367346207).epsilon(1e-10));
  CHECK(fit->r_squared == Approx(0.9949130555845481).epsilon(1e-12));
}

TEST_CASE("noisy power laws: the CI covers the true slope at its level, std_error is honest",
          "[rates]") {
  // y = C x^p exp(sigma z): i.i.d. normal errors in ln y, the model the fit assumes.
  constexpr double c = 2.0, p = -1.5, sigma = 0.2;
  constexpr int replicates = 2000;
  std::vector<double> x;
  for (int k = 0; k < 10; ++k) x.push_back(10.0 * std::pow(1.5, k));

  Normal normal(20240611);
  int covered95 = 0, covered99 = 0;
  double sum = 0.0, sum_sq = 0.0, sum_se_sq = 0.0;
  std::vector<double> y(x.size());
  for (int rep = 0; rep < replicates; ++rep) {
    for (std::size_t k = 0; k < x.size(); ++k)
      y[k] = c * std::pow(x[k], p) * std::exp(sigma * normal());
    const auto fit = rkhs::fit_power_law(x, y);
    const auto fit99 = rkhs::fit_power_law(x, y, 0.99);
    REQUIRE(fit);
    REQUIRE(fit99);
    covered95 += fit->ci_low <= p && p <= fit->ci_high;
    covered99 += fit99->ci_low <= p && p <= fit99->ci_high;
    sum += fit->rate;
    sum_sq += fit->rate * fit->rate;
    sum_se_sq += fit->std_error * fit->std_error;
  }
  const double n = replicates;
  const double mean = sum / n;
  const double empirical_sd = std::sqrt((sum_sq - n * mean * mean) / (n - 1.0));
  const double reported_se = std::sqrt(sum_se_sq / n);  // E[se^2] = Var(slope) exactly

  // Binomial(2000, 0.95) has sd 0.0049: [0.93, 0.97] is about +-4 sd.
  CHECK(covered95 / n >= 0.93);
  CHECK(covered95 / n <= 0.97);
  // Binomial(2000, 0.99) has sd 0.0022.
  CHECK(covered99 / n >= 0.98);
  CHECK(covered99 / n <= 0.999);
  CHECK(reported_se == Approx(empirical_sd).epsilon(0.10));
  // Theory: sd = sigma / sqrt(sum (ln x - mean)^2).
  double mean_log = 0.0;
  for (double e : x) mean_log += std::log(e) / static_cast<double>(x.size());
  double suu = 0.0;
  for (double e : x) suu += (std::log(e) - mean_log) * (std::log(e) - mean_log);
  CHECK(empirical_sd == Approx(sigma / std::sqrt(suu)).epsilon(0.10));
  CHECK(std::fabs(mean - p) < 4.0 * empirical_sd / std::sqrt(n));  // unbiased
}

TEST_CASE("NaN, infinite, zero and negative values are excluded with a note", "[rates]") {
  std::vector<double> x{1, 2, 3, 4, 5, 6, 7, 8};
  auto y = power_series(x, 1.0, -2.0);
  y[2] = quiet_nan;
  y[4] = 0.0;
  y[5] = -1.0;
  y[7] = infinity;
  const auto fit = rkhs::fit_power_law(x, y);
  REQUIRE(fit);
  CHECK(fit->rate == Approx(-2.0).margin(1e-12));
  CHECK(fit->used == std::vector<std::size_t>{0, 1, 3, 6});
  CHECK(fit->points == 4);
  CHECK(fit->note ==
        "excluded 4 of 8 points: 2 with non-finite value, 2 with zero or negative value");
}

TEST_CASE("non-positive abscissae are excluded by the power law, kept by the exponential",
          "[rates]") {
  const std::vector<double> x{0, 1, 2, 3, 4};
  std::vector<double> y;
  for (double e : x) y.push_back(5.0 * std::exp(-0.3 * e));
  const auto power = rkhs::fit_power_law(x, y);
  REQUIRE(power);
  CHECK(power->used == std::vector<std::size_t>{1, 2, 3, 4});
  CHECK(power->note == "excluded 1 of 5 points: 1 with non-finite, zero or negative abscissa");
  const auto exponential = rkhs::fit_exponential(x, y);
  REQUIRE(exponential);
  CHECK(exponential->points == 5);
  CHECK(exponential->note.empty());
}

TEST_CASE("two points give an exact slope without statistics: fewer give no fit", "[rates]") {
  const std::vector<double> x{10, 40};
  const std::vector<double> y{1.0, 1.0 / 64.0};
  const auto fit = rkhs::fit_power_law(x, y);
  REQUIRE(fit);
  CHECK(fit->rate == Approx(-3.0).margin(1e-13));
  CHECK(fit->points == 2);
  CHECK(std::isnan(fit->std_error));
  CHECK(std::isnan(fit->ci_low));
  CHECK(std::isnan(fit->ci_high));
  CHECK(std::isnan(fit->residual_std));
  CHECK(fit->note == "only 2 points: slope exact, no standard error or confidence interval");

  // Two usable of three: both notes, joined.
  const auto two_of_three = rkhs::fit_power_law(std::vector<double>{10, 20, 40},
                                                std::vector<double>{1.0, quiet_nan, 1.0 / 64});
  REQUIRE(two_of_three);
  CHECK(two_of_three->rate == Approx(-3.0).margin(1e-13));
  CHECK(two_of_three->note ==
        "excluded 1 of 3 points: 1 with non-finite value; only 2 points: slope exact, no standard "
        "error or confidence interval");

  CHECK_FALSE(rkhs::fit_power_law(std::vector<double>{10}, std::vector<double>{1.0}));
  CHECK_FALSE(rkhs::fit_power_law(std::vector<double>{10, 20}, std::vector<double>{1.0, 0.0}));
  CHECK_FALSE(rkhs::fit_power_law({}, {}));
  CHECK_FALSE(rkhs::fit_exponential(std::vector<double>{3, 3, 3}, std::vector<double>{1, 2, 3}));
}

TEST_CASE("constant values fit a zero rate with R² undefined", "[rates]") {
  const auto fit = rkhs::fit_power_law(std::vector<double>{1, 2, 4}, std::vector<double>{3, 3, 3});
  REQUIRE(fit);
  CHECK(fit->rate == 0.0);
  CHECK(std::isnan(fit->r_squared));
  CHECK(fit->note == "all used values are equal: R² undefined");
}

TEST_CASE("invalid arguments throw", "[rates]") {
  const std::vector<double> three{1, 2, 3};
  const std::vector<double> two{1, 2};
  CHECK_THROWS_AS(rkhs::fit_power_law(three, two), std::invalid_argument);
  CHECK_THROWS_AS(rkhs::fit_exponential(three, two), std::invalid_argument);
  CHECK_THROWS_AS(rkhs::fit_power_law(three, three, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(rkhs::fit_power_law(three, three, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(rkhs::fit_power_law(three, three, quiet_nan), std::invalid_argument);
}

TEST_CASE("the exponential model recovers exp(-0.3 n)", "[rates]") {
  std::vector<double> n, y;
  for (int k = 4; k <= 40; k += 4) {
    n.push_back(k);
    y.push_back(2.5 * std::exp(-0.3 * k));
  }
  const auto fit = rkhs::fit_exponential(n, y);
  REQUIRE(fit);
  CHECK(fit->model == rkhs::RateModel::exponential);
  CHECK(fit->rate == Approx(-0.3).margin(1e-12));
  CHECK(fit->intercept == Approx(std::log(2.5)).margin(1e-11));
  CHECK(fit->r_squared == Approx(1.0).margin(1e-14));
  CHECK(fit->std_error < 1e-13);

  // The power law does not describe it: its fit is visibly worse.
  const auto power = rkhs::fit_power_law(n, y);
  REQUIRE(power);
  CHECK(power->r_squared < 0.99);
}

TEST_CASE("centring keeps the exponential fit accurate far from the origin", "[rates]") {
  // ln y = -0.3 (x - 1e6): uncentred normal equations would lose about 12 digits here.
  std::vector<double> x, y;
  for (int k = 0; k <= 20; ++k) {
    x.push_back(1e6 + k);
    y.push_back(std::exp(-0.3 * k));
  }
  const auto fit = rkhs::fit_exponential(x, y);
  REQUIRE(fit);
  CHECK(fit->rate == Approx(-0.3).margin(1e-12));
  CHECK(fit->r_squared == Approx(1.0).margin(1e-12));
}
