// StudyDefinition's grid: the trials (Cartesian product of the plugin axes and n), its axes,
// and the metrics of each study kind. Reading study files is study_file.cpp.
#include "rkhs/study/study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <variant>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/metrics.hpp"
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

const std::vector<std::string>& StudyDefinition::all_metrics() const {
  return metric_names(kind());
}

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

namespace {

// The alternative of `Variant` with index `index`, default-constructed.
template <class Variant, std::size_t... I>
Variant default_alternative(std::size_t index, std::index_sequence<I...>) {
  using Make = Variant (*)();
  static constexpr Make make[] = {[] { return Variant(std::in_place_index<I>); }...};
  if (index >= sizeof...(I))
    throw std::logic_error(fmt::format("study kind {} has no kind axes", index));
  return make[index]();
}

// The Axes `kind_axes` holds; throws std::logic_error naming the kind it holds otherwise.
template <class Axes, class Variant>
Axes& axes_or_throw(Variant& kind_axes, const char* what, const char* plural) {
  if (auto* axes = std::get_if<std::remove_const_t<Axes>>(&kind_axes)) return *axes;
  throw std::logic_error(fmt::format("{}: {} {} have none", what,
                                     study_kind_name(static_cast<StudyKind>(kind_axes.index())),
                                     plural));
}

}  // namespace

StudyKindAxes study_kind_axes(StudyKind kind) {
  return default_alternative<StudyKindAxes>(
      static_cast<std::size_t>(kind),
      std::make_index_sequence<std::variant_size_v<StudyKindAxes>>());
}

TrialKindAxes trial_kind_axes(StudyKind kind) {
  return default_alternative<TrialKindAxes>(
      static_cast<std::size_t>(kind),
      std::make_index_sequence<std::variant_size_v<TrialKindAxes>>());
}

const AdaptiveStudyAxes& StudyDefinition::adaptive_axes() const {
  return axes_or_throw<const AdaptiveStudyAxes>(kind_axes, "StudyDefinition::adaptive_axes",
                                                "studies");
}
AdaptiveStudyAxes& StudyDefinition::adaptive_axes() {
  return axes_or_throw<AdaptiveStudyAxes>(kind_axes, "StudyDefinition::adaptive_axes", "studies");
}
const AdaptiveTrialAxes& TrialSpec::adaptive_axes() const {
  return axes_or_throw<const AdaptiveTrialAxes>(kind_axes, "TrialSpec::adaptive_axes", "trials");
}
AdaptiveTrialAxes& TrialSpec::adaptive_axes() {
  return axes_or_throw<AdaptiveTrialAxes>(kind_axes, "TrialSpec::adaptive_axes", "trials");
}

namespace {

// StudyDefinition::plugin_axes(), const or not.
template <class Study>
auto plugin_axes_of(Study& study) {
  std::vector<std::pair<const char*, decltype(&study.kernels)>> out{
      {"kernel", &study.kernels},
      {"target", &study.targets},
      {"centres", &study.centres},
      {"projection", &study.projections}};
  if (auto* adaptive = study.adaptive_axes_if())
    out.insert(out.end(), {{"plant", &adaptive->plants},
                           {"law", &adaptive->laws},
                           {"integrator", &adaptive->integrators}});
  return out;
}

// TrialSpec::plugin_choices(), const or not.
template <class Trial>
auto plugin_choices_of(Trial& trial) {
  std::vector<std::pair<const char*, decltype(&trial.kernel)>> out{
      {"kernel", &trial.kernel},
      {"target", &trial.target},
      {"centres", &trial.centres},
      {"projection", &trial.projection}};
  if (auto* adaptive = trial.adaptive_axes_if())
    out.insert(out.end(), {{"plant", &adaptive->plant},
                           {"law", &adaptive->law},
                           {"integrator", &adaptive->integrator}});
  return out;
}

}  // namespace

std::vector<std::pair<const char*, const std::vector<PluginChoice>*>> StudyDefinition::plugin_axes()
    const {
  return plugin_axes_of(*this);
}
std::vector<std::pair<const char*, std::vector<PluginChoice>*>> StudyDefinition::plugin_axes() {
  return plugin_axes_of(*this);
}
std::vector<std::pair<const char*, const PluginChoice*>> TrialSpec::plugin_choices() const {
  return plugin_choices_of(*this);
}
std::vector<std::pair<const char*, PluginChoice*>> TrialSpec::plugin_choices() {
  return plugin_choices_of(*this);
}

std::vector<StudyDefinition::GridAxis> StudyDefinition::grid_axes() const {
  std::vector<GridAxis> axes{{"kernel", "kernels", kernels.size()},
                             {"target", "targets", targets.size()},
                             {"centre placement", "centre placements", centres.size()}};
  if (!projections.empty())
    axes.push_back({"projection", "projections", projections.size()});
  // The adaptive axes are there when the study has them (trials() nests them the same way).
  if (const auto* adaptive = adaptive_axes_if()) {
    for (const auto& axis : {GridAxis{"plant", "plants", adaptive->plants.size()},
                             GridAxis{"learning law", "learning laws", adaptive->laws.size()},
                             GridAxis{"integrator", "integrators", adaptive->integrators.size()}})
      if (axis.count) axes.push_back(axis);
    if (const auto& laps = adaptive->laps_values; !laps.empty())
      axes.push_back({"value of laps", "values of laps", laps.size()});
  }
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
  const auto* adaptive = adaptive_axes_if();
  const auto& plants = adaptive ? adaptive->plants : none;
  const auto& laws = adaptive ? adaptive->laws : none;
  const auto& integrators = adaptive ? adaptive->integrators : none;
  std::vector<std::optional<double>> lap_counts;
  if (adaptive) lap_counts.assign(adaptive->laps_values.begin(), adaptive->laps_values.end());
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
                    trial.kind_axes = trial_kind_axes(kind());
                    if (auto* own = trial.adaptive_axes_if()) *own = {plant, law, integrator, laps};
                    trial.n = n;
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
  const auto& adaptive = study.adaptive_axes();
  const auto& own = trial.adaptive_axes();
  AdaptiveSettings settings = adaptive.settings;
  if (!adaptive.reference.name.empty()) settings.engine = AdaptiveEngine::time_stepping;
  // The optional work the study's metrics need (MetricInfo::needs of the adaptive table).
  MetricSelection asked;
  for (const auto& row : MetricTable<AdaptiveMetric>::rows)
    asked.push_back(std::ranges::find(study.metrics, row.name) != study.metrics.end());
  const unsigned work = work_needed<AdaptiveMetric>(asked);
  settings.initial_data_dependence = (work & adaptive_work_initial_data) != 0;
  for (const auto& [name, value] : own.integrator.parameters.values()) {
    if (name != "rtol" && name != "atol") continue;
    (name == "rtol" ? settings.integrator_rtol : settings.integrator_atol) =
        own.integrator.parameters.real(name);
  }
  if (!own.laps) return settings;
  settings.laps = *own.laps;
  std::erase_if(settings.snapshot_laps, [&](double lap) { return lap > settings.laps; });
  return settings;
}

}  // namespace rkhs
