// The adaptive system's hot path: one right-hand-side evaluation, one Jacobian, and a whole
// one-lap trial of the learning configuration (v = 1e-4 m/s, Gamma = 2e4, rosenbrock4 at
// rtol 1e-6), against n, for each kernel and law. The right-hand side allocates nothing; for
// B-spline kernels it costs O(n x features at s), not O(n^2). Also the right-hand side and
// Jacobian of a read-out in R^2 (vehicle_surface over the unit square, Wendland sections on a
// grid): n point evaluations, then M phi.
#include <benchmark/benchmark.h>

#include <numbers>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace {

const rkhs::Domain track{2 * std::numbers::pi * 4, true};

std::unique_ptr<rkhs::AnyKernel> make(const std::string& name) {
  const auto* entry = rkhs::kernel_registry().find(name);
  std::map<std::string, rkhs::ParameterValue> given;
  if (name == "bspline") given = {{"degree", std::int64_t{2}}, {"J", std::int64_t{6}}};
  return entry->factory(rkhs::ParameterSet::resolve(entry->info.parameters, given), track);
}

// One evaluation of F(z, t) (and of its Jacobian) of the coupled system at n centres. Whole
// trials stop at n = 100: each step factorises the dense (8 + n) x (8 + n) stage matrix.
void right_hand_side(benchmark::State& state, const std::string& kernel_name, bool rkhs_law,
                     bool jacobian) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto kernel = make(kernel_name);
  std::vector<double> centres(n);
  for (std::size_t i = 0; i < n; ++i)
    centres[i] = track.length * static_cast<double>(i) / static_cast<double>(n);
  const auto* plant_entry = rkhs::plant_registry().find("quarter_car");
  const auto plant =
      plant_entry->factory(rkhs::ParameterSet::resolve(plant_entry->info.parameters, {}));
  const auto P = rkhs::solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(4, 4)).P;
  const rkhs::GramSolver solver(kernel->gram(centres), {});
  const auto size = static_cast<Eigen::Index>(n);
  const Eigen::MatrixXd map =
      rkhs_law ? Eigen::MatrixXd(
                     solver.solve(Eigen::MatrixXd(Eigen::MatrixXd::Identity(size, size))) / 2e4)
               : Eigen::MatrixXd(Eigen::MatrixXd::Identity(size, size) / 2e4);
  const auto basis = kernel->basis(centres);
  const std::function<double(double)> road = [](double s) { return 2 * std::sin(s / 4); };
  const std::function<double(double)> slope = [](double s) { return 0.5 * std::cos(s / 4); };
  rkhs::AdaptiveSystem system(plant->A(), plant->B(), P, *basis, map, road, slope, track, 1e-4,
                              rkhs::learning_signal_for(*kernel));
  Eigen::VectorXd z = Eigen::VectorXd::Constant(system.dimension(), 0.1), dz(system.dimension());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(system.dimension(),
                                                                           system.dimension());
  Eigen::VectorXd dfdt(system.dimension());
  double t = 1.0;
  for (auto _ : state) {
    if (jacobian)
      system.jacobian(z.data(), J.data(), t, dfdt.data());
    else
      system.rhs(z.data(), dz.data(), t);
    t += 37.0;  // move along the track
    benchmark::DoNotOptimize(dz.data());
    benchmark::DoNotOptimize(J.data());
  }
  state.SetComplexityN(state.range(0));
}

