#include "rkhs/verify/study_rates.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <variant>

#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/metrics.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

namespace {

// The row's flag and its floor flag, where they leave a value out of fits.
std::vector<std::string> excluding_flags_of(const MetricInfo* row) {
  std::vector<std::string> flags;
  if (!row || !row->flag_excludes_from_fits) return flags;
  if (!row->flag.empty()) flags.emplace_back(row->flag);
  if (auto floor = floor_flag(*row); !floor.empty() && floor != row->flag)
    flags.push_back(std::move(floor));
  return flags;
}

}  // namespace

namespace {

// A kernel's properties (rkhs/kernel/kernel.hpp), or why it cannot be rebuilt.
using PropertiesOrError = std::variant<KernelProperties, std::string>;

PropertiesOrError properties_of(const StudyDefinition& study, const PluginChoice& kernel) {
  try {
    return kernel_properties(kernel.name, kernel.parameters, study.domain);
  } catch (const std::exception& e) {
    return std::string(e.what());
  }
}

// series_theory with the kernel's properties from `properties` (called only for a metric with
// a theory law).
template <class Properties>
SeriesTheory theory_of(const StudyDefinition& study, std::string_view metric,
                       Properties&& properties) {
  SeriesTheory out;
  const auto* row = study.kind_descriptor().find_metric(metric);
  if (!row || row->theory == TheoryLaw::none) {
    out.why_none = no_theory_law(metric);
    return out;
  }
  const PropertiesOrError& kernel = properties();
  if (const auto* error = std::get_if<std::string>(&kernel)) {
    out.kernel_unavailable = true;
    out.why_none = *error;
    return out;
  }
  out.rate = theory_rate(*row, std::get<KernelProperties>(kernel), &out.why_none);
  if (out.rate) out.why_none.clear();
  return out;
}

}  // namespace

SeriesTheory series_theory(const StudyDefinition& study, const PluginChoice& kernel,
                           std::string_view metric) {
  std::optional<PropertiesOrError> properties;
  return theory_of(study, metric, [&]() -> const PropertiesOrError& {
    return properties ? *properties : properties.emplace(properties_of(study, kernel));
  });
}

std::string_view excluding_flag(StudyKind kind, std::string_view metric) {
  const auto* row = describe(kind).find_metric(metric);
  return row && row->flag_excludes_from_fits ? row->flag : std::string_view();
}

