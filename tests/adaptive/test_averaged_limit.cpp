// The averaged (v -> 0) limit of the adaptive estimator, P_L2 f: the Gauss-Legendre rule, the
// composite quadrature of Mbar and bbar (checked against independent quadratures and closed
// forms), the projection's defining properties, and its metrics in adaptive trials.
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/adaptive/averaged_limit.hpp"
#include "study_support.hpp"

using namespace rkhs;
using test::Given;

namespace {

const Domain track{test::track_length, true};  // the paper's track, radius 4 m

std::vector<double> uniform_centres(std::size_t n, const Domain& domain) {
  std::vector<double> centres(n);
  for (std::size_t i = 0; i < n; ++i)
    centres[i] = domain.length * static_cast<double>(i) / static_cast<double>(n);
  return centres;
}

// The paper's synthetic road and a richer one, both smooth and periodic on the track.
double sine_road(double s) {
  return 2.0 * std::sin(2 * std::numbers::pi * s / track.length);
}
double two_tone_road(double s) {
  const double w = 2 * std::numbers::pi / track.length;
  return 2.0 * std::sin(w * s) + 0.5 * std::cos(3 * w * s + 0.3);
}

double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / b.norm();
}

const SolverOptions solver{};

}  // namespace

TEST_CASE("Gauss-Legendre rules integrate polynomials of degree 2q - 1 exactly",
          "[averaged_limit]") {
  for (std::size_t q : {1u, 2u, 3u, 4u, 7u, 12u, 20u, 40u}) {
    INFO("q = " << q);
    const auto rule = gauss_legendre(q);
    REQUIRE(rule.nodes.size() == q);
    REQUIRE(rule.weights.size() == q);
    for (std::size_t k = 0; k < q; ++k) {
      CHECK(rule.weights[k] > 0);
      CHECK(rule.nodes[k] == Approx(-rule.nodes[q - 1 - k]).margin(1e-16));
      if (k > 0) CHECK(rule.nodes[k] > rule.nodes[k - 1]);
    }
    // int_{-1}^{1} x^k = 2 / (k + 1) for even k, 0 for odd k; and over [0.3, 1.7] after the
    // affine map, as the composite rule uses it.
    for (std::size_t degree = 0; degree <= 2 * q - 1; ++degree) {
      INFO("degree " << degree);
      const double k = static_cast<double>(degree);
      double sum = 0, shifted = 0;
      const double a = 0.3, b = 1.7;
      for (std::size_t j = 0; j < q; ++j) {
        sum += rule.weights[j] * std::pow(rule.nodes[j], k);
        const double s = 0.5 * (a + b) + 0.5 * (b - a) * rule.nodes[j];
        shifted += 0.5 * (b - a) * rule.weights[j] * std::pow(s, k);
      }
      const double exact = degree % 2 == 0 ? 2 / (k + 1) : 0.0;
      CHECK(std::abs(sum - exact) <= 1e-15 * 4);
      const double exact_shifted = (std::pow(b, k + 1) - std::pow(a, k + 1)) / (k + 1);
      CHECK(std::abs(shifted - exact_shifted) <= 1e-14 * exact_shifted);
    }
    // Degree 2q is not integrated exactly (the error, 2^(2q+1) (q!)^4 / ((2q+1) ((2q)!)^2), is
    // above round-off up to q = 12): the rule has no more precision than it claims.
    double sum = 0;
    for (std::size_t j = 0; j < q; ++j)
      sum += rule.weights[j] * std::pow(rule.nodes[j], static_cast<double>(2 * q));
    if (q <= 12) CHECK(std::abs(sum - 2.0 / static_cast<double>(2 * q + 1)) > 1e-12);
  }
  // Known rules.
  const auto two = gauss_legendre(2);
  CHECK(two.nodes[1] == Approx(1 / std::sqrt(3.0)).epsilon(1e-15));
  CHECK(two.weights[0] == Approx(1.0).epsilon(1e-15));
  const auto three = gauss_legendre(3);
  CHECK(three.nodes[1] == 0.0);
  CHECK(three.nodes[2] == Approx(std::sqrt(0.6)).epsilon(1e-15));
  CHECK(three.weights[1] == Approx(8.0 / 9.0).epsilon(1e-15));
  CHECK(three.weights[2] == Approx(5.0 / 9.0).epsilon(1e-15));
  CHECK_THROWS_AS(gauss_legendre(0), std::invalid_argument);
}

