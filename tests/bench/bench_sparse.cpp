// The sparse path against the dense one, against n, for Wendland's phi_{d,1} on the unit square
// (d = 2: m x m grid centres of spacing h = 1/(m - 1), support radius 4 h, about 50 nonzeros a
// row whatever n) and on the unit cube (d = 3: m x m x m grid centres, support radius 3 h, 123
// nonzeros a row): the stationary setting.
//   *_factorisation   the Gram matrix assembled and factorised: CHOLMOD's supernodal Cholesky
//                     factorisation with its fill-reducing ordering (the sparse path,
//                     rkhs/approx/sparse_gram.hpp) against GramSolver's dense Cholesky
//                     factorisation with its Lanczos spectrum estimates (the dense path of a
//                     trial that reports no Gram eigenvalue);
//   *_power_phase     the blocked pass over M ~ n uniform evaluation points that
//                     power_function_sup needs, the factor built outside the timing: the sparse
//                     path's (sparse cross columns, densified by blocks, permuted and solved with
//                     L and L^T through CHOLMOD, as measure_sparse_approximation runs it) against
//                     the dense path's (cross blocks, GramSolver::quadratic_forms_in_place);
//   *_trial           a whole trial, measure_approximation with only power_function_sup
//                     selected and `[linear_algebra] solver` forced to "sparse" or "dense".
// Complexity() fits the usual laws; at the end the run prints, for each benchmark, the exponent
// p of the least-squares fit t = c n^p in log-log over its sizes (and between its two largest
// sizes), and for each sparse/dense pair the ratio of times at their common sizes and the n
// where sparse becomes the faster (log-log interpolation between the bracketing sizes).
//
// One thread: run it as `OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 build/release/bench/bench_sparse`
// (main also asks OpenBLAS for one thread; every timed body runs in an arena of one thread, so
// the framework's parallel strips, tiles and blocks do not spread to the other core). About 2.5
// minutes on a 2-core EPYC.
#include <benchmark/benchmark.h>
#include <dlfcn.h>
#include <fmt/format.h>

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace {

// The support radius in grid spacings: about 50 nonzeros a row in 2-D, 123 in 3-D.
constexpr double radius_in_spacings(int d) {
  return d == 2 ? 4.0 : 3.0;
}

template <int D>
rkhs::Domain unit_box() {
  rkhs::Domain domain{1.0, false};
  domain.dimension = D;
  domain.width = 1.0;
  if constexpr (D == 3) domain.height = 1.0;
  return domain;
}

// The m of n = m^D.
template <int D>
std::int64_t side(std::int64_t n) {
  return static_cast<std::int64_t>(std::lround(std::pow(static_cast<double>(n), 1.0 / D)));
}

template <int D>
std::unique_ptr<rkhs::AnyKernel> wendland(std::int64_t n) {
  const auto* entry = rkhs::kernel_registry().find("wendland");
  return entry->factory(
      rkhs::ParameterSet::resolve(
          entry->info.parameters,
          {{"k", std::int64_t{1}},
           {"radius", radius_in_spacings(D) / static_cast<double>(side<D>(n) - 1)}}),
      unit_box<D>());
}

// The grid of m^D = n centres (end points included): the domain's own uniform points.
template <int D>
std::vector<double> grid(std::int64_t n) {
  return unit_box<D>().uniform_points(static_cast<std::size_t>(n));
}

// Runs `work` in an arena of one thread: the framework's run_parts (GramSolver's strips and
// tiles, the trial's blocks) then stay on the calling thread, whose CPU time the benchmark
// reports; outside it they would spread to the other core, uncounted.
template <class Work>
void on_one_thread(Work&& work) {
  rkhs::run_concurrently(1, 1, [&](std::size_t) { work(); });
}

// CHOLMOD's supernodal LL^T with access to the factor for the partial solves (P, L^-1, L^-T),
// as the sparse path holds it.
class SparseCholesky
    : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  cholmod_factor* factor() const { return m_cholmodFactor; }
};

void solve_in_place(int system, cholmod_factor* factor, Eigen::MatrixXd& x,
                    cholmod_common& common) {
  cholmod_dense b = Eigen::viewAsCholmod(x);
  cholmod_dense* result = cholmod_solve(system, factor, &b, &common);
  std::copy_n(static_cast<const double*>(result->x), x.size(), x.data());
  cholmod_free_dense(&result, &common);
}

