// Work counters (rkhs/core/work_counters.hpp): scopes nest and are per thread; the kernel
// interface counts exactly what a trial asks for, one count per matrix or basis call; the
// allocation interposer (core/allocation_tracking.cpp, linked into this executable) counts
// heap blocks into the scope of the thread that allocates them.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <numbers>
#include <thread>
#include <vector>

#include "rkhs/core/work_counters.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/point_sections.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<AnyKernel> builtin_kernel(const std::string& name, const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {}), domain);
}

std::vector<double> uniform(std::size_t count, double length) {
  std::vector<double> out;
  for (std::size_t i = 0; i < count; ++i)
    out.push_back(length * (static_cast<double>(i) + 0.25) / static_cast<double>(count));
  return out;
}

// `block`, seen by the compiler as used: it may not elide a malloc and free of it.
void* used(void* block) {
  asm volatile("" : : "r"(block) : "memory");
  return block;
}

}  // namespace

TEST_CASE("work counter scopes nest and restore what was current", "[core][work]") {
  CHECK(current_work_counters() == nullptr);
  count_kernel_evaluations(5);  // outside every scope: counts nothing, and does not crash
  count_factorisation();
  WorkCounters outer, inner;
  {
    const WorkCounterScope a(&outer);
    CHECK(current_work_counters() == &outer);
    count_kernel_evaluations(3);
    {
      const WorkCounterScope b(&inner);
      CHECK(current_work_counters() == &inner);
      count_kernel_evaluations(7);
      count_factorisation();
      {
        const WorkCounterScope none(nullptr);  // a part that must not count
        CHECK(current_work_counters() == nullptr);
        count_kernel_evaluations(100);
      }
      CHECK(current_work_counters() == &inner);
      count_kernel_derivative_evaluations(2);
    }
    CHECK(current_work_counters() == &outer);
    count_factorisation();
  }
  CHECK(current_work_counters() == nullptr);
  const auto o = snapshot(outer), i = snapshot(inner);
  CHECK(o.kernel_evaluations == 3);
  CHECK(o.factorisations == 1);
  CHECK(o.kernel_derivative_evaluations == 0);
  CHECK(i.kernel_evaluations == 7);
  CHECK(i.factorisations == 1);
  CHECK(i.kernel_derivative_evaluations == 2);
}

TEST_CASE("the kernel interface counts each matrix and basis call exactly", "[core][work]") {
  const Domain track{2 * std::numbers::pi * 4, true};
  constexpr std::size_t n = 12, M = 30;
  const auto centres = uniform(n, track.length), points = uniform(M, track.length);
  // A dense kernel (gaussian), a feature-map kernel (bspline) and a compactly supported one
  // (wendland): the count does not depend on the assembly path.
  for (const std::string name : {"gaussian", "bspline", "wendland"}) {
    INFO(name);
    const auto kernel = builtin_kernel(name, track);
    WorkCounters counters;
    const WorkCounterScope scope(&counters);
    const auto expect = [&](std::uint64_t values, std::uint64_t derivatives) {
      const auto now = snapshot(counters);
      CHECK(now.kernel_evaluations == values);
      CHECK(now.kernel_derivative_evaluations == derivatives);
      CHECK(now.factorisations == 0);
    };
    (void)kernel->gram(centres);
    expect(n * (n + 1) / 2, 0);  // symmetric: its distinct entries
    (void)kernel->cross(points, centres);
    expect(n * (n + 1) / 2 + M * n, 0);
    (void)kernel->diagonal(points);
    const std::uint64_t matrices = n * (n + 1) / 2 + M * n + M;
    expect(matrices, 0);
    // Pointwise virtuals count nothing (tests and contracts; loops over them count).
    (void)kernel->evaluate(0.5, 1.0);
    (void)kernel->derivative(0.5, 1.0);
    expect(matrices, 0);

    const auto basis = kernel->basis(centres);
    std::vector<double> phi(n), mapped(n);
    basis->evaluate(1.0, phi.data());
    basis->evaluate_derivative(1.0, phi.data());
    basis->set_map(Eigen::MatrixXd::Identity(n, n) * 0.5);
    basis->evaluate_mapped(1.0, mapped.data());
    basis->evaluate_mapped_derivative(1.0, mapped.data());
    Eigen::MatrixXd general = Eigen::MatrixXd::Random(n, n);
    basis->set_map(general);  // a general map: evaluate_mapped goes through evaluate's loop
    basis->evaluate_mapped(2.0, mapped.data());
    basis->evaluate_mapped_derivative(2.0, mapped.data());
    expect(matrices + 3 * n, 3 * n);

    if (const auto features = kernel->feature_basis()) {
      const auto F = features->size();
      std::vector<double> psi(F);
      features->evaluate(1.0, psi.data());
      features->evaluate_derivative(1.0, psi.data());
      expect(matrices + 3 * n + F, 3 * n + F);
    }
  }
}

