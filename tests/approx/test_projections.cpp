// The contract of every projection (projection.hpp): idempotent, nested and H-orthogonal where
// declared, convergent, and its norms against independent computations (the power function,
// the H-orthogonal projection's norm 1).
#include <catch2/catch.hpp>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <random>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/kernel/kernel.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<AnyKernel> kernel(const std::string& name, std::map<std::string, ParameterValue> p,
                                  const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, p), domain);
}

std::unique_ptr<Projection> projection(const std::string& name) {
  const auto* entry = projection_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {}));
}

ProjectionOperator build(const std::string& name, const AnyKernel& k, std::size_t n,
                         std::span<const double> centres = {}) {
  return build_projection(
      name, ParameterSet::resolve(projection_registry().find(name)->info.parameters, {}),
      ProjectionRequest{k, n, centres, {}});
}

/// A function of H: f = sum_t a_t k(t, .) at seeded random points and coefficients.
struct FunctionInH {
  std::vector<double> points;
  Eigen::VectorXd coefficients;
  Eigen::VectorXd at(const AnyKernel& k, std::span<const double> s) const {
    return k.cross(s, points) * coefficients;
  }
};

FunctionInH function_in_h(const Domain& domain, std::uint64_t seed, int count = 40) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> where(0.0, domain.length), value(-1.0, 1.0);
  FunctionInH f;
  for (int i = 0; i < count; ++i) f.points.push_back(where(random));
  f.coefficients = Eigen::VectorXd::NullaryExpr(count, [&] { return value(random); });
  return f;
}

std::vector<double> uniform(std::size_t n, const Domain& domain) {
  std::vector<double> c(n);
  for (std::size_t i = 0; i < n; ++i) c[i] = domain.length * (i + 0.5) / n;
  return c;
}

const std::vector<std::string> level_projections{"mra_level", "l2_projection", "quasi_interpolant"};

}  // namespace

TEST_CASE("every built-in projection is registered with what it declares", "[projection]") {
  for (const auto* name : {"interpolation", "mra_level", "l2_projection", "quasi_interpolant"}) {
    INFO(name);
    REQUIRE(projection_registry().find(name));
  }
  CHECK(projection("interpolation")->properties().h_orthogonal);
  CHECK(projection("mra_level")->properties().h_orthogonal);
  CHECK_FALSE(projection("l2_projection")->properties().h_orthogonal);
  CHECK_FALSE(projection("quasi_interpolant")->properties().h_orthogonal);
  CHECK_FALSE(projection("quasi_interpolant")->properties().nested);
  CHECK(projection("mra_level")->properties().operator_norm_bound == 1.0);
  CHECK(describe_projection(projection("mra_level")->properties()) ==
        "resolution: level j (n = n0 2^j cells), nested, H-orthogonal, ||Pi_j||_(H->H) <= 1, "
        "kernel: bspline");
}

TEST_CASE("level projections: idempotent, nested and H-orthogonal as declared", "[projection]") {
  for (const bool periodic : {true, false})
    for (const int degree : {1, 2, 3}) {
      const Domain domain{8.0, periodic};
      const auto k = kernel(
          "bspline",
          {{"degree", std::int64_t{degree}}, {"n0", std::int64_t{4}}, {"J", std::int64_t{5}}},
          domain);
      const auto f = function_in_h(domain, 7 + degree);
      const auto grid = domain.uniform_points(997);
      for (const auto& name : level_projections) {
        INFO(name << " degree " << degree << (periodic ? " periodic" : " interval"));
        const auto properties = projection(name)->properties();
        const auto coarse = build(name, *k, 8);  // j = 1
        const auto fine = build(name, *k, 32);   // j = 3
        CHECK(coarse.level == 1);
        CHECK(coarse.dimension() == (periodic ? 8u : 8u + degree));
        const double scale = f.at(*k, grid).cwiseAbs().maxCoeff();

        // Pi Pi f = Pi f.
        const Eigen::VectorXd once = apply_projection(*k, coarse, f.at(*k, coarse.samples()), grid);
        const Eigen::VectorXd at_samples =
            apply_projection(*k, coarse, f.at(*k, coarse.samples()), coarse.samples());
        const Eigen::VectorXd twice = apply_projection(*k, coarse, at_samples, grid);
        CHECK((twice - once).cwiseAbs().maxCoeff() < 1e-9 * scale);

        // Pi_j Pi_k f = Pi_j f for j <= k exactly when declared nested.
        const Eigen::VectorXd fine_at_coarse_samples =
            apply_projection(*k, fine, f.at(*k, fine.samples()), coarse.samples());
        const Eigen::VectorXd nested = apply_projection(*k, coarse, fine_at_coarse_samples, grid);
        const double nested_gap = (nested - once).cwiseAbs().maxCoeff();
        if (properties.nested)
          CHECK(nested_gap < 1e-9 * scale);
        else
          CHECK(nested_gap > 1e-6 * scale);

        // (f - Pi f, b_i)_H = 0 for every basis function exactly when declared H-orthogonal:
        // (f, b_i)_H = sum_t a_t b_i(t) and (Pi f, b_i)_H = (G_B c)_i.
        const Eigen::VectorXd c = coarse.weights() * f.at(*k, coarse.samples());
        const Eigen::VectorXd f_dot_b =
            projection_basis_values(*k, coarse, f.points).transpose() * f.coefficients;
        const Eigen::VectorXd pif_dot_b = projection_basis_gram(*k, coarse) * c;
        const double orthogonality =
            (f_dot_b - pif_dot_b).cwiseAbs().maxCoeff() / f_dot_b.cwiseAbs().maxCoeff();
        if (properties.h_orthogonal)
          CHECK(orthogonality < 1e-8);
        else
          CHECK(orthogonality > 1e-6);

        // ||Pi||_{H -> H}: 1 for the H-orthogonal projection, at least 1 for any projection.
        const double norm = projection_operator_norm(*k, coarse);
        if (properties.h_orthogonal)
          CHECK(norm == Approx(1.0).epsilon(1e-8));
        else
          CHECK(norm > 1.0 - 1e-8);
      }
    }
}

