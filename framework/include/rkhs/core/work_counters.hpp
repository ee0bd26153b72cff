#pragma once
// Deterministic work counters of a trial: what it asked of the kernels, how many Gram matrices
// it factorised, and how much memory it allocated. They measure work, not time: the same trial
// gives the same counts on every machine and run, so a cost gate can pin them
// (tests/cost/, docs/results.md "Work counters").
//
// A trial owns one WorkCounters and installs it with a WorkCounterScope on the thread that runs
// it (run_trial does); a part of the trial that runs on another thread (a oneTBB task) installs
// the same counters there with a scope of its own. Code anywhere below then counts into the
// counters current on its thread (count_kernel_evaluations, count_factorisation, ...); outside a
// scope counting does nothing. The counters are atomics, so the threads of one trial may count
// at the same time.
//
// What is counted:
//   - kernel_evaluations: kernel values k(x, y) a trial asked for through the kernel interface
//     (KernelModel in kernel/kernel_algorithms.hpp, PointSections): a Gram matrix of n centres
//     counts its n (n + 1) / 2 distinct entries (it is symmetric), a cross matrix rows x cols, a
//     diagonal one per point, a KernelBasis evaluation (plain or mapped) its size() sections,
//     whatever path assembled them (dense, windowed or through a feature map). One count per
//     matrix or basis call, never per element. The per-value virtuals (AnyKernel::evaluate,
//     evaluate_point, derivative, gradient_point) count nothing themselves: loops over them
//     count where they loop (PointSections);
//   - kernel_derivative_evaluations: derivatives of sections asked for the same way: a
//     KernelBasis derivative (plain or mapped) counts size(), a PointSections gradient n x d;
//   - factorisations: factorisations of Gram matrices (count_factorisation, called by the Gram
//     solver for each Cholesky factorisation and each symmetric eigenvalue solve, and by the
//     sparse path for each sparse Cholesky factorisation);
//   - sparse_nonzeros, factor_nonzeros, sparse_solve_columns: the sparse path's work
//     (count_sparse_work): the stored nonzeros of the sparse Gram and cross matrices it
//     assembled, the nonzeros of the Cholesky factors it computed, and the right-hand sides it
//     solved with a sparse triangular factor (a solve with L and one with L^T count two);
//   - allocations, allocated_bytes, peak_bytes: heap blocks allocated by the trial's threads
//     while its counters are current, their bytes, and the peak over the trial of the bytes they
//     allocated minus the bytes they freed (starting from 0 when the scope opens). Counted only
//     when the process tracks allocations (allocation_tracking_enabled(): the rkhs-study command
//     and the test executable interpose malloc, core/allocation_tracking.cpp; never under the
//     sanitizers, which interpose it themselves). A block is counted by its allocated size
//     (malloc_usable_size; blocks of 128 KiB and more rounded up to whole pages), so the counts
//     do not depend on which threads allocated what before. With one thread per trial they are
//     exactly reproducible; when parts of a trial run on several threads the totals still are,
//     the peak depends on how the parts interleave.

#include <array>
#include <atomic>
#include <cstdint>
#include <string_view>

namespace rkhs {

/// The counters of one trial (see above). Not copyable: read them with snapshot().
struct WorkCounters {
  std::atomic<std::uint64_t> kernel_evaluations{0};
  std::atomic<std::uint64_t> kernel_derivative_evaluations{0};
  std::atomic<std::uint64_t> factorisations{0};
  std::atomic<std::uint64_t> sparse_nonzeros{0};
  std::atomic<std::uint64_t> factor_nonzeros{0};
  std::atomic<std::uint64_t> sparse_solve_columns{0};
  std::atomic<std::uint64_t> allocations{0};
  std::atomic<std::uint64_t> allocated_bytes{0};
  /// Bytes allocated minus bytes freed while these counters were current (may go below 0 when
  /// the trial frees memory allocated before its scope opened).
  std::atomic<std::int64_t> live_bytes{0};
  /// The largest live_bytes reached (0 or more).
  std::atomic<std::int64_t> peak_bytes{0};
};

/// The values of a WorkCounters at one moment: what a finished trial reports
/// (TrialResult::work, summary.json "work"). Allocation counts are meaningful only when
/// `allocations_tracked`.
struct WorkCounts {
  std::uint64_t kernel_evaluations = 0;
  std::uint64_t kernel_derivative_evaluations = 0;
  std::uint64_t factorisations = 0;
  std::uint64_t sparse_nonzeros = 0;
  std::uint64_t factor_nonzeros = 0;
  std::uint64_t sparse_solve_columns = 0;
  bool allocations_tracked = false;
  std::uint64_t allocations = 0;
  std::uint64_t allocated_bytes = 0;
  std::uint64_t peak_bytes = 0;

