// Adaptive trials end to end: integrators agree, restarts at kinks do not change results, the
// state error goes to zero, and a road in H_n is learnt (alpha -> alpha*, V non-increasing).
#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>

#include "rkhs/adaptive/breakpoints.hpp"

#include "study_support.hpp"

using namespace rkhs;

namespace {

// Every trial of the study must succeed.
test::StudyOutcome run(const std::string& text) {
  return test::run_study_text(text, "adaptive.toml");
}

double relative(double a, double b) {
  return std::abs(a - b) / std::max(std::abs(b), 1e-300);
}

}  // namespace

TEST_CASE("integrators agree with each other on a short horizon", "[adaptive]") {
  // The quarter car of the learning configuration (Gamma = 2e4) over 2 s, from rest: the plant
  // transients (modes of -430 /s and -26 +- 208i /s) are resolved by every method, and the
  // explicit ones stay within their stability limits.
  const auto out = run(R"(
[study]
name = "agree"
kind = "adaptive"
evaluation_points = 512
[domain]
radius = 4.0
[grid]
n = [12]
[[kernel]]
name = "bspline"
degree = 1
J = 3
[[law]]
name = "rkhs"
gamma = 2e4
[[integrator]]
name = "rk_fehlberg78"
rtol = 1e-11
atol = 1e-13
[[integrator]]
name = "rodas4"
rtol = 1e-9
atol = 1e-11
[[integrator]]
name = "rosenbrock4"
rtol = 1e-9
atol = 1e-11
[[integrator]]
name = "dopri5"
rtol = 1e-9
atol = 1e-11
[[integrator]]
name = "rk4"
step = 1e-4
[adaptive]
speed = 1e-4
final_time = 2.0
)");
  REQUIRE(out.trials.size() == 5);
  // Reference: the 7(8) pair at tight tolerance.
  for (std::size_t i = 1; i < out.trials.size(); ++i) {
    INFO(out.trials[i].adaptive_axes().integrator.name);
    CHECK(relative(out.metric(i, "final_state_error"), out.metric(0, "final_state_error")) < 1e-5);
    CHECK(relative(out.metric(i, "l2_error"), out.metric(0, "l2_error")) < 1e-7);
    CHECK(relative(out.metric(i, "max_state_error"), out.metric(0, "max_state_error")) < 1e-5);
  }
  CHECK(out.metric(0, "max_state_error") > 1e-6);  // the comparison is not of zeros

  // A loop that learns quickly (scalar plant, Gamma = 0.1): fhat moves far from 0 in 20 s, so
  // the estimate itself is compared, not only the state.
  const auto learning = run(R"(
[study]
name = "agree_learning"
kind = "adaptive"
evaluation_points = 512
[domain]
radius = 4.0
[grid]
n = [8]
[[kernel]]
name = "gaussian"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 0.1
[[integrator]]
name = "rk_fehlberg78"
rtol = 1e-11
atol = 1e-13
[[integrator]]
name = "rodas4"
rtol = 1e-9
atol = 1e-11
[[integrator]]
name = "rosenbrock4"
rtol = 1e-9
atol = 1e-11
[[integrator]]
name = "dopri5"
rtol = 1e-9
atol = 1e-11
[[integrator]]
name = "rk4"
step = 1e-4
[adaptive]
speed = 0.1
final_time = 20.0
)");
  CHECK(std::abs(learning.metric(0, "l2_error") - 7.0898) > 0.1);  // fhat moved (||f|| = 7.09)
  for (std::size_t i = 1; i < learning.trials.size(); ++i) {
    INFO(learning.trials[i].adaptive_axes().integrator.name);
    CHECK(relative(learning.metric(i, "l2_error"), learning.metric(0, "l2_error")) < 1e-6);
    // x - xhat is a small difference of states of order 1: compare it absolutely, at a level
    // set by the tolerances (rtol 1e-9 on states of order 1, accumulated over the run).
    CHECK(std::abs(learning.metric(i, "final_state_error") -
                   learning.metric(0, "final_state_error")) < 1e-7);
    UNSCOPED_INFO(learning.trials[i].adaptive_axes().integrator.name
                  << " " << learning.metric(i, "final_state_error"));
  }
  CHECK(learning.metric(0, "final_state_error") > 1e-5);
}

