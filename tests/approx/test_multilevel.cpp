// Multilevel interpolation (rkhs/approx/multilevel.hpp, plugins/projections/multilevel.cpp):
// one level is the sparse path's interpolant, the sum interpolates f on the finest grid, the
// error falls level by level, the metrics do not depend on the threads, an n that is not a
// level's centre count is refused, and the predicted footprint is of the levels' size.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <map>

#include "approx_support.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/multilevel.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"
#include "rkhs/kernel/kernel.hpp"

using namespace rkhs;
using namespace rkhs::test;

namespace {

ParameterSet multilevel_parameters(std::int64_t m0, double nu) {
  const auto* entry = projection_registry().find("multilevel");
  REQUIRE(entry);
  return ParameterSet::resolve(entry->info.parameters, Given{{"m0", m0}, {"nu", nu}});
}

// The metrics the multilevel projection computes.
MetricSelection multilevel_metrics() {
  using M = ApproximationMetric;
  MetricSelection selection(MetricValues<ApproximationMetric>::count, false);
  for (const auto m : {M::fill_distance, M::separation_distance, M::l2_error, M::sup_error,
                       M::level_reduction_factor, M::level_condition_number, M::level_nonzeros})
    selection[static_cast<std::size_t>(m)] = true;
  return selection;
}

const char* const smooth_target = "exp(x1) * cos(x2) + x1 * x2";

}  // namespace

TEST_CASE("multilevel: one level is the sparse path's interpolant at its centres",
          "[approx][multilevel]") {
  const Domain domain = box(2);
  const auto target = expression(smooth_target, domain);
  // Level 0 with m0 = 8: 9 x 9 centres, radius nu h_0 = 4 / 8.
  const MultilevelSettings settings{8, 4.0};
  const auto kernel = wendland(1, 0.5, domain);
  const std::size_t evaluation = 65 * 65;
  const auto points = domain.uniform_points(evaluation);
  const auto result = multilevel_interpolation(*kernel, *target, settings, 0, points, false);
  REQUIRE(result.levels.size() == 1);
  CHECK(result.levels[0].centres == 81);
  CHECK(result.levels[0].radius == 0.5);

  const auto centres = domain.uniform_points(81);
  SolverOptions options;
  options.algebra = GramAlgebra::sparse;
  MetricSelection errors(MetricValues<ApproximationMetric>::count, false);
  errors[static_cast<std::size_t>(ApproximationMetric::l2_error)] = true;
  errors[static_cast<std::size_t>(ApproximationMetric::sup_error)] = true;
  const auto sparse = measure_approximation(*kernel, *target, centres, evaluation, options, errors);
  CHECK_THAT(sparse.solve_method, Catch::StartsWith("sparse Cholesky (CHOLMOD"));
  const double l2 = sparse.metrics[ApproximationMetric::l2_error];
  const double sup = sparse.metrics[ApproximationMetric::sup_error];
  REQUIRE(l2 > 0);
  CHECK(std::abs(result.levels[0].l2_error - l2) <= 1e-10 * l2);
  CHECK(std::abs(result.levels[0].sup_error - sup) <= 1e-10 * sup);
  CHECK(result.levels[0].nonzeros ==
        static_cast<std::size_t>(sparse_gram(*kernel, centres).nonZeros()));
}

TEST_CASE(
    "multilevel: the sum interpolates f on the finest grid, and each level reduces the "
    "error",
    "[approx][multilevel]") {
  const Domain domain = box(2);
  const auto target = expression(smooth_target, domain);
  const auto kernel = wendland(1, 1.0, domain);
  const MultilevelSettings settings{4, 4.0};
  const auto points = domain.uniform_points(129 * 129);
  const auto result = multilevel_interpolation(*kernel, *target, settings, 3, points, true);
  REQUIRE(result.levels.size() == 4);
  CHECK(result.finest_centres.size() == 2 * 33 * 33);

  // e_J on X_J is f - s there: round-off of the size of f.
  Eigen::VectorXd f(33 * 33);
  target->evaluate(result.finest_centres, std::span<double>(f.data(), 33 * 33));
  CHECK(result.finest_residual.cwiseAbs().maxCoeff() <= 1e-12 * f.cwiseAbs().maxCoeff() * 33);

  double previous = result.target_l2;
  for (std::size_t j = 0; j < result.levels.size(); ++j) {
    const auto& level = result.levels[j];
    INFO("level " << j << ": L2 error " << level.l2_error << ", previous " << previous);
    CHECK(level.centres == (4u * (1u << j) + 1) * (4u * (1u << j) + 1));
    CHECK(level.radius == 4.0 * 0.25 / static_cast<double>(1 << j));
    CHECK(level.l2_error / previous < 1.0);
    CHECK(level.l2_error < previous);
    previous = level.l2_error;
  }
  // The finest level's Lanczos estimates: a well-conditioned Gram matrix (nu = 4).
  const auto& finest = result.levels.back();
  CHECK(finest.lambda_min > 0);
  CHECK(finest.lambda_max / finest.lambda_min > 1);
  CHECK(std::isfinite(finest.lambda_max / finest.lambda_min));
  for (std::size_t j = 0; j + 1 < result.levels.size(); ++j)
    CHECK(std::isnan(result.levels[j].lambda_min));
}

