// The infinite-dimensional estimator in feature coordinates (law rkhs_embedding, docs/model.md
// section 14): it equals the rkhs law where H_n = H, keeps its coordinates in the range of the
// features (so beta^T beta is the H-norm of fhat), updates (p + 1)(J + 1) coordinates per
// right-hand side, and refuses kernels without a finite feature map.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "paper_track_support.hpp"
#include "study_support.hpp"

using namespace rkhs;
using test::Given;

namespace {

const Domain& track = test::paper_track;  // the paper's track, radius 4 m
using test::finest_points;
constexpr auto road = test::sine_road;
constexpr auto road_slope = test::sine_road_slope;

// fhat = sum_j c_j basis_j at `points`.
Eigen::VectorXd values_at(const KernelBasis& basis, const Eigen::VectorXd& c,
                          const std::vector<double>& points) {
  std::vector<double> row(basis.size());
  Eigen::VectorXd out(static_cast<Eigen::Index>(points.size()));
  for (std::size_t m = 0; m < points.size(); ++m) {
    basis.evaluate(points[m], row.data());
    out(static_cast<Eigen::Index>(m)) =
        Eigen::Map<const Eigen::VectorXd>(row.data(), c.size()).dot(c);
  }
  return out;
}

// A linear plant (time constant 1 s), the degree-`degree` B-spline kernel (n0 = 4, J = 3:
// n_J = 32 finest cells, F = 60 features), 2 laps at 1 m/s with Gamma = 0.1 (fhat learns about
// half of the road): z(T) for the rkhs law on `centres` and for rkhs_embedding, integrated by
// radau5 through every kink.
struct Pair {
  std::unique_ptr<AnyKernel> kernel;
  Eigen::VectorXd sections_state, features_state;
  std::unique_ptr<KernelBasis> sections, features;
};

Pair integrate_both(std::int64_t degree, const std::vector<double>& centres) {
  Pair out;
  out.kernel = test::make_registered_kernel(
      "bspline", {{"degree", degree}, {"n0", std::int64_t{4}}, {"J", std::int64_t{3}}}, track);
  const Eigen::MatrixXd A = Eigen::MatrixXd::Constant(1, 1, -1.0);
  const Eigen::VectorXd B = Eigen::VectorXd::Constant(1, 1.0);
  const Eigen::MatrixXd P = solve_lyapunov(A, Eigen::MatrixXd::Identity(1, 1)).P;
  const double gamma = 0.1, speed = 1.0, lap_time = track.length / speed;
  const std::function<double(double)> f = road, slope = road_slope;
  std::vector<double> times{0.0};
  for (int lap = 0; lap < 2; ++lap)
    for (double kink : out.kernel->kink_points())
      if (lap > 0 || kink > 0) times.push_back(lap * lap_time + kink / speed);
  times.push_back(2 * lap_time);
  const auto* radau = integrator_registry().find("radau5");
  REQUIRE(radau);
  const auto integrator = radau->factory(
      ParameterSet::resolve(radau->info.parameters, {{"rtol", 1e-12}, {"atol", 1e-13}}));

  out.sections = out.kernel->basis(centres);
  const GramSolver solver(out.kernel->gram(centres), {});
  REQUIRE(solver.method() == "cholesky");  // H_n = H: the sections are a basis of H
  AdaptiveSystem rkhs_law(A, B, P, *out.sections, LearningMap::gram_inverse(solver, gamma), f,
                          slope, track, speed);
  out.sections_state = Eigen::VectorXd::Zero(rkhs_law.dimension());
  integrator->integrate(rkhs_law, out.sections_state, times, [](std::size_t, const double*) {});

  out.features = out.kernel->feature_basis();
  REQUIRE(out.features);
  const auto count = static_cast<Eigen::Index>(out.features->size());
  CHECK(count == static_cast<Eigen::Index>(out.kernel->feature_count()));
  AdaptiveSystem embedding(A, B, P, *out.features, LearningMap::scalar(count, 1.0 / gamma), f,
                           slope, track, speed);
  out.features_state = Eigen::VectorXd::Zero(embedding.dimension());
  integrator->integrate(embedding, out.features_state, times, [](std::size_t, const double*) {});
  return out;
}

}  // namespace

