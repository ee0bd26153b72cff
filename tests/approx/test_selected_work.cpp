// An approximation trial computes what its metrics need and nothing else, from one Gram
// factorisation: each shortcut is checked against the computation it replaces.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>

#include "approx_support.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/dense_kernels.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/kernel/kernel.hpp"

using namespace rkhs;
using M = ApproximationMetric;

namespace {

std::unique_ptr<AnyKernel> kernel(const std::string& name, std::map<std::string, ParameterValue> p,
                                  const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, p), domain);
}

std::unique_ptr<TargetFunction> sine(const Domain& domain) {
  const auto* entry = target_registry().find("sine");
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {{"amplitude", 2.0}}),
                        domain);
}

std::vector<double> uniform_centres(std::size_t n, const Domain& domain) {
  std::vector<double> c;
  for (std::size_t i = 0; i < n; ++i)
    c.push_back(domain.length * (static_cast<double>(i) + 0.5) / static_cast<double>(n));
  return c;
}

MetricSelection only(std::initializer_list<M> metrics) {
  MetricSelection selection(MetricValues<M>::count, false);
  for (const auto m : metrics) selection[static_cast<std::size_t>(m)] = true;
  return selection;
}

bool has_flag(const ApproximationMeasurement& m, const std::string& flag) {
  return std::find(m.flags.begin(), m.flags.end(), flag) != m.flags.end();
}

}  // namespace

TEST_CASE("a metric's needs include what its round-off flag needs", "[approximation][work]") {
  // The flags of the power function and the errors compare with floors that need
  // |G^-1 k_X(s)|^2: a second triangular solve per point.
  for (const auto m : {M::power_function_sup, M::l2_error, M::sup_error})
    CHECK((MetricTable<M>::rows[static_cast<std::size_t>(m)].needs & work_cardinal) != 0);
  CHECK(work_needed<M>(only({M::fill_distance})) == work_fill);
  CHECK((work_needed<M>(only({M::gram_condition_number})) & work_power) == 0);
  // Every metric needs something, and every part of the work serves some metric.
  unsigned all = 0;
  for (const auto& row : MetricTable<M>::rows) {
    CHECK(row.needs != 0);
    all |= row.needs;
  }
  CHECK(all == work_needed<M>({}));
}

TEST_CASE("selected metrics equal the full measurement's and the rest are not computed",
          "[approximation][work]") {
  const Domain circle{4.0, true};
  const auto k = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.6}}, circle);
  const auto f = sine(circle);
  const auto centres = uniform_centres(24, circle);
  const auto full = measure_approximation(*k, *f, centres, 1000, {});
  // Every metric but the matrix-free projections' own (NaN here).
  for (std::size_t i = 0; i < MetricValues<M>::count; ++i)
    CHECK(std::isfinite(full.metrics[i]) != MetricTable<M>::rows[i].matrix_free_only);

  SECTION("errors and the power function without the spectrum, the geometry or the operator") {
    const auto some = measure_approximation(
        *k, *f, centres, 1000, {}, only({M::power_function_sup, M::l2_error, M::sup_error}));
    // The same factorisation and the same blocked pass: the same bits.
    CHECK(some.metrics[M::power_function_sup] == full.metrics[M::power_function_sup]);
    CHECK(some.metrics[M::l2_error] == full.metrics[M::l2_error]);
    CHECK(some.metrics[M::sup_error] == full.metrics[M::sup_error]);
    for (const auto m :
         {M::fill_distance, M::separation_distance, M::gram_condition_number,
          M::gram_min_eigenvalue, M::gram_max_eigenvalue, M::power_function_floor, M::error_floor,
          M::interpolant_native_norm, M::projection_norm_H_to_C, M::projection_operator_norm})
      CHECK(std::isnan(some.metrics[m]));
    CHECK(some.solve_method == full.solve_method);
    for (const auto& flag : {"power_function_at_floor", "l2_error_at_floor", "sup_error_at_floor"})
      CHECK(has_flag(some, flag) == has_flag(full, flag));
  }
  SECTION("the spectrum alone") {
    const auto some =
        measure_approximation(*k, *f, centres, 1000, {}, only({M::gram_condition_number}));
    CHECK(some.metrics[M::gram_condition_number] == full.metrics[M::gram_condition_number]);
    CHECK(std::isnan(some.metrics[M::power_function_sup]));
  }
}

