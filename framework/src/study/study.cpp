// StudyDefinition's grid: the trials (Cartesian product of the plugin axes and n), its axes,
// and the metrics of each study kind. Reading study files is study_file.cpp.
#include "rkhs/study/study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/core/random.hpp"

namespace rkhs {

std::string PluginChoice::label() const {
  auto canonical = parameters.canonical();
  return canonical.empty() ? name : name + " " + canonical;
}

std::string PluginChoice::given_label() const {
  auto canonical = parameters.given_canonical();
  return canonical.empty() ? name : name + " " + canonical;
}

std::string_view study_kind_name(StudyKind kind) noexcept {
  return describe(kind).name();
}

std::optional<StudyKind> study_kind_from_name(std::string_view name) noexcept {
  if (const auto* descriptor = find_study_kind(name)) return descriptor->kind();
  return std::nullopt;
}

const std::vector<std::string>& metric_names(StudyKind kind) {
  return describe(kind).metric_names();
}

FloorRule metric_floor_rule(StudyKind kind, std::string_view metric) {
  const auto* row = describe(kind).find_metric(metric);
  return row ? row->floor : FloorRule::exact;
}

std::string metric_axis_label(StudyKind kind, std::string_view metric) {
  const auto* row = describe(kind).find_metric(metric);
  if (!row) return std::string(metric);
  const bool physical =
      row->unit == "m" || row->unit == "s" || row->unit == "1/s" || row->unit == "laps";
  return physical ? fmt::format("{} ({})", row->label, row->unit) : std::string(row->label);
}

const std::vector<std::string>& PlotStyle::legend_positions() {
  static const std::vector<std::string> positions{
      "below", "outside", "top right", "top left", "bottom right", "bottom left", "none"};
  return positions;
}

const std::vector<std::string>& StudyDefinition::all_metrics() const { return metric_names(kind); }

std::size_t StudyDefinition::metric_index(std::string_view metric) const {
  const auto& names = all_metrics();
  const auto it = std::find(names.begin(), names.end(), metric);
  if (it == names.end()) throw std::out_of_range(fmt::format("unknown metric '{}'", metric));
  return static_cast<std::size_t>(it - names.begin());
}

MetricSelection StudyDefinition::computed_metrics() const {
  return kind_descriptor().computed_metrics(*this);
}

std::vector<std::string> StudyDefinition::computed_metric_reasons() const {
  return kind_descriptor().computed_metric_reasons(*this);
}

std::vector<std::string> StudyDefinition::computed_metric_names() const {
  const auto& names = all_metrics();
  const auto computed = computed_metrics();
  std::vector<std::string> out;
  for (std::size_t i = 0; i < names.size(); ++i)
    if (computed[i]) out.push_back(names[i]);
  return out;
}

std::vector<StudyDefinition::GridAxis> StudyDefinition::grid_axes() const {
  std::vector<GridAxis> axes{{"kernel", "kernels", kernels.size()},
                             {"target", "targets", targets.size()},
                             {"centre placement", "centre placements", centres.size()}};
  if (!projections.empty())
    axes.push_back({"projection", "projections", projections.size()});
  // The adaptive axes are there when the study has them (trials() nests them the same way).
  for (const auto& axis : {GridAxis{"plant", "plants", plants.size()},
                           GridAxis{"learning law", "learning laws", laws.size()},
                           GridAxis{"integrator", "integrators", integrators.size()}})
    if (axis.count) axes.push_back(axis);
  if (!laps_values.empty()) axes.push_back({"value of laps", "values of laps", laps_values.size()});
  axes.push_back({"value of n", "values of n", n_values.size()});
  return axes;
}

std::vector<TrialSpec> StudyDefinition::trials() const {
  // Axes a study kind does not have contribute one empty choice (and nothing to the keys);
  // a study without a laps axis has one lap count, std::nullopt.
  const std::vector<PluginChoice> none{PluginChoice{}};
  auto or_none = [&](const std::vector<PluginChoice>& axis) -> const std::vector<PluginChoice>& {
    return axis.empty() ? none : axis;
  };
  std::vector<std::optional<double>> lap_counts(laps_values.begin(), laps_values.end());
  if (lap_counts.empty()) lap_counts.emplace_back();
  std::vector<TrialSpec> out;
  for (const auto& kernel : kernels)
    for (const auto& target : targets)
      for (const auto& placement : centres)
        for (const auto& projection : or_none(projections))
          for (const auto& plant : or_none(plants))
            for (const auto& law : or_none(laws))
              for (const auto& integrator : or_none(integrators))
                for (const auto& laps : lap_counts)
                  for (std::size_t n : n_values) {
                    TrialSpec trial;
                    trial.index = out.size();
                    trial.kernel = kernel;
                    trial.target = target;
                    trial.centres = placement;
                    trial.projection = projection;
                    trial.plant = plant;
                    trial.law = law;
                    trial.integrator = integrator;
                    trial.n = n;
                    trial.laps = laps;
                    trial.group_key =
                        fmt::format("kernel={} | target={} | centres={}", kernel.label(),
                                    target.label(), placement.label());
                    using Named = std::pair<const char*, const PluginChoice*>;
                    for (const auto& [axis, choice] :
                         {Named{"projection", &projection}, Named{"plant", &plant},
                          Named{"law", &law}, Named{"integrator", &integrator}})
                      if (!choice->name.empty())
                        trial.group_key += fmt::format(" | {}={}", axis, choice->label());
                    // The seed leaves laps out: every lap count of a series sees the same random
                    // centres, so its trials differ in nothing but how long they learn.
                    trial.seed = hash64(fmt::format("{} | n={}", trial.group_key, n));
                    if (laps) trial.group_key += fmt::format(" | laps={}", laps_text(*laps));
                    trial.key = fmt::format("{} | n={}", trial.group_key, n);
                    out.push_back(std::move(trial));
                  }
  return out;
}

std::string laps_text(double laps) {
  if (std::isinf(laps) && laps > 0) return "limit";
  if (laps == std::floor(laps) && std::abs(laps) < 1e15)
    return fmt::format("{}", static_cast<long long>(laps));
  return format_real(laps);
}

AdaptiveSettings trial_adaptive_settings(const StudyDefinition& study, const TrialSpec& trial) {
  AdaptiveSettings settings = study.adaptive;
  if (!study.reference.name.empty()) settings.engine = AdaptiveEngine::time_stepping;
  for (const auto& [name, value] : trial.integrator.parameters.values()) {
    if (name != "rtol" && name != "atol") continue;
    (name == "rtol" ? settings.integrator_rtol : settings.integrator_atol) =
        trial.integrator.parameters.real(name);
  }
  if (!trial.laps) return settings;
  settings.laps = *trial.laps;
  std::erase_if(settings.snapshot_laps, [&](double lap) { return lap > settings.laps; });
  return settings;
}

}  // namespace rkhs
