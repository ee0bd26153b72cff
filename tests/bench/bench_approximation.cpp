// Power-function evaluation and whole approximation trials against n, for every built-in
// kernel. The B-spline path assembles k_X(s) through the sparse feature map, so its cross-matrix
// cost grows with the kernel's support, not with n per evaluation point; what remains O(n^2) per
// point is the triangular solve with the Cholesky factor.
#include <benchmark/benchmark.h>

#include <numbers>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/approx/target.hpp"

namespace {

const rkhs::Domain track{2 * std::numbers::pi * 4, true};
constexpr std::size_t evaluation_points = 4096;

std::unique_ptr<rkhs::AnyKernel> make(const std::string& name) {
  const auto* entry = rkhs::kernel_registry().find(name);
  std::map<std::string, rkhs::ParameterValue> given;
  if (name == "bspline") given = {{"degree", std::int64_t{2}}, {"J", std::int64_t{8}}};
  if (name == "wendland") given = {{"radius", 2.0}};
  return entry->factory(rkhs::ParameterSet::resolve(entry->info.parameters, given), track);
}

std::vector<double> uniform_centres(std::size_t n) {
  std::vector<double> c(n);
  for (std::size_t i = 0; i < n; ++i) c[i] = track.length * static_cast<double>(i) / static_cast<double>(n);
  return c;
}

void power_function(benchmark::State& state, const std::string& name) {
  const auto kernel = make(name);
  const auto centres = uniform_centres(static_cast<std::size_t>(state.range(0)));
  const auto points = track.uniform_points(evaluation_points);
  const rkhs::GramSolver solver(kernel->gram(centres), {});
  for (auto _ : state) benchmark::DoNotOptimize(rkhs::power_function(*kernel, solver, centres, points));
  state.SetComplexityN(state.range(0));
}

void approximation_trial(benchmark::State& state, const std::string& name) {
  const auto kernel = make(name);
  const auto* sine = rkhs::target_registry().find("sine");
  const auto target = sine->factory(rkhs::ParameterSet::resolve(sine->info.parameters, {}), track);
  const auto centres = uniform_centres(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(
        rkhs::measure_approximation(*kernel, *target, centres, evaluation_points, {}));
  state.SetComplexityN(state.range(0));
}

}  // namespace

#define RKHS_BENCH_KERNEL(kernel)                                                             \
  BENCHMARK_CAPTURE(power_function, kernel, std::string(#kernel))                             \
      ->RangeMultiplier(2)->Range(16, 512)->Complexity()->Unit(benchmark::kMillisecond);      \
  BENCHMARK_CAPTURE(approximation_trial, kernel, std::string(#kernel))                        \
      ->RangeMultiplier(2)->Range(16, 512)->Complexity()->Unit(benchmark::kMillisecond);

RKHS_BENCH_KERNEL(gaussian)
RKHS_BENCH_KERNEL(bspline)
RKHS_BENCH_KERNEL(wendland)
RKHS_BENCH_KERNEL(matern)

BENCHMARK_MAIN();
