// The cost of the adaptive engine, stated as complexity fits in n, and the cost of the lap map
// against the lap count.
//
// Configuration of every benchmark in n: the quarter car (d = 4, P from A^T P + P A = -I),
// v = 1e-4 m/s, Gamma = 2e4, the sine road of amplitude 2 on the radius-4 track, n centres
// evenly spaced on the track, n = 16 .. 4096 by factors of 4. Kernels: gaussian (sigma = 1),
// bspline of degree 1 and 2 (n0 = 5, J = 10: rank n0 2^J = 5120 > 4096, F = n0 (2^(J+1) - 1)
// = 10235 features), wendland (k = 1, radius 1) and matern (nu = 1.5, length scale 1). Laws:
// gradient (M = Gamma^-1 I) and rkhs (M = Gamma^-1 G^-1, G^-1 from GramSolver). The system is
// built as measure_adaptive builds it (learning_signal_for: by_basis for the B-splines,
// from_phi otherwise). Set-up (Gram matrix, its eigen-decomposition, G^-1, the basis and its
// mapped features) is done once per (kernel, law, n) outside the timed loops; the rkhs law
// stops at n = 1024 because that set-up (a symmetric eigen-decomposition of G and, for the
// B-splines, the n x n x F product M Phi_c) is O(n^3) and takes minutes at n = 4096.
//
// Families (each fitted with ->Complexity):
//   step/<kernel>/<law>/<solver>  one Radau IIA (order 5) step of one trajectory (RadauIIA5 on a
//     one-column problem, TrajectoryStages of rkhs/adaptive/stage_solves.hpp) at
//     rtol 1e-6, atol 1e-8, from a fixed state on a trajectory (1 s after t = 2.5e4 s, the
//     plant's transients gone) with a fixed h (the controller's, counter `h`): the state copy,
//     reset(), and try_step: 1 rhs at the start, StageSolves::factor (one linearisation = one basis
//     evaluation, and the real and complex factorisations), per Newton iteration 3 rhs +
//     solve_real + solve_complex, the error estimate's solve_real, 1 rhs at the end. The
//     counters say how many Newton iterations and right-hand sides that was (every step is
//     accepted; the counter `accepted` is 1).
//   stage/<kernel>/<law>/<solver>  StageSolves::factor(t, real, complex) + solve_real +
//     solve_complex of one column, at Radau's shifts for h = 1e-3 s.
//   coupled_solver/<kernel>/<law>  ShiftedCoupledSolver alone (real and complex factor +
//     solve) on a fixed CoupledLinearization: the linear algebra of the structured solve
//     without the basis evaluation.
//   rhs/<kernel>/<law>  one AdaptiveSystem::rhs.
// <solver> is structured (n = 16 .. 4096) or dense (LinearSolver::dense, n = 16 .. 256, fitted
// with oNCubed).
//
// Expected, and what the fits show: the structured solve is O(n) for every kernel and law. A
// right-hand side (and the linearisation inside factor) evaluates phi(s) and psi(s) = M phi(s):
//   - B-splines (feature map): phi = Phi_c f(s) and psi = (M Phi_c) f(s), each a sum of
//     (p + 1)(J + 1) columns of length n: O(n (p + 1)(J + 1)), i.e. O(n), for both laws (not
//     O(support): Phi_c is stored dense, n x F);
//   - direct kernels (gaussian, wendland, matern), gradient law: n kernel evaluations and a
//     scalar product, O(n);
//   - direct kernels, rkhs law: psi = M phi with M = G^-1 / Gamma in the form of
//     rkhs/adaptive/learning_map.hpp. The Gaussian's Gram matrix has numerical rank about 63
//     on this track whatever n, and its pseudo-inverse is applied as V diag(w) V^T: O(63 n),
//     fitted with oN. Wendland (radius 1) and Matern have full-rank Gram matrices: M is a
//     DENSE n x n matrix-vector product, O(n^2), and their step, stage solve (through its
//     linearisation) and rhs are fitted with oNSquared. That is inherent to the rkhs law:
//     G^-1 phi(s) are the n cardinal functions at s, all non-zero.
//
// lap_map/<kernel>/<law>/<laps>: one whole trial (parse_study + run_trial, i.e.
// measure_adaptive) of the paper_synthetic configuration with engine = "lap_map" at
// laps = 100, 1e4, 1e5, 1e6 (bspline degree 1 J = 6 and gaussian, n = 20). Acceptance:
// cost(1e4) <= 3 cost(100) and cost(1e6) <= 1.5 cost(1e4).
// The last lap is integrated over [0, T] from the state the map gives (the dynamics are
// T-periodic), so 1e6 laps run like 100: measured (CPU time, 2 shared cores, n = 20),
// cost(1e4)/cost(100) = 0.95-1.05 and cost(1e6)/cost(1e4) = 0.78-1.13 over the four cases.
// lap_map_functions/<kernel>/<law>/<laps> times the lap map alone (see there), which meets the
// acceptance figures at every lap count.
//
// Run, e.g.: bench_engine --benchmark_min_time=0.05 --benchmark_filter='^(step|stage)/'
#include <benchmark/benchmark.h>