  bool operator==(const WorkCounts&) const = default;
};

/// A counter of WorkCounts by name: the one list that the stored records, summary.json and
/// `rkhs-study store show` write and read, in their order. The allocation counters come last
/// and are written only when allocations_tracked.
struct WorkCountField {
  std::string_view name;
  std::uint64_t WorkCounts::*member;
  bool allocation = false;
};
inline constexpr std::array<WorkCountField, 9> work_count_fields = {{
    {"kernel_evaluations", &WorkCounts::kernel_evaluations},
    {"kernel_derivative_evaluations", &WorkCounts::kernel_derivative_evaluations},
    {"factorisations", &WorkCounts::factorisations},
    {"sparse_nonzeros", &WorkCounts::sparse_nonzeros},
    {"factor_nonzeros", &WorkCounts::factor_nonzeros},
    {"sparse_solve_columns", &WorkCounts::sparse_solve_columns},
    {"allocations", &WorkCounts::allocations, true},
    {"allocated_bytes", &WorkCounts::allocated_bytes, true},
    {"peak_bytes", &WorkCounts::peak_bytes, true},
}};

/// The counters' values now; allocations_tracked is allocation_tracking_enabled().
WorkCounts snapshot(const WorkCounters& counters) noexcept;

/// The counters current on the calling thread; null outside every WorkCounterScope.
WorkCounters* current_work_counters() noexcept;

/// Makes `counters` (may be null: count nothing) current on the calling thread until
/// destruction, then restores the counters that were current before: scopes nest. `counters`
/// must outlive the scope. Open and close it on the same thread.
class WorkCounterScope {
 public:
  explicit WorkCounterScope(WorkCounters* counters) noexcept;
  ~WorkCounterScope();
  WorkCounterScope(const WorkCounterScope&) = delete;
  WorkCounterScope& operator=(const WorkCounterScope&) = delete;

 private:
  WorkCounters* previous_;
};

/// Adds `count` kernel values to the current counters (nothing outside a scope).
void count_kernel_evaluations(std::uint64_t count) noexcept;
/// Adds `count` derivative values of kernel sections to the current counters.
void count_kernel_derivative_evaluations(std::uint64_t count) noexcept;
/// Counts one factorisation of a Gram matrix in the current counters.
void count_factorisation() noexcept;
/// Adds the sparse path's work to the current counters: stored nonzeros of assembled sparse
/// matrices, nonzeros of computed Cholesky factors, right-hand sides of sparse triangular solves.
void count_sparse_work(std::uint64_t nonzeros, std::uint64_t factor_nonzeros,
                       std::uint64_t solve_columns) noexcept;

/// Records a heap block of `bytes` allocated (`allocated`) or freed on the calling thread into
/// the current counters. Called by the allocation interposer (core/allocation_tracking.cpp)
/// only: nothing here allocates.
void count_heap_block(std::uint64_t bytes, bool allocated) noexcept;

/// True when this process counts its allocations: the executable interposes malloc and has
/// called enable_allocation_tracking() (the rkhs-study command and the test executable do,
/// unless built with sanitizers).
bool allocation_tracking_enabled() noexcept;
/// Called once by the allocation interposer when the process starts.
void enable_allocation_tracking() noexcept;

}  // namespace rkhs
