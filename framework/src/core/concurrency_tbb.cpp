// run_concurrently on oneTBB (rkhs/core/concurrency.hpp; CMake RKHS_STUDY_SCHEDULER=tbb).
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/work_counters.hpp"

namespace rkhs {

void run_concurrently(std::size_t count, int threads,
                      const std::function<void(std::size_t)>& task) {
  // Raise TBB's worker limit to the requested count (it defaults to the hardware threads).
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<std::size_t>(threads));
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(
        std::size_t{0}, count, std::size_t{1}, [&](std::size_t i) { task(i); },
        tbb::simple_partitioner());
  });
}

void run_parts(std::size_t count, const std::function<void(std::size_t)>& part) {
  if (count <= 1) {
    if (count == 1) part(0);
    return;
  }
  const CancellationScope* scope = current_cancellation_scope();
  WorkCounters* counters = current_work_counters();
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(
        std::size_t{0}, count, std::size_t{1},
        [&](std::size_t i) {
          const SharedCancellationScope shared(scope);
          const WorkCounterScope counting(counters);
          part(i);
        },
        tbb::simple_partitioner());
  });
}

int default_concurrency() {
  return tbb::this_task_arena::max_concurrency();
}

const char* scheduler_backend() noexcept {
  return "oneTBB";
}

}  // namespace rkhs