TEST_CASE("floors from a sample of the points where no floor metric is reported",
          "[approximation][work][floor]") {
  // power_function_floor and error_floor, when reported, are the maxima of |G^-1 k_X(s_m)|^2
  // over every point, as in the full measurement. When only the flags and floor
  // columns of power_function_sup, l2_error and sup_error need them, the second solve runs on a
  // sample of the points and at the points that set the sups (docs/metrics.md, "Floors"): a
  // lower bound of the full maximum, within a factor of 2 of it.
  const Domain square = test::box(2);
  const auto k = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.2}}, square);
  const auto* entry = target_registry().find("expression");
  REQUIRE(entry);
  std::map<std::string, ParameterValue> given{{"f", std::string("exp(x1) * cos(x2) + x1 * x2")}};
  const auto f = entry->factory(
      ParameterSet::resolve(entry->info.parameters, given,
                            entry->info.user_parameters ? &*entry->info.user_parameters : nullptr),
      square);
  std::vector<double> centres;
  constexpr int m = 46;  // n = 2116: at least the 2048 centres from which the floors are sampled
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      centres.push_back(static_cast<double>(i) / (m - 1));
      centres.push_back(static_cast<double>(j) / (m - 1));
    }
  const std::size_t points = 32 * 32;
  const auto reported = measure_approximation(*k, *f, centres, points, {},
                                              only({M::power_function_sup, M::power_function_floor,
                                                    M::l2_error, M::sup_error, M::error_floor}));
  REQUIRE(reported.solve_method == "cholesky");

  // Either floor listed: both are maxima over every point.
  const auto one_floor = measure_approximation(
      *k, *f, centres, points, {},
      only({M::power_function_sup, M::power_function_floor, M::l2_error, M::sup_error}));
  CHECK(one_floor.metrics[M::power_function_floor] == reported.metrics[M::power_function_floor]);
  CHECK(one_floor.floors[M::sup_error] == reported.floors[M::sup_error]);

  const auto sampled = measure_approximation(
      *k, *f, centres, points, {}, only({M::power_function_sup, M::l2_error, M::sup_error}));
  CHECK(sampled.metrics[M::power_function_sup] == reported.metrics[M::power_function_sup]);
  CHECK(sampled.metrics[M::sup_error] == reported.metrics[M::sup_error]);
  for (const auto metric : {M::power_function_sup, M::sup_error, M::l2_error}) {
    INFO(approximation_metric_names()[static_cast<std::size_t>(metric)]);
    const double ratio = sampled.floors[metric] / reported.floors[metric];
    CHECK(ratio <= 1.0 + 1e-12);
    CHECK(ratio >= 0.5);
  }
  for (const auto& flag : {"power_function_at_floor", "l2_error_at_floor", "sup_error_at_floor"})
    CHECK(has_flag(sampled, flag) == has_flag(reported, flag));
}

TEST_CASE("projection norms of the interpolation projection from the trial's own factorisation",
          "[approximation][work][projection]") {
  const Domain circle{4.0, true};
  const auto k = kernel("gaussian", {{"sigma", 0.5}}, circle);
  const auto f = sine(circle);
  const auto centres = uniform_centres(16, circle);
  const auto points = circle.uniform_points(800);
  const auto measured = measure_approximation(*k, *f, centres, 800, {});
  // Independently: the operator the plugin builds (its own Gram matrix and solver), and
  // ||(I - Pi)^* k(s, .)||_H from the operator's definition.
  const auto op = build_projection("interpolation", {}, ProjectionRequest{*k, 16, centres, {}});
  const double from_operator = projection_residual_norms(*k, op, points).maxCoeff();
  // Both are square roots of k(s, s) minus a quadratic form: they agree in the squares to the
  // round-off of those forms, n eps k(s, s) (here k(s, s) = 1).
  const double norm = measured.metrics[M::projection_norm_H_to_C];
  CHECK(norm == measured.metrics[M::power_function_sup]);
  CHECK(std::abs(norm * norm - from_operator * from_operator) <=
        16 * std::numeric_limits<double>::epsilon() * 16);
  CHECK(measured.metrics[M::projection_operator_norm] ==
        Approx(projection_operator_norm(*k, op)).epsilon(1e-12));
  // The operator built from the trial's solver is the plugin's, bit for bit.
  const Eigen::MatrixXd gram = k->gram(centres);
  ProjectionOperator shared;
  interpolation_operator(*k, centres, gram, GramSolver(gram, {}), shared);
  CHECK(shared.weights() == op.weights());
  CHECK(shared.basis_coefficients() == op.basis_coefficients());
}

