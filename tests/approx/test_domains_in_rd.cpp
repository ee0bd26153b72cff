// Domains, kernels, centres, targets and approximation metrics in R^d (d = 2, 3), against closed
// forms, identities and independent computations.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"

using namespace rkhs;

namespace {

using Given = std::map<std::string, ParameterValue>;

Domain box(double length, double width, bool periodic = false) {
  Domain d{length, periodic};
  d.dimension = 2;
  d.width = width;
  return d;
}

Domain cube(double side, bool periodic = false) {
  Domain d{side, periodic};
  d.dimension = 3;
  d.width = side;
  d.height = side;
  return d;
}

std::unique_ptr<AnyKernel> kernel(const std::string& name, const Given& given,
                                  const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

std::unique_ptr<TargetFunction> expression(const std::string& f, const Domain& domain,
                                           Given given = {}) {
  const auto* entry = target_registry().find("expression");
  REQUIRE(entry);
  given["f"] = f;
  return entry->factory(
      ParameterSet::resolve(entry->info.parameters, given,
                            entry->info.user_parameters ? &*entry->info.user_parameters : nullptr),
      domain);
}

std::vector<double> centres(const std::string& name, std::size_t n, const Domain& domain,
                            const Given& given = {}) {
  const auto* entry = centre_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given))->place(n, domain, 0);
}

double k_at(const AnyKernel& k, std::vector<double> x, std::vector<double> y) {
  return k.evaluate_point(x, y);
}

// int_r^1 t g(t) dt by composite Simpson on `intervals` panels: Wendland's operator I.
double integrate_I(const std::function<double(double)>& g, double r, int intervals = 2000) {
  const double h = (1.0 - r) / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double t = r + i * h;
    const double w = (i == 0 || i == intervals) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    sum += w * t * g(t);
  }
  return sum * h / 3.0;
}

}  // namespace

TEST_CASE("a box's uniform points are the tensor grid and its L2 rule is exact where it must be",
          "[domain][rd]") {
  const Domain rectangle = box(2.0, 3.0);
  REQUIRE_NOTHROW(rectangle.validate());
  CHECK(rectangle.volume() == 6.0);
  const auto points = rectangle.uniform_points(16);  // 4 x 4, end points included
  REQUIRE(points.size() == 32);
  CHECK(rectangle.point_count(points) == 16);
  CHECK(points[0] == 0.0);
  CHECK(points[1] == 0.0);
  CHECK(points[2] == Approx(2.0 / 3));  // axis 1 varies fastest
  CHECK(points[3] == 0.0);
  CHECK(points[30] == 2.0);
  CHECK(points[31] == 3.0);
  // The tensor trapezoid rule integrates bilinear functions exactly: f^2 = x1 x2, so
  // ||f||^2 = (2^2 / 2)(3^2 / 2) = 9.
  const auto grid = rectangle.uniform_points(900);
  std::vector<double> f(rectangle.point_count(grid));
  for (std::size_t p = 0; p < f.size(); ++p) f[p] = std::sqrt(grid[2 * p] * grid[2 * p + 1]);
  CHECK(rectangle.l2_norm(f) == Approx(3.0).epsilon(1e-13));
  // On a torus the rectangle rule integrates trigonometric polynomials exactly:
  // ||sin(2 pi x1 / L1) cos(4 pi x2 / L2)||^2 = L1 L2 / 4.
  const Domain torus = box(2.0, 3.0, true);
  const auto torus_grid = torus.uniform_points(400);
  std::vector<double> g(torus.point_count(torus_grid));
  for (std::size_t p = 0; p < g.size(); ++p)
    g[p] = std::sin(std::numbers::pi * torus_grid[2 * p]) *
           std::cos(4 * std::numbers::pi * torus_grid[2 * p + 1] / 3);
  CHECK(torus.l2_norm(g) == Approx(std::sqrt(1.5)).epsilon(1e-13));
  // A value count that is no tensor grid is refused.
  CHECK_THROWS_AS(rectangle.l2_norm(std::vector<double>(15, 1.0)), std::invalid_argument);
  // Torus differences take the nearest image on each axis.
  CHECK(torus.difference(1.9, 0.1, 0) == Approx(-0.2));
  CHECK(torus.difference(0.1, 2.8, 1) == Approx(0.3));
  Domain bad = box(1.0, 0.0);
  CHECK_THROWS_WITH(bad.validate(), "domain width must be between 1e-100 and 1e+100 metres, not 0");
  // Beyond Domain::max_extent the numerics on the domain overflow: refused like a 0.
  Domain huge = box(1e101, 1.0);
  CHECK_THROWS_WITH(huge.validate(),
                    "domain length must be between 1e-100 and 1e+100 metres, not 1e+101");
}

