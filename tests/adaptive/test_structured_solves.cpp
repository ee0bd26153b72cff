// Stage solves with the structure of the coupled system's Jacobian against the dense
// reference, the Radau IIA integrator against closed forms, and the lap map against time
// stepping.
#include <catch2/catch.hpp>
#include <complex>
#include <numbers>
#include <limits>
#include <random>

#include <Eigen/SVD>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/lap_map.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/radau.hpp"
#include "rkhs/adaptive/stage_solves.hpp"
#include "rkhs/approx/gram_solver.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<AnyKernel> make(const std::string& name,
                                std::map<std::string, ParameterValue> parameters,
                                const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, parameters), domain);
}

std::unique_ptr<Plant> quarter_car() {
  const auto* entry = plant_registry().find("quarter_car");
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {}));
}

const Domain track{2 * std::numbers::pi * 4, true};

struct Case {
  std::string kernel;
  std::map<std::string, ParameterValue> parameters;
};

const std::vector<Case> kernels{{"gaussian", {{"sigma", 1.0}}},
                                {"bspline", {{"degree", std::int64_t{1}}, {"J", std::int64_t{6}}}},
                                {"bspline", {{"degree", std::int64_t{2}}, {"J", std::int64_t{6}}}},
                                {"wendland", {}},
                                {"matern", {}}};

/// The coupled system of one trial: quarter car, Q = I, n uniform centres, the rkhs law's
/// learning map Gamma^-1 G^-1 or the gradient law's Gamma^-1 I, f = 2 sin(2 pi s / L).
struct Trial {
  Trial(const Case& c, std::size_t n, bool rkhs_law, double gamma, double speed)
      : kernel(make(c.kernel, c.parameters, track)), plant(quarter_car()) {
    for (std::size_t i = 0; i < n; ++i)
      centres.push_back(track.length * static_cast<double>(i) / static_cast<double>(n));
    P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(4, 4)).P;
    const auto gram = kernel->gram(centres);
    const auto identity = Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(n),
                                                    static_cast<Eigen::Index>(n));
    map = rkhs_law ? Eigen::MatrixXd(GramSolver(gram, {}).solve(Eigen::MatrixXd(identity)) / gamma)
                   : Eigen::MatrixXd(identity / gamma);
    basis = kernel->basis(centres);
    road = [](double s) { return 2 * std::sin(2 * std::numbers::pi * s / track.length); };
    slope = [](double s) {
      const double k = 2 * std::numbers::pi / track.length;
      return 2 * k * std::cos(k * s);
    };
    system = std::make_unique<AdaptiveSystem>(plant->A(), plant->B(), P, *basis, map, road, slope,
                                              track, speed, learning_signal_for(*kernel));
  }
  std::unique_ptr<AnyKernel> kernel;
  std::unique_ptr<Plant> plant;
  std::vector<double> centres;
  Eigen::MatrixXd P, map;
  std::unique_ptr<KernelBasis> basis;
  std::function<double(double)> road, slope;
  std::unique_ptr<AdaptiveSystem> system;
};

}  // namespace

TEST_CASE("structured stage solves equal the dense ones", "[adaptive][structured]") {
  // Both are backward stable, so they agree to round-off times the condition number of
  // c I - J: to 1e-12 relative, or to 10 eps cond(c I - J) where that is larger (long steps,
  // where c I - J nears the singular -J: cond up to 1e8 at h = 1e4 s).
  std::mt19937_64 random(7);
  std::normal_distribution<double> normal;
  for (const auto& c : kernels)
    for (bool rkhs_law : {false, true})
      for (std::size_t n : {std::size_t{10}, std::size_t{40}}) {
        Trial trial(c, n, rkhs_law, 2e4, 1e-4);
        StageSolves structured(*trial.system, LinearSolver::structured);
        StageSolves dense(*trial.system, LinearSolver::dense);
        const Eigen::Index m = trial.system->dimension();
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
        for (double t : {0.0, 1.234e4, 9.87e4}) {
          trial.system->jacobian_matrix(t, J.data());
          for (double h : {1e-3, 10.0, 1e3, 1e4}) {
            const double shift = 1 / (0.25 * h);
            const std::complex<double> complex_shift{2.68 / h, -3.05 / h};
            structured.factor(t, shift, complex_shift);
            dense.factor(t, shift, complex_shift);
            auto tolerance = [&](auto s) {
              using Complex = std::complex<double>;
              const Eigen::MatrixXcd matrix =
                  Complex(s) * Eigen::MatrixXcd::Identity(m, m) - Eigen::MatrixXd(J).cast<Complex>();
              const auto sigma = Eigen::JacobiSVD<Eigen::MatrixXcd>(matrix).singularValues();
              return std::max(1e-12,
                              10 * std::numeric_limits<double>::epsilon() * sigma(0) / sigma(m - 1));
            };
            Eigen::MatrixXd r(m, 2);
            for (Eigen::Index i = 0; i < r.size(); ++i) r.data()[i] = normal(random);
            Eigen::MatrixXd a = r, b = r;
            structured.solve_real(a);
            dense.solve_real(b);
            INFO(c.kernel << " n = " << n << (rkhs_law ? " rkhs" : " gradient") << " t = " << t
                          << " h = " << h);
            CHECK((a - b).norm() <= tolerance(shift) * b.norm());
            Eigen::MatrixXcd rc(m, 2);
            for (Eigen::Index i = 0; i < rc.size(); ++i)
              rc.data()[i] = {normal(random), normal(random)};
            Eigen::MatrixXcd ac = rc, bc = rc;
            structured.solve_complex(ac);
            dense.solve_complex(bc);
            CHECK((ac - bc).norm() <= tolerance(complex_shift) * bc.norm());
          }
        }
      }
}