#include <chrono>
#include <complex>
#include <map>
#include <memory>
#include <numbers>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/coupled_structure.hpp"
#include "rkhs/adaptive/lap_map.hpp"
#include "rkhs/adaptive/learning_map.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/radau.hpp"
#include "rkhs/adaptive/stage_solves.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace {

using namespace rkhs;

const Domain track{2 * std::numbers::pi * 4, true};

struct KernelCase {
  std::string label;  // in benchmark names
  std::string name;   // in the registry
  std::map<std::string, ParameterValue> parameters;
  bool feature_map;  // B-spline: psi through the mapped features, O(n) for both laws
};

const std::vector<KernelCase>& kernel_cases() {
  static const std::vector<KernelCase> cases = {
      {"gaussian", "gaussian", {{"sigma", 1.0}}, false},
      {"bspline1", "bspline",
       {{"degree", std::int64_t{1}}, {"n0", std::int64_t{5}}, {"J", std::int64_t{10}}}, true},
      {"bspline2", "bspline",
       {{"degree", std::int64_t{2}}, {"n0", std::int64_t{5}}, {"J", std::int64_t{10}}}, true},
      {"wendland", "wendland", {}, false},
      {"matern", "matern", {}, false},
  };
  return cases;
}

// The coupled system at n centres, built as measure_adaptive builds it.
struct Engine {
  std::unique_ptr<AnyKernel> kernel;
  std::vector<double> centres;
  Eigen::MatrixXd A, P;
  LearningMap M;
  Eigen::VectorXd B;
  std::unique_ptr<KernelBasis> basis;
  std::function<double(double)> road = [](double s) { return 2 * std::sin(s / 4); };
  std::function<double(double)> slope = [](double s) { return 0.5 * std::cos(s / 4); };
  std::unique_ptr<AdaptiveSystem> system;
  double setup_seconds = 0;
  // Where the timed Radau step starts (prepare_step): a state on a trajectory, its time and a
  // step size that the controller accepts from there.
  Eigen::VectorXd step_state;
  double step_time = 0, step_size = 0;
};

void prepare_step(Engine& e);

// Set-up is cached per (kernel, law, n); the cache is emptied when the (kernel, law) changes,
// so that at most one pair's large matrices (n x F mapped features at n = 4096) are held.
Engine& engine(const KernelCase& kernel_case, bool rkhs_law, std::size_t n) {
  static std::map<std::size_t, std::unique_ptr<Engine>> cache;
  static std::string cached_pair;
  const std::string pair = kernel_case.label + (rkhs_law ? "/rkhs" : "/gradient");
  if (pair != cached_pair) {
    cache.clear();
    cached_pair = pair;
  }
  auto& slot = cache[n];
  if (slot) return *slot;
  const auto start = std::chrono::steady_clock::now();
  auto e = std::make_unique<Engine>();
  const auto* entry = kernel_registry().find(kernel_case.name);
  e->kernel = entry->factory(ParameterSet::resolve(entry->info.parameters, kernel_case.parameters),
                             track);
  e->centres.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    e->centres[i] = track.length * static_cast<double>(i) / static_cast<double>(n);
  const auto* plant_entry = plant_registry().find("quarter_car");
  const auto plant = plant_entry->factory(ParameterSet::resolve(plant_entry->info.parameters, {}));
  e->A = plant->A();
  e->B = plant->B();
  e->P = solve_lyapunov(e->A, Eigen::MatrixXd::Identity(4, 4)).P;
  const auto size = static_cast<Eigen::Index>(n);
  if (rkhs_law) {
    const GramSolver solver(e->kernel->gram(e->centres), {});
    e->M = LearningMap::gram_inverse(solver, 2e4);
  } else {
    e->M = LearningMap::scalar(size, 1 / 2e4);
  }
  e->basis = e->kernel->basis(e->centres);
  e->system = std::make_unique<AdaptiveSystem>(e->A, e->B, e->P, *e->basis, e->M, e->road,
                                               e->slope, track, 1e-4,
                                               learning_signal_for(*e->kernel));
  prepare_step(*e);
  e->setup_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  slot = std::move(e);
  return *slot;
}