template <int D>
void sparse_factorisation(benchmark::State& state) {
  const auto kernel = wendland<D>(state.range(0));
  const auto x = grid<D>(state.range(0));
  for (auto _ : state)
    on_one_thread([&] {
      const Eigen::SparseMatrix<double> gram = rkhs::sparse_gram(*kernel, x);
      Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> cholesky(gram);
      benchmark::DoNotOptimize(cholesky.info());
      state.counters["nnz_G"] = static_cast<double>(gram.nonZeros());
      state.counters["nnz_L"] = cholesky.cholmod().lnz;
    });
  state.SetComplexityN(state.range(0));
}

template <int D>
void dense_factorisation(benchmark::State& state) {
  const auto kernel = wendland<D>(state.range(0));
  const auto x = grid<D>(state.range(0));
  for (auto _ : state)
    on_one_thread([&] {
      const rkhs::GramSolver solver(kernel->gram(x), {}, rkhs::GramSpectrumMode::estimate);
      benchmark::DoNotOptimize(solver.spectrum());
    });
  state.SetComplexityN(state.range(0));
}

// measure_sparse_approximation's pass for power_function_sup: the sparse cross matrix, then by
// blocks of its columns (as many as about 32 MB of dense columns hold, 16 to 512) densified,
// permuted and solved with L (|L^-1 P k_X(s)|^2) and L^T (|G^-1 k_X(s)|^2, the floor).
template <int D>
void sparse_power_phase(benchmark::State& state) {
  const auto n = state.range(0);
  const auto kernel = wendland<D>(n);
  const auto centres = grid<D>(n);
  const auto points = grid<D>(n);  // M = n evaluation points
  SparseCholesky cholesky;
  cholesky.compute(rkhs::sparse_gram(*kernel, centres));
  const auto m_total = static_cast<Eigen::Index>(unit_box<D>().point_count(points));
  const Eigen::Index per_block = std::clamp<Eigen::Index>((Eigen::Index{1} << 22) / n, 16, 512);
  Eigen::VectorXd quadratic(m_total), solution_norm_squared(m_total);
  cholmod_common common;
  cholmod_start(&common);
  for (auto _ : state)
    on_one_thread([&] {
      const Eigen::SparseMatrix<double> cross =
          rkhs::sparse_cross_columns(*kernel, points, centres);
      for (Eigen::Index first = 0; first < m_total; first += per_block) {
        const Eigen::Index count = std::min(per_block, m_total - first);
        Eigen::MatrixXd columns = Eigen::MatrixXd(cross.middleCols(first, count));
        solve_in_place(CHOLMOD_P, cholesky.factor(), columns, common);
        solve_in_place(CHOLMOD_L, cholesky.factor(), columns, common);
        quadratic.segment(first, count) = columns.colwise().squaredNorm().transpose();
        solve_in_place(CHOLMOD_Lt, cholesky.factor(), columns, common);
        solution_norm_squared.segment(first, count) = columns.colwise().squaredNorm().transpose();
      }
      benchmark::DoNotOptimize(quadratic.data());
      benchmark::DoNotOptimize(solution_norm_squared.data());
    });
  cholmod_finish(&common);
  state.counters["M"] = static_cast<double>(m_total);
  state.counters["nnz_L"] = cholesky.cholmod().lnz;
  state.SetComplexityN(n);
}

// The dense path's pass for power_function_sup: blocks of 256 rows of the cross matrix,
// transposed, and both triangular solves (bench_dense's power_function_phase).
template <int D>
void dense_power_phase(benchmark::State& state) {
  const auto n = state.range(0);
  const auto kernel = wendland<D>(n);
  const auto centres = grid<D>(n);
  const auto points = grid<D>(n);
  const rkhs::GramSolver solver(kernel->gram(centres), {}, rkhs::GramSpectrumMode::estimate);
  const std::size_t m_total = unit_box<D>().point_count(points);
  Eigen::MatrixXd columns(n, 256);
  Eigen::VectorXd quadratic(256), norms(256);
  for (auto _ : state)
    on_one_thread([&] {
      for (std::size_t first = 0; first < m_total; first += 256) {
        const std::size_t rows = std::min<std::size_t>(256, m_total - first);
        Eigen::MatrixXd block(static_cast<Eigen::Index>(rows), n);
        kernel->cross_into(std::span<const double>(points).subspan(first * D, rows * D), centres,
                           block);
        columns.leftCols(static_cast<Eigen::Index>(rows)) = block.transpose();
        solver.quadratic_forms_in_place(columns.leftCols(static_cast<Eigen::Index>(rows)),
                                        quadratic.data(), norms.data());
      }
      benchmark::DoNotOptimize(quadratic.data());
    });
  state.counters["M"] = static_cast<double>(m_total);
  state.SetComplexityN(n);
}