TEST_CASE("estimated spectrum: the same singularity decision as the exact one",
          "[approximation][work][gram]") {
  // Gaussian Gram matrices from well conditioned to singular to working precision.
  const Domain circle{4.0, true};
  for (const double sigma : {0.1, 0.3, 0.6, 1.0, 2.0}) {
    const auto k = kernel("gaussian", {{"sigma", sigma}}, circle);
    for (const std::size_t n : {8u, 20u, 40u, 80u}) {
      const Eigen::MatrixXd gram = k->gram(uniform_centres(n, circle));
      const GramSolver exact(gram, {}, GramSpectrumMode::exact);
      const GramSolver estimated(gram, {}, GramSpectrumMode::estimate);
      INFO("sigma = " << sigma << ", n = " << n << ", exact lambda_min "
                      << exact.spectrum().lambda_min);
      CHECK(estimated.spectrum().singular == exact.spectrum().singular);
      CHECK(estimated.method() == exact.method());
      CHECK(estimated.spectrum().lambda_max == Approx(exact.spectrum().lambda_max).epsilon(1e-11));
      if (estimated.spectrum().estimated) {
        // Never below the true smallest eigenvalue (up to round-off), close to it.
        CHECK(estimated.spectrum().lambda_min >= exact.spectrum().lambda_min * (1 - 1e-8));
        CHECK(estimated.spectrum().lambda_min == Approx(exact.spectrum().lambda_min).epsilon(1e-3));
      }
    }
  }
}

TEST_CASE("the blocked power function equals one solve over every point", "[approximation][work]") {
  Domain square;
  square.dimension = 2;
  square.length = square.width = 1.0;
  square.periodic = false;
  const auto k = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.3}}, square);
  const auto centres = square.uniform_points(100);  // a 10 x 10 grid
  const auto points = square.uniform_points(1600);  // 40 x 40: several blocks
  const Eigen::MatrixXd gram = k->gram(centres);
  const GramSolver solver(gram, {});
  const Eigen::VectorXd blocked = power_function(*k, solver, centres, points);
  const Eigen::LLT<Eigen::MatrixXd> llt(gram);
  const Eigen::MatrixXd half =
      llt.matrixL().solve(Eigen::MatrixXd(k->cross(points, centres).transpose()));
  const Eigen::VectorXd direct =
      (k->diagonal(points) - half.colwise().squaredNorm().transpose()).cwiseMax(0.0).cwiseSqrt();
  REQUIRE(blocked.size() == direct.size());
  // P^2 = k(s, s) - |L^-1 k_X(s)|^2 agrees to the round-off of the quadratic form, n eps k(s, s)
  // (k(s, s) = 1); P itself near a centre, where P^2 is that small, does not.
  const Eigen::ArrayXd squares = blocked.array().square() - direct.array().square();
  CHECK(squares.abs().maxCoeff() <= 100 * std::numeric_limits<double>::epsilon() * 100);
}

TEST_CASE("parts of a trial run under the trial's cancellation scope", "[concurrency][work]") {
  bool stop = false;
  const std::function<bool()> stop_requested = [&] { return stop; };
  const CancellationScope scope(stop_requested, std::nullopt);
  std::vector<int> done(64, 0);
  run_parts(done.size(), [&](std::size_t i) {
    check_cancelled();
    done[i] = 1;
  });
  CHECK(std::count(done.begin(), done.end(), 1) == 64);
  stop = true;
  CHECK_THROWS_AS(run_parts(8, [&](std::size_t) { check_cancelled(); }), TrialCancelled);
}

TEST_CASE("every dense-kernel variant this processor runs agrees with the baseline",
          "[approximation][work][dense]") {
  // An SPD matrix of condition about 1e6 (a Matern Gram matrix) and 300 right-hand sides.
  const Domain circle{4.0, true};
  const auto k = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.4}}, circle);
  const Eigen::MatrixXd gram = k->gram(uniform_centres(300, circle));
  const Eigen::MatrixXd rhs = k->cross(uniform_centres(300, circle), circle.uniform_points(300));
  const auto n = static_cast<dense::Index>(gram.rows());
  auto run = [&](const dense::Kernels& variant) {
    Eigen::MatrixXd factor = gram, x = rhs;
    REQUIRE(variant.cholesky(factor.data(), n, n));
    variant.solve_lower(factor.data(), n, n, x.data(), x.cols(), n);
    variant.solve_lower_transposed(factor.data(), n, n, x.data(), x.cols(), n);
    Eigen::MatrixXd product(n, x.cols());
    variant.multiply(gram.data(), n, n, n, x.data(), x.cols(), n, product.data(), n);
    return std::pair{Eigen::MatrixXd(factor.triangularView<Eigen::Lower>()), product};
  };
  const auto [baseline_factor, baseline_product] = run(dense::baseline_kernels);
  // G (G^-1 K) = K: the solve and the product together, backward stable.
  CHECK((baseline_product - rhs).norm() <= 1e-10 * rhs.norm());
  int variants = 0;
  for (const auto* variant : {&dense::avx2_kernels, &dense::avx512_kernels}) {
    if (!dense::supported(*variant)) continue;
    ++variants;
    INFO(variant->instruction_set);
    const auto [factor, product] = run(*variant);
    // Backward stable like the baseline: L L^T = G to n eps |G| (the factors themselves differ
    // by cond(G) eps, as rounding differs).
    CHECK((factor * factor.transpose() - gram).norm() <= 300 * 1e-16 * gram.norm());
    CHECK((factor - baseline_factor).norm() <= 1e-6 * baseline_factor.norm());
    CHECK((product - rhs).norm() <= 1e-10 * rhs.norm());
  }
  CHECK(std::string(dense::kernels().instruction_set).size() > 0);
  WARN(variants << " vector variants supported here; chosen: " << dense::kernels().instruction_set);
}

