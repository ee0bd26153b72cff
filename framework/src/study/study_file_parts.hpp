#pragma once
// The parts of the study file reader (study_file.cpp) that its sections share: plugin axes
// ([[kernel]], [[plant]], ...) read, checked and expanded; the grid's size counted before it is
// built; and the sections a study kind owns (StudyFileSections, one per kind, reached through
// StudyKindDescriptor::file_sections). Internal to the study layer.

#include <toml++/toml.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rkhs/core/registry.hpp"
#include "rkhs/study/study.hpp"
#include "toml_reader.hpp"

namespace rkhs::detail {

/// The product a * b, or the largest std::uint64_t when it overflows.
std::uint64_t saturating_product(std::uint64_t a, std::uint64_t b);

/// One factor of the grid's size, counted from the file's lists before anything is built.
struct GridFactor {
  std::string text;           ///< "60 kernels ([[kernel]] 'gaussian' at line 8: sigma 10 x nu 6)"
  std::uint64_t count = 1;    ///< of this axis
  std::uint64_t largest = 0;  ///< of its largest entry (or list)
  toml::source_region where;  ///< of that entry
  std::string key;            ///< of that entry: "kernel", "grid.n", "adaptive.laps"
};

/// `[[section]]` entries: how many choices they expand to, without expanding them.
GridFactor count_plugin_axis(const toml::table& root, std::string_view section,
                             std::string_view singular, std::string_view plural);

/// What the reader needs of a plugin registry: its kind, its names and each plugin's
/// declaration.
struct PluginCatalogue {
  std::string kind;
  std::vector<std::string> names;
  std::function<const PluginInfo*(const std::string&)> find;
};

template <class RegistryType>
PluginCatalogue catalogue_of(const RegistryType& registry) {
  return {registry.kind(), registry.names(), [&registry](const std::string& name) {
            const auto* entry = registry.find(name);
            return entry ? &entry->info : nullptr;
          }};
}

/// A [[kernel]] / [[target]] / [[centres]] / ... entry read and checked (its name, its
/// parameters' names, each value), not yet expanded: a name and parameters, each a value or an
/// array of values (an axis).
struct PluginEntry {
  struct Axis {
    std::string name;
    std::vector<std::pair<ParameterValue, toml::source_region>> values;
  };
  std::string name;
  const std::vector<ParameterSpec>* specs = nullptr;
  std::vector<Axis> axes;  ///< declared parameters in declaration order, then the user's by name
  std::vector<std::string> tiers;
  toml::source_region where;
  const ParameterSpec* user_parameters = nullptr;  ///< PluginInfo::user_parameters
};

/// A plugin axis ([[kernel]], [[target]], ...) read and checked, expanded later
/// (expand_plugins): everything cheap in a study file is checked before anything large is built.
struct PluginAxis {
  std::string section;
  const toml::node* node = nullptr;  ///< the section; nullptr: the default plugin
  std::vector<PluginEntry> entries;
};

/// Where the entry gives `parameter` in the combination `at`: its value, or the entry's table
/// when the parameter took its default.
toml::source_region parameter_location(const PluginEntry& entry, const std::vector<std::size_t>& at,
                                       const std::string& parameter);

/// The choice of `entry` with value at[a] of each axis a; fails at the value a ParameterError
/// names.
PluginChoice resolve_choice(const Reporter& report, std::string_view section,
                            const PluginEntry& entry, const std::vector<std::size_t>& at);

/// Calls visit(at) for every combination of an entry's lists (at[a]: the value of axis a), the
/// first parameter varying slowest.
template <class Visit>
void for_each_combination(const PluginEntry& entry, Visit&& visit) {
  std::vector<std::size_t> at(entry.axes.size(), 0);
  while (true) {
    visit(at);
    std::size_t a = entry.axes.size();
    while (a > 0 && ++at[a - 1] == entry.axes[a - 1].values.size()) at[--a] = 0;
    if (a == 0) break;
  }
}

/// The `[[section]]` entries of `root`, read and checked against `plugins`; without the section,
/// the plugin `default_name` with its defaults (a missing section without a default fails).
PluginAxis read_plugins(const Reporter& report, const toml::table& root, std::string_view section,
                        const PluginCatalogue& plugins, std::optional<std::string> default_name);

/// The first choice of each entry of `axis` (an outline of the axis: the same parameters).
std::vector<PluginChoice> first_choices(const Reporter& report, const PluginAxis& axis);

/// Every choice of `axis`, each entry's combinations with the first parameter varying slowest;
/// a choice listed twice fails.
std::vector<PluginChoice> expand_plugins(const Reporter& report, const PluginAxis& axis);

/// Builds every choice of `axis` with make(choice, entry): a combination that is invalid only
/// for this study (e.g. a non-periodic sine on a closed track) is an input error, not a failed
/// trial. A ParameterError is reported at the value of the parameter it names (at the entry when
/// that took its default); any other error at the section.
void check_instances(const Reporter& report, const toml::table& root, const PluginAxis& axis,
                     const std::function<void(const PluginChoice&, const PluginEntry&)>& make);

/// [study] metrics into study.metrics (metrics_section.cpp): the listed ones in output order,
/// or, when the file lists none, the kind's metrics that every one of `projections` computes
/// (the interpolation projection's when it is empty); a listed metric that a projection does not
/// compute fails at its name.
void read_metrics(const Reporter& report, const toml::table& header, StudyDefinition& study,
                  const std::vector<PluginChoice>& projections);

/// Refuses an evaluation grid no finer than the centres when the study asks for a metric taken
/// on it (MetricInfo::on_grid) and warns below 4 points per centre spacing.
void check_evaluation_grid(const Reporter& report, const toml::table& header,
                           StudyDefinition& study);

/// `plugins = ["path.so", ...]`: plugin modules, relative to the study file's directory, loaded
/// before any plugin name in the file is looked up.
void load_study_plugins(const Reporter& report, const toml::table& root);

/// The sections of a study file that a study kind owns, read by its descriptor
/// (StudyKindDescriptor::file_sections).
class StudyFileSections {
 public:
  virtual ~StudyFileSections() = default;
  /// The factors of the grid's size the kind's axes and sections add, before n.
  virtual void add_grid_factors(const toml::table& root,
                                std::vector<GridFactor>& factors) const = 0;
  /// Reads the kind's plugin axes (appended to `axes`, in the order of axis_members()) and its
  /// sections into `study`.
  virtual void read(const Reporter& report, const toml::table& root, StudyDefinition& study,
                    std::vector<PluginAxis>& axes) const = 0;
  /// Where the kind's axes go in `study` (its kind's axes), in the order read() appends them.
  virtual std::vector<std::vector<PluginChoice>*> axis_members(StudyDefinition& study) const = 0;
  /// Checks what the kind's sections and axes must agree on, once every axis is expanded;
  /// `kind_axes` are the axes read() appended.
  virtual void check(const Reporter& report, const toml::table& root, StudyDefinition& study,
                     const std::vector<PluginAxis>& kind_axes) const = 0;
};

/// The sections of a kind that owns none (approximation).
const StudyFileSections& no_file_sections();
/// The adaptive kind's: [adaptive], [[plant]], [[law]], [[integrator]] (adaptive_sections.cpp).
const StudyFileSections& adaptive_file_sections();

/// [plot] (docs/study-files.md): metrics, labels, title, size, font_size, legend, png_dpi
/// (plot_section.cpp).
PlotStyle parse_plot(const Reporter& report, const toml::table& table,
                     const StudyDefinition& study);

}  // namespace rkhs::detail
