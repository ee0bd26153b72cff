#pragma once
// The one stepping loop of every integrator of an AdaptiveSystem (built-in and from plugins):
// from breakpoint to breakpoint, landing exactly on each, with output at every breakpoint,
// cancellation checks, step counting and the step budget. What differs between methods, how
// one step is taken and how the next step size is chosen, is a stepping policy.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/core/cancellation.hpp"

namespace rkhs {

enum class StepOutcome { accepted, rejected };

/// A stepping policy owns the state of the integration, dimension() contiguous doubles at
/// state() (the address may change with each step), and takes steps:
///   StepOutcome try_step(double& t, double& dt)
///     attempts one step of size dt from t. accepted: the state and t have advanced by that dt
///     and dt is the size proposed for the next step. rejected: the state and t are unchanged
///     and dt is the (smaller) size to retry with. A fixed-step method accepts every step and
///     leaves dt alone.
///   void reset()  (optional)
///     forgets what the policy carries from step to step (a first-same-as-last derivative);
///     called at the start of each segment when SteppingOptions::reset_per_segment is set.
template <class P>
concept SteppingPolicy = requires(P& policy, double& t, double& dt) {
  { policy.state() } -> std::same_as<double*>;
  { policy.try_step(t, dt) } -> std::same_as<StepOutcome>;
};

struct SteppingOptions {
  std::int64_t max_steps = 20'000'000;  ///< budget of accepted + rejected steps, whole run
  double initial_step = 0;              ///< first dt; <= 0: 1e-6 of the first segment
  bool reset_per_segment = false;       ///< call the policy's reset() at each segment start
  std::string non_finite_hint;          ///< appended to the non-finite-state message
};

namespace detail {
[[noreturn]] void throw_step_underflow(double t);
[[noreturn]] void throw_step_budget_exhausted(std::int64_t max_steps, double t, double final_time);
[[noreturn]] void throw_non_finite_state(double t, const std::string& hint);
}  // namespace detail

/// Integrates from t = breakpoints[0] through every later breakpoint with the steps of
/// `stepper`, starting from z and leaving the final state in z. Contract (Integrator):
///   - observe(k, state) at every breakpoint k, including 0, with the state there;
///   - each smooth segment (breakpoints[k-1], breakpoints[k]] is stepped on its own: a step
///     longer than the rest of the segment is shortened to land exactly on its end, and does
///     not shrink the next step;
///   - check_cancelled() before every step (and observe may check too);
///   - throws std::runtime_error when a rejected step falls below 1e-14 of the time scale,
///     when accepted + rejected steps exceed options.max_steps, and when the state at a
///     breakpoint is not finite.
template <SteppingPolicy Stepper>
IntegrationStats drive_steps(Stepper& stepper, Eigen::VectorXd& z,
                             std::span<const double> breakpoints,
                             const std::function<void(std::size_t, const double*)>& observe,
                             const SteppingOptions& options) {
  IntegrationStats stats;
  const std::size_t size = static_cast<std::size_t>(z.size());
  std::copy(z.data(), z.data() + z.size(), stepper.state());
  double t = breakpoints.front();
  observe(0, stepper.state());
  double dt = options.initial_step;
  for (std::size_t k = 1; k < breakpoints.size(); ++k) {
    const double end = breakpoints[k];
    if (!(end > t)) {
      observe(k, stepper.state());
      continue;
    }
    if constexpr (requires { stepper.reset(); })
      if (options.reset_per_segment) stepper.reset();
    if (dt <= 0) dt = 1e-6 * (end - t);
    ++stats.segments;
    while (t < end) {
      check_cancelled();
      const bool last = dt >= end - t;
      double step = last ? end - t : dt;
      const double before = t;
      if (stepper.try_step(t, step) == StepOutcome::accepted) {
        ++stats.steps;
        if (last) t = end;  // land exactly
        // A step shortened to hit the breakpoint does not shrink the next one.
        dt = last ? std::max(dt, step) : step;
      } else {
        ++stats.rejected_steps;
        dt = step;
        if (!(dt > 1e-14 * std::max(std::abs(before), end - before)))
          detail::throw_step_underflow(before);
      }
      if (static_cast<std::int64_t>(stats.steps + stats.rejected_steps) > options.max_steps)
        detail::throw_step_budget_exhausted(options.max_steps, t, breakpoints.back());
    }
    const double* x = stepper.state();
    for (std::size_t i = 0; i < size; ++i)
      if (!std::isfinite(x[i])) detail::throw_non_finite_state(t, options.non_finite_hint);
    observe(k, x);
  }
  std::copy(stepper.state(), stepper.state() + size, z.data());
  return stats;
}

}  // namespace rkhs