// A whole trial (M = n evaluation points, power_function_sup only) on the path `algebra`, in an
// arena of one thread.
template <int D>
void trial(benchmark::State& state, rkhs::GramAlgebra algebra) {
  const auto n = state.range(0);
  const auto kernel = wendland<D>(n);
  const auto centres = grid<D>(n);
  const auto* entry = rkhs::target_registry().find("expression");
  const auto target = entry->factory(
      rkhs::ParameterSet::resolve(
          entry->info.parameters, {{"f", std::string("exp(x1) * cos(x2) + x1 * x2")}},
          entry->info.user_parameters ? &*entry->info.user_parameters : nullptr),
      unit_box<D>());
  rkhs::MetricSelection selection(rkhs::MetricValues<rkhs::ApproximationMetric>::count, false);
  selection[static_cast<std::size_t>(rkhs::ApproximationMetric::power_function_sup)] = true;
  rkhs::SolverOptions options;
  options.algebra = algebra;
  double power = 0;
  for (auto _ : state)
    on_one_thread([&] {
      power = rkhs::measure_approximation(*kernel, *target, centres, static_cast<std::size_t>(n),
                                          options, selection)
                  .metrics[rkhs::ApproximationMetric::power_function_sup];
    });
  state.counters["power_sup"] = power;
  state.SetComplexityN(n);
}

template <int D>
void sparse_trial(benchmark::State& state) {
  trial<D>(state, rkhs::GramAlgebra::sparse);
}
template <int D>
void dense_trial(benchmark::State& state) {
  trial<D>(state, rkhs::GramAlgebra::dense);
}

// n = m^D for each m.
template <int D>
void sizes(benchmark::internal::Benchmark* b, std::initializer_list<std::int64_t> sides) {
  for (const auto m : sides) b->Arg(D == 2 ? m * m : m * m * m);
}

// The sizes (n = m^d for each m).
void squares_to_66049(benchmark::internal::Benchmark* b) {
  sizes<2>(b, {9, 13, 17, 25, 33, 45, 65, 129, 257});
}
void squares_to_4225(benchmark::internal::Benchmark* b) {
  sizes<2>(b, {9, 13, 17, 25, 33, 45, 65});
}
void squares_to_2025(benchmark::internal::Benchmark* b) {
  sizes<2>(b, {9, 13, 17, 25, 33, 45});
}
void cubes_to_35937(benchmark::internal::Benchmark* b) {
  sizes<3>(b, {7, 9, 11, 13, 17, 21, 26, 33});
}
void cubes_to_8000(benchmark::internal::Benchmark* b) {
  sizes<3>(b, {7, 9, 11, 13, 17, 20});
}
void cubes_to_4913(benchmark::internal::Benchmark* b) {
  sizes<3>(b, {7, 9, 11, 13, 17});
}
void cubes_to_2197(benchmark::internal::Benchmark* b) {
  sizes<3>(b, {7, 9, 11, 13});
}

