// The hypotheses of the paper's Theorem 3 as metrics of every adaptive trial (docs/theorems.md):
// kernel_diagonal_l1, coercivity_of_minus_a and lyapunov_p_distance_from_identity, against
// closed forms.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "study_support.hpp"

using namespace rkhs;

namespace {

test::StudyOutcome run_linear(const std::string& A, const std::string& B, const std::string& kernel,
                              const std::string& adaptive) {
  return test::run_study_text(R"([study]
name = "hypotheses"
kind = "adaptive"
evaluation_points = 1024
metrics = ["kernel_diagonal_l1", "coercivity_of_minus_a", "lyapunov_p_distance_from_identity"]
[domain]
radius = 4.0
[grid]
n = [8]
[[kernel]]
)" + kernel + R"(
[[plant]]
name = "linear"
A = ")" + A + R"("
B = ")" + B + R"("
[[law]]
name = "rkhs"
gamma = 0.1
[[integrator]]
name = "radau5"
[adaptive]
)" + adaptive,
                              "hypotheses.toml");
}

}  // namespace

TEST_CASE("Theorem 3's hypothesis (ii) for a normal and a non-normal A", "[adaptive][theorem3]") {
  // A = diag(-1, -2): -(A + A^T) / 2 = diag(1, 2), so c = 1; A^T P + P A = -I gives
  // P = diag(1/2, 1/4) and ||P - I||_2 = 3/4.
  const auto normal =
      run_linear("-1 0; 0 -2", "1; 0", "name = \"gaussian\"", "speed = 1.0\nfinal_time = 2.0\n");
  CHECK(normal.metric(0, "coercivity_of_minus_a") == Approx(1.0).epsilon(1e-14));
  CHECK(normal.metric(0, "lyapunov_p_distance_from_identity") == Approx(0.75).epsilon(1e-14));

  // A = [-1 10; 0 -2], Hurwitz but not coercive: the symmetric part [1 -5; -5 2] of -A has the
  // eigenvalues (3 +- sqrt(101)) / 2. P = [1/2 5/3; 5/3 103/12], and P - I has trace 85/12 and
  // determinant -(1/2)(91/12) - 25/9; its norm is its larger eigenvalue.
  const auto skewed =
      run_linear("-1 10; 0 -2", "1; 0", "name = \"gaussian\"", "speed = 1.0\nfinal_time = 2.0\n");
  CHECK(skewed.metric(0, "coercivity_of_minus_a") ==
        Approx((3.0 - std::sqrt(101.0)) / 2.0).epsilon(1e-13));
  const double trace = 85.0 / 12.0, determinant = -0.5 * 91.0 / 12.0 - 25.0 / 9.0;
  const double norm = (trace + std::sqrt(trace * trace - 4.0 * determinant)) / 2.0;
  CHECK(skewed.metric(0, "lyapunov_p_distance_from_identity") == Approx(norm).epsilon(1e-12));
}

TEST_CASE("Theorem 3's hypothesis (i): the integral of k(x, x) over the horizon",
          "[adaptive][theorem3]") {
  // The Gaussian with sigma = 1 on the 25 m track has k(s, s) = 1 (its images are below 1e-16):
  // the integral over [0, T] is T.
  const auto gaussian =
      run_linear("-1", "1", "name = \"gaussian\"", "speed = 1.0\nfinal_time = 20.0\n");
  CHECK(gaussian.metric(0, "kernel_diagonal_l1") == Approx(20.0).epsilon(1e-13));

  // In the periodic limit the horizon is infinite, and so is the integral: NaN, and the trial
  // is not failed as an overflow.
  const auto limit = run_linear("-1", "1", "name = \"gaussian\"",
                                "speed = 1.0\nlaps = \"limit\"\nroad = \"projection\"\n");
  CHECK(std::isnan(limit.metric(0, "kernel_diagonal_l1")));

  // Hats (p = 1, r = 1, n0 = 4, J = 3) on laps: each level j adds 2^-j sum_k N(x)^2 with
  // int N^2 = 2/3 per cell, so the mean of k(s, s) over the track is (2/3)(2 - 2^-J) and the
  // integral over two laps at 1 m/s is 2 L times it (the grid's rectangle rule on a piecewise
  // quadratic: to about 1e-5).
  const auto hats =
      run_linear("-1", "1", "name = \"bspline\"\ndegree = 1\nJ = 3", "speed = 1.0\nlaps = 2\n");
  const double length = 8.0 * std::acos(-1.0);
  CHECK(hats.metric(0, "kernel_diagonal_l1") ==
        Approx(2.0 * length * (2.0 / 3.0) * (2.0 - 0.125)).epsilon(1e-4));

  // The same on a shuttle over half the track (two whole level-0 cells) for the same time:
  // k(s, s) has the same mean on any union of whole level-0 cells. The grid's points in
  // [0, L / 2] count both ends, a bias of about 1 / 512 of the mean.
  const auto shuttle =
      run_linear("-1", "1", "name = \"bspline\"\ndegree = 1\nJ = 3",
                 "speed = 1.0\nfinal_time = " + std::to_string(2.0 * length) +
                     "\npath = { from = 0.0, to = " + std::to_string(length / 2.0) + " }\n");
  CHECK(shuttle.metric(0, "kernel_diagonal_l1") ==
        Approx(2.0 * length * (2.0 / 3.0) * (2.0 - 0.125)).epsilon(4e-3));
}
