#pragma once
// Tiers: subsets of a study for quick runs, e.g. in CI (`rkhs-study check --tier quick`).
// A plugin entry ([[kernel]], [[target]], ...) or an [[expect]] table joins tiers with
// `tier = "quick"` or `tier = ["quick", "nightly"]` (docs/verification.md).
//
// Running a tier keeps, on each plugin axis where some entry names a tier, only the entries of
// that tier; an axis whose entries name no tier is not restricted (so marking one kernel
// "quick" does not drop the default target). `[grid] tier_n = { quick = [10, 20] }` names the
// values of n a tier runs (all of them for a tier it does not name). Only the expectations of
// the tier are checked.

#include <string>
#include <string_view>
#include <vector>

#include "rkhs/study/study.hpp"

namespace rkhs {

/// Every tier named in the study (plugin entries, expectations and [grid] tier_n), sorted,
/// without repeats.
std::vector<std::string> study_tiers(const StudyDefinition& study);

/// The study restricted to `tier` as described above. Throws StudyError when the study names
/// no such tier, when the tier leaves an axis without entries, or when an expectation of the
/// tier selects no group that remains.
StudyDefinition restrict_to_tier(StudyDefinition study, std::string_view tier);

}  // namespace rkhs
