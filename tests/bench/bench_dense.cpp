// The dense kernel algebra against the machine's own speed, in one run: a DGEMM probe (C = A B,
// n x n times n x 8192, the dense kernels of this processor, rkhs/approx/dense_kernels.hpp)
// sets the speed of light, and the power-function phase of an approximation trial (per block of
// evaluation points: k_X(s) for a 2-D Matern 5/2 kernel, |L^-1 k_X(s)|^2 and |G^-1 k_X(s)|^2,
// two triangular solves) reports its GFLOP/s and their fraction of the probe's
// (`of_dgemm`). One thread: run it with the machine otherwise idle.
//
//   build/release/bench/bench_dense --benchmark_min_time=1
//   RKHS_STUDY_DENSE_KERNELS=x86-64 build/release/bench/bench_dense   # another variant
#include <benchmark/benchmark.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/dense_kernels.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace {

rkhs::Domain unit_square() {
  rkhs::Domain d;
  d.dimension = 2;
  d.length = d.width = 1.0;
  d.periodic = false;
  return d;
}

// GFLOP/s of C = A B (n x n times n x 8192), the best of three, measured once.
double dgemm_gflops(rkhs::dense::Index n) {
  constexpr rkhs::dense::Index columns = 8192;
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n), b = Eigen::MatrixXd::Random(n, columns);
  Eigen::MatrixXd c(n, columns);
  double best = 0;
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto start = std::chrono::steady_clock::now();
    rkhs::dense::kernels().multiply(a.data(), n, n, n, b.data(), columns, n, c.data(), n);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    best = std::max(best, 2.0 * double(n) * double(n) * double(columns) / seconds * 1e-9);
  }
  benchmark::DoNotOptimize(c.data());
  return best;
}

void dgemm(benchmark::State& state) {
  const auto n = static_cast<rkhs::dense::Index>(state.range(0));
  constexpr rkhs::dense::Index columns = 8192;
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n), b = Eigen::MatrixXd::Random(n, columns);
  Eigen::MatrixXd c(n, columns);
  for (auto _ : state) {
    rkhs::dense::kernels().multiply(a.data(), n, n, n, b.data(), columns, n, c.data(), n);
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["GFLOP/s"] = benchmark::Counter(2.0 * double(n) * double(n) * columns,
                                                 benchmark::Counter::kIsIterationInvariantRate,
                                                 benchmark::Counter::kIs1000);
  state.SetLabel(rkhs::dense::kernels().instruction_set);
}

// The grid pass of measure_approximation with power_function_sup asked for: the cross matrix
// and both solves for every evaluation point (GFLOP/s count the solves' 2 n^2 per point only).
void power_function_phase(benchmark::State& state) {
  const auto side = static_cast<std::size_t>(state.range(0));
  const std::size_t n = side * side, m = 4 * n;
  const auto domain = unit_square();
  const auto* entry = rkhs::kernel_registry().find("matern");
  const auto kernel = entry->factory(
      rkhs::ParameterSet::resolve(entry->info.parameters, {{"nu", 2.5}, {"length_scale", 0.2}}),
      domain);
  const auto centres = domain.uniform_points(n);
  // The Gram factorisation is outside the phase: time it once and subtract.
  const Eigen::MatrixXd gram = kernel->gram(centres);
  const rkhs::GramSolver solver(gram, {}, rkhs::GramSpectrumMode::estimate);
  const auto points = domain.uniform_points(m);
  Eigen::MatrixXd columns(static_cast<Eigen::Index>(n), 256);
  Eigen::VectorXd quadratic(256), norms(256);
  for (auto _ : state) {
    for (std::size_t first = 0; first < domain.point_count(points); first += 256) {
      const std::size_t rows = std::min<std::size_t>(256, domain.point_count(points) - first);
      Eigen::MatrixXd block(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(n));
      kernel->cross_into(std::span<const double>(points).subspan(first * 2, rows * 2), centres,
                         block);
      columns.leftCols(static_cast<Eigen::Index>(rows)) = block.transpose();
      solver.quadratic_forms_in_place(columns.leftCols(static_cast<Eigen::Index>(rows)),
                                      quadratic.data(), norms.data());
    }
    benchmark::DoNotOptimize(quadratic.data());
  }
  const double flops = 2.0 * double(n) * double(n) * double(domain.point_count(points));
  state.counters["GFLOP/s"] = benchmark::Counter(flops, benchmark::Counter::kIsIterationInvariantRate,
                                                 benchmark::Counter::kIs1000);
  static const double probe = dgemm_gflops(2048);
  state.counters["dgemm_GFLOP/s"] = probe;
  state.counters["of_dgemm"] = benchmark::Counter(flops / probe * 1e-9,
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(fmt::format("{} n={} M={}", rkhs::dense::kernels().instruction_set, n,
                             domain.point_count(points)));
}

}  // namespace

BENCHMARK(dgemm)->Arg(2048)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(power_function_phase)->Arg(32)->Arg(45)->Arg(64)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_MAIN();
