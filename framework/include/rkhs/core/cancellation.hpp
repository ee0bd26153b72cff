#pragma once
// Cooperative cancellation and time limits of the trial running on the calling thread.
//
// A trial runs on one thread from start to end. run_trial() opens a CancellationScope there
// with the run's stop predicate and the trial's deadline; long computations inside the trial
// call check_cancelled() at points where stopping is safe (every integrator step, between the
// phases of an approximation trial, at every output sample of a plugin integrator; plugin code
// may call it too). check_cancelled() throws
//   - TrialCancelled once the stop predicate returns true: run_trial() records the trial as
//     not run (TrialResult::skipped), never as failed or ok, so a later run computes it again;
//   - TrialTimeLimitExceeded once the deadline has passed: the trial failed (limits.trial_seconds).
// Outside a scope it does nothing. A check costs one call of the predicate and one clock read:
// call it per step or per row of work, not per kernel evaluation.
//
// Work inside one library call that never returns to such a point cannot be stopped this way
// (the Gram matrix's eigen-decomposition and Cholesky factorisation check it themselves,
// approx/symmetric_eigen.hpp and approx/dense_kernels.hpp); run_trials() handles that case by
// abandoning the trial after a grace period (rkhs/run/run.hpp).

#include <chrono>
#include <functional>
#include <optional>
#include <stdexcept>

namespace rkhs {

/// The run was asked to stop while this trial was running.
class TrialCancelled : public std::runtime_error {
 public:
  TrialCancelled();
};

/// The trial ran past its deadline (limits.trial_seconds).
class TrialTimeLimitExceeded : public std::runtime_error {
 public:
  explicit TrialTimeLimitExceeded(double elapsed_seconds);
  double elapsed_seconds;  ///< when it was noticed, from the start of the scope
};

/// Throws TrialCancelled or TrialTimeLimitExceeded as described above; otherwise returns.
void check_cancelled();

/// Installs the stop predicate (may be empty: never stop) and deadline (none: no limit) for the
/// calling thread until destruction; scopes nest (the inner one applies, the outer is restored).
/// `stop_requested` must outlive the scope and be callable from this thread.
class CancellationScope {
 public:
  CancellationScope(const std::function<bool()>& stop_requested,
                    std::optional<std::chrono::steady_clock::time_point> deadline) noexcept;
  ~CancellationScope();
  CancellationScope(const CancellationScope&) = delete;
  CancellationScope& operator=(const CancellationScope&) = delete;

 private:
  const CancellationScope* previous_;
  const std::function<bool()>* stop_requested_;
  friend class SharedCancellationScope;
  std::optional<std::chrono::steady_clock::time_point> deadline_;
  std::chrono::steady_clock::time_point start_;
  friend void check_cancelled();
};

/// The calling thread's innermost scope, null outside one: what a thread that runs a part of
/// the same trial installs with SharedCancellationScope (run_parts, core/concurrency.hpp).
const CancellationScope* current_cancellation_scope() noexcept;

/// Makes `scope` (another thread's, which must outlive this object; may be null) the calling
/// thread's scope until destruction, so that check_cancelled() in a part of a trial run on a
/// helper thread stops it like the trial itself. The previous scope is restored.
class SharedCancellationScope {
 public:
  explicit SharedCancellationScope(const CancellationScope* scope) noexcept;
  ~SharedCancellationScope();
  SharedCancellationScope(const SharedCancellationScope&) = delete;
  SharedCancellationScope& operator=(const SharedCancellationScope&) = delete;

 private:
  const CancellationScope* previous_;
};

}  // namespace rkhs