TEST_CASE("fill and separation distances in the plane and in space against closed forms",
          "[approximation][rd]") {
  const Domain square = box(1.0, 1.0);
  // One centre: the farthest point of the square is a corner.
  const std::vector<double> one{0.2, 0.3};
  CHECK(fill_distance(one, square) == Approx(std::sqrt(0.8 * 0.8 + 0.7 * 0.7)).epsilon(1e-9));
  CHECK(std::isnan(separation_distance(one, square)));
  // The m x m grid with end points: h is half a cell's diagonal, q half the spacing.
  for (const std::size_t m : {3, 6, 11}) {
    const auto grid = centres("uniform", m * m, square);
    const double spacing = 1.0 / static_cast<double>(m - 1);
    CHECK(fill_distance(grid, square) == Approx(spacing * std::sqrt(2.0) / 2).epsilon(1e-9));
    CHECK(separation_distance(grid, square) == Approx(spacing / 2).epsilon(1e-12));
  }
  // On the torus the grid's spacing is 1/m and the cell centre is again farthest.
  const Domain torus = box(1.0, 1.0, true);
  const auto periodic_grid = centres("uniform", 25, torus);
  CHECK(fill_distance(periodic_grid, torus) == Approx(0.2 * std::sqrt(2.0) / 2).epsilon(1e-9));
  CHECK(separation_distance(periodic_grid, torus) == Approx(0.1).epsilon(1e-12));
  // The unit cube with its 2 x 2 x 2 corners: the centre is sqrt(3)/2 from each.
  const Domain unit_cube = cube(1.0);
  const auto corners = centres("uniform", 8, unit_cube);
  CHECK(fill_distance(corners, unit_cube) == Approx(std::sqrt(3.0) / 2).epsilon(1e-9));
  CHECK(separation_distance(corners, unit_cube) == Approx(0.5).epsilon(1e-12));
}

TEST_CASE("centre placements in d dimensions", "[centres][rd]") {
  const Domain rectangle = box(2.0, 1.0);
  SECTION("the grid needs n = m^d and says which n would do") {
    const auto grid = centres("uniform", 9, rectangle);
    REQUIRE(grid.size() == 18);
    CHECK(grid[0] == 0.0);
    CHECK(grid[2] == 1.0);
    CHECK(grid[4] == 2.0);
    CHECK(grid[17] == 1.0);
    CHECK_THROWS_WITH(centres("uniform", 10, rectangle),
                      "centres 'uniform' in d = 2 place a grid of m^2 centres; n = 10 is not such "
                      "a number (nearest: 9, 16)");
  }
  SECTION("Halton points are the radical inverses in bases 2, 3 and 5") {
    const auto points = centres("halton", 3, cube(1.0));
    const std::vector<double> expected{0.5, 1.0 / 3, 0.2, 0.25, 2.0 / 3, 0.4, 0.75, 1.0 / 9, 0.6};
    REQUIRE(points.size() == 9);
    for (std::size_t i = 0; i < 9; ++i) CHECK(points[i] == Approx(expected[i]).epsilon(1e-15));
    // Scaled to the axes, and nested: the first n of 2n are the n.
    const auto scaled = centres("halton", 4, rectangle);
    CHECK(scaled[0] == 1.0);
    CHECK(scaled[1] == Approx(1.0 / 3));
    const auto more = centres("halton", 8, rectangle);
    CHECK(std::equal(scaled.begin(), scaled.end(), more.begin()));
  }
  SECTION("passes: n / passes centres on each straight pass, and h stays at the lateral gap") {
    const Domain square = box(1.0, 1.0);
    const auto on_passes = centres("passes", 10, square);  // 2 passes at x2 = 0.25, 0.75
    REQUIRE(on_passes.size() == 20);
    CHECK(on_passes[0] == 0.0);
    CHECK(on_passes[1] == 0.25);
    CHECK(on_passes[8] == 1.0);
    CHECK(on_passes[11] == 0.75);
    // Between the passes (x2 = 1/2) and halfway between two centres of a pass: the farthest
    // point, sqrt(1/4^2 + (s/2)^2) with s = 1/(m - 1) for m centres on a pass.
    for (const std::size_t m : {5, 17, 65}) {
      const auto c = centres("passes", 2 * m, square);
      const double half_spacing = 0.5 / static_cast<double>(m - 1);
      CHECK(fill_distance(c, square) ==
            Approx(std::sqrt(0.0625 + half_spacing * half_spacing)).epsilon(1e-9));
    }
    CHECK_THROWS_WITH(centres("passes", 9, square),
                      "centres 'passes' put n / passes centres on each of 2 passes; n = 9 is not "
                      "a multiple of 2");
    CHECK_THROWS_WITH(centres("passes", 8, Domain{1.0, false}),
                      "centres 'passes' lie on passes across a plane: they need a domain of "
                      "d = 2, this domain has d = 1");
  }
  SECTION("random centres are seeded and lie in the box") {
    const auto a = centres("random", 50, rectangle, {{"seed", std::int64_t{7}}});
    const auto b = centres("random", 50, rectangle, {{"seed", std::int64_t{7}}});
    const auto c = centres("random", 50, rectangle, {{"seed", std::int64_t{8}}});
    CHECK(a == b);
    CHECK(a != c);
    for (std::size_t p = 0; p < 50; ++p) {
      CHECK((a[2 * p] >= 0.0 && a[2 * p] < 2.0));
      CHECK((a[2 * p + 1] >= 0.0 && a[2 * p + 1] < 1.0));
    }
  }
}

