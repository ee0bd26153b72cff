#pragma once
// The one scheduling interface the framework runs concurrent work through (trials in
// run/run.cpp, consumer threads in the MPI runner). Two backends implement it, chosen when the
// framework is built (CMake RKHS_STUDY_SCHEDULER):
//   tbb      oneTBB (task_arena + parallel_for), the default: work stealing on a shared pool;
//   threads  plain std::thread workers taking indices from an atomic counter: no dependency,
//            and every synchronisation is visible to ThreadSanitizer (Debian's oneTBB is not
//            instrumented, so TSan reports its internal handshakes as races, hiding real ones);
//            the tsan preset uses it.
// Results do not depend on the backend: callers that need an order impose it themselves
// (run_trials claims trials in its own order under its mutex).

#include <cstddef>
#include <functional>

namespace rkhs {

/// Calls task(i) once for every i in [0, count), on at most `threads` threads at a time (the
/// calling thread may be one of them), and returns when every call has returned. Each call is
/// one unit of scheduling (no batching of indices). When a call throws, indices not started yet
/// are not started and the first exception is rethrown once the running calls have returned.
/// threads >= 1.
void run_concurrently(std::size_t count, int threads, const std::function<void(std::size_t)>& task);

/// Calls part(i) once for every i in [0, count): the parts of one piece of work of the calling
/// thread (the blocks of one trial). With oneTBB they run on the threads of the arena the
/// caller runs in that are idle (a study with fewer trials than threads gives its big trials
/// the other cores; no thread is added, so nothing is oversubscribed), isolated so that a
/// waiting thread takes no unrelated task; with the std::thread backend they run one after
/// the other on the calling thread. Each part runs with the caller's cancellation scope
/// (check_cancelled() stops the trial) and work counters (core/work_counters.hpp). Parts must write disjoint results: their order is
/// unspecified. The first exception is rethrown once the running parts have returned.
void run_parts(std::size_t count, const std::function<void(std::size_t)>& part);

/// The number of threads run_concurrently would use when none is asked for (the hardware
/// threads this process may use).
int default_concurrency();

/// "oneTBB" or "std::thread": the backend this framework was built with (for provenance).
const char* scheduler_backend() noexcept;

}  // namespace rkhs