TEST_CASE("rkhs_embedding equals the rkhs law on H_n = H", "[adaptive][embedding]") {
  // Degree 1 with centres at every finest knot, degree 2 at the finest cells' midpoints: in both
  // the n = n0 2^J sections span H, so P_n k(s, .) = k(s, .) and the two laws are one ODE for
  // (x, xhat, fhat) in different coordinates.
  for (const auto& [degree, offset] : {std::pair<std::int64_t, double>{1, 0.0}, {2, 0.5}}) {
    const auto centres = finest_points(4, 3, offset);
    const auto pair = integrate_both(degree, centres);
    INFO("degree " << degree);
    REQUIRE(pair.sections_state.size() == 2 + 32);
    REQUIRE(pair.features_state.size() == 2 + 60);
    // xhat(T) (and x(T), which no law changes).
    CHECK(std::abs(pair.features_state(0) - pair.sections_state(0)) < 1e-10);
    CHECK(std::abs(pair.features_state(1) - pair.sections_state(1)) < 1e-10);
    // fhat(T) on a fine grid.
    const auto grid = track.uniform_points(1000);
    const Eigen::VectorXd by_sections =
        values_at(*pair.sections, pair.sections_state.tail(32), grid);
    const Eigen::VectorXd by_features =
        values_at(*pair.features, pair.features_state.tail(60), grid);
    const double scale = by_sections.cwiseAbs().maxCoeff();
    UNSCOPED_INFO("fhat(T) max " << scale << ", difference "
                                 << (by_features - by_sections).cwiseAbs().maxCoeff());
    CHECK(scale >
          0.5);  // fhat learnt a good part of the road (amplitude 2): not a comparison of zeros
    CHECK((by_features - by_sections).cwiseAbs().maxCoeff() < 1e-9 * scale);
    CHECK(std::abs(pair.features_state(0) - pair.features_state(1)) > 1e-3);  // x - xhat != 0
  }
  // Fewer centres (H_n a proper subspace of H): the laws differ, so the comparison above can fail.
  const auto pair = integrate_both(1, finest_points(4, 2));
  const auto grid = track.uniform_points(1000);
  const Eigen::VectorXd by_sections = values_at(*pair.sections, pair.sections_state.tail(16), grid);
  const Eigen::VectorXd by_features = values_at(*pair.features, pair.features_state.tail(60), grid);
  CHECK((by_features - by_sections).cwiseAbs().maxCoeff() > 1e-4);
}