TEST_CASE("a structured solve inverts c I - J", "[adaptive][structured]") {
  // Independent of the dense path: multiply back with the Jacobian.
  Trial trial(kernels[0], 12, true, 3.0, 0.7);
  const Eigen::Index m = trial.system->dimension();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
  trial.system->jacobian_matrix(2.5, J.data());
  StageSolves structured(*trial.system, LinearSolver::structured);
  const double shift = 40.0;
  structured.factor(2.5, shift);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Random(m, 3);
  Eigen::MatrixXd k = r;
  structured.solve_real(k);
  const Eigen::MatrixXd back = shift * k - Eigen::MatrixXd(J) * k;
  CHECK((back - r).norm() <= 1e-12 * r.norm());
}

namespace {

/// y' = lambda (y - g(t)) + g'(t), g(t) = sin(t): y(t) = g(t) + (y0 - g(0)) e^(lambda t), in
/// every column, as a RadauProblem with exact solves (J = lambda I).
struct ScalarProblem {
  double lambda;
  Eigen::Index columns_ = 1;
  double real_shift = 0;
  std::complex<double> complex_shift = 0;
  std::size_t rhs_calls = 0;
  Eigen::Index rows() const { return 1; }
  Eigen::Index columns() const { return columns_; }
  void rhs(double t, const Eigen::MatrixXd& y, Eigen::MatrixXd& dy) {
    ++rhs_calls;
    dy = (lambda * (y.array() - std::sin(t)) + std::cos(t)).matrix();
  }
  void factor(double, const Eigen::MatrixXd&, double re, std::complex<double> cx) {
    real_shift = re;
    complex_shift = cx;
  }
  void solve_real(Eigen::MatrixXd& r) const { r /= (real_shift - lambda); }
  void solve_complex(Eigen::MatrixXcd& r) const { r /= (complex_shift - lambda); }
};

// The error at t = 2 of fixed steps h (every step accepted at any error: huge tolerances).
double radau_error(double lambda, double h) {
  ScalarProblem problem{lambda};
  RadauIIA5<ScalarProblem> radau(problem, 1e10, 1e10);
  radau.state()[0] = 1.0;
  double t = 0;
  const int steps = static_cast<int>(std::lround(2.0 / h));
  for (int k = 0; k < steps; ++k) {
    double dt = h;
    REQUIRE(radau.try_step(t, dt) == StepOutcome::accepted);
  }
  const double exact = std::sin(2.0) + (1.0 - 0.0) * std::exp(lambda * 2.0);
  return std::abs(radau.state()[0] - exact);
}

}  // namespace

TEST_CASE("Radau IIA converges with order 5 and is stiffly accurate", "[adaptive][radau]") {
  // Non-stiff: the error falls 2^5 = 32-fold per halving of h.
  const double e1 = radau_error(-1.0, 0.1), e2 = radau_error(-1.0, 0.05);
  CHECK(std::log2(e1 / e2) > 4.7);
  CHECK(std::log2(e1 / e2) < 5.5);
  // Stiff (lambda h = -1e5): the slow solution is followed, the fast transient damped.
  CHECK(radau_error(-1e6, 0.1) < 1e-6);
}

TEST_CASE("Radau IIA's step control meets its tolerance", "[adaptive][radau]") {
  for (double rtol : {1e-4, 1e-7, 1e-10}) {
    ScalarProblem problem{-50.0};
    RadauIIA5<ScalarProblem> radau(problem, rtol, rtol);
    radau.state()[0] = 3.0;
    double t = 0, dt = 1e-6;
    while (t < 10) {
      double step = std::min(dt, 10 - t);
      const bool last = step == 10 - t;
      if (radau.try_step(t, step) == StepOutcome::accepted) {
        if (last) t = 10;
        dt = last ? std::max(dt, step) : step;
      } else {
        dt = step;
      }
    }
    const double exact = std::sin(10.0) + 3.0 * std::exp(-500.0);
    INFO("rtol " << rtol);
    CHECK(std::abs(radau.state()[0] - exact) < 30 * rtol);
  }
}

