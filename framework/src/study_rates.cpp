#include "rkhs/study_rates.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "rkhs/approximation.hpp"

namespace rkhs {

std::string_view excluding_flag(std::string_view metric) {
  if (metric == "gram_condition_number" || metric == "gram_min_eigenvalue") return "gram_singular";
  if (metric == "power_function_sup") return "power_function_at_floor";
  if (metric == "sup_error") return "sup_error_at_floor";
  if (metric == "l2_error") return "l2_error_at_floor";
  return "";
}

std::vector<MetricSeries> compute_rates(const StudyDefinition& study,
                                        const std::vector<TrialSpec>& trials,
                                        const std::vector<TrialResult>& results) {
  std::vector<std::string> group_keys;
  std::map<std::string, std::vector<std::size_t>> members;
  for (const auto& trial : trials) {
    if (!members.contains(trial.group_key)) group_keys.push_back(trial.group_key);
    members[trial.group_key].push_back(trial.index);
  }
  const auto& names = study.all_metrics();
  const bool has_fill = std::find(names.begin(), names.end(), "fill_distance") != names.end();
  const std::size_t fill_index = has_fill ? study.metric_index("fill_distance") : 0;

  std::vector<MetricSeries> out;
  for (std::size_t g = 0; g < group_keys.size(); ++g) {
    auto indices = members[group_keys[g]];
    std::sort(indices.begin(), indices.end(),
              [&](auto a, auto b) { return trials[a].n < trials[b].n; });
    for (const auto& metric : study.metrics) {
      const std::size_t m = study.metric_index(metric);
      const auto flag = excluding_flag(metric);
      MetricSeries series;
      series.metric = metric;
      series.group = g;
      series.trials = indices;
      std::vector<double> fit_x, fit_y;
      std::vector<std::size_t> fit_positions;
      std::size_t failed = 0, flagged = 0;
      for (std::size_t k = 0; k < indices.size(); ++k) {
        const auto& result = results[indices[k]];
        const double x = study.abscissa == Abscissa::n ? static_cast<double>(trials[indices[k]].n)
                                                       : result.metrics[fill_index];
        const double y = result.metrics[m];
        const bool excluded =
            !flag.empty() &&
            std::find(result.flags.begin(), result.flags.end(), flag) != result.flags.end();
        series.abscissa.push_back(x);
        series.values.push_back(y);
        series.flagged.push_back(excluded);
        if (!result.ok) ++failed;
        else if (excluded) ++flagged;
        else {
          fit_x.push_back(x);
          fit_y.push_back(y);
          fit_positions.push_back(k);
        }
      }
      series.pairwise = pairwise_rates(series.abscissa, series.values);
      std::vector<std::string> notes;
      if (failed) notes.push_back(fmt::format("{} failed trial{} excluded", failed, failed > 1 ? "s" : ""));
      if (flagged) notes.push_back(fmt::format("{} value{} excluded ({})", flagged,
                                               flagged > 1 ? "s" : "", flag));
      series.fit = fit_power_law(fit_x, fit_y);
      if (series.fit) {
        for (auto& u : series.fit->used) u = fit_positions[u];
        if (!series.fit->note.empty()) notes.push_back(series.fit->note);
      } else {
        notes.push_back(fmt::format("no fit: {} usable point{}", fit_x.size(),
                                    fit_x.size() == 1 ? "" : "s"));
      }
      for (std::size_t i = 0; i < notes.size(); ++i) series.note += (i ? "; " : "") + notes[i];
      out.push_back(std::move(series));
    }
  }
  return out;
}

}  // namespace rkhs