// Prints, after the console table, the fitted exponents and the sparse/dense ratios.
class ExponentReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const auto& run : runs)
      if (run.run_type == Run::RT_Iteration && run.complexity_n > 0 && !run.error_occurred) {
        auto& entry = times_[run.run_name.function_name][run.complexity_n];
        entry.first += run.GetAdjustedCPUTime();
        entry.second += 1;
      }
  }

  void Finalize() override {
    ConsoleReporter::Finalize();
    auto& out = GetOutputStream();
    out << "\nPower-law fits t = c n^p of the CPU time (least squares in log-log over all sizes, "
           "over the three largest, and between the two largest):\n";
    for (const auto& [name, by_n] : times_) {
      const auto points = mean(by_n);
      if (points.size() < 2) continue;
      const Points top(points.end() - std::min<std::ptrdiff_t>(3, std::ssize(points)),
                       points.end());
      out << fmt::format(
          "  {:<28} p = {:.2f} (n = {} .. {}), {:.2f} (n >= {}), {:.2f} (last pair)\n", name,
          slope(points), points.front().first, points.back().first, slope(top), top.front().first,
          slope({points[points.size() - 2], points.back()}));
    }
    out << "\nSparse / dense CPU time at the common sizes, and the crossover n (sparse faster "
           "above it):\n";
    for (const auto& [name, by_n] : times_) {
      if (name.rfind("sparse_", 0) != 0) continue;
      const std::string dense = "dense_" + name.substr(7);
      const auto other = times_.find(dense);
      if (other == times_.end()) continue;
      const auto a = mean(by_n), b = mean(other->second);
      std::vector<std::pair<double, double>> ratio;  // (n, sparse / dense)
      for (const auto& [n, t] : a)
        for (const auto& [m, u] : b)
          if (n == m) ratio.emplace_back(n, t / u);
      std::string line;
      for (const auto& [n, r] : ratio) line += fmt::format(" n={}: {:.3g};", n, r);
      std::string crossover = "not within the common sizes";
      if (!ratio.empty() && ratio.front().second < 1)
        crossover = fmt::format("below {}", ratio.front().first);
      for (std::size_t i = 0; i + 1 < ratio.size(); ++i)
        if (ratio[i].second >= 1 && ratio[i + 1].second < 1) {
          const double l0 = std::log(ratio[i].first), l1 = std::log(ratio[i + 1].first);
          const double r0 = std::log(ratio[i].second), r1 = std::log(ratio[i + 1].second);
          crossover = fmt::format("about {:.0f}", std::exp(l0 + (l1 - l0) * r0 / (r0 - r1)));
        }
      out << fmt::format("  {:<28}{} crossover n {}\n", name.substr(7), line, crossover);
    }
  }

 private:
  using Points = std::vector<std::pair<double, double>>;  // (n, mean time), increasing n
  static Points mean(const std::map<std::int64_t, std::pair<double, int>>& by_n) {
    Points points;
    for (const auto& [n, sum] : by_n)
      points.emplace_back(static_cast<double>(n), sum.first / sum.second);
    return points;
  }
  static double slope(const Points& points) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto& [n, t] : points) {
      const double x = std::log(n), y = std::log(t);
      sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const auto k = static_cast<double>(points.size());
    return (k * sxy - sx * sy) / (k * sxx - sx * sx);
  }
  std::map<std::string, std::map<std::int64_t, std::pair<double, int>>> times_;
};

}  // namespace

// Sizes n = m^d that are not powers of two: dense blocks of n rows (a leading dimension of 2^k
// doubles) run up to twice as slow from cache-set conflicts when n is one (sparse_power_phase<2>
// at n = 4096 takes 1.7 times as long as at 3969 and 2 times as long as at 4225), which would bend
// the fits. Sparse and dense share their smaller sizes, for the ratios.

// 2-D, phi_{2,1}, radius 4 h.
BENCHMARK(sparse_factorisation<2>)
    ->Apply(squares_to_66049)
    ->Complexity()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(dense_factorisation<2>)
    ->Apply(squares_to_4225)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(sparse_power_phase<2>)
    ->Apply(squares_to_4225)
    ->Complexity()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(dense_power_phase<2>)
    ->Apply(squares_to_2025)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(sparse_trial<2>)->Apply(squares_to_4225)->Complexity()->Unit(benchmark::kMillisecond);
BENCHMARK(dense_trial<2>)
    ->Apply(squares_to_2025)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);

// 3-D, phi_{3,1}, radius 3 h.
BENCHMARK(sparse_factorisation<3>)
    ->Apply(cubes_to_35937)
    ->Complexity()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(dense_factorisation<3>)
    ->Apply(cubes_to_4913)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(sparse_power_phase<3>)->Apply(cubes_to_8000)->Complexity()->Unit(benchmark::kMillisecond);
BENCHMARK(dense_power_phase<3>)
    ->Apply(cubes_to_2197)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(sparse_trial<3>)->Apply(cubes_to_4913)->Complexity()->Unit(benchmark::kMillisecond);
BENCHMARK(dense_trial<3>)
    ->Apply(cubes_to_2197)
    ->Complexity(benchmark::oNCubed)
    ->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  using SetThreads = void (*)(int);
  if (auto* set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
    set(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ExponentReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