TEST_CASE("a road in span{phi_i} is its own L2 projection: alpha = a", "[averaged_limit]") {
  struct Case {
    std::string name;
    Given given;
    std::size_t n;
  };
  const std::vector<Case> cases{{"bspline", {{"degree", std::int64_t{2}}}, 8},
                                {"bspline", {{"degree", std::int64_t{1}}}, 16},
                                {"wendland", {{"k", std::int64_t{1}}, {"radius", 3.0}}, 12},
                                {"matern", {{"nu", 1.5}}, 12},
                                {"gaussian", {{"sigma", 1.0}}, 10}};
  for (const auto& c : cases) {
    INFO(c.name << " n = " << c.n);
    const auto kernel = test::make_registered_kernel(c.name, c.given, track);
    const auto centres = uniform_centres(c.n, track);
    Eigen::VectorXd a(static_cast<Eigen::Index>(c.n));
    for (Eigen::Index i = 0; i < a.size(); ++i)
      a(i) = std::sin(1.7 * static_cast<double>(i * i) + 0.4) + 0.1;
    const auto road = [&](double s) {
      double sum = 0;
      for (std::size_t i = 0; i < c.n; ++i)
        sum += a(static_cast<Eigen::Index>(i)) * kernel->evaluate(centres[i], s);
      return sum;
    };
    const auto limit = averaged_limit(*kernel, centres, road, {}, solver);
    CHECK(limit.quadrature_converged);
    CHECK(limit.solve_method == "cholesky");
    INFO("condition number of Mbar " << limit.spectrum.condition_number);
    CHECK(relative_difference(limit.coefficients, a) < 1e-10);
  }
}

TEST_CASE("Galerkin orthogonality, checked with an independent periodic trapezoid rule",
          "[averaged_limit]") {
  // The periodised Gaussian and a trigonometric road are smooth and periodic on the track: the
  // M-point rectangle rule is spectrally accurate for their products (at M = 1024 its error is
  // far below round-off), and shares no node or weight with the Gauss-Legendre rule.
  const auto kernel = test::make_registered_kernel("gaussian", {{"sigma", 1.0}}, track);
  for (std::size_t n : {10u, 16u}) {
    INFO("n = " << n);
    const auto centres = uniform_centres(n, track);
    const auto limit = averaged_limit(*kernel, centres, two_tone_road, {}, solver);
    REQUIRE(limit.quadrature_converged);
    const auto grid = track.uniform_points(1024);
    const Eigen::MatrixXd phi = kernel->cross(grid, centres);
    Eigen::VectorXd f(static_cast<Eigen::Index>(grid.size()));
    for (std::size_t m = 0; m < grid.size(); ++m)
      f(static_cast<Eigen::Index>(m)) = two_tone_road(grid[m]);
    const double weight = track.length / static_cast<double>(grid.size());
    const Eigen::VectorXd residual = f - phi * limit.coefficients;
    const Eigen::VectorXd inner = weight * phi.transpose() * residual;  // (f - P f, phi_i)
    const double f_norm = std::sqrt(weight * f.squaredNorm());
    for (Eigen::Index i = 0; i < inner.size(); ++i) {
      const double phi_norm = std::sqrt(weight * phi.col(i).squaredNorm());
      INFO("i = " << i);
      CHECK(std::abs(inner(i)) <= 1e-12 * f_norm * phi_norm);
    }
    // The independent rule gives the same Mbar and bbar.
    const Eigen::MatrixXd gram = weight * phi.transpose() * phi / track.length;
    const Eigen::VectorXd load = weight * phi.transpose() * f / track.length;
    const double scale = gram.diagonal().maxCoeff();
    CHECK((gram - limit.averaged_gram).cwiseAbs().maxCoeff() <= 1e-14 * scale);
    CHECK((load - limit.averaged_load).cwiseAbs().maxCoeff() <= 1e-14 * std::sqrt(scale) * 2);
    // The projection is the best approximation in L2: no worse than the interpolant Pi_n f.
    Eigen::VectorXd at_centres(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i)
      at_centres(static_cast<Eigen::Index>(i)) = two_tone_road(centres[i]);
    const Eigen::VectorXd interpolant = kernel->gram(centres).llt().solve(at_centres);
    const double projection_error = residual.norm();
    const double interpolant_error = (f - phi * interpolant).norm();
    CHECK(projection_error < interpolant_error);
  }
}