TEST_CASE("point sections count n evaluations and n x d derivatives per call", "[core][work]") {
  Domain square{1.0, false};
  square.dimension = 2;
  square.width = 1.0;
  const auto kernel = builtin_kernel("wendland", square);
  const std::vector<double> centres = {0.1, 0.2, 0.5, 0.5, 0.9, 0.7};  // 3 points of R^2
  const PointSections sections(*kernel, centres);
  WorkCounters counters;
  const WorkCounterScope scope(&counters);
  const double y[2] = {0.4, 0.4};
  double phi[3], dphi[6];
  sections.evaluate(y, phi);
  sections.gradient(y, dphi);
  (void)kernel->gram(centres);  // 3 points: 6 distinct entries
  const auto now = snapshot(counters);
  CHECK(now.kernel_evaluations == 3 + 6);
  CHECK(now.kernel_derivative_evaluations == 3 * 2);
}

TEST_CASE("each thread counts into its own scope's counters", "[core][work]") {
  WorkCounters first, second, shared;
  const auto work = [](WorkCounters* counters, int calls, std::uint64_t each) {
    const WorkCounterScope scope(counters);
    for (int i = 0; i < calls; ++i) count_kernel_evaluations(each);
  };
  {
    // Two trials at once, and two parts of a third trial on two threads.
    std::jthread a(work, &first, 20000, 3), b(work, &second, 30000, 5);
    std::jthread c(work, &shared, 10000, 1), d(work, &shared, 10000, 2);
  }
  CHECK(snapshot(first).kernel_evaluations == 60000);
  CHECK(snapshot(second).kernel_evaluations == 150000);
  CHECK(snapshot(shared).kernel_evaluations == 30000);
  CHECK(current_work_counters() == nullptr);  // this thread never had a scope
}

TEST_CASE("the allocation interposer counts a trial's heap blocks and its peak", "[core][work]") {
  if (!allocation_tracking_enabled()) {
    WARN("this build does not track allocations (sanitizers): nothing to check");
    return;
  }
  constexpr std::size_t megabyte = 1 << 20;
  const std::uint64_t together = megabyte + 128 * 128 * 8;
  void* before = used(std::malloc(4096));  // allocated outside the scope
  WorkCounters counters;
  // No Catch assertion inside the scope: it would allocate there too.
  std::int64_t live_with_both = 0, live_after_both = 0, live_after_paths = 0;
  int aligned_status = -1;
  {
    const WorkCounterScope scope(&counters);
    {
      std::vector<char> big(megabyte, 'x');  // operator new -> malloc
      Eigen::MatrixXd matrix(128, 128);      // Eigen -> malloc, 128 KiB
      matrix.setZero();
      live_with_both = counters.live_bytes.load();
    }
    live_after_both = counters.live_bytes.load();
    void* aligned = nullptr;
    aligned_status = posix_memalign(&aligned, 64, 1000);
    void* zeroed = used(std::calloc(100, 10));
    void* grown = used(std::realloc(used(std::malloc(10)), 5000));
    std::free(used(aligned));
    std::free(zeroed);
    std::free(grown);
    live_after_paths = counters.live_bytes.load();
    std::free(used(before));  // allocated before the scope, freed inside: lowers the level only
  }
  const auto work = snapshot(counters);
  REQUIRE(work.allocations_tracked);
  REQUIRE(aligned_status == 0);
  CHECK(live_with_both >= static_cast<std::int64_t>(together));
  CHECK(live_after_both == 0);   // the peak was the two blocks together; then nothing was live
  CHECK(live_after_paths == 0);  // memalign, calloc, malloc and realloc are balanced by free
  CHECK(counters.live_bytes.load() < 0);
  // vector, matrix; memalign, calloc, malloc, realloc's block.
  CHECK(work.allocations == 6);
  CHECK(work.peak_bytes >= together);
  CHECK(work.peak_bytes <= together + 3 * 4096);  // the two large blocks rounded to pages
  CHECK(work.allocated_bytes >= together + 1000 + 1000 + 10 + 5000);
  CHECK(work.allocated_bytes <= together + 3 * 4096 + 1000 + 1000 + 10 + 5000 + 4 * 64);
  // Blocks allocated outside every scope are not counted.
  const std::vector<double> outside(10000);
  CHECK(snapshot(counters).allocations == work.allocations);
}
