#include "rkhs/core/work_counters.hpp"

namespace rkhs {

namespace {

// The initial-exec TLS model: reading it never allocates (a general-dynamic access in a shared
// library may call malloc on a thread's first access), so the malloc interposer may read it.
// This library is linked, never dlopen()ed, so the model is available.
[[gnu::tls_model("initial-exec")]] thread_local WorkCounters* current = nullptr;

std::atomic<bool> tracking_allocations{false};

constexpr auto relaxed = std::memory_order_relaxed;

}  // namespace

WorkCounts snapshot(const WorkCounters& counters) noexcept {
  WorkCounts out;
  out.kernel_evaluations = counters.kernel_evaluations.load(relaxed);
  out.kernel_derivative_evaluations = counters.kernel_derivative_evaluations.load(relaxed);
  out.factorisations = counters.factorisations.load(relaxed);
  out.sparse_nonzeros = counters.sparse_nonzeros.load(relaxed);
  out.factor_nonzeros = counters.factor_nonzeros.load(relaxed);
  out.sparse_solve_columns = counters.sparse_solve_columns.load(relaxed);
  out.allocations_tracked = allocation_tracking_enabled();
  if (out.allocations_tracked) {
    out.allocations = counters.allocations.load(relaxed);
    out.allocated_bytes = counters.allocated_bytes.load(relaxed);
    out.peak_bytes = static_cast<std::uint64_t>(counters.peak_bytes.load(relaxed));
  }
  return out;
}

WorkCounters* current_work_counters() noexcept { return current; }

WorkCounterScope::WorkCounterScope(WorkCounters* counters) noexcept : previous_(current) {
  current = counters;
}

WorkCounterScope::~WorkCounterScope() { current = previous_; }

void count_kernel_evaluations(std::uint64_t count) noexcept {
  if (auto* counters = current) counters->kernel_evaluations.fetch_add(count, relaxed);
}

void count_kernel_derivative_evaluations(std::uint64_t count) noexcept {
  if (auto* counters = current) counters->kernel_derivative_evaluations.fetch_add(count, relaxed);
}

void count_factorisation() noexcept {
  if (auto* counters = current) counters->factorisations.fetch_add(1, relaxed);
}

void count_sparse_work(std::uint64_t nonzeros, std::uint64_t factor_nonzeros,
                       std::uint64_t solve_columns) noexcept {
  auto* counters = current;
  if (!counters) return;
  counters->sparse_nonzeros.fetch_add(nonzeros, relaxed);
  counters->factor_nonzeros.fetch_add(factor_nonzeros, relaxed);
  counters->sparse_solve_columns.fetch_add(solve_columns, relaxed);
}

void count_heap_block(std::uint64_t bytes, bool allocated) noexcept {
  auto* counters = current;
  if (!counters) return;
  const auto signed_bytes = static_cast<std::int64_t>(bytes);
  if (!allocated) {
    counters->live_bytes.fetch_sub(signed_bytes, relaxed);
    return;
  }
  counters->allocations.fetch_add(1, relaxed);
  counters->allocated_bytes.fetch_add(bytes, relaxed);
  const std::int64_t live = counters->live_bytes.fetch_add(signed_bytes, relaxed) + signed_bytes;
  std::int64_t peak = counters->peak_bytes.load(relaxed);
  while (live > peak && !counters->peak_bytes.compare_exchange_weak(peak, live, relaxed)) {
  }
}

bool allocation_tracking_enabled() noexcept { return tracking_allocations.load(relaxed); }

void enable_allocation_tracking() noexcept { tracking_allocations.store(true, relaxed); }

}  // namespace rkhs