TEST_CASE("multilevel: the projection's metrics are bit-identical on one and two threads",
          "[approx][multilevel]") {
  const Domain domain = box(2);
  const auto target = expression(smooth_target, domain);
  const auto kernel = wendland(1, 1.0, domain);
  const auto parameters = multilevel_parameters(4, 4.0);
  // 257^2 evaluation points: three chunks of the residual update, on different threads.
  const std::size_t evaluation = 257 * 257;
  const std::vector<double> unused;
  auto measure = [&](int threads) {
    ApproximationMeasurement out;
    run_concurrently(1, threads, [&](std::size_t) {
      const ProjectionRequest request{*kernel, 4225, unused, SolverOptions{}};
      out = measure_projection_trial("multilevel", parameters, request, *target, evaluation,
                                     multilevel_metrics());
    });
    return out;
  };
  const auto one = measure(1);
  const auto two = measure(2);
  const auto& names = approximation_metric_names();
  const auto selection = multilevel_metrics();
  for (std::size_t i = 0; i < names.size(); ++i) {
    INFO(names[i]);
    if (!selection[i]) {
      CHECK(std::isnan(one.metrics[i]));
      continue;
    }
    CHECK(std::isfinite(one.metrics[i]));
    const double a = one.metrics[i], b = two.metrics[i];
    CHECK(std::memcmp(&a, &b, sizeof(double)) == 0);
  }
  CHECK(one.metrics[ApproximationMetric::level_reduction_factor] < 1.0);
  CHECK(one.metrics[ApproximationMetric::level_nonzeros] > 4225);
  CHECK_THAT(one.solve_method, Catch::StartsWith("multilevel interpolation, levels 0..4"));
  CHECK(one.solve_method == two.solve_method);
}

TEST_CASE("multilevel: an n that is not a level's centre count is refused, naming the valid ones",
          "[approx][multilevel]") {
  const Domain domain = box(2);
  const auto kernel = wendland(1, 1.0, domain);
  const auto* entry = projection_registry().find("multilevel");
  REQUIRE(entry);
  const auto projection = entry->factory(multilevel_parameters(4, 4.0));
  CHECK_NOTHROW(projection->check(*kernel, 1089));
  CHECK_THROWS_WITH(projection->check(*kernel, 1000),
                    Catch::Contains("n = 1000") && Catch::Contains("25, 81, 289, 1089, 4225"));
  // A kernel of global support has no radius to scale.
  const auto* gaussian = kernel_registry().find("gaussian");
  REQUIRE(gaussian);
  const auto global =
      gaussian->factory(ParameterSet::resolve(gaussian->info.parameters, {}), domain);
  CHECK_THROWS_WITH(projection->check(*global, 1089), Catch::Contains("compact support"));
}

TEST_CASE("multilevel: the predicted footprint is of the levels' sparse factors",
          "[approx][multilevel]") {
  const Domain domain = box(2);
  const auto target = expression(smooth_target, domain);
  const auto kernel = wendland(1, 1.0, domain);
  const MultilevelSettings settings{4, 4.0};
  const std::size_t evaluation = 129 * 129;
  const auto predicted = predict_multilevel(*kernel, settings, 4, evaluation);
  const auto points = domain.uniform_points(evaluation);
  WorkCounters counters;
  MultilevelResult result;
  {
    const WorkCounterScope counting(&counters);
    result = multilevel_interpolation(*kernel, *target, settings, 4, points, false);
  }
  const auto work = snapshot(counters);
  double gram = 0, factor = 0;
  for (const auto& level : result.levels) {
    gram += static_cast<double>(level.nonzeros);
    factor += static_cast<double>(level.factor_nonzeros);
  }
  INFO("G: predicted " << predicted.gram_nonzeros << ", found " << gram << "; L: predicted "
                       << predicted.factor_nonzeros << ", found " << factor);
  CHECK(predicted.gram_nonzeros > gram / 2);
  CHECK(predicted.gram_nonzeros < gram * 2);
  CHECK(predicted.factor_nonzeros > factor / 2);
  CHECK(predicted.factor_nonzeros < factor * 2);
  CHECK(predicted.flops > 0);
  // Far below the dense estimate (three 4225^2 matrices: 400 MiB), and an upper bound of the
  // heap the run held at once, within a factor 4 of it (plus the 64 MiB of solve blocks).
  CHECK(predicted.megabytes < 400);
  if (work.allocations_tracked) {
    const double peak = static_cast<double>(work.peak_bytes) / 1048576.0;
    INFO("peak " << peak << " MiB, predicted " << predicted.megabytes << " MiB");
    CHECK(predicted.megabytes >= peak);
    CHECK(predicted.megabytes <= 4 * peak + 64);
  }
  // Through the plugin, as run and validate ask it.
  const auto projection =
      projection_registry().find("multilevel")->factory(multilevel_parameters(4, 4.0));
  const auto through_plugin = projection->footprint(*kernel, 4225, evaluation);
  REQUIRE(through_plugin);
  CHECK(through_plugin->megabytes == predicted.megabytes);
  CHECK_THROWS_AS(projection->footprint(*kernel, 4000, evaluation), std::invalid_argument);
}
