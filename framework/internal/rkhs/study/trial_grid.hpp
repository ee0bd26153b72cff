#pragma once
// The columns that name a trial's place in the grid of a study: one per plugin axis and one per
// parameter of each axis. trials.csv and rates.csv print them, [[expect]] selectors and verdicts
// select and label groups by them.

#include <string>
#include <vector>

#include "rkhs/study/study.hpp"

namespace rkhs {

/// The axis columns of trials.csv and rates.csv: kernel, each kernel parameter by its own name,
/// target, target_<parameter>, centres, centres_<parameter>, plant, law, integrator (each with
/// its parameters), in order of first appearance, then laps when the study has a laps axis
/// (values "10", "1000000", "limit": laps_text). Axes a study does not have are left out.
std::vector<std::string> axis_columns(const std::vector<TrialSpec>& trials);

/// The values of those columns for one trial ("" where a column does not apply).
std::vector<std::string> axis_values(const std::vector<std::string>& columns, const TrialSpec& trial);

}  // namespace rkhs