// A state on no particular trajectory, with x != xhat so that the learning law is active.
Eigen::VectorXd start_state(Eigen::Index m) {
  Eigen::VectorXd z = Eigen::VectorXd::Constant(m, 0.1);
  z.head(4) << 1e-2, -2e-2, 3e-3, 5e-3;
  z.segment(4, 4).setZero();
  return z;
}

constexpr double t0 = 2.5e4;  // s = 2.5 m: inside the track, on no knot
constexpr double h = 1e-3;    // s
// Radau IIA's shifts mu / h.
const double mu_real = RadauIIA5<TrajectoryStages>::mu_real;
const std::complex<double> mu_complex = RadauIIA5<TrajectoryStages>::mu_complex;

// Integrates 1 s (the plant's transients decay) from start_state at t0 with structured
// Radau IIA steps at rtol 1e-6, atol 1e-8; the timed step starts from the state reached, with
// the step size the controller proposes there, halved until a step from a reset stepper is
// accepted.
void prepare_step(Engine& e) {
  TrajectoryStages problem(*e.system, LinearSolver::structured);
  RadauIIA5<TrajectoryStages> stepper(problem, 1e-8, 1e-6);
  const Eigen::Index m = e.system->dimension();
  const Eigen::VectorXd z0 = start_state(m);
  std::copy(z0.data(), z0.data() + m, stepper.state());
  double t = t0, dt = 1e-6;
  for (int i = 0; i < 100000 && t < t0 + 1.0; ++i) stepper.try_step(t, dt);
  e.step_state = Eigen::Map<const Eigen::VectorXd>(stepper.state(), m);
  e.step_time = t;
  for (int i = 0; i < 60; ++i, dt /= 2) {
    std::copy(e.step_state.data(), e.step_state.data() + m, stepper.state());
    stepper.reset();
    double tt = t, hh = dt;
    if (stepper.try_step(tt, hh) == StepOutcome::accepted) break;
  }
  e.step_size = dt;
}

void implicit_step(benchmark::State& state, const KernelCase& kernel_case, bool rkhs_law,
                   LinearSolver solver) {
  const auto n = static_cast<std::size_t>(state.range(0));
  auto& e = engine(kernel_case, rkhs_law, n);
  TrajectoryStages problem(*e.system, solver);
  RadauIIA5<TrajectoryStages> stepper(problem, 1e-8, 1e-6);
  const Eigen::VectorXd& z0 = e.step_state;
  const std::size_t rhs_before = e.system->rhs_evaluations();
  const std::size_t newton_before = stepper.newton_iterations();
  std::size_t accepted = 0;
  for (auto _ : state) {
    std::copy(z0.data(), z0.data() + z0.size(), stepper.state());
    stepper.reset();
    double t = e.step_time, dt = e.step_size;
    if (stepper.try_step(t, dt) == StepOutcome::accepted) ++accepted;
    benchmark::DoNotOptimize(stepper.state());
  }
  const auto steps = static_cast<double>(state.iterations());
  state.counters["accepted"] = static_cast<double>(accepted) / steps;
  state.counters["newton"] = static_cast<double>(stepper.newton_iterations() - newton_before) / steps;
  state.counters["rhs"] = static_cast<double>(e.system->rhs_evaluations() - rhs_before) / steps;
  state.counters["h"] = e.step_size;
  state.counters["setup_s"] = e.setup_seconds;
  state.SetComplexityN(state.range(0));
}

