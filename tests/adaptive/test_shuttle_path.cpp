// A path that does not go around the track ([adaptive] path, AdaptiveSettings::shuttle_from):
// s(t) back and forth over part of it. The path's kinks in time, s(t) and s'(t); and a trial on
// one level of hats (G = I, closed forms), where the hats the path never reaches are never
// learnt: persistence of excitation fails, and the trial says so.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/breakpoints.hpp"
#include "rkhs/study/study.hpp"
#include "study_support.hpp"

using namespace rkhs;

TEST_CASE("a shuttle path: its kink times, s(t) and s'(t)", "[adaptive][path]") {
  const Domain track{8.0, true};
  AdaptiveSettings settings;
  settings.speed = 2.0;
  // Laps around the track: the kinks at s / v.
  CHECK(path_kink_times(settings, track, {0.0, 3.0}) == std::vector<double>{0.0, 1.5});
  CHECK(settings.lap_time(track.length) == 4.0);
  // Back and forth over [1, 5]: a lap is 8 m (4 s), the turning point at 2 s; a kink at 3 is
  // crossed at 1 s and 3 s, the ones at 0 and 6 (off the path) never.
  settings.shuttle_from = 1.0;
  settings.shuttle_length = 4.0;
  CHECK(settings.lap_time(track.length) == 4.0);
  CHECK(path_kink_times(settings, track, {0.0, 3.0, 6.0}) == std::vector<double>{1.0, 2.0, 3.0});
  settings.laps = 3;
  CHECK(settings.final_time_or_laps(track.length) == 12.0);

  const Eigen::MatrixXd A = Eigen::MatrixXd::Constant(1, 1, -1.0);
  const Eigen::VectorXd B = Eigen::VectorXd::Constant(1, 1.0);
  const auto kernel = test::make_registered_kernel(
      "bspline", {{"n0", std::int64_t{8}}, {"J", std::int64_t{0}}}, track);
  const std::vector<double> centres{0, 1, 2, 3, 4, 5, 6, 7};
  const auto basis = kernel->basis(centres);
  const std::function<double(double)> zero = [](double) { return 0.0; };
  AdaptiveSystem system(A, B, A, *basis, Eigen::MatrixXd(Eigen::MatrixXd::Identity(8, 8)), zero,
                        zero, track, 2.0);
  CHECK(system.arc_length(1.0) == 2.0);
  system.set_shuttle(1.0, 4.0);
  for (const auto& [t, s, v] : std::vector<std::tuple<double, double, double>>{{0.0, 1.0, 2.0},
                                                                               {1.0, 3.0, 2.0},
                                                                               {2.0, 5.0, -2.0},
                                                                               {3.0, 3.0, -2.0},
                                                                               {4.0, 1.0, 2.0},
                                                                               {4.5, 2.0, 2.0},
                                                                               {7.5, 2.0, -2.0}}) {
    INFO("t = " << t);
    CHECK(system.arc_length(t) == Approx(s));
    CHECK(system.path_velocity(t) == v);
  }
}

namespace {

// One level of hats on 8 cells of the 25 m track (G = I at the knots), a scalar plant, the rkhs
// law; `path` is the [adaptive] path line ("" for laps around the track).
std::string hats_study(const std::string& path) {
  return R"(
[study]
name = "shuttle"
kind = "adaptive"
evaluation_points = 1024
[domain]
radius = 4.0
[grid]
n = [8]
[[kernel]]
name = "bspline"
degree = 1
n0 = 8
J = 0
)" + test::scalar_plant_sections("1e-10", "1e-12") +
         R"([[law]]
name = "rkhs"
gamma = 0.1
[adaptive]
speed = 1.0
laps = 3
)" + path +
         "\n";
}

}  // namespace