// One right-hand side of rkhs_embedding: the feature coordinates of the B-spline kernel
// (degree 2, n0 = 4) with finest level J = range(0), F = 4 (2^(J+1) - 1) coordinates of which
// (p + 1)(J + 1) change; the rest of the cost is the O(F) vector work on the state.
void embedding_rhs(benchmark::State& state) {
  const auto* entry = rkhs::kernel_registry().find("bspline");
  const auto kernel = entry->factory(
      rkhs::ParameterSet::resolve(entry->info.parameters,
                                  {{"degree", std::int64_t{2}}, {"J", state.range(0)}}),
      track);
  const auto* plant_entry = rkhs::plant_registry().find("quarter_car");
  const auto plant =
      plant_entry->factory(rkhs::ParameterSet::resolve(plant_entry->info.parameters, {}));
  const auto P = rkhs::solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(4, 4)).P;
  const auto basis = kernel->feature_basis();
  const auto count = static_cast<Eigen::Index>(basis->size());
  const std::function<double(double)> road = [](double s) { return 2 * std::sin(s / 4); };
  const std::function<double(double)> slope = [](double s) { return 0.5 * std::cos(s / 4); };
  rkhs::AdaptiveSystem system(plant->A(), plant->B(), P, *basis,
                              rkhs::LearningMap::scalar(count, 1 / 2e4), road, slope, track, 1e-4);
  Eigen::VectorXd z = Eigen::VectorXd::Constant(system.dimension(), 0.1), dz(system.dimension());
  double t = 1.0;
  for (auto _ : state) {
    system.rhs(z.data(), dz.data(), t);
    t += 37.0;
    benchmark::DoNotOptimize(dz.data());
  }
  state.counters["F"] = static_cast<double>(count);
  state.SetComplexityN(count);
}

// A whole trial: one lap of the learning configuration.
void one_lap_trial(benchmark::State& state, const std::string& kernel_name,
                   const std::string& law) {
  const std::string text = R"(
[study]
name = "bench"
kind = "adaptive"
evaluation_points = 1024
[domain]
radius = 4.0
[grid]
n = [)" + std::to_string(state.range(0)) +
                           R"(]
[[kernel]]
name = ")" + kernel_name + R"("
)" + (kernel_name == "bspline" ? "degree = 2\nJ = 6\n" : "") +
                           R"(
[[law]]
name = ")" + law + R"("
gamma = 2e4
[[integrator]]
name = "rosenbrock4"
[adaptive]
speed = 1e-4
laps = 1
)";
  const auto study = rkhs::parse_study(text, "bench.toml");
  const auto trials = study.trials();
  for (auto _ : state) {
    auto result = rkhs::run_trial(study, trials[0]);
    if (!result.ok) state.SkipWithError(result.reason.c_str());
    state.counters["steps"] = result.metrics[study.metric_index("steps")];
  }
  state.SetComplexityN(state.range(0));
}

}  // namespace

BENCHMARK_CAPTURE(right_hand_side, gaussian_gradient, std::string("gaussian"), false, false)
    ->RangeMultiplier(2)
    ->Range(16, 1024)
    ->Complexity();
BENCHMARK_CAPTURE(right_hand_side, gaussian_rkhs, std::string("gaussian"), true, false)
    ->RangeMultiplier(2)
    ->Range(16, 1024)
    ->Complexity();
BENCHMARK_CAPTURE(right_hand_side, bspline_gradient, std::string("bspline"), false, false)
    ->RangeMultiplier(2)
    ->Range(16, 1024)
    ->Complexity();
BENCHMARK_CAPTURE(right_hand_side, bspline_rkhs, std::string("bspline"), true, false)
    ->RangeMultiplier(2)
    ->Range(16, 1024)
    ->Complexity();
BENCHMARK_CAPTURE(right_hand_side, wendland_gradient, std::string("wendland"), false, false)
    ->RangeMultiplier(2)->Range(16, 1024)->Complexity();
BENCHMARK_CAPTURE(right_hand_side, wendland_rkhs, std::string("wendland"), true, false)
    ->RangeMultiplier(2)->Range(16, 1024)->Complexity();
BENCHMARK_CAPTURE(right_hand_side, matern_gradient, std::string("matern"), false, false)
    ->RangeMultiplier(2)->Range(16, 1024)->Complexity();
BENCHMARK_CAPTURE(right_hand_side, matern_rkhs, std::string("matern"), true, false)
    ->RangeMultiplier(2)->Range(16, 1024)->Complexity();
