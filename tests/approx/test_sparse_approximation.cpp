// The sparse path of approximation trials (rkhs/approx/sparse_gram.hpp) against the dense one:
// the same metrics and floors for a compactly supported kernel, bit-identical whatever the
// number of threads.
#include <Eigen/Dense>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>

#include "approx_support.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"
#include "rkhs/kernel/kernel.hpp"

using namespace rkhs;
using namespace rkhs::test;

namespace {

std::vector<double> centres(const std::string& name, std::size_t n, const Domain& domain) {
  const auto* entry = centre_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {}))->place(n, domain, 0);
}

MetricSelection sparse_metrics() {
  // Every metric of the interpolation projection (not the matrix-free projections' own) but
  // the operator norm.
  MetricSelection selection;
  for (const auto& row : MetricTable<ApproximationMetric>::rows)
    selection.push_back(!row.matrix_free_only &&
                        row.id != ApproximationMetric::projection_operator_norm);
  return selection;
}

ApproximationMeasurement measure(const AnyKernel& kernel, const TargetFunction& target,
                                 const std::vector<double>& x, std::size_t points,
                                 GramAlgebra algebra, int threads = 1) {
  SolverOptions options;
  options.algebra = algebra;
  ApproximationMeasurement out;
  run_concurrently(1, threads, [&](std::size_t) {
    out = measure_approximation(kernel, target, x, points, options, sparse_metrics());
  });
  return out;
}

// The sparse and dense paths agree on every metric and floor to `tolerance` relative.
void check_agreement(const AnyKernel& kernel, const TargetFunction& target,
                     const std::vector<double>& x, std::size_t points, double tolerance) {
  const auto dense = measure(kernel, target, x, points, GramAlgebra::dense);
  const auto sparse = measure(kernel, target, x, points, GramAlgebra::sparse);
  CHECK(dense.solve_method == "cholesky");
  CHECK_THAT(sparse.solve_method, Catch::StartsWith("sparse Cholesky (CHOLMOD"));
  const auto& names = approximation_metric_names();
  const auto selection = sparse_metrics();
  for (std::size_t i = 0; i < names.size(); ++i) {
    INFO(names[i]);
    if (!selection[i]) {
      CHECK(std::isnan(sparse.metrics[i]));
      continue;
    }
    REQUIRE(std::isfinite(dense.metrics[i]));
    CHECK(std::abs(sparse.metrics[i] - dense.metrics[i]) <= tolerance * std::abs(dense.metrics[i]));
    if (std::isnan(dense.floors[i])) {
      CHECK(std::isnan(sparse.floors[i]));
    } else {
      CHECK(std::abs(sparse.floors[i] - dense.floors[i]) <= tolerance * std::abs(dense.floors[i]));
    }
  }
  CHECK(sparse.flags == dense.flags);
}

}  // namespace

TEST_CASE("sparse Gram matrix: the dense one without its zeros, exactly symmetric",
          "[approximation][sparse]") {
  for (const bool periodic : {false, true}) {
    INFO("periodic " << periodic);
    const Domain square = box(2, periodic);
    const auto kernel = wendland(1, 0.23, square);
    const auto x = centres("halton", 300, square);
    const Eigen::SparseMatrix<double> sparse = sparse_gram(*kernel, x);
    const Eigen::MatrixXd dense = kernel->gram(x);
    CHECK((Eigen::MatrixXd(sparse) - dense).cwiseAbs().maxCoeff() == 0.0);
    CHECK((Eigen::MatrixXd(sparse) - Eigen::MatrixXd(sparse).transpose()).cwiseAbs().maxCoeff() ==
          0.0);
    CHECK(sparse.nonZeros() == (dense.array() != 0.0).count());
    CHECK(sparse.nonZeros() < dense.size() / 4);
    const auto points = square.uniform_points(1024);
    const Eigen::SparseMatrix<double> cross = sparse_cross_columns(*kernel, points, x);
    CHECK((Eigen::MatrixXd(cross).transpose() - kernel->cross(points, x)).cwiseAbs().maxCoeff() ==
          0.0);
  }
}

TEST_CASE("sparse and dense paths agree: Wendland phi_{2,1} in 2-D and phi_{3,1} in 3-D",
          "[approximation][sparse]") {
  SECTION("2-D, 400 Halton centres, radius 0.2 (about 5 spacings)") {
    const Domain square = box(2);
    const auto kernel = wendland(1, 0.2, square);
    const auto target = expression("exp(x1) * cos(x2) + x1 * x2", square);
    check_agreement(*kernel, *target, centres("halton", 400, square), 4096, 1e-9);
  }
  SECTION("3-D, 512 grid centres, radius 0.35") {
    const Domain unit_cube = box(3);
    const auto kernel = wendland(1, 0.35, unit_cube);
    const auto target = expression("exp(x1) * cos(x2) + x3", unit_cube);
    check_agreement(*kernel, *target, centres("uniform", 512, unit_cube), 8000, 1e-9);
  }
}