TEST_CASE("Mbar of hat functions equals its closed form", "[averaged_limit]") {
  // The degree-1 B-spline kernel's sections are piecewise linear between the finest knots
  // s_k = k L / (n0 2^J), so int phi_i phi_j over [s_k, s_k+1] is exactly
  // h / 6 (2 a_i a_j + a_i b_j + b_i a_j + 2 b_i b_j) with a = phi(s_k), b = phi(s_k+1).
  for (std::int64_t levels : {3, 6}) {
    INFO("J = " << levels);
    const auto kernel = test::make_registered_kernel(
        "bspline", {{"degree", std::int64_t{1}}, {"J", levels}}, track);
    const auto centres = uniform_centres(12, track);
    const auto limit = averaged_limit(*kernel, centres, sine_road, {}, solver);
    const std::size_t cells = std::size_t{4} << levels;
    const double h = track.length / static_cast<double>(cells);
    Eigen::MatrixXd closed = Eigen::MatrixXd::Zero(12, 12);
    for (std::size_t k = 0; k < cells; ++k) {
      const double left = h * static_cast<double>(k), right = h * static_cast<double>(k + 1);
      for (std::size_t i = 0; i < 12; ++i)
        for (std::size_t j = 0; j < 12; ++j) {
          const double ai = kernel->evaluate(centres[i], left);
          const double bi = kernel->evaluate(centres[i], right);
          const double aj = kernel->evaluate(centres[j], left);
          const double bj = kernel->evaluate(centres[j], right);
          closed(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) +=
              h / 6 * (2 * ai * aj + ai * bj + bi * aj + 2 * bi * bj);
        }
    }
    closed /= track.length;
    CHECK((closed - limit.averaged_gram).cwiseAbs().maxCoeff() <=
          1e-14 * closed.diagonal().maxCoeff());
    CHECK(limit.averaged_gram.isApprox(limit.averaged_gram.transpose(), 0.0));
  }
}

TEST_CASE("the quadrature is converged: doubling the panels changes alpha by < 1e-12",
          "[averaged_limit]") {
  struct Case {
    std::string name;
    Given given;
    std::size_t n;
  };
  const std::vector<Case> cases{{"gaussian", {{"sigma", 1.0}}, 16},
                                {"gaussian", {{"sigma", 0.1}}, 60},
                                {"bspline", {{"degree", std::int64_t{1}}}, 16},
                                {"bspline", {{"degree", std::int64_t{2}}}, 8},
                                {"wendland", {{"k", std::int64_t{2}}, {"radius", 2.0}}, 20}};
  for (const auto& c : cases) {
    INFO(c.name << " n = " << c.n);
    const auto kernel = test::make_registered_kernel(c.name, c.given, track);
    const auto centres = uniform_centres(c.n, track);
    const auto limit = averaged_limit(*kernel, centres, two_tone_road, {}, solver);
    REQUIRE(limit.quadrature_converged);
    CHECK(limit.quadrature_change <= 1e-14);
    AveragedLimitQuadrature finer;
    finer.min_refinements = limit.refinements + 1;
    const auto doubled = averaged_limit(*kernel, centres, two_tone_road, {}, solver, finer);
    CHECK(doubled.quadrature_nodes == 2 * limit.quadrature_nodes);
    CHECK(doubled.panels == 2 * limit.panels);
    // The coefficients where Mbar is well conditioned (round-off in Mbar is amplified by its
    // condition number), the projection itself (its L2 norm, sqrt(a^T Mbar a)) always.
    INFO("condition number of Mbar " << limit.spectrum.condition_number);
    if (limit.spectrum.condition_number < 1e3)
      CHECK(relative_difference(doubled.coefficients, limit.coefficients) < 1e-12);
    const Eigen::VectorXd change = doubled.coefficients - limit.coefficients;
    CHECK(std::sqrt(change.dot(limit.averaged_gram * change)) <
          1e-12 * std::sqrt(limit.coefficients.dot(limit.averaged_gram * limit.coefficients)));
    CHECK((doubled.averaged_gram - limit.averaged_gram).cwiseAbs().maxCoeff() <=
          1e-14 * limit.averaged_gram.diagonal().maxCoeff());
  }
}