TEST_CASE("Wendland's phi_{3,k} is Wendland's integral operator applied to (1 - r)^(k + 2)",
          "[kernel][wendland][rd]") {
  // phi_{3,k} = I^k (1 - r)_+^(k + 2) / its value at 0, with (I g)(r) = int_r^1 t g(t) dt,
  // computed here by nested Simpson rules, independently of the closed forms.
  const Domain unit_cube = cube(10.0);
  const std::function<double(double)> base1 = [](double t) { return std::pow(1 - t, 3); };
  const std::function<double(double)> base2 = [](double t) { return std::pow(1 - t, 4); };
  const std::function<double(double)> base3 = [](double t) { return std::pow(1 - t, 5); };
  const std::function<double(double)> once2 = [&](double t) { return integrate_I(base2, t, 400); };
  const std::function<double(double)> once3 = [&](double t) { return integrate_I(base3, t, 200); };
  const std::function<double(double)> twice3 = [&](double t) { return integrate_I(once3, t, 200); };
  std::vector<std::function<double(double)>> reference{
      [](double r) { return std::pow(1 - r, 2); },
      [&](double r) { return integrate_I(base1, r) / integrate_I(base1, 0); },
      [&](double r) { return integrate_I(once2, r, 400) / integrate_I(once2, 0, 400); },
      [&](double r) { return integrate_I(twice3, r, 200) / integrate_I(twice3, 0, 200); }};
  for (int k = 0; k <= 3; ++k) {
    CAPTURE(k);
    const auto w = kernel("wendland", {{"k", std::int64_t{k}}, {"radius", 2.0}}, unit_cube);
    CHECK(w->properties().dimension == 3);
    CHECK(*w->properties().sobolev_order == Approx(k + 2.0));
    for (const double r : {0.0, 0.1, 0.37, 0.5, 0.81, 0.99}) {
      CAPTURE(r);
      // Two points at distance 2 r along a diagonal direction (1, 2, 2) / 3.
      const double d = 2 * r / 3;
      const double value = k_at(*w, {1.0, 1.0, 1.0}, {1.0 + d, 1.0 + 2 * d, 1.0 + 2 * d});
      CHECK(value == Approx(reference[k](r)).epsilon(1e-6).margin(1e-10));
    }
    CHECK(k_at(*w, {1.0, 1.0, 1.0}, {3.0, 1.0, 1.0}) == 0.0);  // at the support radius
  }
  // In d = 2 the same functions, with tau = k + 3/2.
  const auto planar = kernel("wendland", {{"k", std::int64_t{1}}, {"radius", 2.0}}, box(4, 4));
  CHECK(*planar->properties().sobolev_order == Approx(2.5));
  CHECK(k_at(*planar, {0.1, 0.2}, {0.4, 0.6}) == Approx(std::pow(0.75, 4) * 2.0));
}