TEST_CASE("sparse path: bit-identical on 1 and 2 threads", "[approximation][sparse]") {
  const Domain square = box(2);
  const auto kernel = wendland(1, 0.2, square);
  const auto target = expression("sin(3 * x1) * x2", square);
  const auto x = centres("halton", 400, square);
  const auto one = measure(*kernel, *target, x, 4096, GramAlgebra::sparse, 1);
  const auto two = measure(*kernel, *target, x, 4096, GramAlgebra::sparse, 2);
  for (std::size_t i = 0; i < one.metrics.size(); ++i) {
    INFO(approximation_metric_names()[i]);
    CHECK(std::memcmp(&one.metrics.values()[i], &two.metrics.values()[i], sizeof(double)) == 0);
    CHECK(std::memcmp(&one.floors.values()[i], &two.floors.values()[i], sizeof(double)) == 0);
  }
  CHECK(one.solve_method == two.solve_method);
}

TEST_CASE("choosing the sparse path", "[approximation][sparse]") {
  const Domain square = box(2);
  const auto compact = wendland(1, 0.2, square);
  const auto everywhere = wendland(1, 2.0, square);  // covers the square: dense
  SolverOptions options;
  const unsigned all = work_needed<ApproximationMetric>({});
  const unsigned some = work_needed<ApproximationMetric>(sparse_metrics());
  CHECK_FALSE(choose_sparse(*compact, 1000, options, some));  // dense by default
  options.algebra = GramAlgebra::automatic;
  CHECK(choose_sparse(*compact, 1000, options, some));
  CHECK_FALSE(choose_sparse(*compact, 1000, options, all));  // the operator norm: dense
  CHECK_FALSE(choose_sparse(*everywhere, 1000, options, some));
  CHECK(predicted_gram_nonzeros(compact->properties(), square, 1000) ==
        Approx(1000 + 1000.0 * 999 * std::numbers::pi * 0.04));
  options.algebra = GramAlgebra::sparse;
  CHECK(choose_sparse(*everywhere, 1000, options, some));  // forced
  CHECK_THROWS_WITH(choose_sparse(*compact, 1000, options, all),
                    Catch::Contains("does not compute projection_operator_norm"));
  const auto* gaussian = kernel_registry().find("gaussian");
  REQUIRE(gaussian);
  const auto global =
      gaussian->factory(ParameterSet::resolve(gaussian->info.parameters, {}), square);
  CHECK_THROWS_WITH(choose_sparse(*global, 1000, options, some),
                    Catch::Contains("has global support"));
}

TEST_CASE("predicted factor nonzeros: within a factor 2 of CHOLMOD's analysis",
          "[approximation][sparse]") {
  struct Case {
    int dimension;
    std::size_t n;
    double radius;
  };
  // Grids from a few to tens of neighbours a row, the support radius fixed or a multiple of h.
  for (const auto& c :
       {Case{1, 4000, 0.01}, Case{2, 1024, 0.2}, Case{2, 4096, 0.08}, Case{2, 16384, 0.03},
        Case{3, 4096, 0.2}, Case{3, 4913, 0.25}, Case{3, 13824, 0.1}}) {
    const Domain domain = box(c.dimension);
    const auto kernel = wendland(1, c.radius, domain);
    const auto x = centres("uniform", c.n, domain);
    const auto gram = sparse_gram(*kernel, x);
    const auto predicted = predict_sparse_factor(kernel->properties(), domain, c.n);
    const double analysed = analysed_factor_nonzeros(gram);
    INFO("d = " << c.dimension << ", n = " << c.n << ", radius " << c.radius << ": predicted "
                << predicted.factor_nonzeros << " nonzeros in L, CHOLMOD " << analysed
                << "; G: predicted " << predicted.gram_nonzeros << ", built " << gram.nonZeros());
    CHECK(predicted.factor_nonzeros > analysed / 2);
    CHECK(predicted.factor_nonzeros < analysed * 2);
    CHECK(predicted.gram_nonzeros > 0.5 * static_cast<double>(gram.nonZeros()));
    CHECK(predicted.gram_nonzeros < 2.0 * static_cast<double>(gram.nonZeros()));
  }
}

