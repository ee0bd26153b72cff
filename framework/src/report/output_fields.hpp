#pragma once
// Internal to the report layer: the fields trials.csv, rates.csv and summary.json write alike
// (output.cpp, summary_json.cpp).

#include <string>
#include <vector>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::report_detail {

/// "n" or "h": the abscissa the study fits its power laws against.
std::string abscissa_name(const StudyDefinition& study);

/// "power_law" or "exponential": a rate model as the outputs name it.
std::string model_id(RateModel model);

/// The flags of a trial that concern what `study` reports: every flag but the floor flag
/// "<metric>_at_floor" of a metric the study does not report (a trial flags every metric it
/// computes; rows' own flags, such as power_function_at_floor, are always written).
std::vector<std::string> reported_flags(const StudyDefinition& study,
                                        const std::vector<std::string>& flags);

}  // namespace rkhs::report_detail
