// Approximation metrics against closed forms and independent computations.
#include <catch2/catch.hpp>

#include <cmath>
#include <set>
#include <numbers>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/approx/target.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<AnyKernel> kernel(const std::string& name, std::map<std::string, ParameterValue> p,
                                  const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, p), domain);
}

std::unique_ptr<TargetFunction> sine(const Domain& domain, double amplitude = 2.0) {
  const auto* entry = target_registry().find("sine");
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {{"amplitude", amplitude}}),
                        domain);
}

std::size_t index_of(const std::string& metric) {
  const auto& names = approximation_metric_names();
  return std::find(names.begin(), names.end(), metric) - names.begin();
}

}  // namespace

TEST_CASE("fill and separation distances", "[approximation]") {
  const Domain circle{10.0, true};
  std::vector<double> uniform;
  for (int i = 0; i < 8; ++i) uniform.push_back(10.0 * i / 8);
  CHECK(fill_distance(uniform, circle) == Approx(10.0 / 16));
  CHECK(separation_distance(uniform, circle) == Approx(10.0 / 16));
  // Unsorted points with a gap across the seam: 9 -> 1 is a gap of 2.
  const std::vector<double> seam{1.0, 9.0, 5.0};
  CHECK(fill_distance(seam, circle) == Approx(2.0));    // the 1 -> 5 and 5 -> 9 gaps of 4
  CHECK(separation_distance(seam, circle) == Approx(1.0));
  const Domain interval{10.0, false};
  CHECK(fill_distance(seam, interval) == Approx(2.0));  // max(1, 10 - 9, 4 / 2)
  CHECK(fill_distance(std::vector<double>{3.0, 4.0}, interval) == Approx(6.0));  // 10 - 4
  CHECK(std::isnan(separation_distance(std::vector<double>{3.0}, interval)));
}

TEST_CASE("Gram solver: Cholesky, pseudo-inverse, regularised, fail", "[approximation]") {
  Eigen::MatrixXd spd(3, 3);
  spd << 4, 1, 0, 1, 3, 1, 0, 1, 2;
  const GramSolver cholesky(spd, {});
  CHECK(cholesky.method() == "cholesky");
  CHECK_FALSE(cholesky.spectrum().singular);
  const Eigen::Vector3d b(1, 2, 3);
  CHECK((spd * cholesky.solve(Eigen::VectorXd(b)) - b).norm() < 1e-14);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(spd);
  CHECK(cholesky.spectrum().condition_number ==
        Approx(eigen.eigenvalues()(2) / eigen.eigenvalues()(0)).epsilon(1e-13));

  // Rank 2: v v^T + w w^T.
  Eigen::Vector3d v(1, 1, 0), w(0, 1, 1);
  const Eigen::MatrixXd singular = v * v.transpose() + w * w.transpose();
  const GramSolver pseudo(singular, {});
  CHECK(pseudo.spectrum().singular);
  CHECK(std::isinf(pseudo.spectrum().condition_number));
  CHECK_THAT(pseudo.method(), Catch::StartsWith("pseudo-inverse (rank 2 of 3"));
  // The pseudo-inverse solution of a consistent system reproduces the right-hand side.
  const Eigen::VectorXd consistent = singular * Eigen::Vector3d(1, -2, 0.5);
  CHECK((singular * pseudo.solve(consistent) - consistent).norm() < 1e-13);

  const GramSolver regularised(singular, {SingularPolicy::regularised, 1e-10});
  CHECK_THAT(regularised.method(), Catch::StartsWith("regularised (mu = 1.000e-10"));
  CHECK((singular * regularised.solve(consistent) - consistent).norm() < 1e-8);

  CHECK_THROWS_AS(GramSolver(singular, {SingularPolicy::fail, 0}), SingularGramError);
}

TEST_CASE("one centre: P^2 = k(x,x) - k(x,c)^2 / k(c,c)", "[approximation]") {
  const Domain circle{2 * std::numbers::pi * 4, true};
  for (const std::string name : {"gaussian", "matern", "wendland", "bspline"}) {
    const auto k = kernel(name, {}, circle);
    const std::vector<double> centre{3.0};
    const GramSolver solver(k->gram(centre), {});
    const auto points = circle.uniform_points(97);
    const auto power = power_function(*k, solver, centre, points);
    for (std::size_t m = 0; m < points.size(); ++m) {
      const double x = points[m];
      const double expected = k->evaluate(x, x) - std::pow(k->evaluate(x, 3.0), 2) / k->evaluate(3.0, 3.0);
      INFO(name << " at x = " << x);
      CHECK(power(static_cast<Eigen::Index>(m)) * power(static_cast<Eigen::Index>(m)) ==
            Approx(std::max(expected, 0.0)).margin(1e-13));
    }
  }
}