TEST_CASE("level projections reproduce their own space and converge", "[projection]") {
  const Domain domain{8.0, true};
  const auto k = kernel("bspline", {{"degree", std::int64_t{2}}, {"J", std::int64_t{7}}}, domain);
  const auto grid = domain.uniform_points(2003);
  const auto* sine_entry = target_registry().find("sine");
  const auto sine =
      sine_entry->factory(ParameterSet::resolve(sine_entry->info.parameters, {}), domain);
  Eigen::VectorXd truth(static_cast<Eigen::Index>(grid.size()));
  sine->evaluate(grid, std::span<double>(truth.data(), grid.size()));
  for (const auto& name : level_projections) {
    INFO(name);
    // A spline of level 2 is reproduced by every level j >= 2.
    const auto level2 = build(name, *k, 16);
    const Eigen::VectorXd spline = projection_basis_values(*k, level2, grid).col(3) -
                                   0.5 * projection_basis_values(*k, level2, grid).col(9);
    const auto level4 = build(name, *k, 64);
    const Eigen::VectorXd spline_at_samples =
        projection_basis_values(*k, level2, level4.samples()).col(3) -
        0.5 * projection_basis_values(*k, level2, level4.samples()).col(9);
    CHECK((apply_projection(*k, level4, spline_at_samples, grid) - spline).cwiseAbs().maxCoeff() <
          1e-9);
    // Pi_j f -> f for the sine: the sup error falls at least 3x per level over j = 1..5
    // (h^3 of a local degree-2 quasi-interpolant would be 8x).
    double previous = INFINITY;
    for (std::size_t n = 8; n <= 128; n *= 2) {
      const auto op = build(name, *k, n);
      Eigen::VectorXd at_samples(static_cast<Eigen::Index>(op.samples().size()));
      sine->evaluate(op.samples(), std::span<double>(at_samples.data(), op.samples().size()));
      const double error =
          (apply_projection(*k, op, at_samples, grid) - truth).cwiseAbs().maxCoeff();
      CHECK(error < previous / 3);
      previous = error;
    }
  }
}

TEST_CASE("interpolation: ||I - Pi||_{H -> C} is the power function", "[projection]") {
  const Domain domain{2 * std::numbers::pi * 4, true};
  const auto gaussian = kernel("gaussian", {{"sigma", 1.0}}, domain);
  const auto wendland = kernel("wendland", {}, domain);
  const auto bspline = kernel("bspline", {{"degree", std::int64_t{2}}}, domain);
  for (const AnyKernel* k : {gaussian.get(), wendland.get(), bspline.get()}) {
    INFO(k->name());
    const auto centres = uniform(24, domain);
    const auto op = build("interpolation", *k, centres.size(), centres);
    const auto grid = domain.uniform_points(1000);
    const Eigen::VectorXd residual = projection_residual_norms(*k, op, grid);
    const GramSolver solver(k->gram(centres), {});
    const Eigen::VectorXd power = power_function(*k, solver, centres, grid);
    // The sups (the metrics) to 1e-10; pointwise, the squares to 1e-12 k(s, s) (next to the
    // centres both are square roots of round-off).
    INFO(std::setprecision(17) << residual.maxCoeff() << " vs " << power.maxCoeff());
    CHECK(std::abs(residual.maxCoeff() - power.maxCoeff()) < 1e-10 * power.maxCoeff());
    CHECK((residual.cwiseAbs2() - power.cwiseAbs2()).cwiseAbs().maxCoeff() <
          1e-12 * k->diagonal(grid).maxCoeff());
    CHECK(projection_operator_norm(*k, op) == Approx(1.0).epsilon(1e-8));
  }
}