TEST_CASE("kernels on a torus: image sums against independent sums and the Gaussian's product",
          "[kernel][rd]") {
  const Domain torus = box(3.0, 2.0, true);
  SECTION("the periodic Gaussian in d = 2 is the product of the periodic Gaussians of the axes") {
    const auto planar = kernel("gaussian", {{"sigma", 0.9}}, torus);
    const auto along = kernel("gaussian", {{"sigma", 0.9}}, Domain{3.0, true});
    const auto across = kernel("gaussian", {{"sigma", 0.9}}, Domain{2.0, true});
    for (const auto& [x, y] : std::vector<std::pair<std::vector<double>, std::vector<double>>>{
             {{0.1, 0.2}, {2.9, 1.9}}, {{1.5, 1.0}, {0.0, 0.0}}, {{0.7, 0.3}, {0.7, 0.3}}})
      CHECK(k_at(*planar, x, y) ==
            Approx(along->evaluate(x[0], y[0]) * across->evaluate(x[1], y[1])).epsilon(1e-14));
  }
  SECTION("the periodic Wendland kernel is the sum over all lattice images") {
    const auto w = kernel("wendland", {{"k", std::int64_t{2}}, {"radius", 2.5}}, torus);
    const auto plain =
        kernel("wendland", {{"k", std::int64_t{2}}, {"radius", 2.5}}, box(100.0, 100.0));
    const std::vector<double> x{0.2, 1.7}, y{2.6, 0.1};
    double sum = 0.0;
    for (int m1 = -4; m1 <= 4; ++m1)
      for (int m2 = -4; m2 <= 4; ++m2)
        sum += k_at(*plain, {50.0, 50.0},
                    {50.0 + y[0] - x[0] + 3.0 * m1, 50.0 + y[1] - x[1] + 2.0 * m2});
    CHECK(k_at(*w, x, y) == Approx(sum).epsilon(1e-13));
    CHECK(k_at(*w, x, y) == Approx(k_at(*w, y, x)).epsilon(1e-15));
  }
  SECTION("Matern on a box is the profile of the distance; on a torus it is refused") {
    const auto planar = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.7}}, box(4, 4));
    const auto line = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.7}}, Domain{10.0, false});
    CHECK(k_at(*planar, {0.5, 0.5}, {1.1, 1.3}) == Approx(line->evaluate(0.0, 1.0)).epsilon(1e-15));
    CHECK(*planar->properties().sobolev_order == Approx(3.5));
    CHECK_THROWS_WITH(kernel("matern", {}, torus),
                      "the Matern kernel is not periodised on a torus (d = 2); use a box "
                      "(periodic = false)");
  }
}

TEST_CASE("Gram matrices in d = 2 and 3 are symmetric and positive definite", "[kernel][rd]") {
  const Domain space = cube(1.0);
  const auto points = centres("halton", 60, space);
  for (const auto& [name, given] : std::vector<std::pair<std::string, Given>>{
           {"wendland", {{"k", std::int64_t{0}}, {"radius", 0.6}}},
           {"wendland", {{"k", std::int64_t{3}}, {"radius", 1.5}}},
           {"gaussian", {{"sigma", 0.3}}},
           {"matern", {{"nu", 0.5}}}}) {
    CAPTURE(name);
    const auto k = kernel(name, given, space);
    const Eigen::MatrixXd gram = k->gram(points);
    REQUIRE(gram.rows() == 60);
    CHECK(gram.isApprox(gram.transpose(), 0.0));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram, Eigen::EigenvaluesOnly);
    CHECK(eigen.eigenvalues().minCoeff() > 0.0);
    // Entries against single evaluations.
    CHECK(gram(3, 17) ==
          k->evaluate_point(std::span(points).subspan(9, 3), std::span(points).subspan(51, 3)));
  }
}

