// The metric pe_level (rkhs/adaptive/excitation.hpp, docs/model.md section 14): persistence of
// excitation over one lap of the space a law learns in, against closed forms, decreasing with n,
// equal in H_n = H and in feature coordinates, and NaN or flagged where round-off decides it.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/adaptive/averaged_limit.hpp"
#include "rkhs/adaptive/excitation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "paper_track_support.hpp"
#include "study_support.hpp"

using namespace rkhs;
using test::Given;

namespace {

const Domain& track = test::paper_track;  // the paper's track, radius 4 m
using test::finest_points;
constexpr auto road = test::sine_road;

}  // namespace

TEST_CASE("pe_level: closed forms for B-splines of degree 0 and 1 on uniform knots",
          "[adaptive][pe_level]") {
  // One level (J = 0), N cells, centres at the knots (degree 1) or the cells' midpoints
  // (degree 0): the sections are the level's splines themselves and G = I. Degree 1: E = (1/L) int
  // hat_i hat_j = (1/N) circ(2/3, 1/6, 0, ..., 1/6) with eigenvalues (1/N)(2/3 + 1/3 cos(2 pi m /
  // N)), the smallest (m = N/2) 1/(3N). Degree 0: E = (1/N) I, so 1/N. In feature coordinates (J =
  // 0: the features are these splines, not redundant) the same values.
  const std::function<double(double)> f = road;
  for (const std::int64_t degree : {0, 1})
    for (const std::int64_t cells : {4, 8, 16}) {
      Given given{{"degree", degree}, {"n0", cells}, {"J", std::int64_t{0}}};
      if (degree == 0) given["r"] = 1.0;
      const auto kernel = test::make_registered_kernel("bspline", given, track);
      // Degree 0 at the cells' midpoints (a knot may round into the cell to its left).
      const auto knots = finest_points(cells, 0, degree == 0 ? 0.5 : 0.0);
      const Eigen::MatrixXd G = kernel->gram(knots);
      CHECK((G - Eigen::MatrixXd::Identity(cells, cells)).cwiseAbs().maxCoeff() < 1e-14);
      const double exact =
          degree == 1 ? 1.0 / (3.0 * static_cast<double>(cells)) : 1.0 / static_cast<double>(cells);
      const auto limit = averaged_limit(*kernel, knots, f, {}, {});
      const auto level = excitation_level(limit.averaged_gram, G, GramSolver(G, {}).spectrum());
      INFO("degree " << degree << ", N = " << cells << ": pe_level " << level.value
                     << ", closed form " << exact);
      CHECK(level.resolved);
      CHECK(level.dimension == cells);
      CHECK(std::abs(level.value - exact) < 1e-13 * exact);
      const auto in_features = averaged_limit_in_features(*kernel, f, {});
      const auto on_range = excitation_level_on_range(in_features.averaged_gram_eigenvalues);
      CHECK(on_range.resolved);
      CHECK(on_range.dimension == cells);
      CHECK(std::abs(on_range.value - exact) < 1e-13 * exact);
    }
}

TEST_CASE("pe_level decreases with n and reaches the level of H where H_n = H",
          "[adaptive][pe_level]") {
  const std::function<double(double)> f = road;
  // Degree 1, J = 5: H has dimension n_J = 128; nested uniform centres.
  const auto kernel = test::make_registered_kernel(
      "bspline", {{"degree", std::int64_t{1}}, {"n0", std::int64_t{4}}, {"J", std::int64_t{5}}},
      track);
  double previous = std::numeric_limits<double>::infinity();
  for (const std::size_t n : {8u, 16u, 32u, 64u, 128u}) {
    const auto centres = track.uniform_points(n);
    const Eigen::MatrixXd G = kernel->gram(centres);
    const auto limit = averaged_limit(*kernel, centres, f, {}, {});
    const auto level = excitation_level(limit.averaged_gram, G, GramSolver(G, {}).spectrum());
    UNSCOPED_INFO("bspline p = 1, J = 5, n = " << n << ": pe_level " << level.value);
    CHECK(level.resolved);
    CHECK(level.value < previous);
    previous = level.value;
  }
  // n = 128 centres at the finest knots span H: the level of H_n is that of H, measured in
  // feature coordinates (F = 252 features, rank 128).
  const auto in_features = averaged_limit_in_features(*kernel, f, {});
  const auto on_range = excitation_level_on_range(in_features.averaged_gram_eigenvalues);
  UNSCOPED_INFO("in feature coordinates: pe_level " << on_range.value << ", rank "
                                                    << on_range.dimension);
  CHECK(on_range.resolved);
  CHECK(on_range.dimension == 128);
  CHECK(std::abs(on_range.value - previous) < 1e-9 * previous);

  // The Gaussian (sigma = 1): decreasing while G is regular; NaN once G is singular.
  const auto gaussian = test::make_registered_kernel("gaussian", {}, track);
  previous = std::numeric_limits<double>::infinity();
  for (const std::size_t n : {4u, 8u, 16u, 32u, 100u}) {
    const auto centres = track.uniform_points(n);
    const Eigen::MatrixXd G = gaussian->gram(centres);
    const GramSolver solver(G, {});
    const auto limit = averaged_limit(*gaussian, centres, f, {}, {});
    const auto level = excitation_level(limit.averaged_gram, G, solver.spectrum());
    UNSCOPED_INFO("gaussian sigma = 1, n = " << n << ": pe_level " << level.value << " (bound "
                                             << level.error_bound << ")");
    if (n == 100) {
      CHECK(solver.spectrum().singular);
      CHECK(std::isnan(level.value));
      CHECK_FALSE(level.resolved);
      continue;
    }
    CHECK(level.value < previous);
    previous = level.value;
  }
}

TEST_CASE("pe_level in trials: NaN and gram_singular for a singular G, flagged when unresolved",
          "[adaptive][pe_level]") {
  const auto out = test::run_study_text(R"(
[study]
name = "pe"
kind = "adaptive"
evaluation_points = 1024
metrics = ["pe_level", "gram_condition_number"]
[domain]
radius = 4.0
[grid]
n = [16, 100]
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
[[integrator]]
name = "radau5"
[adaptive]
speed = 1.0
laps = 1
)",
                                        "pe.toml");
  REQUIRE(out.trials.size() == 2);
  CHECK(out.metric(0, "pe_level") > 0);
  CHECK(std::isinf(out.metric(1, "gram_condition_number")));
  CHECK(std::isnan(out.metric(1, "pe_level")));
  const auto& flags = out.results[1].flags;
  CHECK(std::find(flags.begin(), flags.end(), "gram_singular") != flags.end());
  // The unresolved case in feature coordinates: eigenvalues with no gap above the cutoff.
  Eigen::VectorXd values(4);
  values << 1e-30, 2e-16, 1e-15, 1.0;
  const auto unresolved = excitation_level_on_range(values);
  CHECK(std::isnan(unresolved.value));
  CHECK_FALSE(unresolved.resolved);
  values << 1e-30, 2e-17, 1e-3, 1.0;
  const auto resolved = excitation_level_on_range(values);
  CHECK(resolved.resolved);
  CHECK(resolved.value == 1e-3);
  CHECK(resolved.dimension == 2);
}