TEST_CASE("a path over half the track leaves the hats it never reaches unexcited and unlearnt",
          "[adaptive][path]") {
  const double L = 8 * std::numbers::pi, h = L / 8;
  // Back and forth over [0, L/2] = [0, 4h]: the hats at 5h, 6h and 7h (supports (4h, 6h),
  // (5h, 7h), (6h, 8h)) never see the path.
  const auto half =
      test::run_study_text(hats_study("path = { from = 0.0, to = " + std::to_string(L / 2) + " }"));
  const auto& flags = half.results[0].flags;
  CHECK(half.metric(0, "unexcited_dimension") == 3);
  CHECK(std::count(flags.begin(), flags.end(), "not_persistently_excited") == 1);
  CHECK(half.metric(0, "pe_level") == 0);
  // fhat = 0 on [5h, 7h], where f = 2 sin(2 pi s / L): the error there is all of f's.
  const double w = 2 * std::numbers::pi / L;
  const auto integral = [&](double a, double b) {  // int_a^b (2 sin(w s))^2 ds
    return 2 * (b - a) - (std::sin(2 * w * b) - std::sin(2 * w * a)) / w;
  };
  const double unlearnt = std::sqrt(integral(5 * h, 7 * h));
  CHECK(half.metric(0, "off_path_l2_error") >= 0.99 * unlearnt);
  CHECK(half.metric(0, "off_path_l2_error") <= std::sqrt(integral(4 * h, 8 * h)) * 1.01);
  // The error over the whole track splits into the two parts.
  CHECK(std::hypot(half.metric(0, "path_l2_error"), half.metric(0, "off_path_l2_error")) ==
        Approx(half.metric(0, "l2_error")).epsilon(1e-3));

  // Around the track every hat is excited: no flag, NaN for the split errors.
  const auto around = test::run_study_text(hats_study(""));
  CHECK(around.metric(0, "unexcited_dimension") == 0);
  CHECK(around.metric(0, "pe_level") > 0);
  CHECK(std::isnan(around.metric(0, "path_l2_error")));
  const auto& around_flags = around.results[0].flags;
  CHECK(std::count(around_flags.begin(), around_flags.end(), "not_persistently_excited") == 0);
}

TEST_CASE("a path is checked when the study file is read", "[adaptive][path]") {
  const auto error = [](const std::string& path) {
    try {
      parse_study(hats_study(path), "shuttle.toml");
    } catch (const StudyError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(error("path = { from = 3.0, to = 2.0 }"),
             Catch::Contains("shuttle.toml:") && Catch::Contains("adaptive.path.to") &&
                 Catch::Contains("found 2, expected a point after from = 3"));
  CHECK_THAT(error("path = { from = 0.0, to = 30.0 }"),
             Catch::Contains("adaptive.path.to") && Catch::Contains("track's length"));
  CHECK_THAT(error("path = { from = 0.0 }"), Catch::Contains("adaptive.path.to: missing"));
  CHECK_THAT(error("path = \"half\""), Catch::Contains("adaptive.path: expected { from"));
  CHECK_THAT(error("path = { from = 0.0, to = 1.0, back = 2 }"),
             Catch::Contains("adaptive.path.back"));
}

TEST_CASE(
    "the limit of a path that leaves directions unexcited is searched only as far as the "
    "lap map says anything",
    "[adaptive][path][lap_map]") {
  // The persistence_of_excitation study at n = 64: half of H_n is never excited, so the lap
  // map has 27 eigenvalues 1 up to its own error (lap_map_rtol). Searched up to 2^62 laps, the
  // map's powers raised that error to 2.9e17 laps: laps_to_limit = 2.9e17 and the state sampled
  // there +inf (max_state_error = +inf, a trial that overflowed). The search stops at 50 time
  // constants of the slowest excited mode: fhat is not within 1% of its limit by then (the
  // unexcited directions drift), so laps_to_limit is NaN, flagged, and every sample is finite.
  const auto study = test::run_study_text(R"(
[study]
name = "unexcited"
kind = "adaptive"
evaluation_points = 1024
metrics = ["path_l2_error", "max_state_error", "laps_to_limit", "slowest_time_constant_laps",
           "unexcited_directions"]
[domain]
radius = 4.0
[grid]
n = [64]
[[kernel]]
name = "bspline"
degree = 1
n0 = 16
J = 4
[[target]]
name = "sine"
amplitude = 2.0
[[plant]]
name = "quarter_car"
[[law]]
name = "rkhs"
gamma = 2e4
[[integrator]]
name = "radau5"
rtol = 1e-6
atol = 1e-8
[adaptive]
speed = 1e-4
laps = "limit"
path = { from = 0.0, to = 12.566370614359172 }
lap_map_rtol = 1e-8
)");
  const auto& result = study.results[0];
  INFO(result.reason);
  REQUIRE(result.ok);
  CHECK(study.metric(0, "unexcited_directions") > 0);
  CHECK(std::isfinite(study.metric(0, "slowest_time_constant_laps")));
  CHECK(std::isfinite(study.metric(0, "max_state_error")));
  CHECK(std::isnan(study.metric(0, "laps_to_limit")));
  CHECK(std::count(result.flags.begin(), result.flags.end(), "laps_to_limit_unresolved") == 1);
}