TEST_CASE(
    "||Pi||_{H -> H}'s floor covers the round-off of a basis built from ill-conditioned solves",
    "[projection][floor]") {
  // The H-orthogonal interpolation projection has norm exactly 1. Its orthonormal basis and
  // weights are solves with the Gram matrix G, so the computed norm misses 1 by about
  // n eps cond(G), and the floor must say so: a floor from the basis Gram matrix alone
  // (n eps cond(G_B) / 2, cond(G_B) = 1 for an orthonormal basis) was 1600 times too small on
  // Theorem 4.1's second-order B-splines at n = 64.
  const Domain domain{2 * std::numbers::pi * 4, true};
  const auto gaussian = kernel("gaussian", {{"sigma", 2.0}}, domain);
  const auto bspline = kernel("bspline", {{"degree", std::int64_t{2}}}, domain);
  for (const AnyKernel* k : {gaussian.get(), bspline.get()})
    for (std::size_t n : {8, 16, 24, 32}) {
      const auto centres = uniform(n, domain);
      const GramSolver solver(k->gram(centres), {});
      const double condition = solver.spectrum().condition_number;
      const auto op = build("interpolation", *k, n, centres);
      double floor = 0;
      const double norm = projection_operator_norm(*k, op, &floor);
      const double round_off = static_cast<double>(n) * std::numeric_limits<double>::epsilon();
      INFO(k->name() << " n = " << n << ": cond(G) = " << condition
                     << ", |norm - 1| = " << std::abs(norm - 1) << ", floor = " << floor);
      CHECK(std::abs(norm - 1) <= floor);
      // ... and is not inflated beyond the conditioning it accounts for.
      CHECK(floor >= 0.5 * round_off * condition);
      CHECK(floor <= 4 * round_off * condition);
    }
}

TEST_CASE("mra_level: ||I - Pi_j||_{H -> C} is the power function of V_j", "[projection]") {
  const Domain domain{8.0, false};
  const auto k = kernel("bspline", {{"degree", std::int64_t{1}}, {"J", std::int64_t{5}}}, domain);
  const auto op = build("mra_level", *k, 16);
  const auto grid = domain.uniform_points(801);
  const Eigen::VectorXd residual = projection_residual_norms(*k, op, grid);
  // P_j(s)^2 = k(s, s) - b(s)^T G_B^-1 b(s), an independent formula for the same number.
  const Eigen::MatrixXd b = projection_basis_values(*k, op, grid);
  const Eigen::MatrixXd gram = projection_basis_gram(*k, op);
  const Eigen::MatrixXd solved = gram.llt().solve(Eigen::MatrixXd(b.transpose()));
  const Eigen::VectorXd diagonal = k->diagonal(grid);
  for (Eigen::Index m = 0; m < b.rows(); ++m) {
    const double power = std::sqrt(std::max(0.0, diagonal[m] - b.row(m).dot(solved.col(m))));
    CHECK(residual[m] == Approx(power).margin(1e-7 * diagonal.maxCoeff()));
  }
  // Another projection Q onto the same V_j has I - Q = (I - Q)(I - Pi_j), so
  // ||I - Q||_{H -> C} <= (1 + ||Q||_{C -> C}) ||I - Pi_j||_{H -> C}, with ||Q||_{C -> C} the
  // Lebesgue constant max_s sum_m |c_m(s)|, c(s) = W^T b(s).
  for (const auto* name : {"l2_projection", "quasi_interpolant"}) {
    INFO(name);
    const auto other = build(name, *k, 16);
    const Eigen::MatrixXd c =
        other.weights().transpose() * projection_basis_values(*k, other, grid).transpose();
    const double lebesgue = c.cwiseAbs().colwise().sum().maxCoeff();
    CHECK(lebesgue < 4.0);
    CHECK(projection_residual_norms(*k, other, grid).maxCoeff() <=
          (1 + lebesgue) * residual.maxCoeff());
  }
}

TEST_CASE("projections refuse what they cannot build, naming it", "[projection]") {
  const Domain domain{8.0, true};
  const auto gaussian = kernel("gaussian", {}, domain);
  const auto bspline = kernel("bspline", {{"J", std::int64_t{3}}}, domain);
  CHECK_THROWS_WITH(
      build("mra_level", *gaussian, 8),
      Catch::Contains("works with the bspline kernel only") && Catch::Contains("'gaussian'"));
  CHECK_THROWS_WITH(build("quasi_interpolant", *bspline, 24),
                    Catch::Contains("n = 24 is not n0 = 4 times a power of 2"));
  CHECK_THROWS_WITH(build("l2_projection", *bspline, 64),
                    Catch::Contains("level j = 4, finer than the kernel's finest level J = 3"));
  CHECK_THROWS_AS(projection("mra_level")->check(*bspline, 24), std::invalid_argument);
  CHECK_NOTHROW(projection("mra_level")->check(*bspline, 32));
  CHECK_THROWS_WITH(build("interpolation", *bspline, 0), Catch::Contains("needs centres"));
}