TEST_CASE("restarting at the kinks of phi(s(t)) changes results only within tolerance",
          "[adaptive]") {
  const auto out = run(R"(
[study]
name = "kinks"
kind = "adaptive"
evaluation_points = 512
[domain]
radius = 4.0
[grid]
n = [16]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 4
[[law]]
name = "rkhs"
gamma = 2e4
[[integrator]]
name = "rodas4"
rtol = 1e-8
atol = 1e-10
restart_at_kinks = [true, false]
[adaptive]
speed = 1e-4
laps = 1
)");
  for (std::size_t degree = 0; degree < 2; ++degree) {
    const std::size_t with = 2 * degree, without = with + 1;
    INFO("degree " << degree + 1);
    CHECK(out.metric(with, "segments") > 60);
    CHECK(out.metric(without, "segments") < 25);
    CHECK(relative(out.metric(with, "l2_error"), out.metric(without, "l2_error")) < 1e-4);
    CHECK(relative(out.metric(with, "final_state_error"),
                   out.metric(without, "final_state_error")) < 1e-3);
  }
}

TEST_CASE("the paper's gain: x - xhat -> 0 while fhat does not learn f", "[adaptive]") {
  const auto out = run(R"(
[study]
name = "literal"
kind = "adaptive"
evaluation_points = 1024
[domain]
radius = 4.0
[grid]
n = [10]
[[kernel]]
name = "gaussian"
[[law]]
name = "gradient"
gamma = 1e-3
[adaptive]
speed = 1.0
laps = 2
samples_per_lap = 50
)");
  const auto& samples = out.results[0].samples;
  REQUIRE(samples.size() == 101);
  // |x - xhat| stays at the 1e-5 level (the plant's states are of order 1e-4..1) while fhat
  // stays as far from f as f is from 0 (||f||_L2 = 7.09): the estimator tracks, it does not learn.
  CHECK(out.metric(0, "max_state_error") < 1e-4);
  CHECK(out.metric(0, "final_state_error") < 1e-4);
  CHECK(out.metric(0, "l2_error") > 5.0);
}

TEST_CASE("manufactured: a road in H_n is learnt, alpha -> alpha*, V non-increasing",
          "[adaptive]") {
  const std::string base = R"(
[study]
name = "manufactured"
kind = "adaptive"
evaluation_points = 512
[domain]
radius = 4.0
[grid]
n = [6, 8]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
gamma = 0.1
[[law]]
name = "rkhs"
gamma = 0.1
[[integrator]]
name = "rodas4"
rtol = 1e-9
atol = 1e-12
[adaptive]
speed = 0.1
road = "projection"
samples_per_lap = 40
)";
  const auto short_run = run(base + "laps = 5\n");
  const auto long_run = run(base + "laps = 20\n");
  for (std::size_t i = 0; i < long_run.trials.size(); ++i) {
    INFO(long_run.trials[i].key);
    // V' = -1/2 e^T Q e <= 0 for a road in H_n: between samples V may not grow beyond the
    // integration tolerance (relative to V(0)).
    CHECK(long_run.metric(i, "lyapunov_max_increase") <= 1e-8);
    CHECK(long_run.metric(i, "lyapunov_ratio") < short_run.metric(i, "lyapunov_ratio"));
    CHECK(long_run.metric(i, "coefficient_error") < short_run.metric(i, "coefficient_error"));
    CHECK(long_run.metric(i, "coefficient_error") < 0.1);
    // x - xhat -> 0 as alpha -> alpha*.
    CHECK(long_run.metric(i, "final_state_error") < 0.01 * long_run.metric(i, "max_state_error"));
    // The projection road is in H_n: its static interpolation error is round-off.
    CHECK(long_run.metric(i, "interpolant_l2_error") < 1e-10);
    // V decreases monotonically sample by sample.
    const auto& samples = long_run.results[i].samples;
    for (std::size_t k = 1; k < samples.size(); ++k)
      CHECK(samples[k].lyapunov <= samples[k - 1].lyapunov * (1 + 1e-9) + 1e-14);
  }
}