void fit_series(MetricSeries& series, const FitWindow& window) {
  const std::size_t size = series.values.size();
  std::vector<bool> usable(size);
  std::size_t failed = 0, flagged = 0, first_flagged = size;
  for (std::size_t k = 0; k < size; ++k) {
    usable[k] = !series.failed[k] && !series.flagged[k];
    if (series.failed[k]) ++failed;
    else if (series.flagged[k]) {
      ++flagged;
      first_flagged = std::min(first_flagged, k);
    }
  }
  series.analysis = analyse_series(series.abscissa, series.n, series.values, usable, 0.95, window,
                                   series.floors, series.constant_within);
  const auto& reported = series.analysis.reported_analysis();
  series.pairwise = reported.pairwise;
  series.fit = series.constant() ? std::nullopt : reported.fit;
  series.note.clear();
  series.no_fit_reason.clear();

  std::vector<std::string> notes;
  if (failed) notes.push_back(fmt::format("{} failed trial{} excluded", failed, failed > 1 ? "s" : ""));
  // Flagged values that run to the end of the series are a floor the trials measured.
  bool flagged_tail = flagged > 0;
  for (std::size_t k = first_flagged; flagged_tail && k < size; ++k)
    flagged_tail = series.flagged[k] || series.failed[k];
  if (flagged_tail)
    notes.push_back(fmt::format("floor from n = {}: {} value{} flagged ({})",
                                format_real(series.n[first_flagged]), flagged,
                                flagged > 1 ? "s" : "", series.exclusion_flag));
  else if (flagged)
    notes.push_back(fmt::format("{} value{} excluded ({})", flagged, flagged > 1 ? "s" : "",
                                series.exclusion_flag));
  if (!window.empty())
    notes.push_back(fmt::format("window set by {}: n = {}", window.text(),
                                label_range(series.n, reported.window.points)));
  if (const auto& constant = series.analysis.constant) {
    series.no_fit_reason = fmt::format("constant {}: not a rate", constant->text(series.n));
    if (!constant->head.empty())
      notes.push_back(fmt::format("constant from n = {}: head n = {} excluded",
                                  format_real(series.n[constant->points.front()]),
                                  label_range(series.n, constant->head)));
  } else if (!reported.window.note.empty()) {
    notes.push_back(reported.window.note);
  }
  if (series.fit) {
    if (!series.fit->note.empty()) notes.push_back(series.fit->note);
  } else if (!series.constant()) {
    std::size_t usable_points = 0;
    for (std::size_t k = 0; k < size; ++k)
      usable_points += usable[k] && std::isfinite(series.values[k]) && series.values[k] > 0.0;
    const auto in_window = reported.window.points.size();
    series.no_fit_reason =
        !window.empty() && in_window < usable_points
            ? fmt::format("{} of {} usable points in the window set by {}; a fit needs at least 2",
                          in_window, usable_points, window.text())
            : fmt::format("{} of {} points usable{}; a fit needs at least 2", usable_points, size,
                          failed + flagged > 0
                              ? fmt::format(" after excluding {} failed or flagged", failed + flagged)
                              : std::string());
    notes.push_back(fmt::format("no fit: {} usable point{}", usable_points,
                                usable_points == 1 ? "" : "s"));
  }
  for (std::size_t i = 0; i < notes.size(); ++i) series.note += (i ? "; " : "") + notes[i];
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

  // Each kernel's properties, rebuilt once for every series of a metric with a theory law.
  std::map<std::string, PropertiesOrError> kernels;
  std::vector<MetricSeries> out;
  for (std::size_t g = 0; g < group_keys.size(); ++g) {
    auto indices = members[group_keys[g]];
    std::sort(indices.begin(), indices.end(),
              [&](auto a, auto b) { return trials[a].n < trials[b].n; });
    for (const auto& metric : study.metrics) {
      const std::size_t m = study.metric_index(metric);
      const auto flags = excluding_flags_of(study.kind_descriptor().find_metric(metric));
      std::vector<std::string> seen;  // the flags found, in the order of `flags`
      MetricSeries series;
      series.metric = metric;
      series.group = g;
      series.trials = indices;
      series.constant_within = study.constant_within;
      const auto& kernel = trials[indices.front()].kernel;
      series.theory = theory_of(study, metric, [&]() -> const PropertiesOrError& {
        auto found = kernels.find(kernel.label());
        if (found == kernels.end())
          found = kernels.emplace(kernel.label(), properties_of(study, kernel)).first;
        return found->second;
      });
      for (std::size_t k = 0; k < indices.size(); ++k) {
        const auto& result = results[indices[k]];
        const double x = study.abscissa == Abscissa::n ? static_cast<double>(trials[indices[k]].n)
                                                       : result.metrics[fill_index];
        series.abscissa.push_back(x);
        series.n.push_back(static_cast<double>(trials[indices[k]].n));
        series.values.push_back(result.metrics[m]);
        series.floors.push_back(m < result.floors.size()
                                    ? result.floors[m]
                                    : std::numeric_limits<double>::quiet_NaN());
        bool flagged = false;
        for (const auto& flag : flags)
          if (std::find(result.flags.begin(), result.flags.end(), flag) != result.flags.end()) {
            flagged = true;
            if (std::find(seen.begin(), seen.end(), flag) == seen.end()) seen.push_back(flag);
          }
        series.flagged.push_back(flagged);
        series.failed.push_back(!result.ok);
      }
      std::sort(seen.begin(), seen.end(), [&](const auto& a, const auto& b) {
        return std::find(flags.begin(), flags.end(), a) < std::find(flags.begin(), flags.end(), b);
      });
      series.exclusion_flag = seen.empty() ? (flags.empty() ? std::string() : flags.front())
                                           : fmt::format("{}", fmt::join(seen, ", "));
      fit_series(series, study.rates_window);
      out.push_back(std::move(series));
    }
  }
  return out;
}

}  // namespace rkhs