TEST_CASE("feature coordinates are redundant, and the law keeps beta^T beta = ||fhat||_H^2",
          "[adaptive][embedding]") {
  const auto centres = finest_points(4, 3);
  const auto pair = integrate_both(1, centres);
  const Eigen::VectorXd beta = pair.features_state.tail(60);
  // ||fhat||_H computed independently: fhat lies in H = H_n (n = 32 finest knots, degree 1), so
  // it is its own interpolant, fhat = sum_i a_i k(c_i, .) with G a = fhat(c), and
  // ||fhat||_H^2 = a^T G a = fhat(c)^T G^-1 fhat(c).
  const Eigen::MatrixXd G = pair.kernel->gram(centres);
  const Eigen::VectorXd at_knots = values_at(*pair.features, beta, centres);
  const double native = at_knots.dot(G.llt().solve(at_knots));
  INFO("beta^T beta " << beta.squaredNorm() << ", ||fhat||_H^2 " << native);
  CHECK(std::abs(beta.squaredNorm() - native) < 1e-9 * native);
  CHECK(native > 0.1);
  // The coordinates are redundant: F = 60 features span a space of dimension n_J = 32. A null
  // direction of the feature evaluations changes beta, not fhat, and adds to beta^T beta.
  const Eigen::MatrixXd features = [&] {
    Eigen::MatrixXd out(60, 2000);
    std::vector<double> row(60);
    const auto points = track.uniform_points(2000);
    for (std::size_t m = 0; m < points.size(); ++m) {
      pair.features->evaluate(points[m], row.data());
      out.col(static_cast<Eigen::Index>(m)) = Eigen::Map<const Eigen::VectorXd>(row.data(), 60);
    }
    return out;
  }();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(features, Eigen::ComputeFullU);
  const auto& sigma = svd.singularValues();
  Eigen::Index rank = 0;
  while (rank < sigma.size() && sigma(rank) > 1e-10 * sigma(0)) ++rank;
  CHECK(rank == 32);
  const Eigen::VectorXd null_direction = svd.matrixU().col(59);
  CHECK((features.transpose() * null_direction).cwiseAbs().maxCoeff() < 1e-12);
  const Eigen::VectorXd other = beta + null_direction;
  CHECK((values_at(*pair.features, other, centres) - at_knots).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(other.squaredNorm() > beta.squaredNorm() + 0.5);
  // beta itself has no component in the null space: it is the least-norm representation.
  const Eigen::VectorXd null_part = svd.matrixU().rightCols(60 - 32).transpose() * beta;
  CHECK(null_part.norm() < 1e-10 * beta.norm());
}

TEST_CASE("a right-hand side of rkhs_embedding updates (p + 1)(J + 1) coordinates",
          "[adaptive][embedding]") {
  for (const std::int64_t degree : {1, 2, 3}) {
    const std::int64_t levels = 6;
    const auto kernel = test::make_registered_kernel(
        "bspline", {{"degree", degree}, {"n0", std::int64_t{4}}, {"J", levels}}, track);
    const auto basis = kernel->feature_basis();
    const auto count = static_cast<Eigen::Index>(basis->size());
    CHECK(count == 4 * ((std::int64_t{1} << (levels + 1)) - 1));
    const Eigen::MatrixXd A = Eigen::MatrixXd::Constant(1, 1, -1.0);
    const Eigen::VectorXd B = Eigen::VectorXd::Constant(1, 1.0);
    const std::function<double(double)> f = road, slope = road_slope;
    AdaptiveSystem system(A, B, Eigen::MatrixXd::Constant(1, 1, 0.5), *basis,
                          LearningMap::scalar(count, 10.0), f, slope, track, 0.3);
    Eigen::VectorXd z = Eigen::VectorXd::Constant(system.dimension(), 0.1), dz(system.dimension());
    z(0) = 1.0;  // x - xhat = 0.9
    for (const double t : {0.123, 7.77, 40.0}) {
      system.rhs(z.data(), dz.data(), t);
      const auto changed = (dz.tail(count).array() != 0.0).count();
      INFO("degree " << degree << " at t = " << t);
      CHECK(changed <= (degree + 1) * (levels + 1));
      CHECK(changed >= levels + 1);  // at least one feature per level
    }
  }
}

TEST_CASE("rkhs_embedding refuses a kernel without a finite feature map, naming it",
          "[adaptive][embedding]") {
  const auto* entry = law_registry().find("rkhs_embedding");
  REQUIRE(entry);
  const auto law = entry->factory(ParameterSet::resolve(entry->info.parameters, {}));
  CHECK(law->coordinates() == LawCoordinates::features);
  for (const std::string name : {"gaussian", "wendland", "matern"}) {
    const auto kernel = test::make_registered_kernel(name, {}, track);
    CHECK(kernel->feature_basis() == nullptr);
    CHECK_THROWS_WITH(law->require_kernel(*kernel), Catch::Contains("rkhs_embedding") &&
                                                        Catch::Contains("'" + name + "'") &&
                                                        Catch::Contains("finite feature map"));
  }
  const auto bspline = test::make_registered_kernel("bspline", {}, track);
  CHECK_NOTHROW(law->require_kernel(*bspline));
  // The other laws take any kernel.
  for (const std::string other : {"gradient", "rkhs"}) {
    const auto* e = law_registry().find(other);
    const auto l = e->factory(ParameterSet::resolve(e->info.parameters, {}));
    CHECK(l->coordinates() == LawCoordinates::centres);
    CHECK_NOTHROW(l->require_kernel(*test::make_registered_kernel("gaussian", {}, track)));
  }
}

namespace {

const std::string embedding_study = R"(
[study]
name = "embedding"
kind = "adaptive"
evaluation_points = 1024
metrics = ["l2_error", "sup_error", "interpolant_l2_error", "gap_to_projection",
           "l2_projection_l2_error", "gap_to_l2_projection", "coefficient_error",
           "final_state_error", "max_state_error", "lyapunov_max_increase", "lyapunov_ratio",
           "pe_level"]
[domain]
radius = 4.0
[grid]
n = [32]
[[kernel]]
name = "bspline"
degree = 1
n0 = 4
J = 3
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 0.1
[[law]]
name = "rkhs_embedding"
gamma = 0.1
[[integrator]]
name = "radau5"
rtol = 1e-11
atol = 1e-12
[adaptive]
speed = 1.0
)";

}  // namespace