TEST_CASE("adaptive study file errors", "[adaptive]") {
  const std::string base = R"(
[study]
name = "bad"
kind = "adaptive"
[domain]
radius = 4.0
[grid]
n = [4]
[[kernel]]
name = "gaussian"
)";
  auto error_of = [&](const std::string& extra) {
    try {
      parse_study(base + extra, "bad.toml");
    } catch (const StudyError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(error_of(""), Catch::Contains("adaptive: missing [adaptive] table"));
  CHECK_THAT(error_of("[adaptive]\nroad = \"other\"\n"),
             Catch::Contains("adaptive.road: found \"other\", expected \"target\""));
  CHECK_THAT(error_of("[adaptive]\n[[plant]]\nname = \"linear\"\nA = \"1\"\nB = \"1\"\n"),
             Catch::Contains("A is not Hurwitz"));
  CHECK_THAT(error_of("[adaptive]\n[[integrator]]\nname = \"rosenbrok4\"\n"),
             Catch::Contains("did you mean 'rosenbrock4'?"));
  CHECK_THAT(error_of("[adaptive]\nq = \"diag(1, 2)\"\n"),
             Catch::Contains("adaptive.q is 2 x 2, this plant needs 4 x 4"));
  const auto approximation = R"(
[study]
name = "bad"
[domain]
radius = 4.0
[grid]
n = [4]
[[kernel]]
name = "gaussian"
[adaptive]
speed = 1
)";
  CHECK_THROWS_WITH(parse_study(approximation, "a.toml"),
                    Catch::Contains("adaptive: only for adaptive studies"));
}

TEST_CASE("a horizon too long to step through fails its trial before the first step",
          "[adaptive][limits]") {
  // laps = 1e300 is not a lap count the lap map can take (it needs a whole number below
  // 9.2e18), so the trial steps through time; its 3.2e301 output samples were built one by one
  // before the first step, with no bound and no cancellation point (property fuzzer, seed 53).
  const auto study = parse_study(R"(
[study]
name = "long"
kind = "adaptive"
evaluation_points = 128
[domain]
radius = 0.5
[grid]
n = [4]
[[kernel]]
name = "wendland"
k = 3
radius = 0.3
[[target]]
name = "sine"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 10.0
[[integrator]]
name = "rk_fehlberg78"
[adaptive]
speed = 0.5
laps = 1e300
)",
                                 "long.toml");
  const auto results = run_trials(study, study.trials(), RunOptions{});
  REQUIRE(results.size() == 1);
  const auto& result = results[0];
  CHECK_FALSE(result.ok);
  CHECK_THAT(result.reason, Catch::Contains("1e+300 laps stepped through time") &&
                                Catch::Contains("more than the 100000000"));

  // The bound itself: one breakpoint more than max_breakpoints is refused, by count.
  AdaptiveSettings settings;
  settings.speed = 1;
  settings.samples_per_lap = 1;
  const Domain track;  // a periodic track of length 1
  const double lap = settings.lap_time(track.length);
  CHECK(adaptive_breakpoints(settings, track, 0, 3 * lap, {}, false).size() == 4);
  CHECK_THROWS_AS(adaptive_breakpoints(settings, track, 0,
                                       static_cast<double>(max_breakpoints + 1) * lap, {}, false),
                  std::length_error);
}
