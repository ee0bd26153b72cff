// [adaptive] reference: every trial is integrated once more with the reference integrator, and
// integration_error measures how far the trial's fhat(T) is from the reference's. The parse
// errors of the reference, the metric (zero for the reference's own settings, smaller for
// tighter tolerances, NaN without a reference) and that the cost metrics count the trial's
// integrator only.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "study_support.hpp"

using namespace rkhs;

namespace {

// The scalar plant that learns in 20 s (Gamma = 0.1): fhat moves far from 0, so its error is
// that of the integration, not of a state that stays near 0.
const std::string learning = R"(
[study]
name = "integration_error"
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
name = "radau5"
rtol = 1e-11
atol = 1e-12
[[integrator]]
name = "rodas4"
rtol = [1e-3, 1e-6]
atol = 1e-8
[adaptive]
speed = 0.1
final_time = 20.0
)";

std::string error_of(const std::string& adaptive_lines) {
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
[adaptive]
speed = 1e-4
)";
  try {
    parse_study(base + adaptive_lines, "bad.toml");
  } catch (const StudyError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("integration_error: zero for the reference's settings, smaller for tighter tolerances",
          "[adaptive][reference]") {
  const auto with = test::run_study_text(
      learning + "reference = { integrator = \"radau5\", rtol = 1e-11, atol = 1e-12 }\n");
  REQUIRE(with.trials.size() == 3);
  CHECK(with.study.adaptive_axes().reference.label() ==
        with.trials[0].adaptive_axes().integrator.label());
  // The trial with the reference's own integrator and tolerances computes the same solution.
  CHECK(with.metric(0, "integration_error") < 1e-13);
  const double loose = with.metric(1, "integration_error");
  const double tight = with.metric(2, "integration_error");
  CHECK(loose > 1e-6);
  CHECK(tight < loose / 100);
  CHECK(tight > 0);
  for (std::size_t i = 0; i < 3; ++i)
    CHECK(with.results[i].engine == AdaptiveEngine::time_stepping);

  // Without a reference: NaN, and the same cost metrics: the reference run is not counted.
  const auto without = test::run_study_text(learning);
  for (std::size_t i = 0; i < 3; ++i) {
    INFO(with.trials[i].key);
    CHECK(std::isnan(without.metric(i, "integration_error")));
    for (const char* cost : {"steps", "rejected_steps", "segments", "rhs_evaluations",
                             "jacobian_evaluations", "l2_error"})
      CHECK(with.metric(i, cost) == without.metric(i, cost));
  }
}

TEST_CASE("a reference forces time stepping where automatic would take the lap map",
          "[adaptive][reference]") {
  // 40 laps of a 10-state system: automatic takes the lap map without a reference.
  std::string text = learning;
  text.replace(text.find("final_time = 20.0"), 17, "laps = 40");
  text.replace(text.find("rtol = [1e-3, 1e-6]"), 19, "rtol = 1e-6");
  const auto plain = parse_study(text, "a.toml");
  CHECK(adaptive_engine_for(trial_adaptive_settings(plain, plain.trials()[1]), 10) ==
        AdaptiveEngine::lap_map);
  const auto referenced =
      parse_study(text + "reference = { integrator = \"rodas4\" }\n", "a.toml");
  CHECK(trial_adaptive_settings(referenced, referenced.trials()[1]).engine ==
        AdaptiveEngine::time_stepping);
  // Left-out tolerances are the reference's defaults, other parameters the integrator's.
  CHECK(referenced.adaptive_axes().reference.parameters.real("rtol") == 1e-11);
  CHECK(referenced.adaptive_axes().reference.parameters.real("atol") == 1e-10);
  CHECK(referenced.adaptive_axes().reference.parameters.boolean("restart_at_kinks"));
}

TEST_CASE("[adaptive] reference errors", "[adaptive][reference]") {
  CHECK(error_of("reference = { integrator = \"radau5\", rtol = 1e-11, atol = 1e-10 }\n") ==
        "no error");
  CHECK_THAT(error_of("reference = \"radau5\"\n"),
             Catch::StartsWith("bad.toml:13:13: adaptive.reference: expected an inline table"));
  CHECK_THAT(error_of("reference = { rtol = 1e-11 }\n"),
             Catch::StartsWith("bad.toml:13:13: adaptive.reference: missing 'integrator'"));
  CHECK_THAT(error_of("reference = { integrator = \"radau\" }\n"),
             Catch::StartsWith("bad.toml:13:28: adaptive.reference.integrator: unknown "
                               "integrator 'radau'") &&
                 Catch::Contains("did you mean 'radau5'?"));
  CHECK_THAT(error_of("reference = { integrator = 5 }\n"),
             Catch::StartsWith("bad.toml:13:28: adaptive.reference.integrator: expected an "
                               "integrator name"));
  CHECK_THAT(error_of("reference = { integrator = \"radau5\", rtool = 1e-9 }\n"),
             Catch::StartsWith("bad.toml:13:38: adaptive.reference.rtool: unknown parameter of "
                               "integrator 'radau5'") &&
                 Catch::Contains("did you mean 'rtol'?"));
  CHECK_THAT(error_of("reference = { integrator = \"radau5\", rtol = -1 }\n"),
             Catch::StartsWith("bad.toml:13:45: adaptive.reference.rtol: "));
  CHECK_THAT(error_of("reference = { integrator = \"radau5\", rtol = [1e-9, 1e-10] }\n"),
             Catch::StartsWith("bad.toml:13:45: adaptive.reference.rtol: expected one value"));
  CHECK_THAT(error_of("reference = { integrator = \"rk4\", rtol = 1e-9 }\n"),
             Catch::StartsWith("bad.toml:13:35: adaptive.reference.rtol: unknown parameter of "
                               "integrator 'rk4'"));
  CHECK_THAT(error_of("engine = \"lap_map\"\nreference = { integrator = \"radau5\" }\n"),
             Catch::StartsWith("bad.toml:13:10: adaptive.engine: found \"lap_map\" with a "
                               "reference"));
  CHECK_THAT(error_of("laps = \"limit\"\nreference = { integrator = \"radau5\" }\n"),
             Catch::StartsWith("bad.toml:13:8: adaptive.laps: found \"limit\" with a reference"));
  CHECK_THAT(error_of("laps = [1, \"limit\"]\nreference = { integrator = \"radau5\" }\n"),
             Catch::StartsWith("bad.toml:13:12: adaptive.laps: found \"limit\" with a reference"));
}
