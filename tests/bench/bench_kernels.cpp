// Kernel matrix assembly through the registry boundary (AnyKernel::gram / cross), as trials use
// it, and the cost of one inlined evaluation of each concrete kernel.
//
//   bench_kernels --benchmark_filter=gram     Gram matrix of n uniform centres, n = 16 .. 1024
//   bench_kernels --benchmark_filter=cross    M = 4096 evaluation points x n centres
//
// Global kernels cost O(n^2) (Gram) and O(M n) (cross) kernel evaluations. Wendland evaluates
// only pairs within its radius. The B-spline kernel goes through its sparse feature map:
// O((p + 1)(J + 1)) per point to build the features, then a sparse product whose work grows with
// the overlap of supports, not with n per point; the dense result matrix is still written
// (O(M n)). With the default n0 = 4 the level-0 support is L / 2, so most pairs overlap; the
// n0 = 64 variant shows the sparse case.

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernels/bspline.hpp"
#include "rkhs/kernels/gaussian.hpp"
#include "rkhs/kernels/matern.hpp"
#include "rkhs/kernels/wendland.hpp"

namespace {

constexpr double track_length = 2 * 3.14159265358979323846 * 4;
constexpr std::size_t evaluation_points = 4096;  // M of docs/model.md section 5

std::vector<double> uniform(std::size_t n, double length) {
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = static_cast<double>(i) * length / static_cast<double>(n);
  return out;
}

using Given = std::map<std::string, rkhs::ParameterValue>;

std::unique_ptr<rkhs::AnyKernel> registered(const std::string& name, const Given& given) {
  const auto* entry = rkhs::kernel_registry().find(name);
  if (entry == nullptr) throw std::runtime_error("kernel '" + name + "' is not registered");
  const rkhs::Domain domain{track_length, true};
  return entry->factory(rkhs::ParameterSet::resolve(entry->info.parameters, given), domain);
}

void bench_gram(benchmark::State& state, std::string name, Given given) {
  const auto kernel = registered(name, given);
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto centres = uniform(n, track_length);
  for (auto _ : state) benchmark::DoNotOptimize(kernel->gram(centres));
  state.SetComplexityN(state.range(0));
}

void bench_cross(benchmark::State& state, std::string name, Given given) {
  const auto kernel = registered(name, given);
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto centres = uniform(n, track_length);
  const auto points = uniform(evaluation_points, track_length);
  for (auto _ : state) benchmark::DoNotOptimize(kernel->cross(points, centres));
  state.SetComplexityN(state.range(0));
  state.counters["entries"] = static_cast<double>(n * evaluation_points);
}

// One evaluation of the concrete kernel (what the templated assembly inlines).
template <class K>
void bench_evaluate(benchmark::State& state) {
  const rkhs::Domain domain{track_length, true};
  const K kernel(rkhs::ParameterSet::resolve(K::info().parameters, {}), domain);
  const auto points = uniform(1024, track_length);
  std::size_t i = 0;
  for (auto _ : state) {
    const double x = points[i & 1023], y = points[(i * 7 + 3) & 1023];
    benchmark::DoNotOptimize(kernel(x, y));
    ++i;
  }
}

// B-spline features of one point: the per-point cost of its Gram and cross assembly.
void bench_bspline_features(benchmark::State& state) {
  const rkhs::Domain domain{track_length, true};
  const rkhs::kernels::MultiscaleBSpline kernel(
      rkhs::ParameterSet::resolve(rkhs::kernels::MultiscaleBSpline::info().parameters, {}), domain);
  const auto points = uniform(1024, track_length);
  rkhs::SparseFeatures features;
  std::size_t i = 0;
  for (auto _ : state) {
    kernel.features(points[i++ & 1023], features);
    benchmark::DoNotOptimize(features.value.data());
  }
}

}  // namespace

// Default parameters of each kernel on the paper's track, plus a B-spline with a narrow level-0
// support (n0 = 64: radius 2 L / 64 = 0.79 m instead of L / 2), whose sparse products are sparse.
#define RKHS_KERNEL_ASSEMBLY(label, kernel, ...)                                 \
  BENCHMARK_CAPTURE(bench_gram, label, std::string(kernel), Given{__VA_ARGS__})  \
      ->RangeMultiplier(2)                                                       \
      ->Range(16, 1024)                                                          \
      ->Complexity()                                                             \
      ->Unit(benchmark::kMicrosecond);                                           \
  BENCHMARK_CAPTURE(bench_cross, label, std::string(kernel), Given{__VA_ARGS__}) \
      ->RangeMultiplier(2)                                                       \
      ->Range(16, 1024)                                                          \
      ->Complexity()                                                             \
      ->Unit(benchmark::kMicrosecond);

RKHS_KERNEL_ASSEMBLY(gaussian, "gaussian")
RKHS_KERNEL_ASSEMBLY(bspline, "bspline")
RKHS_KERNEL_ASSEMBLY(bspline_n0_64, "bspline", {"n0", std::int64_t{64}}, {"J", std::int64_t{4}})
RKHS_KERNEL_ASSEMBLY(wendland, "wendland")
RKHS_KERNEL_ASSEMBLY(matern, "matern")

BENCHMARK_TEMPLATE(bench_evaluate, rkhs::kernels::Gaussian);
BENCHMARK_TEMPLATE(bench_evaluate, rkhs::kernels::MultiscaleBSpline);
BENCHMARK_TEMPLATE(bench_evaluate, rkhs::kernels::Wendland);
BENCHMARK_TEMPLATE(bench_evaluate, rkhs::kernels::Matern);
BENCHMARK(bench_bspline_features);

BENCHMARK_MAIN();
