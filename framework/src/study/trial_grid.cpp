#include "rkhs/study/trial_grid.hpp"

#include <algorithm>
#include <map>
#include <optional>

namespace rkhs {

namespace {
// The plugin axes of a trial in column order; the kernel's parameters are not prefixed.
std::vector<std::pair<std::string, const PluginChoice*>> plugin_axes(const TrialSpec& trial) {
  std::vector<std::pair<std::string, const PluginChoice*>> out;
  for (const auto& [axis, choice] : trial.plugin_choices()) out.emplace_back(axis, choice);
  return out;
}
// The lap count of a trial of a study with a laps axis.
std::optional<double> laps_of(const TrialSpec& trial) {
  const auto* adaptive = trial.adaptive_axes_if();
  return adaptive ? adaptive->laps : std::nullopt;
}
std::string parameter_column(const std::string& axis, const std::string& parameter) {
  if (axis == "kernel") return parameter;
  std::string column = axis;  // (operator+ here trips GCC 12's -Wrestrict false positive)
  column += '_';
  column += parameter;
  return column;
}
}  // namespace

std::vector<std::string> axis_columns(const std::vector<TrialSpec>& trials) {
  std::vector<std::string> out;
  if (trials.empty()) return out;
  for (const auto& [axis, first] : plugin_axes(trials.front())) {
    if (first->name.empty()) continue;  // an axis this kind of study does not have
    std::vector<std::string> columns{axis};
    for (const auto& trial : trials)
      for (const auto& [other, choice] : plugin_axes(trial))
        if (other == axis)
          for (const auto& [name, value] : choice->parameters.values())
            if (auto column = parameter_column(axis, name);
                std::find(columns.begin(), columns.end(), column) == columns.end())
              columns.push_back(column);
    out.insert(out.end(), columns.begin(), columns.end());
  }
  if (laps_of(trials.front())) out.push_back("laps");  // nested just outside n
  return out;
}

std::vector<std::string> axis_values(const std::vector<std::string>& columns, const TrialSpec& trial) {
  std::map<std::string, std::string> values;
  for (const auto& [axis, choice] : plugin_axes(trial)) {
    values[axis] = choice->name;
    for (const auto& [name, value] : choice->parameters.values())
      values[parameter_column(axis, name)] = format_value(value);
  }
  if (const auto laps = laps_of(trial)) values["laps"] = laps_text(*laps);
  std::vector<std::string> out;
  for (const auto& column : columns) out.push_back(values.contains(column) ? values[column] : "");
  return out;
}

}  // namespace rkhs