namespace {
// A kernel with the one-dimensional form only.
struct LineOnly {
  static PluginInfo info() { return {"line_only", "test kernel", {}, {}}; }
  LineOnly(const ParameterSet&, const Domain&) {}
  double operator()(double x, double y) const noexcept { return std::exp(-(x - y) * (x - y)); }
  KernelProperties properties() const noexcept {
    KernelProperties p;
    p.analytic = true;
    return p;
  }
};
}  // namespace

TEST_CASE("kernels and targets of the arc length refuse a domain of d > 1", "[kernel][rd]") {
  const Domain square = box(1.0, 1.0);
  CHECK_THROWS_WITH(KernelModel<LineOnly>(ParameterSet{}, square),
                    "kernel 'line_only' is defined on one-dimensional domains only; this domain "
                    "has d = 2");
  const auto* sine = target_registry().find("sine");
  CHECK_THROWS_WITH(sine->factory(ParameterSet::resolve(sine->info.parameters, {}), square),
                    Catch::Contains("target 'sine' is a function of the arc length s (d = 1)"));
  const auto w = kernel("wendland", {}, square);
  CHECK_THROWS_AS(w->evaluate(0.1, 0.2), std::logic_error);
  CHECK_THROWS_AS(w->basis(std::vector<double>{0.1, 0.2}), std::logic_error);
}

TEST_CASE("the expression target in d = 2 reads x1, x2, L1 and L2", "[target][rd]") {
  const Domain rectangle = box(2.0, 3.0);
  const auto f = expression("a * x1 * L2 + x2 / L1", rectangle, {{"a", 2.0}});
  const std::vector<double> points{0.5, 1.0, 2.0, 3.0};
  std::vector<double> values(2);
  f->evaluate(points, values);
  CHECK(values[0] == Approx(2 * 0.5 * 3 + 0.5));
  CHECK(values[1] == Approx(2 * 2 * 3 + 1.5));
  CHECK_THROWS_WITH(
      expression("s + x1", rectangle),
      Catch::Contains(
          "found the unknown name \"s\", expected a variable or constant (x1, x2, L1, L2, pi)"));
  CHECK_THROWS_WITH(expression("x1", rectangle, {{"x2", 1.0}}),
                    Catch::Contains("parameter name 'x2' is taken: f reads x2 as a coordinate"));
  CHECK_THROWS_WITH(expression("log(x1 - 1)", rectangle),
                    Catch::Contains("is nan at x1 = 0, x2 = 0"));
}

TEST_CASE(
    "interpolation in d = 2: a kernel section is reproduced, the power function of one "
    "centre is the closed form",
    "[approximation][rd]") {
  const Domain square = box(1.0, 1.0);
  const auto gaussian = kernel("gaussian", {{"sigma", 1.0}}, square);
  SECTION("f = k((1/2, 1/2), .) at a 3 x 3 grid holding (1/2, 1/2)") {
    const auto f = expression("exp(-((x1 - 0.5)^2 + (x2 - 0.5)^2) / 2)", square);
    const auto grid = centres("uniform", 9, square);
    const auto measured = measure_approximation(*gaussian, *f, grid, 1024, SolverOptions{});
    CHECK(measured.metrics[ApproximationMetric::l2_error] < 1e-9);
    CHECK(measured.metrics[ApproximationMetric::interpolant_native_norm] ==
          Approx(1.0).epsilon(1e-9));  // ||k(c, .)||_H^2 = k(c, c) = 1
    CHECK(measured.metrics[ApproximationMetric::fill_distance] ==
          Approx(0.5 * std::sqrt(2.0) / 2).epsilon(1e-9));
  }
  SECTION("P(x)^2 = k(x, x) - k(x, c)^2 / k(c, c)") {
    const auto w = kernel("wendland", {{"k", std::int64_t{1}}, {"radius", 1.5}}, square);
    const std::vector<double> centre{0.3, 0.6};
    const GramSolver solver(w->gram(centre), SolverOptions{});
    const auto points = square.uniform_points(49);
    const Eigen::VectorXd power = power_function(*w, solver, centre, points);
    REQUIRE(power.size() == 49);
    for (Eigen::Index m = 0; m < power.size(); ++m) {
      const auto x = std::span<const double>(points).subspan(2 * m, 2);
      const double kxc = w->evaluate_point(x, centre);
      CHECK(power[m] == Approx(std::sqrt(1.0 - kxc * kxc)).epsilon(1e-12).margin(1e-7));
    }
  }
}

