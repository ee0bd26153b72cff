#include "rkhs/report/convergence_in_time.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "rkhs/verify/expectation_cases.hpp"

namespace rkhs {

namespace {

// The series of `metric` in the group `key`, nullptr when the study has none.
const MetricSeries* series_of(const RunRecord& run, std::string_view metric,
                              const std::string& key) {
  for (const auto& series : run.rates)
    if (series.metric == metric && !series.trials.empty() &&
        run.trials[series.trials.front()].group_key == key)
      return &series;
  return nullptr;
}

// The value of `series` at the trial `trial`, NaN when it has none there.
double value_at(const MetricSeries* series, std::size_t trial) {
  if (!series) return std::nan("");
  const auto found = std::find(series->trials.begin(), series->trials.end(), trial);
  if (found == series->trials.end()) return std::nan("");
  return series->values[static_cast<std::size_t>(found - series->trials.begin())];
}

bool asks_for(const StudyDefinition& study, std::string_view metric) {
  return std::find(study.metrics.begin(), study.metrics.end(), metric) != study.metrics.end();
}

}  // namespace

std::vector<TimeConvergence> time_convergence(const RunRecord& run) {
  std::vector<TimeConvergence> out;
  const auto& study = run.study;
  if (!asks_for(study, "gap_to_projection") || !asks_for(study, "interpolant_l2_error")) return out;
  const bool laps_asked = asks_for(study, "laps_to_limit");
  const auto labels = group_labels(run.trials);
  for (const auto& gap : run.rates) {
    if (gap.metric != "gap_to_projection" || gap.trials.empty()) continue;
    const auto& key = run.trials[gap.trials.front()].group_key;
    const auto* error = series_of(run, "interpolant_l2_error", key);
    const auto* laps = laps_asked ? series_of(run, "laps_to_limit", key) : nullptr;
    // The largest n where both are usable.
    std::optional<std::size_t> at;
    for (auto k = gap.trials.size(); k-- > 0 && !at;) {
      const double e = value_at(error, gap.trials[k]);
      if (std::isfinite(gap.values[k]) && std::isfinite(e) && e > 0) at = k;
    }
    if (!at) continue;
    const auto trial = gap.trials[*at];
    const double gap_value = gap.values[*at], error_value = value_at(error, trial);
    const double percent = 100.0 * gap_value / error_value;
    std::string sentence =
        percent <= converged_gap_percent
            ? fmt::format(
                  "converged in time: gap to the projection {:.2g} is {:.2g}% of the "
                  "projection's own error {:.2g}",
                  gap_value, percent, error_value)
        : percent <= 100.0
            ? fmt::format(
                  "not yet converged in time: gap to the projection {:.2g} is {:.2g}% of "
                  "the projection's own error {:.2g}",
                  gap_value, percent, error_value)
            : fmt::format(
                  "not converged in time: gap to the projection {:.2g} exceeds the "
                  "projection's own error {:.2g}",
                  gap_value, error_value);
    sentence += fmt::format(" (n = {})", run.trials[trial].n);
    if (const double predicted = value_at(laps, trial); std::isfinite(predicted)) {
      const double ran =
          run.trials[trial].adaptive_axes().laps.value_or(study.adaptive_axes().settings.laps);
      sentence += fmt::format(
          "; the lap map predicts {:.0f} laps to within 1% of the limit ({})", predicted,
          std::isinf(ran) ? std::string("ran to the limit") : fmt::format("ran {:.4g}", ran));
    }
    const auto label = labels.find(key);
    out.push_back({key, label != labels.end() && !label->second.empty() ? label->second : key,
                   std::move(sentence)});
  }
  return out;
}

std::string format_time_convergence(const std::vector<TimeConvergence>& groups) {
  if (groups.empty()) return "";
  std::string out = "convergence in time:\n";
  for (const auto& group : groups) out += fmt::format("  {}: {}\n", group.label, group.sentence);
  return out;
}

}  // namespace rkhs
