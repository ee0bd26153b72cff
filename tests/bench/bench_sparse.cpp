// Sparse against dense factorisation of the Gram matrix of Wendland's phi_{2,1} on the unit
// square, against n (m x m grid centres of spacing h = 1/(m - 1), support radius 4 h: about 50
// nonzeros a row whatever n, the stationary setting): CHOLMOD's supernodal Cholesky
// factorisation with its fill-reducing ordering (the sparse path, rkhs/approx/sparse_gram.hpp)
// and GramSolver's dense Cholesky factorisation with its Lanczos spectrum estimates (the dense
// path of a trial that reports no Gram eigenvalue). Complexity() fits the exponents.
#include <benchmark/benchmark.h>

#include <Eigen/CholmodSupport>
#include <cmath>

#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace {

rkhs::Domain square() {
  rkhs::Domain d{1.0, false};
  d.dimension = 2;
  d.width = 1.0;
  return d;
}

// The m of n = m^2.
std::int64_t side(std::int64_t n) {
  return static_cast<std::int64_t>(std::lround(std::sqrt(static_cast<double>(n))));
}

std::unique_ptr<rkhs::AnyKernel> wendland(std::int64_t n) {
  const auto* entry = rkhs::kernel_registry().find("wendland");
  return entry->factory(
      rkhs::ParameterSet::resolve(
          entry->info.parameters,
          {{"k", std::int64_t{1}}, {"radius", 4.0 / static_cast<double>(side(n) - 1)}}),
      square());
}

// The m x m grid with n = m^2 (end points included).
std::vector<double> grid(std::int64_t n) {
  const auto m = side(n);
  std::vector<double> x;
  for (std::int64_t j = 0; j < m; ++j)
    for (std::int64_t i = 0; i < m; ++i) {
      x.push_back(static_cast<double>(i) / static_cast<double>(m - 1));
      x.push_back(static_cast<double>(j) / static_cast<double>(m - 1));
    }
  return x;
}

void sparse_factorisation(benchmark::State& state) {
  const auto kernel = wendland(state.range(0));
  const auto x = grid(state.range(0));
  for (auto _ : state) {
    const Eigen::SparseMatrix<double> gram = rkhs::sparse_gram(*kernel, x);
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> cholesky(gram);
    benchmark::DoNotOptimize(cholesky.info());
    state.counters["nnz_G"] = static_cast<double>(gram.nonZeros());
    state.counters["nnz_L"] = cholesky.cholmod().lnz;
  }
  state.SetComplexityN(state.range(0));
}

void dense_factorisation(benchmark::State& state) {
  const auto kernel = wendland(state.range(0));
  const auto x = grid(state.range(0));
  for (auto _ : state) {
    const rkhs::GramSolver solver(kernel->gram(x), {}, rkhs::GramSpectrumMode::estimate);
    benchmark::DoNotOptimize(solver.spectrum());
  }
  state.SetComplexityN(state.range(0));
}

}  // namespace

BENCHMARK(sparse_factorisation)
    ->Arg(1024)
    ->Arg(4096)
    ->Arg(16384)
    ->Arg(65536)
    ->Complexity()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(dense_factorisation)
    ->Arg(1024)
    ->Arg(2025)
    ->Arg(4096)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
