#include "rkhs/study/expectation.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <variant>

#include "rkhs/core/printable.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/trial_grid.hpp"

namespace rkhs {

namespace {

// Whether a selector's value accepts a column's value: the same text, or the same number
// (laps = 1e6 selects the column's "1000000").
bool accepts(const ParameterValue& accepted, const std::string& value) {
  if (format_value(accepted) == value) return true;
  double wanted = 0;
  if (const auto* real = std::get_if<double>(&accepted)) wanted = *real;
  else if (const auto* integer = std::get_if<std::int64_t>(&accepted))
    wanted = static_cast<double>(*integer);
  else
    return false;
  double found = 0;
  const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), found);
  return error == std::errc() && end == value.data() + value.size() && found == wanted;
}

}  // namespace

bool Expectation::selects(const TrialSpec& trial) const {
  return std::all_of(selectors.begin(), selectors.end(), [&](const AxisSelector& selector) {
    const auto value = axis_values({selector.column}, trial).front();
    return std::any_of(selector.values.begin(), selector.values.end(),
                       [&](const ParameterValue& accepted) { return accepts(accepted, value); });
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

std::string Expectation::id() const {
  if (!name.empty()) return name;
  return selectors.empty() ? metric : metric + ' ' + selector_text();
}

std::string_view expectation_kind_name(ExpectationKind kind) {
  switch (kind) {
    case ExpectationKind::theory: return "theory";
    case ExpectationKind::rate: return "rate";
    case ExpectationKind::model: return "model";
    case ExpectationKind::bound: return "bound";
    case ExpectationKind::constant:
      return "constant";
    case ExpectationKind::reference:
      return "reference";
  }
  return "";
}

std::string ReferenceSpec::text() const {
  // Names from the study file, echoed: control characters escaped.
  std::string out = printable(file) + ", " + printable(value_column);
  for (std::size_t k = 0; k < where.size(); ++k)
    out += (k == 0 ? " where " : " and ") + printable(where[k].first) + " = " +
           printable(where[k].second);
  return out;
}

}  // namespace rkhs