void stage_solve(benchmark::State& state, const KernelCase& kernel_case, bool rkhs_law,
                 LinearSolver solver) {
  const auto n = static_cast<std::size_t>(state.range(0));
  auto& e = engine(kernel_case, rkhs_law, n);
  StageSolves solves(*e.system, solver);
  const Eigen::Index m = e.system->dimension();
  const Eigen::MatrixXd r0 = start_state(m);
  const Eigen::MatrixXcd c0 = r0.cast<std::complex<double>>() * std::complex<double>(1, -0.5);
  Eigen::MatrixXd r = r0;
  Eigen::MatrixXcd c = c0;
  for (auto _ : state) {
    solves.factor(t0, mu_real / h, mu_complex / h);
    r = r0;
    c = c0;
    solves.solve_real(r);
    solves.solve_complex(c);
    benchmark::DoNotOptimize(r.data());
    benchmark::DoNotOptimize(c.data());
  }
  state.SetComplexityN(state.range(0));
}

void coupled_solver(benchmark::State& state, const KernelCase& kernel_case, bool rkhs_law) {
  const auto n = static_cast<std::size_t>(state.range(0));
  auto& e = engine(kernel_case, rkhs_law, n);
  CoupledLinearization linearization;
  e.system->linearize(t0, linearization);
  ShiftedCoupledSolver<double> real;
  ShiftedCoupledSolver<std::complex<double>> complex;
  const Eigen::Index m = e.system->dimension();
  const Eigen::MatrixXd r0 = start_state(m);
  const Eigen::MatrixXcd c0 = r0.cast<std::complex<double>>() * std::complex<double>(1, -0.5);
  Eigen::MatrixXd r = r0;
  Eigen::MatrixXcd c = c0;
  for (auto _ : state) {
    real.factor(linearization, mu_real / h);
    complex.factor(linearization, mu_complex / h);
    r = r0;
    c = c0;
    real.solve_in_place(r);
    complex.solve_in_place(c);
    benchmark::DoNotOptimize(r.data());
    benchmark::DoNotOptimize(c.data());
  }
  state.SetComplexityN(state.range(0));
}

void right_hand_side(benchmark::State& state, const KernelCase& kernel_case, bool rkhs_law) {
  const auto n = static_cast<std::size_t>(state.range(0));
  auto& e = engine(kernel_case, rkhs_law, n);
  const Eigen::VectorXd z = start_state(e.system->dimension());
  Eigen::VectorXd dz(z.size());
  for (auto _ : state) {
    e.system->rhs(z.data(), dz.data(), t0);
    benchmark::DoNotOptimize(dz.data());
  }
  state.SetComplexityN(state.range(0));
}

// One whole lap-map trial of the paper_synthetic configuration.
void lap_map_trial(benchmark::State& state, const std::string& kernel_lines,
                   const std::string& law) {
  const std::string text = R"(
[study]
name = "lap_map_cost"
kind = "adaptive"
evaluation_points = 4096
[domain]
radius = 4.0
[grid]
n = [20]
[[kernel]]
)" + kernel_lines + R"(
[[target]]
name = "sine"
amplitude = 2.0
cycles = 1
[[plant]]
name = "quarter_car"
[[law]]
name = ")" + law + R"("
gamma = 2e4
[[integrator]]
name = "radau5"
rtol = 1e-6
atol = 1e-8
[adaptive]
speed = 1e-4
laps = )" + std::to_string(state.range(0)) + R"(
engine = "lap_map"
q = "identity"
snapshot_laps = [1, 10]
snapshot_points = 512
samples_per_lap = 20
)";
  const auto study = parse_study(text, "lap_map_cost.toml");
  const auto trials = study.trials();
  for (auto _ : state) {
    const auto result = run_trial(study, trials.at(0));
    if (!result.ok) {
      state.SkipWithError(result.reason.c_str());
      break;
    }
    state.counters["steps"] = result.metrics[study.metric_index("steps")];
    state.counters["l2_error"] = result.metrics[study.metric_index("l2_error")];
    state.counters["residual"] = result.metrics[study.metric_index("lap_map_residual")];
  }
}