TEST_CASE("the multiscale B-spline kernel in d = 2: level sums of tensor-product splines",
          "[kernel][bspline][rd]") {
  // Level j of the d-dimensional kernel is 2^{j (d - 2r)} prod_a S_j(u_a, v_a), with S_j the
  // unweighted level sum of the line; S_j comes from the registered one-dimensional kernels,
  // (k_1D with levels 0..j) - (levels 0..j-1) = 2^{j (1 - 2r)} S_j, on each axis's own domain.
  const double r = 1.6;
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    const Domain plane = box(2.0, 1.5, periodic);
    const Given common{{"degree", std::int64_t{2}}, {"r", r}, {"n0", std::int64_t{3}}};
    auto with_levels = [&](int J, const Domain& domain) {
      Given given = common;
      given["J"] = std::int64_t{J};
      return kernel("bspline", given, domain);
    };
    const auto planar = with_levels(3, plane);
    CHECK(planar->properties().dimension == 2);
    CHECK(*planar->properties().sobolev_order == Approx(r));
    const Domain axis1{2.0, periodic}, axis2{1.5, periodic};
    const std::vector<std::vector<double>> pairs{
        {0.13, 0.4, 0.2, 0.55}, {1.9, 1.4, 0.05, 0.1}, {0.7, 0.7, 0.7, 0.7}, {1.0, 0.0, 1.2, 0.3}};
    for (const auto& p : pairs) {
      double expected = 0.0;
      for (int j = 0; j <= 3; ++j) {
        double product = std::exp2(j * (2 - 2 * r));
        for (const auto& [domain, a] : {std::pair{axis1, 0}, std::pair{axis2, 1}}) {
          const double finer = with_levels(j, domain)->evaluate(p[a], p[2 + a]);
          const double coarser = j ? with_levels(j - 1, domain)->evaluate(p[a], p[2 + a]) : 0.0;
          product *= (finer - coarser) / std::exp2(j * (1 - 2 * r));
        }
        expected += product;
      }
      CHECK(k_at(*planar, {p[0], p[1]}, {p[2], p[3]}) == Approx(expected).epsilon(1e-12));
    }
  }
  SECTION("partition of unity: each level integrates to the volume of one level-j cell") {
    // sum_k N(x - k) = 1 and int N = 1 give int_torus S_j(u, v) dv = prod_a h0_a 2^-j: on the
    // torus, level j of the kernel (k_J - k_{J-1}) integrates to 2^{j (d - 2r)} (h0_1 h0_2) 4^-j.
    const Domain torus = box(2.0, 1.5, true);
    const auto grid = torus.uniform_points(480 * 480);
    const auto count = torus.point_count(grid);
    const std::vector<double> u{0.37, 1.21};
    std::vector<double> at_u(2 * count);
    for (std::size_t p = 0; p < count; ++p) {
      at_u[2 * p] = u[0];
      at_u[2 * p + 1] = u[1];
    }
    double previous = 0.0;
    for (int J = 0; J <= 2; ++J) {
      Given given{
          {"degree", std::int64_t{1}}, {"r", r}, {"n0", std::int64_t{4}}, {"J", std::int64_t{J}}};
      const auto k = kernel("bspline", given, torus);
      // The rectangle rule of the torus: the integral is the mean times the area.
      const Eigen::MatrixXd row = k->cross(u, grid);
      const double integral = row.sum() * torus.volume() / static_cast<double>(count);
      const double cell = (2.0 / 4) * (1.5 / 4) / std::exp2(2.0 * J);
      CHECK(integral - previous == Approx(std::exp2(J * (2 - 2 * r)) * cell).epsilon(1e-4));
      previous = integral;
    }
  }
}