BENCHMARK_CAPTURE(right_hand_side, bspline_rkhs_jacobian, std::string("bspline"), true, true)
    ->RangeMultiplier(2)
    ->Range(16, 256)
    ->Complexity();
// f of a read-out in R^2: the vehicle_surface plant's wheel over the unit square, n = m^2
// Wendland sections (k = 1, radius 0.25) on a grid, the rkhs law (M = G^-1 / Gamma, dense).
void planar_readout(benchmark::State& state, bool jacobian) {
  const auto side = static_cast<std::size_t>(state.range(0));
  rkhs::Domain square{1.0, false};
  square.dimension = 2;
  square.width = 1.0;
  const auto* kernel_entry = rkhs::kernel_registry().find("wendland");
  const auto kernel = kernel_entry->factory(
      rkhs::ParameterSet::resolve(kernel_entry->info.parameters,
                                  {{"k", std::int64_t{1}}, {"radius", 0.25}}),
      square);
  std::vector<double> centres;
  for (std::size_t j = 0; j < side; ++j)
    for (std::size_t i = 0; i < side; ++i) {
      centres.push_back(static_cast<double>(i) / static_cast<double>(side - 1));
      centres.push_back(static_cast<double>(j) / static_cast<double>(side - 1));
    }
  const auto* plant_entry = rkhs::plant_registry().find("vehicle_surface");
  const auto plant = plant_entry->factory(rkhs::ParameterSet::resolve(
      plant_entry->info.parameters, {{"passes", std::string("0.25; 0.75")}}));
  const auto P = rkhs::solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(6, 6)).P;
  const rkhs::GramSolver solver(kernel->gram(centres), {});
  const rkhs::PointSections sections(*kernel, centres);
  const auto map = rkhs::LearningMap::gram_inverse(solver, 1.0);
  const std::function<double(const double*)> f = [](const double* y) {
    return 0.01 * std::sin(6 * y[0]) * std::cos(4 * y[1]);
  };
  const std::function<void(const double*, double*)> gradient = [](const double* y, double* g) {
    g[0] = 0.06 * std::cos(6 * y[0]) * std::cos(4 * y[1]);
    g[1] = -0.04 * std::sin(6 * y[0]) * std::sin(4 * y[1]);
  };
  rkhs::AdaptiveSystem system(plant->A(), plant->B(), P, sections, map, *plant, f, gradient,
                              square);
  const auto m = system.dimension();
  Eigen::VectorXd z = Eigen::VectorXd::Constant(m, 0.01), dz(m), dfdt(m);
  z(4) = z(10) = 0.43;  // the wheel inside the square
  z(5) = z(11) = 0.57;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
  for (auto _ : state) {
    if (jacobian)
      system.jacobian(z.data(), J.data(), 1.0, dfdt.data());
    else
      system.rhs(z.data(), dz.data(), 1.0);
    benchmark::DoNotOptimize(jacobian ? J.data() : dz.data());
  }
  state.SetComplexityN(static_cast<benchmark::IterationCount>(side * side));
}

BENCHMARK(embedding_rhs)->DenseRange(4, 10, 2)->Complexity();
BENCHMARK_CAPTURE(planar_readout, rhs, false)->Arg(6)->Arg(8)->Arg(12)->Arg(16)->Complexity();
BENCHMARK_CAPTURE(planar_readout, jacobian, true)->Arg(6)->Arg(8)->Arg(12)->Arg(16)->Complexity();
BENCHMARK_CAPTURE(one_lap_trial, gaussian_gradient, std::string("gaussian"), std::string("gradient"))
    ->Arg(10)->Arg(20)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(one_lap_trial, gaussian_rkhs, std::string("gaussian"), std::string("rkhs"))
    ->Arg(10)
    ->Arg(20)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(one_lap_trial, bspline_gradient, std::string("bspline"), std::string("gradient"))
    ->Arg(10)
    ->Arg(20)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(one_lap_trial, bspline_rkhs, std::string("bspline"), std::string("rkhs"))
    ->Arg(10)
    ->Arg(20)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

BENCHMARK_MAIN();
