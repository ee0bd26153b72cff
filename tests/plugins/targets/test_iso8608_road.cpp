// The `iso8608` target: class levels, the periodogram of a realisation against Gd(n), seeds.
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <numbers>

#include "rkhs/targets/iso8608.hpp"
#include "rkhs/approx/target.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<TargetFunction> road(std::map<std::string, ParameterValue> given, Domain domain) {
  const auto* entry = target_registry().find("iso8608");
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

// One-sided periodogram at the harmonics n_k = k / L, k = 1..k_max, of f sampled at M uniform
// points of the track: G(n_k) = 2 |Z_k|^2 / dn with Z_k = (1/M) sum_m f(s_m) e^(-2 pi i k m / M).
std::vector<double> periodogram(const TargetFunction& f, const Domain& track, std::size_t k_max,
                                std::size_t samples) {
  const auto points = track.uniform_points(samples);
  std::vector<double> values(samples);
  f.evaluate(points, values);
  std::vector<double> out(k_max + 1, 0.0);
  for (std::size_t k = 1; k <= k_max; ++k) {
    std::complex<double> z = 0;
    for (std::size_t m = 0; m < samples; ++m)
      z += values[m] *
           std::polar(1.0, -2 * std::numbers::pi * double(k * m % samples) / double(samples));
    z /= double(samples);
    out[k] = 2 * std::norm(z) * track.length;
  }
  return out;
}

}  // namespace

TEST_CASE("ISO 8608 class levels and the PSD", "[iso8608]") {
  CHECK(iso8608_class_level('A') == 16e-6);
  CHECK(iso8608_class_level('B') == 64e-6);
  CHECK(iso8608_class_level('C') == 256e-6);
  CHECK(iso8608_class_level('D') == 1024e-6);
  CHECK(iso8608_class_level('H') == Approx(262144e-6).epsilon(1e-15));
  CHECK_THROWS_WITH(iso8608_class_level('I'), "ISO 8608 class 'I' does not exist (A to H)");
  CHECK(iso8608_psd(0.1, 256e-6, 2) == 256e-6);
  CHECK(iso8608_psd(1.0, 256e-6, 2) == Approx(2.56e-6).epsilon(1e-14));
}

TEST_CASE("ISO 8608 profile: the periodogram is the class's PSD", "[iso8608]") {
  const Domain track{25.0, true};
  // Deterministic amplitudes: every harmonic carries exactly Gd(n_k) dn of variance.
  for (const std::string road_class : {"A", "C", "D"}) {
    const auto f = road({{"class", road_class}, {"n_max", 4.0}, {"seed", std::int64_t{7}}}, track);
    const auto g = periodogram(*f, track, 100, 1024);
    const double level = iso8608_class_level(road_class[0]);
    for (std::size_t k = 1; k <= 100; ++k) {
      INFO("class " << road_class << ", k = " << k);
      CHECK(g[k] == Approx(iso8608_psd(double(k) / 25.0, level, 2.0)).epsilon(1e-9));
    }
  }
  // Random amplitudes: each periodogram ordinate is Gd(n_k) times chi-squared(2) / 2, so the
  // ratio to Gd averaged over 100 harmonics and 20 seeds is 1 with standard deviation 1/sqrt(2000).
  for (const std::string road_class : {"B", "E"}) {
    double sum = 0;
    std::size_t count = 0;
    for (std::int64_t seed = 1; seed <= 20; ++seed) {
      const auto f = road({{"class", road_class},
                           {"n_max", 4.0},
                           {"seed", seed},
                           {"amplitudes", std::string("random")}},
                          track);
      const auto g = periodogram(*f, track, 100, 1024);
      for (std::size_t k = 1; k <= 100; ++k) {
        const double n = double(k) / 25.0;
        sum += g[k] / iso8608_psd(n, iso8608_class_level(road_class[0]), 2.0);
        ++count;
      }
    }
    const double mean_ratio = sum / double(count);
    INFO("class " << road_class << ": mean periodogram / Gd = " << mean_ratio);
    CHECK(std::abs(mean_ratio - 1) < 4 / std::sqrt(double(count)));
  }
}

