#pragma once
// Whether an adaptive study's estimate has converged in time, per group, in words: fhat(T)
// learns towards the projection Pi_n f of the road, so it has converged when its distance to
// the projection (gap_to_projection) is small against the projection's own error
// (interpolant_l2_error). The console (`run`), rates.md and report.html state it.

#include <string>
#include <vector>

#include "rkhs/report/output.hpp"

namespace rkhs {

/// The convergence in time of one group.
struct TimeConvergence {
  std::string group;     ///< the group's key (every axis but n)
  std::string label;     ///< the axes that tell it from the other groups; its key when none
  std::string sentence;  ///< the statement, see time_convergence
};

/// Percent of the projection's error below which the gap counts as converged.
inline constexpr double converged_gap_percent = 10.0;

/// One entry per group of an adaptive study whose metrics (StudyDefinition::metrics, what the
/// study asks for: nothing more is computed) include gap_to_projection and
/// interpolant_l2_error, judged at the largest n where both are finite and the projection's
/// error is positive (a group without such n has no entry):
///
///   gap <= 10% of error: "converged in time: gap to the projection 3.1e-05 is 0.2% of the
///                         projection's own error 0.015 (n = 576)"
///   gap <= error:        "not yet converged in time: gap to the projection 0.05 is 40% of ..."
///   gap > error:         "not converged in time: gap to the projection 0.8 exceeds the
///                         projection's own error 0.3 (n = 576)"
///
/// followed, when the study asks for laps_to_limit and it is finite there, by "; the lap map
/// predicts 1200 laps to within 1% of the limit (ran 10)" ("ran to the limit" for laps =
/// "limit"). Numbers have 2 significant digits, the predicted laps none after the point. Empty for
/// an approximation study. Never throws except std::bad_alloc.
std::vector<TimeConvergence> time_convergence(const RunRecord& run);

/// The console's lines: "convergence in time:" and "  <label>: <sentence>" per group; "" when
/// time_convergence is empty.
std::string format_time_convergence(const std::vector<TimeConvergence>& groups);

}  // namespace rkhs
