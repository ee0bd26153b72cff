#include "rkhs/study/expectation.hpp"

#include <algorithm>

#include "rkhs/study/trial_grid.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs {

bool Expectation::selects(const TrialSpec& trial) const {
  return std::all_of(selectors.begin(), selectors.end(), [&](const AxisSelector& selector) {
    const auto value = axis_values({selector.column}, trial).front();
    return std::any_of(selector.values.begin(), selector.values.end(),
                       [&](const ParameterValue& accepted) { return format_value(accepted) == value; });
  });
}

std::string Expectation::selector_text() const {
  if (selectors.empty()) return "every group";
  std::string out;
  for (const auto& selector : selectors) {
    if (!out.empty()) out += ' ';
    out += selector.column;
    out += '=';
    for (std::size_t i = 0; i < selector.values.size(); ++i) {
      if (i) out += '|';
      out += format_value(selector.values[i]);
    }
  }
  return out;
}

bool Expectation::in_tier(std::string_view tier) const {
  return tier.empty() || std::find(tiers.begin(), tiers.end(), tier) != tiers.end();
}

}  // namespace rkhs