TEST_CASE("the tiled Cholesky factorisation: Eigen's, and the same bits on one thread or two",
          "[approximation][work][dense]") {
  // A Matern Gram matrix of condition about 1e7 in 2-D, n = 1100 (the tiles do not divide n).
  const Domain square = test::box(2);
  const auto k = kernel("matern", {{"nu", 2.5}, {"length_scale", 0.2}}, square);
  std::vector<double> centres;
  for (int i = 0; i < 1100; ++i) {
    centres.push_back(std::fmod(0.6180339887 * i, 1.0));
    centres.push_back(std::fmod(0.7548776662 * i + 0.5698402910 * (i % 7), 1.0));
  }
  const Eigen::MatrixXd gram = k->gram(centres);
  const auto n = static_cast<dense::Index>(gram.rows());
  REQUIRE(n == 1100);
  const dense::Kernels& variant = dense::kernels();
  auto factorise = [&](int threads) {
    Eigen::MatrixXd factor = gram;
    bool ok = false;
    run_concurrently(1, threads, [&](std::size_t) {
      ok = dense::parallel_cholesky(variant, factor.data(), n, n);
    });
    REQUIRE(ok);
    return factor;
  };
  const Eigen::MatrixXd one = factorise(1), two = factorise(2);
  // Every bit, the strict upper triangle (left as it was) included.
  CHECK(std::memcmp(one.data(), two.data(), sizeof(double) * one.size()) == 0);
  CHECK(one.triangularView<Eigen::StrictlyUpper>().toDenseMatrix() ==
        gram.triangularView<Eigen::StrictlyUpper>().toDenseMatrix());
  const Eigen::MatrixXd lower = one.triangularView<Eigen::Lower>();
  // Backward stable: L L^T = G to a small multiple of n eps |G|.
  CHECK((lower * lower.transpose() - gram).norm() <= 1100 * 1e-16 * gram.norm());
  // Against the untiled factorisation: the same to cond(G) eps.
  Eigen::MatrixXd reference = gram;
  REQUIRE(variant.cholesky(reference.data(), n, n));
  const Eigen::MatrixXd reference_lower = reference.triangularView<Eigen::Lower>();
  CHECK((lower - reference_lower).norm() <= 1e-6 * reference_lower.norm());

  // Not positive definite (a negative pivot in the last panel): refused, as the untiled one does.
  Eigen::MatrixXd indefinite = gram;
  indefinite(n - 3, n - 3) = -1.0;
  CHECK_FALSE(dense::parallel_cholesky(variant, indefinite.data(), n, n));
}

TEST_CASE("the Gram matrix assembled in strips is the cross matrix's lower triangle, mirrored",
          "[kernel][work]") {
  // 1-D (a kernel without support or feature map) and 2-D (a point kernel), n large enough for
  // strips, on one thread and on two: every entry is k(c_i, c_j) for i >= j, bit for bit.
  const Domain square = test::box(2);
  const Domain circle{4.0, true};
  struct Case {
    const Domain* domain;
    std::unique_ptr<AnyKernel> k;
    std::vector<double> centres;
  };
  std::vector<Case> cases;
  cases.push_back(
      {&circle, kernel("gaussian", {{"sigma", 0.3}}, circle), uniform_centres(700, circle)});
  std::vector<double> flat;
  for (int i = 0; i < 700; ++i) {
    flat.push_back(std::fmod(0.6180339887 * i, 1.0));
    flat.push_back(std::fmod(0.7548776662 * i, 1.0));
  }
  cases.push_back({&square, kernel("matern", {{"nu", 1.5}, {"length_scale", 0.3}}, square), flat});
  for (const auto& c : cases) {
    const Eigen::MatrixXd cross = c.k->cross(c.centres, c.centres);
    const Eigen::Index n = cross.rows();
    for (int threads : {1, 2}) {
      Eigen::MatrixXd gram;
      run_concurrently(1, threads, [&](std::size_t) { gram = c.k->gram(c.centres); });
      INFO("dimension " << c.domain->dimension << ", threads " << threads);
      bool lower_equal = true, symmetric = true;
      for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index i = j; i < n; ++i) {
          lower_equal = lower_equal && gram(i, j) == cross(i, j);
          symmetric = symmetric && gram(j, i) == gram(i, j);
        }
      CHECK(lower_equal);
      CHECK(symmetric);
    }
  }
}
