// Theorem 4.1 measured (rkhs/adaptive/finite_to_infinite.hpp, docs/theorems.md): the finite
// estimator of a projection Pi_j beside the infinite-dimensional one (rkhs_embedding).
//   - Where H_j = H (j = J) every projection is the identity and the two estimators are one ODE:
//     every gap is at the integration's level.
//   - The finite estimator of the interpolation projection is the rkhs law on the same centres,
//     an independent code path (the Gram inverse as the learning map): the same estimate.
//   - As j grows the gaps shrink, and their ratio to ||I - Pi_j||_{H -> C} stays bounded.
//   - A projection study refuses a law other than rkhs_embedding and the projected road.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "rkhs/study/study.hpp"
#include "study_support.hpp"

using namespace rkhs;

namespace {

// The bspline kernel of degree `degree` with n0 = 4 and J levels (4 2^J finest cells), uniform
// centres shifted by `offset` spacings, a linear plant with a time constant of 1 s,
// Gamma = 0.1, 2 laps of the 25 m track at 1 m/s, radau5 at tight tolerances, and the sine road.
std::string gap_study(int degree, const std::string& n, const std::string& projections,
                      const std::string& law = "rkhs_embedding", int levels = 3,
                      double offset = 0.0) {
  return R"(
[study]
name = "gaps"
kind = "adaptive"
evaluation_points = 1024
[domain]
radius = 4.0
[grid]
n = )" + n +
         R"(
[[kernel]]
name = "bspline"
degree = )" +
         std::to_string(degree) + R"(
n0 = 4
J = )" + std::to_string(levels) +
         R"(
[[centres]]
name = "uniform"
offset = )" +
         std::to_string(offset) + R"(
)" + test::scalar_plant_sections("1e-11", "1e-12") +
         projections + R"(
[[law]]
name = ")" +
         law + R"("
gamma = 0.1
[adaptive]
speed = 1.0
laps = 2
)";
}

const std::string all_projections = R"(
[[projection]]
name = "interpolation"
[[projection]]
name = "mra_level"
[[projection]]
name = "l2_projection"
[[projection]]
name = "quasi_interpolant"
)";

}  // namespace

TEST_CASE("Theorem 4.1 trials: where H_j = H every projection's estimator is the infinite one",
          "[adaptive][theorem_4_1]") {
  for (int degree : {1, 2}) {
    INFO("degree " << degree);
    // The sections at the 32 finest knots span H for degree 1, at the cells' midpoints for
    // degree 2 (the interpolation projection is then the identity too).
    const auto out = test::run_study_text(
        gap_study(degree, "[32]", all_projections, "rkhs_embedding", 3, degree == 1 ? 0.0 : 0.5));
    REQUIRE(out.trials.size() == 4);
    for (std::size_t t = 0; t < out.trials.size(); ++t) {
      INFO(out.trials[t].key);
      // The estimate is of size 1 (the road's amplitude is 2, half of it learned in 2 laps).
      CHECK(out.metric(t, "estimate_gap_C") <= 1e-7);
      CHECK(out.metric(t, "state_gap") <= 1e-8);
      CHECK(out.metric(t, "plant_gap") <= 1e-9);
      CHECK(std::abs(out.metric(t, "projected_l2_error") - out.metric(t, "l2_error")) <=
            1e-7 * out.metric(t, "l2_error"));
      // Pi_J = I: ||I - Pi_J||_{H -> C} is round-off and flagged, ||Pi_J|| = 1.
      const auto& flags = out.results[t].flags;
      CHECK(std::count(flags.begin(), flags.end(), "projection_norm_at_floor") == 1);
      CHECK(out.metric(t, "projection_operator_norm") == Approx(1.0).epsilon(1e-8));
    }
  }
}

