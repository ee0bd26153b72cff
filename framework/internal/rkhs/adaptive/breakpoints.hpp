#pragma once
// The times an adaptive trial's integration lands on (rkhs/adaptive/adaptive.hpp): its output
// samples, its snapshots and the kinks it restarts at.

#include <cstddef>
#include <vector>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/core/domain.hpp"

namespace rkhs {

/// What happens at a breakpoint (bits of Breakpoint::roles; a kink alone has none).
enum BreakpointRole : unsigned { sample_role = 1u, snapshot_role = 2u };

struct Breakpoint {
  double t;
  unsigned roles = 0;
  std::size_t snapshot_index = 0;  ///< into settings.snapshot_laps, when snapshot_role is set
};

/// The times in [0, lap_time) at which phi(s(t)) or f(s(t)) has a kink on the path of
/// `settings` (the spatial `kinks` crossed, in [0, L)), and for a shuttle its turning point,
/// where s'(t) jumps; sorted, each once.
std::vector<double> path_kink_times(const AdaptiveSettings& settings, const Domain& domain,
                                    const std::vector<double>& kinks);

/// The most breakpoints one integration holds (2.4 GB of them): a horizon that needs more
/// fails its trial up front instead of exhausting memory or time before its first step.
inline constexpr std::size_t max_breakpoints = 100'000'000;

/// From t = start to t = end (laps of settings.lap_time): sample times (samples_per_lap per lap,
/// evenly spaced, start and end included), snapshot times (when `snapshots`) and, when
/// `restart_at_kinks`, the times at which s(t) = v t mod L crosses one of `kinks`, merged in
/// increasing order; times closer than 1e-12 end are one breakpoint. Throws std::length_error
/// (naming the laps and the count) when they would be more than max_breakpoints, and
/// TrialCancelled or TrialTimeLimitExceeded from check_cancelled while it builds them.
std::vector<Breakpoint> adaptive_breakpoints(const AdaptiveSettings& settings, const Domain& domain,
                                             double start, double end,
                                             const std::vector<double>& kinks,
                                             bool restart_at_kinks, bool snapshots = true);

}  // namespace rkhs