TEST_CASE("kernel gradients in d = 2 and 3: closed forms against formulas and differences",
          "[kernel][rd][gradient]") {
  // The Gaussian's gradient in closed form: grad_y exp(-|x - y|^2 / (2 sigma^2)) is
  // k (x - y) / sigma^2.
  const auto plane = box(2.0, 1.5);
  const auto gaussian = kernel("gaussian", {{"sigma", 0.4}}, plane);
  CHECK(gaussian->has_exact_gradient());
  const std::vector<double> x{0.7, 0.4}, y{1.1, 0.65};
  std::vector<double> g(2);
  gaussian->gradient_point(x, y, g);
  const double k = k_at(*gaussian, x, y);
  CHECK(g[0] == Approx(k * (x[0] - y[0]) / 0.16).epsilon(1e-13));
  CHECK(g[1] == Approx(k * (x[1] - y[1]) / 0.16).epsilon(1e-13));

  // Every built-in kernel, on boxes and tori of d = 2 and 3 (Matern on boxes only): the gradient
  // against central differences of evaluate_point with step 1e-5, at pairs away from the
  // sections' kinks (the centre, the support's sphere, the B-splines' knots).
  struct Case {
    std::string name;
    Given given;
    bool torus;
  };
  const std::vector<Case> cases{
      {"gaussian", {{"sigma", 0.4}}, false},
      {"gaussian", {{"sigma", 0.7}}, true},
      {"wendland", {{"k", std::int64_t{1}}, {"radius", 1.5}}, false},
      {"wendland", {{"k", std::int64_t{2}}, {"radius", 1.3}}, true},
      {"wendland", {{"k", std::int64_t{3}}, {"radius", 1.7}}, true},
      {"wendland", {{"k", std::int64_t{0}}, {"radius", 1.5}}, false},
      {"matern", {{"nu", 1.5}, {"length_scale", 0.5}}, false},
      {"matern", {{"nu", 2.5}, {"length_scale", 0.5}}, false},
      {"bspline",
       {{"degree", std::int64_t{3}}, {"n0", std::int64_t{4}}, {"J", std::int64_t{2}}},
       false},
      {"bspline",
       {{"degree", std::int64_t{3}}, {"n0", std::int64_t{4}}, {"J", std::int64_t{2}}},
       true}};
  for (const auto& c : cases)
    for (const Domain& domain : {box(2.0, 1.5, c.torus), cube(1.5, c.torus)}) {
      INFO(c.name << " d = " << domain.dimension << (c.torus ? " torus" : " box"));
      const auto kernel_under_test = kernel(c.name, c.given, domain);
      CHECK(kernel_under_test->has_exact_gradient());
      const auto d = static_cast<std::size_t>(domain.dimension);
      // Points at irrational fractions of the extents: never on a knot (multiples of 1/32 of an
      // extent) nor at a support's distance from each other to within the step.
      const std::vector<double> fractions{0.1234567, 0.3819660, 0.7071068,
                                          0.5772157, 0.8414710, 0.2718282};
      std::vector<double> centre(d), point(d), gradient(d), moved(d);
      for (std::size_t a = 0; a < d; ++a) {
        centre[a] = fractions[a] * domain.extent(static_cast<int>(a));
        point[a] = fractions[a + 3] * domain.extent(static_cast<int>(a));
      }
      kernel_under_test->gradient_point(centre, point, gradient);
      double largest = 0;
      for (std::size_t a = 0; a < d; ++a) largest = std::max(largest, std::abs(gradient[a]));
      CHECK(largest > 0);  // a pair within the support: the check is not empty
      const double h = 1e-5;
      for (std::size_t a = 0; a < d; ++a) {
        moved = point;
        moved[a] = point[a] + h;
        const double up = k_at(*kernel_under_test, centre, moved);
        moved[a] = point[a] - h;
        const double down = k_at(*kernel_under_test, centre, moved);
        CHECK(gradient[a] == Approx((up - down) / (2 * h)).margin(1e-7 * std::max(largest, 1.0)));
      }
    }

  // In d = 1 the gradient is the derivative of the sections.
  const Domain track{10.0, true};
  const auto wendland = kernel("wendland", {{"k", std::int64_t{2}}, {"radius", 3.0}}, track);
  std::vector<double> one(1);
  wendland->gradient_point(std::vector<double>{1.0}, std::vector<double>{2.5}, one);
  CHECK(one[0] == wendland->derivative(1.0, 2.5));
  CHECK_THROWS_AS(
      wendland->gradient_point(std::vector<double>{1.0, 2.0}, std::vector<double>{2.5}, one),
      std::invalid_argument);
}