// The lap map alone, for the same configuration: compute_lap_map (one lap of the 2d + n + 1 =
// 29 columns at lap_map_rtol = lap_map_atol = 1e-10, landing on the kernel's kinks), LapPowers,
// advance(z0, laps) and periodic_limit, as measure_adaptive calls them; the system is built
// as in engine() (n = 20). Without measure_adaptive's other work: the static part, the first
// and the last lap integrated with the study's integrator, the lap-boundary samples.
void lap_map_functions(benchmark::State& state, const KernelCase& kernel_case, bool rkhs_law) {
  auto& e = engine(kernel_case, rkhs_law, 20);
  const double lap_time = track.length / 1e-4;
  std::vector<double> kink_times;
  for (double kink : e.kernel->kink_points()) kink_times.push_back(kink / 1e-4);
  const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(e.system->dimension());
  const auto laps = static_cast<std::uint64_t>(state.range(0));
  for (auto _ : state) {
    const LapMap map = compute_lap_map(*e.system, lap_time, kink_times, 1e-10, 1e-10,
                                       std::numeric_limits<std::int64_t>::max());
    const LapPowers powers(map);
    const Eigen::VectorXd z = powers.advance(z0, laps);
    const auto limit = periodic_limit(map, z0, 4, 100 * 1e-10, 1e-10);
    benchmark::DoNotOptimize(z.data());
    benchmark::DoNotOptimize(limit.state.data());
    state.counters["steps"] = static_cast<double>(map.stats.steps);
  }
}

void register_all() {
  const std::vector<std::int64_t> all = {16, 64, 256, 1024, 4096};
  const std::vector<std::int64_t> capped = {16, 64, 256, 1024};   // rkhs law: O(n^3) set-up
  const std::vector<std::int64_t> dense = {16, 64, 256};
  for (const auto& k : kernel_cases())
    for (const bool rkhs_law : {false, true}) {
      const std::string pair = k.label + (rkhs_law ? "/rkhs" : "/gradient");
      // psi = M phi with a dense M: O(n^2) right-hand sides and linearisations. The Gaussian's
      // G^+ has rank about 63 from n = 128 on and is applied in low rank: O(n).
      const bool quadratic = rkhs_law && !k.feature_map && k.label != "gaussian";
      const auto fit = quadratic ? benchmark::oNSquared : benchmark::oN;
      const auto& sizes = rkhs_law ? capped : all;
      auto with = [&](benchmark::internal::Benchmark* b, const std::vector<std::int64_t>& ns,
                      benchmark::BigO big_o) {
        for (auto n : ns) b->Arg(n);
        b->Complexity(big_o)->Unit(benchmark::kMicrosecond);
      };
      with(benchmark::RegisterBenchmark(("step/" + pair + "/structured").c_str(), implicit_step,
                                        k, rkhs_law, LinearSolver::structured),
           sizes, fit);
      with(benchmark::RegisterBenchmark(("stage/" + pair + "/structured").c_str(), stage_solve,
                                        k, rkhs_law, LinearSolver::structured),
           sizes, fit);
      with(benchmark::RegisterBenchmark(("coupled_solver/" + pair).c_str(), coupled_solver, k,
                                        rkhs_law),
           sizes, benchmark::oN);
      with(benchmark::RegisterBenchmark(("rhs/" + pair).c_str(), right_hand_side, k, rkhs_law),
           sizes, fit);
      with(benchmark::RegisterBenchmark(("step/" + pair + "/dense").c_str(), implicit_step, k,
                                        rkhs_law, LinearSolver::dense),
           dense, benchmark::oNCubed);
      with(benchmark::RegisterBenchmark(("stage/" + pair + "/dense").c_str(), stage_solve, k,
                                        rkhs_law, LinearSolver::dense),
           dense, benchmark::oNCubed);
    }
  const std::vector<KernelCase> lap_cases = {
      {"bspline1", "bspline", {{"degree", std::int64_t{1}}, {"J", std::int64_t{6}}}, true},
      {"gaussian", "gaussian", {{"sigma", 1.0}}, false}};
  for (const auto& k : lap_cases)
    for (const bool rkhs_law : {true, false}) {
      auto* b = benchmark::RegisterBenchmark(
          ("lap_map_functions/" + k.label + (rkhs_law ? "/rkhs" : "/gradient")).c_str(),
          lap_map_functions, k, rkhs_law);
      b->Arg(100)->Arg(10'000)->Arg(1'000'000)->Iterations(1)->Unit(benchmark::kMillisecond);
    }
  const std::vector<std::pair<std::string, std::string>> lap_kernels = {
      {"bspline1", "name = \"bspline\"\ndegree = 1\nJ = 6\n"},
      {"gaussian", "name = \"gaussian\"\nsigma = 1.0\n"}};
  for (const auto& [label, lines] : lap_kernels)
    for (const std::string law : {"rkhs", "gradient"}) {
      auto* b = benchmark::RegisterBenchmark(("lap_map/" + label + "/" + law).c_str(),
                                             lap_map_trial, lines, law);
      b->Arg(100)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Iterations(1)->Unit(benchmark::kMillisecond);
    }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