TEST_CASE("the lap map agrees with time stepping over 10 laps", "[adaptive][lap_map]") {
  const auto* radau = integrator_registry().find("radau5");
  REQUIRE(radau);
  for (const auto& c : {kernels[0], kernels[1]})
    for (bool rkhs_law : {false, true}) {
      Trial trial(c, 10, rkhs_law, 2e4, 1e-4);
      auto& system = *trial.system;
      const double lap_time = track.length / 1e-4;
      std::vector<double> kink_times;
      for (double kink : trial.kernel->kink_points()) kink_times.push_back(kink / 1e-4);
      const auto map = compute_lap_map(system, lap_time, kink_times, 1e-10, 1e-10, 1 << 22);
      const LapPowers powers(map);
      const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(system.dimension());
      const Eigen::VectorXd by_map = powers.advance(z0, 10);
      // Time stepping at rtol 1e-10 through the same kinks.
      std::vector<double> times{0.0};
      for (int lap = 0; lap < 10; ++lap) {
        for (double t : kink_times)
          if (t > 0) times.push_back(lap * lap_time + t);
        times.push_back((lap + 1) * lap_time);
      }
      std::sort(times.begin(), times.end());
      times.erase(std::unique(times.begin(), times.end()), times.end());
      const auto integrator = radau->factory(ParameterSet::resolve(
          radau->info.parameters,
          {{"rtol", 1e-10}, {"atol", 1e-10}, {"max_steps", std::int64_t{1} << 22}}));
      Eigen::VectorXd stepped = z0;
      integrator->integrate(system, stepped, times, [](std::size_t, const double*) {});
      INFO(c.kernel << (rkhs_law ? " rkhs" : " gradient"));
      CHECK((by_map - stepped).norm() <= 1e-6 * stepped.norm());
      // Learning contracts: the learning block's spectral radius is below 1, and the limit
      // is a fixed point of the map.
      const auto limit = periodic_limit(map, z0, 4, 1e-8, 1e-10);
      CHECK(limit.spectral_radius < 1);
      const Eigen::VectorXd again = map.monodromy * limit.state + map.offset;
      CHECK((again - limit.state).norm() <= 1e-8 * limit.state.norm());
    }
}

TEST_CASE("lap powers: N laps equal N applications of the map", "[adaptive][lap_map]") {
  LapMap map;
  map.monodromy = Eigen::MatrixXd::Random(5, 5) * 0.3;
  map.offset = Eigen::VectorXd::Random(5);
  const LapPowers powers(map);
  Eigen::VectorXd z = Eigen::VectorXd::Random(5);
  const Eigen::VectorXd z0 = z;
  for (std::uint64_t laps = 1; laps <= 37; ++laps) {
    z = map.monodromy * z + map.offset;
    CHECK((powers.advance(z0, laps) - z).norm() <= 1e-13 * (1 + z.norm()));
  }
  CHECK(powers.advance(z0, 0) == z0);
}

TEST_CASE("the periodic limit keeps unexcited directions at their initial value",
          "[adaptive][lap_map]") {
  // Phi = diag(0.5, 0.9, 1): the third direction is never excited (c_3 = 0).
  LapMap map;
  map.monodromy = Eigen::Vector3d(0.5, 0.9, 1.0).asDiagonal();
  map.offset = Eigen::Vector3d(1.0, 2.0, 0.0);
  const Eigen::VectorXd z0 = Eigen::Vector3d(0.3, -0.2, 7.0);
  const auto limit = periodic_limit(map, z0, 1, 1e-10, 1e-12);
  CHECK(limit.state(0) == Approx(2.0).epsilon(1e-14));
  CHECK(limit.state(1) == Approx(20.0).epsilon(1e-13));
  CHECK(limit.state(2) == 7.0);
  CHECK(limit.unexcited_directions == 1);
  CHECK(limit.spectral_radius == Approx(0.9).epsilon(1e-14));
  CHECK(limit.slowest_time_constant_laps == Approx(-1 / std::log(0.9)).epsilon(1e-12));
}

TEST_CASE("a lap map cache computes each key once and says who computed it",
          "[adaptive][lap_map]") {
  LapMapCache cache;
  int computations = 0;
  auto compute = [&] {
    ++computations;
    LapMap map;
    map.monodromy = Eigen::MatrixXd::Identity(2, 2) * 0.5;
    map.offset = Eigen::VectorXd::Ones(2);
    map.rhs_evaluations = 7;
    return map;
  };
  const auto first = cache.find_or_compute("a", compute);
  const auto second = cache.find_or_compute("a", compute);
  const auto other = cache.find_or_compute("b", compute);
  CHECK(computations == 2);
  CHECK(first.computed_here);
  CHECK_FALSE(second.computed_here);
  CHECK(other.computed_here);
  CHECK(first.map == second.map);  // shared, not copied
  CHECK(first.map != other.map);
  CHECK(second.map->rhs_evaluations == 7);
  // A failed computation reaches every caller of its key.
  auto fail = []() -> LapMap { throw std::runtime_error("step size underflow"); };
  CHECK_THROWS_WITH(cache.find_or_compute("c", fail), "step size underflow");
  CHECK_THROWS_WITH(cache.find_or_compute("c", compute), "step size underflow");
}