TEST_CASE("the sparse path counts its nonzeros and fill and solves",
          "[approximation][sparse][work]") {
  const Domain square = box(2);
  const auto kernel = wendland(1, 0.2, square);
  const auto target = expression("exp(x1) * cos(x2) + x1 * x2", square);
  const auto x = centres("halton", 400, square);
  const std::size_t points = 4096;
  auto counted = [&](GramAlgebra algebra) {
    WorkCounters counters;
    const WorkCounterScope scope(&counters);
    measure(*kernel, *target, x, points, algebra, 2);
    return snapshot(counters);
  };
  const auto sparse = counted(GramAlgebra::sparse);
  const auto gram = sparse_gram(*kernel, x);
  const auto cross = sparse_cross_columns(*kernel, square.uniform_points(points), x);
  CHECK(sparse.factorisations == 1);
  CHECK(sparse.sparse_nonzeros == static_cast<std::uint64_t>(gram.nonZeros() + cross.nonZeros()));
  CHECK(sparse.factor_nonzeros == static_cast<std::uint64_t>(analysed_factor_nonzeros(gram)));
  // A solve with L and one with L^T at every point (the power function and its floor), two
  // for the coefficients, two for each Lanczos step on G^-1.
  CHECK(sparse.sparse_solve_columns >= 2 * points + 2);
  CHECK(sparse.sparse_solve_columns <= 2 * points + 2 + 2 * 500 * 2);
  const auto dense = counted(GramAlgebra::dense);
  CHECK(dense.sparse_nonzeros == 0);
  CHECK(dense.factor_nonzeros == 0);
  CHECK(dense.sparse_solve_columns == 0);
  CHECK(dense.factorisations >= 1);
}

TEST_CASE("sparse and dense paths agree at n = 4096 in 2-D (slower)",
          "[approximation][sparse][slow]") {
  const Domain square = box(2);
  const auto kernel = wendland(1, 0.08, square);  // about 5 spacings of the 64 x 64 grid
  const auto target = expression("exp(x1) * cos(x2) + x1 * x2", square);
  check_agreement(*kernel, *target, centres("uniform", 4096, square), 16384, 1e-9);
}

namespace {

MetricSelection select(std::initializer_list<ApproximationMetric> metrics) {
  MetricSelection selection(MetricValues<ApproximationMetric>::count, false);
  for (const auto metric : metrics) selection[static_cast<std::size_t>(metric)] = true;
  return selection;
}

ApproximationMeasurement measure_selected(const AnyKernel& kernel, const TargetFunction& target,
                                          const std::vector<double>& x, std::size_t points,
                                          const MetricSelection& selection, int threads = 1) {
  SolverOptions options;
  options.algebra = GramAlgebra::sparse;
  ApproximationMeasurement out;
  run_concurrently(1, threads, [&](std::size_t) {
    out = measure_approximation(kernel, target, x, points, options, selection);
  });
  return out;
}

// With at least sampled_floor_min_centres centres and neither floor reported, the sparse path
// finds the power function's sup from local bounds (bounded_power_sup): the same sup, errors and
// flags as the full pass over every point, floors from a sample (at most the full ones).
void check_bounded_sup(const AnyKernel& kernel, const TargetFunction& target,
                       const std::vector<double>& x, std::size_t points) {
  using M = ApproximationMetric;
  REQUIRE(kernel.domain().point_count(x) >= sampled_floor_min_centres);
  const auto bounded_selection = select({M::power_function_sup, M::l2_error, M::sup_error});
  const auto full_selection = select(
      {M::power_function_sup, M::l2_error, M::sup_error, M::power_function_floor, M::error_floor});
  const auto bounded = measure_selected(kernel, target, x, points, bounded_selection);
  const auto full = measure_selected(kernel, target, x, points, full_selection);
  INFO(bounded.solve_method);
  REQUIRE_THAT(bounded.solve_method, Catch::Contains("from local bounds"));
  CHECK_THAT(full.solve_method, !Catch::Contains("from local bounds"));
  for (const auto metric : {M::power_function_sup, M::l2_error, M::sup_error}) {
    INFO(approximation_metric_names()[static_cast<std::size_t>(metric)]);
    CHECK(bounded.metrics[metric] == Approx(full.metrics[metric]).epsilon(1e-12));
    // The floors are maxima over a sample of the points the full pass takes them over.
    CHECK(bounded.floors[metric] <= full.floors[metric] * (1 + 1e-12));
    CHECK(bounded.floors[metric] > 0);
  }
  CHECK(bounded.flags == full.flags);
  // Few points solved: the words "N of M points solved".
  const auto at = bounded.solve_method.find("bounds: ");
  REQUIRE(at != std::string::npos);
  const auto solved = std::stoul(bounded.solve_method.substr(at + 8));
  CHECK(solved < points / 10);
  // The same points and values on two threads.
  const auto two = measure_selected(kernel, target, x, points, bounded_selection, 2);
  CHECK(two.solve_method == bounded.solve_method);
  for (std::size_t i = 0; i < two.metrics.size(); ++i) {
    INFO(approximation_metric_names()[i]);
    CHECK(std::memcmp(&two.metrics.values()[i], &bounded.metrics.values()[i], sizeof(double)) == 0);
    CHECK(std::memcmp(&two.floors.values()[i], &bounded.floors.values()[i], sizeof(double)) == 0);
  }
}

}  // namespace