TEST_CASE("the rule's size for the paper's kernels on the radius-4 track", "[averaged_limit]") {
  // Gaussian sigma = 1: 32 panels of L / 32, accepted after one doubling (64 x 12 nodes).
  // B-splines J = 6 (n0 = 4): 256 knot intervals, one panel each, accepted after one doubling
  // (512 x 12 nodes); q = 12 integrates phi phi^T exactly there, phi f to round-off.
  const auto gaussian = test::make_registered_kernel("gaussian", {{"sigma", 1.0}}, track);
  const auto centres = uniform_centres(50, track);
  const auto g = averaged_limit(*gaussian, centres, sine_road, {}, solver);
  CHECK(g.quadrature_converged);
  CHECK(g.refinements == 1);
  CHECK(g.quadrature_nodes == 768);
  for (std::int64_t degree : {1, 2}) {
    INFO("degree " << degree);
    const auto bspline = test::make_registered_kernel(
        "bspline", {{"degree", degree}, {"J", std::int64_t{6}}}, track);
    const auto b = averaged_limit(*bspline, centres, sine_road, {}, solver);
    CHECK(b.quadrature_converged);
    CHECK(b.refinements == 1);
    CHECK(b.quadrature_nodes == 6144);
  }
}

TEST_CASE("the averaged limit refuses what it cannot integrate and says when it stops",
          "[averaged_limit]") {
  const auto kernel = test::make_registered_kernel("gaussian", {{"sigma", 1.0}}, track);
  const auto centres = uniform_centres(8, track);
  CHECK_THROWS_AS(averaged_limit(*kernel, std::vector<double>{}, sine_road, {}, solver),
                  std::invalid_argument);
  AveragedLimitQuadrature none;
  none.nodes_per_panel = 0;
  CHECK_THROWS_AS(averaged_limit(*kernel, centres, sine_road, {}, solver, none),
                  std::invalid_argument);
  // A road with a kink it does not declare converges only algebraically: the node budget stops
  // the refinement, and the result says so.
  const auto kinked = [](double s) { return std::abs(s - 10.0); };
  AveragedLimitQuadrature budget;
  budget.max_nodes = 20000;
  const auto stopped = averaged_limit(*kernel, centres, kinked, {}, solver, budget);
  CHECK_FALSE(stopped.quadrature_converged);
  CHECK(stopped.quadrature_change > 1e-14);
  CHECK(stopped.quadrature_nodes <= 20000);
  // Declared, the kink is a breakpoint and the rule converges.
  const std::vector<double> kink{10.0};
  const auto declared = averaged_limit(*kernel, centres, kinked, kink, solver, budget);
  CHECK(declared.quadrature_converged);
  CHECK(relative_difference(stopped.coefficients, declared.coefficients) < 1e-6);
}

TEST_CASE("adaptive trials measure the L2 projection and the estimate's gap to it",
          "[averaged_limit][adaptive]") {
  // A scalar plant (time constant 1 s) on a slow lap (2513 s) with a gain that learns a few
  // percent per lap: the averaging regime. After 20 laps fhat(T) is close to P_L2 f, the
  // averaged limit, and far from Pi_n f (measured: gap to P_L2 f 0.059, to Pi_n f 1.31).
  const std::string study = R"(
[study]
name = "averaged"
kind = "adaptive"
evaluation_points = 1024
metrics = ["l2_error", "interpolant_l2_error", "gap_to_projection", "l2_projection_l2_error",
           "l2_projection_sup_error", "gap_to_l2_projection"]
[domain]
radius = 4.0
[grid]
n = [8]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[target]]
name = "sine"
amplitude = 2.0
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 300
[[law]]
name = "gradient"
gamma = 300
[[integrator]]
name = "rodas4"
rtol = 1e-7
atol = 1e-9
[adaptive]
speed = 0.01
laps = 20
)";
  const auto out = test::run_study_text(study, "averaged.toml");
  REQUIRE(out.trials.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    INFO(out.trials[i].adaptive_axes().law.name);
    const double projection_error = out.metric(i, "l2_projection_l2_error");
    CHECK(projection_error > 0.1);  // n = 8 Gaussians resolve the sine only roughly
    // The best approximation in L2 is no worse than the interpolant, nor than fhat(T).
    CHECK(projection_error <= out.metric(i, "interpolant_l2_error"));
    CHECK(projection_error <= out.metric(i, "l2_error"));
    CHECK(out.metric(i, "l2_projection_sup_error") >= projection_error / std::sqrt(track.length));
    CHECK(out.metric(i, "gap_to_l2_projection") < 0.1 * out.metric(i, "gap_to_projection"));
  }
  // A road in H_n (Pi_n f) is its own L2 projection.
  const auto projected =
      test::run_study_text(study + "road = \"projection\"\n", "averaged_projection.toml");
  for (std::size_t i = 0; i < 2; ++i) {
    INFO(projected.trials[i].adaptive_axes().law.name);
    CHECK(projected.metric(i, "l2_projection_l2_error") < 1e-10);
    CHECK(projected.metric(i, "l2_projection_sup_error") < 1e-10);
  }
}