TEST_CASE("rkhs_embedding trials: the same estimate as the rkhs law on H_n = H",
          "[adaptive][embedding]") {
  for (const std::string road : {"target", "projection"}) {
    const auto out = test::run_study_text(
        embedding_study + "laps = 2\nsnapshot_laps = [2]\nroad = \"" + road + "\"\n",
        "embedding.toml");
    REQUIRE(out.trials.size() == 2);
    REQUIRE(out.trials[1].adaptive_axes().law.name == "rkhs_embedding");
    INFO("road = " << road);
    for (const char* metric :
         {"l2_error", "sup_error", "gap_to_projection", "final_state_error", "max_state_error",
          "l2_projection_l2_error", "gap_to_l2_projection", "pe_level"}) {
      INFO(metric << ": rkhs " << out.metric(0, metric) << ", rkhs_embedding "
                  << out.metric(1, metric));
      CHECK(std::abs(out.metric(1, metric) - out.metric(0, metric)) <=
            1e-7 * std::abs(out.metric(0, metric)) + 1e-12);
    }
    // The static part is the trial's centres' in either law.
    CHECK(out.metric(1, "interpolant_l2_error") == out.metric(0, "interpolant_l2_error"));
    const auto& a = out.results[0].snapshots.at(0).estimate;
    const auto& b = out.results[1].snapshots.at(0).estimate;
    REQUIRE(a.size() == b.size());
    double largest = 0, difference = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      largest = std::max(largest, std::abs(a[k]));
      difference = std::max(difference, std::abs(a[k] - b[k]));
    }
    CHECK(largest > 0.5);
    CHECK(difference < 1e-8 * largest);
    if (road == "projection") {
      // V of either law is 1/2 e^T P e + 1/2 Gamma ||Pi_n f - fhat||_H^2: the same numbers.
      // Both defined, each in its own coordinates (alpha against alpha*, beta against
      // beta* = Phi_c^T alpha*), and both small after two laps of learning a road in H.
      CHECK(out.metric(1, "coefficient_error") < 1);
      CHECK(out.metric(0, "coefficient_error") < 1);
      CHECK(out.metric(1, "lyapunov_max_increase") <= 1e-8);
      CHECK(std::abs(out.metric(1, "lyapunov_ratio") - out.metric(0, "lyapunov_ratio")) <
            1e-7 * out.metric(0, "lyapunov_ratio"));
      const auto& va = out.results[0].samples;
      const auto& vb = out.results[1].samples;
      REQUIRE(va.size() == vb.size());
      for (std::size_t k = 0; k < va.size(); ++k)
        CHECK(std::abs(va[k].lyapunov - vb[k].lyapunov) <= 1e-7 * va[0].lyapunov);
    } else {
      CHECK(std::isnan(out.metric(1, "coefficient_error")));
    }
  }
}

TEST_CASE("rkhs_embedding under the lap map: the redundant directions are the unexcited ones",
          "[adaptive][embedding][lap_map]") {
  const auto out = test::run_study_text(embedding_study + "laps = 2\nengine = \"lap_map\"\n",
                                        "embedding_lap_map.toml");
  // F - n_J = 60 - 32 feature directions are never excited; under the rkhs law on n = n_J
  // centres no direction is.
  CHECK(out.metric(1, "unexcited_directions") == 28);
  CHECK(out.metric(0, "unexcited_directions") == 0);
}

TEST_CASE("a study that pairs rkhs_embedding with a kernel without features fails that trial",
          "[adaptive][embedding]") {
  std::string text = embedding_study + "laps = 1\n";
  text.replace(text.find("name = \"bspline\"\ndegree = 1\nn0 = 4\nJ = 3"),
               std::string("name = \"bspline\"\ndegree = 1\nn0 = 4\nJ = 3").size(),
               "name = \"gaussian\"\nsigma = 1.0");
  const auto study = parse_study(text, "embedding_gaussian.toml");
  const auto trials = study.trials();
  RunOptions options;
  options.threads = 1;
  const auto results = run_trials(study, trials, options);
  REQUIRE(results.size() == 2);
  CHECK(results[0].ok);
  CHECK_FALSE(results[1].ok);
  CHECK_THAT(results[1].reason, Catch::Contains("rkhs_embedding") && Catch::Contains("'gaussian'"));
}
