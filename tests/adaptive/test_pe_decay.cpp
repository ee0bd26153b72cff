// The decay of ||f - fhat||_H against the PE level (Theorem 3.3; docs/model.md section 14): the
// metrics learning_decay_rate, averaged_decay_rate and pe_decay_ratio, checked on the scalar plant
// x' = -x + f with one level of hats, where the averaged law's slowest rate and the plant's lag
// have closed forms.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "study_support.hpp"

using namespace rkhs;

namespace {

/// Hats on N = 8 uniform knots of the paper's track (L = 8 pi, cell h = pi), G = I, so
/// pe_level = 1/(3N) = 1/24 (test_pe_level). The plant x' = -x + f with Q = 1: P = 1/2 and
/// H(0) = B^T P (-A)^-1 B = 1/2. Three laws: the rkhs law and rkhs_embedding (the same space, J =
/// 0), and the gradient law, whose averaged rate is another pencil's.
std::string decay_study(double speed, double gamma) {
  const std::string g = fmt::format("{:.17g}", gamma);
  return R"(
[study]
name = "pe_decay"
kind = "adaptive"
evaluation_points = 512
metrics = ["pe_level", "learning_spectral_radius", "learning_decay_rate", "averaged_decay_rate",
           "pe_decay_ratio"]
[domain]
radius = 4.0
[grid]
n = [8]
[[kernel]]
name = "bspline"
degree = 1
n0 = 8
J = 0
[[target]]
name = "sine"
amplitude = 2.0
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = )" + g + R"(
[[law]]
name = "rkhs_embedding"
gamma = )" + g + R"(
[[law]]
name = "gradient"
gamma = )" + g + R"(
[[integrator]]
name = "radau5"
rtol = 1e-8
atol = 1e-10
[adaptive]
speed = )" + fmt::format("{:.17g}", speed) +
         R"(
laps = "limit"
road = "projection"
lap_map_rtol = 1e-10
lap_map_atol = 1e-12
)";
}

/// The slowest direction of H_8 is the alternating combination of the hats, sum (-1)^i hat_i: a
/// triangle wave of period 2 pi in s, so of angular frequency omega = v along the path, whose
/// Fourier coefficients fall like k^-2 over the odd harmonics k. The plant answers harmonic k
/// with H(i k omega) = 1 / (1 + i k omega) instead of H(0) = 1, and the averaged law learns from
/// the part in phase: the slowest rate is H(0) pe_level / Gamma times
///   sum_k k^-4 Re H(i k omega) / sum_k k^-4 = sum_k k^-4 / (1 + k^2 omega^2) / sum_k k^-4.
double lag_factor(double omega) {
  double weighted = 0.0, total = 0.0;
  for (int k = 1; k < 100001; k += 2) {
    const double harmonic = k;  // k * k in int overflows from k = 46341
    const double w = std::pow(harmonic, -4.0);
    weighted += w / (1.0 + harmonic * harmonic * omega * omega);
    total += w;
  }
  return weighted / total;
}

}  // namespace

TEST_CASE("pe_decay_ratio: the lap map's slowest rate is H(0) pe_level / Gamma times the plant's "
          "lag, and 1 in the averaging limit",
          "[adaptive][pe_level][pe_decay]") {
  // Gamma v = 1000 keeps the learning per lap fixed and small: H(0) pe_level L / (v Gamma) =
  // 5.2e-4 of the slowest mode, 1.6e-3 of the fastest, so the averaged law is the limit; only
  // the plant's lag changes with v.
  for (const double speed : {1.0, 0.3, 0.1, 0.01}) {
    const double gamma = 1000.0 / speed;
    const auto out = test::run_study_text(decay_study(speed, gamma), "pe_decay.toml");
    REQUIRE(out.trials.size() == 3);
    const double expected_rate = 0.5 * (1.0 / 24.0) / gamma;
    const double lap_time = 8.0 * std::numbers::pi / speed;
    for (std::size_t i = 0; i < 2; ++i) {  // rkhs, rkhs_embedding
      INFO("v = " << speed << ", Gamma = " << gamma << ", law "
                  << out.trials[i].adaptive_axes().law.name << ": pe_decay_ratio "
                  << out.metric(i, "pe_decay_ratio") << ", lag factor " << lag_factor(speed));
      CHECK(std::abs(out.metric(i, "pe_level") - 1.0 / 24.0) < 1e-12);
      CHECK(std::abs(out.metric(i, "averaged_decay_rate") - expected_rate) <
            1e-12 * expected_rate);
      // The metric is the lap map's spectral radius per second.
      CHECK(std::abs(out.metric(i, "learning_decay_rate") * lap_time +
                     std::log(out.metric(i, "learning_spectral_radius"))) < 1e-14);
      CHECK(std::abs(out.metric(i, "pe_decay_ratio") - lag_factor(speed)) < 1e-3);
    }
    // The gradient law's slowest rate is not H(0) pe_level / Gamma: no averaged rate, no ratio.
    INFO("gradient law");
    CHECK(out.metric(2, "learning_decay_rate") > 0);
    CHECK(std::isnan(out.metric(2, "averaged_decay_rate")));
    CHECK(std::isnan(out.metric(2, "pe_decay_ratio")));
  }
  // The lag is what separates the ratio from 1: at v = 1 the plant's time constant is the path's
  // (ratio 0.49), at v = 0.01 it is 1e-4 below 1.
  CHECK(lag_factor(1.0) < 0.5);
  CHECK(1.0 - lag_factor(0.01) < 2e-4);
}

TEST_CASE("pe_decay_ratio leaves the averaging limit when the law learns within a lap",
          "[adaptive][pe_level][pe_decay]") {
  // v = 0.01 (a lag factor of 1 - 1.2e-4) and Gamma 100 and 1000 times smaller than above: the
  // slowest mode learns 5% and 52% of itself per lap by the averaged rate, and the lap map's
  // rate departs from the averaged one by 5e-4 and by more than 10%: averaging is a limit in
  // the learning per lap, not an approximation at any gain.
  const double speed = 0.01;
  std::vector<double> departures;
  for (const double gamma : {1e3, 1e2}) {
    const auto out = test::run_study_text(decay_study(speed, gamma), "pe_decay.toml");
    departures.push_back(std::abs(out.metric(0, "pe_decay_ratio") - lag_factor(speed)));
    UNSCOPED_INFO("Gamma = " << gamma << ": pe_decay_ratio " << out.metric(0, "pe_decay_ratio")
                             << ", learning_spectral_radius "
                             << out.metric(0, "learning_spectral_radius"));
  }
  CHECK(departures[0] < 1e-3);
  CHECK(departures[1] > 0.1);
}