TEST_CASE("hat functions on their own knots: Pi_n f is the piecewise-linear interpolant",
          "[approximation]") {
  // bspline degree 1 with J = 0 and n0 = N spans the periodic piecewise-linear functions on N
  // knots; with the N knots as centres, H_n = H, so P_n = 0 and Pi_n f interpolates linearly.
  constexpr int N = 16;
  const Domain circle{10.0, true};
  const auto hat = kernel("bspline", {{"degree", std::int64_t{1}}, {"J", std::int64_t{0}},
                                      {"n0", std::int64_t{N}}}, circle);
  const auto f = sine(circle, 2.0);
  std::vector<double> knots;
  for (int i = 0; i < N; ++i) knots.push_back(10.0 * i / N);
  const std::size_t M = 4096;
  const auto measured = measure_approximation(*hat, *f, knots, M, {});
  CHECK(measured.solve_method == "cholesky");

  // Independent computation of the linear interpolation error on the same grid.
  const auto points = circle.uniform_points(M);
  double sup = 0, sum_squares = 0;
  for (double s : points) {
    const double h = 10.0 / N;
    const int cell = static_cast<int>(std::floor(s / h)) % N;
    const double left = (*f)(cell * h), right = (*f)(((cell + 1) % N) * h);
    const double t = s / h - cell;
    const double error = (*f)(s) - ((1 - t) * left + t * right);
    sup = std::max(sup, std::abs(error));
    sum_squares += error * error;
  }
  CHECK(measured.metrics[index_of("sup_error")] == Approx(sup).epsilon(1e-10));
  CHECK(measured.metrics[index_of("l2_error")] == Approx(std::sqrt(sum_squares * 10.0 / M)).epsilon(1e-10));
  CHECK(measured.metrics[index_of("power_function_sup")] < 1e-6);
  CHECK(std::find(measured.flags.begin(), measured.flags.end(), "power_function_at_floor") !=
        measured.flags.end());
  CHECK(measured.metrics[index_of("fill_distance")] == Approx(10.0 / (2 * N)));
}

TEST_CASE("Gaussian sigma = 50 on the paper's track is singular to working precision",
          "[approximation]") {
  const Domain circle{2 * std::numbers::pi * 4, true};
  const auto g = kernel("gaussian", {{"sigma", 50.0}}, circle);
  const auto f = sine(circle);
  for (std::size_t n : {10u, 50u, 100u}) {
    std::vector<double> centres;
    for (std::size_t i = 0; i < n; ++i) centres.push_back(circle.length * static_cast<double>(i) / static_cast<double>(n));
    const auto measured = measure_approximation(*g, *f, centres, 512, {});
    INFO("n = " << n);
    CHECK(std::isinf(measured.metrics[index_of("gram_condition_number")]));
    CHECK(std::find(measured.flags.begin(), measured.flags.end(), "gram_singular") !=
          measured.flags.end());
    CHECK_THAT(measured.solve_method, Catch::StartsWith("pseudo-inverse"));
  }
}

TEST_CASE("interpolation errors of a smooth target shrink as centres are added",
          "[approximation]") {
  const Domain circle{2 * std::numbers::pi * 4, true};
  const auto k = kernel("matern", {{"nu", 2.5}}, circle);
  const auto f = sine(circle);
  double previous = std::numeric_limits<double>::infinity();
  for (std::size_t n : {8u, 16u, 32u, 64u}) {
    std::vector<double> centres;
    for (std::size_t i = 0; i < n; ++i) centres.push_back(circle.length * static_cast<double>(i) / static_cast<double>(n));
    const auto measured = measure_approximation(*k, *f, centres, n * 8, {});
    const double error = measured.metrics[index_of("sup_error")];
    CHECK(error < previous);
    previous = error;
  }
}

TEST_CASE("the approximation metric table: rows in enum order, each named once, indexed by identifier",
          "[approximation]") {
  // The output order and every row's facts are docs/metrics.md's catalogue, which
  // docs.metrics_catalogue checks against `rkhs-study list metrics`; here the table's own rules.
  const auto& rows = MetricTable<ApproximationMetric>::rows;
  STATIC_REQUIRE(table_in_enum_order<ApproximationMetric>());
  CHECK(approximation_metric_names() == metric_table_names<ApproximationMetric>());
  const auto names = metric_table_names<ApproximationMetric>();
  CHECK(std::set<std::string>(names.begin(), names.end()).size() == names.size());
  CHECK(rows[static_cast<std::size_t>(ApproximationMetric::l2_error)].name == "l2_error");
  for (const auto& row : rows) {
    INFO(row.name);
    // A floor flag names a metric whose floor is estimated.
    if (row.flag.ends_with("_at_floor")) CHECK(row.floor != FloorRule::exact);
    // What theory predicts is stated for metrics an approximation trial computes on demand.
    if (row.theory != TheoryLaw::none) CHECK(row.needs != 0);
  }
  MetricValues<ApproximationMetric> values;
  CHECK(values.size() == rows.size());
  CHECK(std::isnan(values[ApproximationMetric::error_floor]));
  values[ApproximationMetric::error_floor] = 2.5;
  CHECK(values[static_cast<std::size_t>(ApproximationMetric::error_floor)] == 2.5);
}