TEST_CASE(
    "the power function's sup from local bounds equals the full pass's with few points solved",
    "[approximation][sparse]") {
  SECTION("3-D, 13^3 grid centres, radius 0.3 (3.6 spacings)") {
    const Domain unit_cube = box(3);
    const auto kernel = wendland(1, 0.3, unit_cube);
    const auto target = expression("exp(x1) * cos(x2) + x1 * x2 * x3", unit_cube);
    check_bounded_sup(*kernel, *target, centres("uniform", 2197, unit_cube), 15625);
  }
  SECTION("3-D, phi_{3,2}, 2500 Halton centres, radius 0.4") {
    const Domain unit_cube = box(3);
    const auto kernel = wendland(2, 0.4, unit_cube);
    const auto target = expression("exp(x1) * cos(x2) + x3", unit_cube);
    check_bounded_sup(*kernel, *target, centres("halton", 2500, unit_cube), 13824);
  }
  SECTION("2-D torus, 48^2 grid centres, radius 0.12") {
    const Domain torus = box(2, true);
    const auto kernel = wendland(1, 0.12, torus);
    const auto target = expression("sin(2 * pi * x1) * cos(2 * pi * x2)", torus);
    check_bounded_sup(*kernel, *target, centres("uniform", 2304, torus), 36864);
  }
  SECTION("2-D, random centres, radius 0.1") {
    const Domain square = box(2);
    const auto kernel = wendland(1, 0.1, square);
    const auto target = expression("exp(x1) * cos(x2) + x1 * x2", square);
    check_bounded_sup(*kernel, *target, centres("random", 2100, square), 16384);
  }
}

TEST_CASE("bounded_power_sup finds the largest power function over every point",
          "[approximation][sparse]") {
  // An exact evaluator from the dense power function: the sup found equals the largest value
  // over every point, and only the points `always` are evaluated without the search.
  const Domain square = box(2);
  const auto kernel = wendland(1, 0.25, square);
  const auto x = centres("halton", 300, square);
  const auto points = square.uniform_points(4096);
  const Eigen::MatrixXd gram = kernel->gram(x);
  const Eigen::LLT<Eigen::MatrixXd> factor(gram);
  const Eigen::MatrixXd cross = kernel->cross(points, x);  // M x n
  Eigen::MatrixXd solved = cross.transpose();
  factor.matrixL().solveInPlace(solved);
  const Eigen::VectorXd power_squared =
      (kernel->diagonal(points) - solved.colwise().squaredNorm().transpose()).cwiseMax(0.0);
  const ExactPowerBlock exact = [&](std::span<const std::size_t> which,
                                    Eigen::Ref<Eigen::VectorXd> power,
                                    Eigen::Ref<Eigen::VectorXd> norms) {
    for (std::size_t k = 0; k < which.size(); ++k) {
      power(static_cast<Eigen::Index>(k)) = power_squared(static_cast<Eigen::Index>(which[k]));
      norms(static_cast<Eigen::Index>(k)) = 1.0;
    }
  };
  const std::vector<std::size_t> always{0, 17};
  const auto found = bounded_power_sup(*kernel, x, points, always, exact);
  CHECK(found.power_squared.maxCoeff() == power_squared.maxCoeff());
  CHECK(found.evaluated.size() < 400);
  CHECK(std::find(found.evaluated.begin(), found.evaluated.end(), 17) != found.evaluated.end());
  const auto sample = bounded_power_sup(*kernel, x, points, always, exact, false);
  CHECK(sample.evaluated == always);
  CHECK(sample.power_squared(1) == power_squared(17));
}

TEST_CASE("CHOLMOD's analyses run one at a time so that two trials at once order alike",
          "[approximation][sparse]") {
  // METIS draws from a process-wide random state: two analyses at once interleaved their draws
  // (4.39e6 to 4.50e6 nonzeros in L against 4.40e6 alone, for this matrix).
  const Domain unit_cube = box(3);
  const auto kernel = wendland(1, 0.3, unit_cube);
  const auto gram = sparse_gram(*kernel, centres("uniform", 4913, unit_cube));
  const double alone = analysed_factor_nonzeros(gram);
  for (int round = 0; round < 3; ++round) {
    std::array<double, 2> together{};
    run_concurrently(2, 2, [&](std::size_t i) { together[i] = analysed_factor_nonzeros(gram); });
    CHECK(together[0] == alone);
    CHECK(together[1] == alone);
  }
}
