// run_concurrently on std::thread (rkhs/core/concurrency.hpp; CMake
// RKHS_STUDY_SCHEDULER=threads): threads - 1 workers and the calling thread take indices from an
// atomic counter until none is left or a call has thrown.
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "rkhs/core/concurrency.hpp"

namespace rkhs {

void run_concurrently(std::size_t count, int threads,
                      const std::function<void(std::size_t)>& task) {
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex first_error_mutex;
  std::exception_ptr first_error;
  auto work = [&] {
    while (!failed.load()) {
      const std::size_t i = next.fetch_add(1);
      if (i >= count) return;
      try {
        task(i);
      } catch (...) {
        std::lock_guard lock(first_error_mutex);
        if (!first_error) first_error = std::current_exception();
        failed = true;
      }
    }
  };
  const auto workers = static_cast<std::size_t>(std::max(1, threads)) - 1;
  std::vector<std::thread> pool;
  pool.reserve(std::min(workers, count));
  for (std::size_t k = 0; k < workers && k + 1 < count; ++k) pool.emplace_back(work);
  work();
  for (auto& thread : pool) thread.join();
  if (first_error) std::rethrow_exception(first_error);
}

void run_parts(std::size_t count, const std::function<void(std::size_t)>& part) {
  for (std::size_t i = 0; i < count; ++i) part(i);
}

int default_concurrency() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

const char* scheduler_backend() noexcept {
  return "std::thread";
}

}  // namespace rkhs
