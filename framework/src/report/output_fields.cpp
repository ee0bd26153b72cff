#include "output_fields.hpp"

#include <algorithm>

#include "rkhs/approx/metrics.hpp"

namespace rkhs::report_detail {

std::string abscissa_name(const StudyDefinition& study) {
  return study.abscissa == Abscissa::n ? "n" : "h";
}

std::string model_id(RateModel model) {
  return model == RateModel::power_law ? "power_law" : "exponential";
}

std::vector<std::string> reported_flags(const StudyDefinition& study,
                                        const std::vector<std::string>& flags) {
  std::vector<std::string> out;
  for (const auto& flag : flags) {
    bool unreported = false;
    for (const auto& row : study.kind_descriptor().metrics())
      if (flag == floor_flag(row) && flag != row.flag &&
          std::find(study.metrics.begin(), study.metrics.end(), row.name) == study.metrics.end())
        unreported = true;
    if (!unreported) out.push_back(flag);
  }
  return out;
}

}  // namespace rkhs::report_detail