TEST_CASE("Theorem 4.1 trials: the interpolation projection's estimator is the rkhs law",
          "[adaptive][theorem_4_1]") {
  const std::string interpolation = "[[projection]]\nname = \"interpolation\"\n";
  for (int degree : {1, 2}) {
    INFO("degree " << degree);
    const auto finite = test::run_study_text(gap_study(degree, "[8, 16]", interpolation));
    const auto rkhs_law = test::run_study_text(gap_study(degree, "[8, 16]", "", "rkhs"));
    REQUIRE(finite.trials.size() == 2);
    REQUIRE(rkhs_law.trials.size() == 2);
    for (std::size_t t = 0; t < 2; ++t) {
      INFO(finite.trials[t].key);
      const double expected = rkhs_law.metric(t, "l2_error");
      CHECK(std::abs(finite.metric(t, "projected_l2_error") - expected) <= 1e-7 * expected);
      // ||I - Pi_n||_{H -> C} of interpolation is the power function.
      CHECK(finite.metric(t, "projection_norm_H_to_C") ==
            Approx(rkhs_law.metric(t, "power_function_sup")).epsilon(1e-9));
      // The infinite estimator is the same in both studies' static parts: a real gap.
      CHECK(finite.metric(t, "estimate_gap_H") > 1e-3);
    }
  }
}

TEST_CASE(
    "Theorem 4.1 trials: the gaps shrink with j, and no faster than ||I - Pi_j|| does "
    "their ratio grow",
    "[adaptive][theorem_4_1]") {
  // J = 6 (256 finest cells), j = 0 .. 3: far from H_j = H, where ||I - Pi_j|| drops to 0.
  const auto out =
      test::run_study_text(gap_study(1, "[4, 8, 16, 32]", all_projections, "rkhs_embedding", 6));
  REQUIRE(out.trials.size() == 16);
  for (const auto& projection : out.study.projections) {
    std::vector<std::size_t> levels;
    for (std::size_t t = 0; t < out.trials.size(); ++t)
      if (out.trials[t].projection.name == projection.name) levels.push_back(t);
    REQUIRE(levels.size() == 4);
    std::sort(levels.begin(), levels.end(),
              [&](auto a, auto b) { return out.trials[a].n < out.trials[b].n; });
    for (std::size_t k = 0; k < levels.size(); ++k) {
      const auto t = levels[k];
      INFO(out.trials[t].key);
      CHECK(out.metric(t, "plant_gap") <= 1e-9);
      CHECK(out.metric(t, "estimate_gap_H") > 0);
      if (k == 0) continue;
      const auto previous = levels[k - 1];
      for (const char* metric :
           {"estimate_gap_H", "estimate_gap_C", "state_gap", "projection_norm_H_to_C"})
        CHECK(out.metric(t, metric) < out.metric(previous, metric));
      // The gap decays at least as fast as the projection's norm (Theorem 4.1's rate).
      CHECK(out.metric(t, "gap_effectivity_H") < out.metric(previous, "gap_effectivity_H"));
    }
  }
}

TEST_CASE("a projection in an adaptive study needs rkhs_embedding and the road f",
          "[adaptive][theorem_4_1]") {
  const std::string interpolation = "[[projection]]\nname = \"interpolation\"\n";
  CHECK_THROWS_WITH(parse_study(gap_study(1, "[8]", interpolation, "gradient"), "gaps.toml"),
                    Catch::Contains("gaps.toml:") && Catch::Contains("law 'gradient") &&
                        Catch::Contains("rkhs_embedding"));
  CHECK_THROWS_WITH(
      parse_study(gap_study(1, "[8]", interpolation) + "road = \"projection\"\n", "gaps.toml"),
      Catch::Contains("gaps.toml:") && Catch::Contains("road must be the target"));
  CHECK_THROWS_WITH(
      parse_study(gap_study(1, "[6]", "[[projection]]\nname = \"mra_level\"\n"), "gaps.toml"),
      Catch::Contains("gaps.toml:") && Catch::Contains("projection"));
}