TEST_CASE("ISO 8608 profile: fitted level and waviness recover Gd(n0) and w", "[iso8608]") {
  // ISO 8608's classification fits ln Gd = ln Gd(n0) - w ln(n / n0) to the periodogram.
  // 2000 harmonics: the slope's standard error is about 0.03, the level's about 6%.
  const Domain track{1000.0, true};
  const std::size_t harmonics = 2000;
  for (double waviness : {2.0, 2.5}) {
    const auto f = road({{"gd_n0", 300e-6},
                         {"waviness", waviness},
                         {"n_max", 2.0},
                         {"amplitudes", std::string("random")},
                         {"seed", std::int64_t{3}}},
                        track);
    const auto g = periodogram(*f, track, harmonics, 4096);
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t k = 1; k <= harmonics; ++k) {
      const double x = std::log(double(k) / 1000.0 / iso8608_reference_frequency);
      // E[ln(chi2(2)/2)] = -euler_gamma: remove the bias of the log-periodogram.
      const double y = std::log(g[k]) + std::numbers::egamma;
      sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const double count = double(harmonics);
    const double slope = (count * sxy - sx * sy) / (count * sxx - sx * sx);
    const double intercept = (sy - slope * sx) / count;
    INFO("waviness " << waviness);
    CHECK(slope == Approx(-waviness).margin(0.15));
    CHECK(std::exp(intercept) == Approx(300e-6).epsilon(0.25));
  }
}

TEST_CASE("ISO 8608 profile: seeds reproduce, the profile is periodic and band-limited",
          "[iso8608]") {
  const Domain track{10.0, true};
  const auto a = road({{"class", std::string("C")}, {"seed", std::int64_t{42}}}, track);
  const auto b = road({{"class", std::string("C")}, {"seed", std::int64_t{42}}}, track);
  const auto c = road({{"class", std::string("C")}, {"seed", std::int64_t{43}}}, track);
  const auto points = track.uniform_points(997);
  std::vector<double> va(points.size()), vb(points.size()), vc(points.size());
  a->evaluate(points, va);
  b->evaluate(points, vb);
  c->evaluate(points, vc);
  CHECK(va == vb);
  CHECK(va != vc);
  CHECK((*a)(0.0) == Approx((*a)(10.0)).margin(1e-12));
  CHECK((*a)(3.7) == Approx((*a)(13.7)).margin(1e-12));
  // The band [n_min, n_max]: harmonics outside it carry nothing.
  const auto band = road({{"class", std::string("C")}, {"n_min", 0.5}, {"n_max", 2.0}}, track);
  const auto g = periodogram(*band, track, 40, 256);
  for (std::size_t k = 1; k <= 40; ++k) {
    INFO("k = " << k);
    if (k < 5 || k > 20)
      CHECK(g[k] < 1e-20);
    else
      CHECK(g[k] == Approx(iso8608_psd(double(k) / 10.0, 256e-6, 2.0)).epsilon(1e-9));
  }
  // The variance is the PSD integrated over the band (sum of Gd(n_k) dn).
  double variance = 0, expected = 0;
  const auto dense = track.uniform_points(4096);
  std::vector<double> values(dense.size());
  a->evaluate(dense, values);
  for (double v : values) variance += v * v / 4096.0;
  for (std::size_t k = 1; k <= 100; ++k)
    expected += iso8608_psd(double(k) / 10.0, 256e-6, 2.0) / 10.0;
  CHECK(variance == Approx(expected).epsilon(1e-9));
  CHECK_THROWS_WITH(road({{"n_min", 0.31}, {"n_max", 0.39}}, track),
                    "no harmonic k / L (L = 10 m) lies in [n_min, n_max] = [0.31, 0.39] cycles/m");
}
