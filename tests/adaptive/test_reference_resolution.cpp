// The infinite-dimensional estimator through a reference resolution H_N
// (rkhs/adaptive/reference_resolution.hpp): its features are orthonormal and reproduce H_N's
// kernel; where H_N = H it is the exact estimator; its own error is the power function of its
// centres; and a kernel without a finite feature map runs rkhs_embedding and Theorem 4.1
// trials through it.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/adaptive/reference_resolution.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/study/study.hpp"
#include "paper_track_support.hpp"
#include "study_support.hpp"

using namespace rkhs;

namespace {

const Domain& track = test::paper_track;

Eigen::VectorXd features_at(const KernelBasis& basis, double s) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(basis.size()));
  basis.evaluate(s, out.data());
  return out;
}

}  // namespace

TEST_CASE("a reference resolution's features reproduce H_N's kernel, orthonormally",
          "[adaptive][reference]") {
  for (const std::string name : {"gaussian", "wendland", "matern"}) {
    INFO(name);
    const auto kernel = test::make_registered_kernel(name, {}, track);
    const ReferenceResolvedKernel resolved(*kernel, 24);
    REQUIRE(resolved.feature_count() == 24);
    const auto& centres = resolved.centres();
    CHECK(centres[1] == Approx(track.length / 24));
    const auto features = resolved.feature_basis();
    // k_N(u, v) = k(C, u)^T G^-1 k(C, v), solved independently.
    const GramSolver solver(kernel->gram(centres), {});
    for (const double u : {0.3, 7.7, 19.1})
      for (const double v : {1.9, 7.7, 24.2}) {
        const Eigen::MatrixXd ku = kernel->cross(std::vector<double>{u}, centres).transpose();
        const Eigen::MatrixXd kv = kernel->cross(std::vector<double>{v}, centres).transpose();
        const double expected = ku.col(0).dot(solver.solve(Eigen::VectorXd(kv.col(0))));
        CHECK(features_at(*features, u).dot(features_at(*features, v)) ==
              Approx(expected).margin(1e-10));
      }
    // At a centre H_N reproduces k(c, c): psi(c)^T psi(c) = k(c, c).
    CHECK(features_at(*features, centres[5]).squaredNorm() ==
          Approx(kernel->evaluate(centres[5], centres[5])).epsilon(1e-10));
    // Its own error: the power function of its centres.
    const auto grid = track.uniform_points(2048);
    CHECK(resolved.norm_H_to_C(grid) ==
          Approx(power_function(*kernel, solver, centres, grid).maxCoeff()).epsilon(1e-6));
  }
  // Refused: no centre, or a Gram matrix singular to working precision.
  const auto gaussian = test::make_registered_kernel("gaussian", {}, track);
  CHECK_THROWS_WITH(ReferenceResolvedKernel(*gaussian, 0), Catch::Contains("at least one"));
  CHECK_THROWS_WITH(ReferenceResolvedKernel(*gaussian, 400),
                    Catch::Contains("reference resolution 400") &&
                        Catch::Contains("choose a smaller resolution"));
}

namespace {

std::string study(const std::string& kernel, const std::string& n, const std::string& law,
                  const std::string& projection = "") {
  return R"(
[study]
name = "reference"
kind = "adaptive"
evaluation_points = 1024
metrics = ["l2_error", "gap_to_l2_projection", "final_state_error", "pe_level",
           "reference_norm_H_to_C", "estimate_gap_H", "estimate_gap_C", "state_gap",
           "projected_l2_error", "projection_norm_H_to_C"]
[domain]
radius = 4.0
[grid]
n = )" + n +
         "\n" + kernel + R"(
)" + test::scalar_plant_sections("1e-11", "1e-12") +
         projection + law + R"(
[adaptive]
speed = 1.0
laps = 2
)";
}

}  // namespace

TEST_CASE("where H_N = H the reference resolution is the exact estimator",
          "[adaptive][reference]") {
  // Hats of one level on 32 cells (J = 0): H has dimension 32, H_32 at the knots is all of it.
  const std::string hats = "[[kernel]]\nname = \"bspline\"\nn0 = 32\nJ = 0\n";
  const auto exact =
      test::run_study_text(study(hats, "[8]", "[[law]]\nname = \"rkhs_embedding\"\ngamma = 0.1\n"));
  // The same kernel through the adapter: the trial runs it when the kernel has no features;
  // here it is built directly around the hats.
  const auto kernel = test::make_registered_kernel(
      "bspline", {{"n0", std::int64_t{32}}, {"J", std::int64_t{0}}}, track);
  const ReferenceResolvedKernel resolved(*kernel, 32);
  CHECK(resolved.norm_H_to_C(track.uniform_points(1024)) < 1e-7);
  const auto features = resolved.feature_basis();
  const auto exact_features = kernel->feature_basis();
  // Both feature maps give the kernel itself.
  for (const double u : {0.1, 5.3})
    for (const double v : {0.2, 5.0, 9.9})
      CHECK(features_at(*features, u).dot(features_at(*features, v)) ==
            Approx(features_at(*exact_features, u).dot(features_at(*exact_features, v)))
                .margin(1e-12));
  CHECK(std::isnan(exact.metric(0, "reference_norm_H_to_C")));
}

TEST_CASE("a kernel without features runs rkhs_embedding and Theorem 4.1 through H_N",
          "[adaptive][reference]") {
  const std::string gaussian = "[[kernel]]\nname = \"gaussian\"\nsigma = 1.0\n";
  const auto out = test::run_study_text(study(
      gaussian, "[4, 8, 16]", "[[law]]\nname = \"rkhs_embedding\"\ngamma = 0.1\nresolution = 48\n",
      "[[projection]]\nname = \"interpolation\"\n"));
  REQUIRE(out.trials.size() == 3);
  for (std::size_t t = 0; t < 3; ++t) {
    INFO(out.trials[t].key);
    // H_48's own error, far below the projections' it stands in for, the same in every trial.
    CHECK(out.metric(t, "reference_norm_H_to_C") > 0);
    CHECK(out.metric(t, "reference_norm_H_to_C") < 1e-3 * out.metric(t, "projection_norm_H_to_C"));
    CHECK(out.metric(t, "reference_norm_H_to_C") == out.metric(0, "reference_norm_H_to_C"));
    if (t > 0) {
      CHECK(out.metric(t, "estimate_gap_H") < out.metric(t - 1, "estimate_gap_H"));
      CHECK(out.metric(t, "state_gap") < out.metric(t - 1, "state_gap"));
    }
  }
  // The finite estimator of interpolation at n centres is the rkhs law there (Theorem 4.1's
  // finite side does not depend on the resolution).
  const auto rkhs_law = test::run_study_text(
      study(gaussian, "[4, 8, 16]", "[[law]]\nname = \"rkhs\"\ngamma = 0.1\n"));
  for (std::size_t t = 0; t < 3; ++t)
    CHECK(out.metric(t, "projected_l2_error") ==
          Approx(rkhs_law.metric(t, "l2_error")).epsilon(1e-7));

  // Without a resolution the kernel is refused, and the message says what to declare.
  auto no_resolution = parse_study(
      study(gaussian, "[8]", "[[law]]\nname = \"rkhs_embedding\"\ngamma = 0.1\n"), "r.toml");
  const auto trials = no_resolution.trials();
  const auto results = run_trials(no_resolution, trials, RunOptions{});
  REQUIRE(results.size() == 1);
  CHECK_FALSE(results[0].ok);
  CHECK_THAT(results[0].reason, Catch::Contains("resolution = N"));
}
