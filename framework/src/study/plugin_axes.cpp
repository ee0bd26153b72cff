// Plugin axes of a study file ([[kernel]], [[target]], [[centres]], [[projection]] and the
// axes a study kind adds): each entry's name and parameters read and checked, the axis counted
// before it is expanded, then expanded into choices (study_file_parts.hpp).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <limits>
#include <map>
#include <set>

#include "expectation_parser.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "study_file_parts.hpp"

namespace rkhs::detail {

std::uint64_t saturating_product(std::uint64_t a, std::uint64_t b) {
  std::uint64_t product = 0;
  return __builtin_mul_overflow(a, b, &product) ? std::numeric_limits<std::uint64_t>::max()
                                                : product;
}

GridFactor count_plugin_axis(const toml::table& root, std::string_view section,
                             std::string_view singular, std::string_view plural) {
  GridFactor factor{std::string(), 1, 1, {}, std::string(section)};
  const auto* node = root.get(section);
  if (!node) {
    factor.text = fmt::format("1 {} (the default)", singular);
    return factor;
  }
  factor.where = node->source();
  std::vector<const toml::node*> entries;
  if (const auto* array = node->as_array())
    for (const auto& item : *array) entries.push_back(&item);
  else
    entries.push_back(node);
  std::uint64_t total = 0;
  std::vector<std::string> parts;
  for (const auto* entry : entries) {
    std::uint64_t count = 1;
    std::vector<std::string> lists;
    if (const auto* table = entry->as_table())
      for (auto&& [key, value] : *table) {
        if (key.str() == "name" || key.str() == "tier") continue;
        if (const auto* values = value.as_array(); values && values->size() > 1) {
          count = saturating_product(count, values->size());
          lists.push_back(fmt::format("{} {}", key.str(), values->size()));
        }
      }
    total = count > std::numeric_limits<std::uint64_t>::max() - total
                ? std::numeric_limits<std::uint64_t>::max()
                : total + count;
    if (count > factor.largest) {
      factor.largest = count;
      factor.where = entry->source();
    }
    if (!lists.empty()) {
      const auto* name = entry->as_table() ? entry->as_table()->get("name") : nullptr;
      parts.push_back(fmt::format("[[{}]] {}at line {}: {}", section,
                                  name ? show(*name) + " " : std::string(),
                                  entry->source().begin.line, fmt::join(lists, " x ")));
    }
  }
  factor.count = total;
  factor.text = fmt::format("{} {}", total, total == 1 ? singular : plural);
  if (!parts.empty()) factor.text += fmt::format(" ({})", fmt::join(parts, "; "));
  return factor;
}

toml::source_region parameter_location(const PluginEntry& entry, const std::vector<std::size_t>& at,
                                       const std::string& parameter) {
  for (std::size_t a = 0; a < entry.axes.size(); ++a)
    if (entry.axes[a].name == parameter) return entry.axes[a].values[at[a]].second;
  return entry.where;
}

PluginChoice resolve_choice(const Reporter& report, std::string_view section,
                            const PluginEntry& entry, const std::vector<std::size_t>& at) {
  std::map<std::string, ParameterValue> given;
  for (std::size_t a = 0; a < entry.axes.size(); ++a)
    given[entry.axes[a].name] = entry.axes[a].values[at[a]].first;
  // A data file (a text parameter `file`) names a file below the data root, or an absolute
  // path: a relative path that climbs out of the root through ".." is refused here, at its key.
  if (const auto it = given.find("file"); it != given.end())
    if (const auto* path = std::get_if<std::string>(&it->second); path && leaves_data_root(*path))
      report.fail(parameter_location(entry, at, "file"), fmt::format("{}.file", section),
                  data_root_escape_message(*path));
  try {
    return {entry.name, ParameterSet::resolve(*entry.specs, given, entry.user_parameters),
            entry.tiers};
  } catch (const ParameterError& e) {
    report.fail(parameter_location(entry, at, e.parameter()),
                fmt::format("{}.{}", section, e.parameter()), e.what());
  }
}

namespace {

// Whether a value in a study file is of a parameter type (a number for real and integer
// parameters: whether it is whole is ParameterSet::resolve's to say).
bool has_type(const toml::node& node, ParameterType type) {
  switch (type) {
    case ParameterType::real:
    case ParameterType::integer:
      return node.is_number();
    case ParameterType::choice:
    case ParameterType::text:
      return node.is_string();
    case ParameterType::boolean:
      return node.is_boolean();
  }
  return false;
}

PluginEntry read_plugin_entry(const Reporter& report, const toml::table& table,
                              std::string_view section, const PluginCatalogue& plugins) {
  const std::string prefix = std::string(section) + ".";
  PluginEntry entry;
  entry.where = table.source();
  entry.name = get_string(report, table, "name", prefix, std::nullopt);
  const auto* plugin = plugins.find(entry.name);
  if (!plugin)
    report.fail(table.get("name")->source(), prefix + "name",
                fmt::format("unknown {} '{}' {}", plugins.kind, entry.name,
                            with_suggestion(entry.name, plugins.names)));
  entry.specs = &plugin->parameters;
  if (plugin->user_parameters) entry.user_parameters = &*plugin->user_parameters;
  std::vector<std::string> known;
  for (const auto& spec : *entry.specs) known.push_back(spec.name);

  for (auto&& [key, node] : table) {
    const std::string parameter(key.str());
    if (parameter == "name") continue;
    if (parameter == "tier") {  // the tiers this entry belongs to (docs/verification.md)
      entry.tiers = detail::parse_tiers(node, report.source(), prefix + "tier");
      continue;
    }
    const bool declared = std::find(known.begin(), known.end(), parameter) != known.end();
    if (!declared && !entry.user_parameters)
      report.fail(key.source(), prefix + parameter,
                  fmt::format("unknown parameter of {} '{}' {}", plugins.kind, entry.name,
                              known.empty() ? std::string("(it has none)")
                                            : with_suggestion(parameter, known)));
    if (!declared) {
      // A parameter the user names: its values must have the user parameters' type (a
      // misspelt declared parameter is said to be one, e.g. F = "..." for f).
      const auto& spec = *entry.user_parameters;
      const auto refuse = [&](const toml::node& value) {
        report.fail(value.source(), prefix + parameter,
                    fmt::format("'{}' is not declared by {} '{}' {}, so it is one of the "
                                "{}'s own parameters, which must be {}: found {} ({})",
                                parameter, plugins.kind, entry.name,
                                known.empty() ? std::string("(it declares none)")
                                              : with_suggestion(parameter, known),
                                plugins.kind, type_name(spec.type), describe(value), show(value)));
      };
      if (auto why = check_user_parameter_name(parameter); !why.empty())
        report.fail(key.source(), prefix + parameter,
                    fmt::format("'{}' {} (a parameter of {} '{}' that it does not declare names "
                                "one of its own parameters)",
                                parameter, why, plugins.kind, entry.name));
      if (const auto* array = node.as_array()) {
        for (const auto& item : *array)
          if (!has_type(item, spec.type)) refuse(item);
      } else if (!has_type(node, spec.type)) {
        refuse(node);
      }
    }
    PluginEntry::Axis axis{parameter, {}};
    if (const auto* array = node.as_array()) {
      if (array->empty()) report.fail(node.source(), prefix + parameter, "empty list of values");
      for (const auto& item : *array) {
        auto value = scalar_value(item);
        if (!value)
          report.fail(item.source(), prefix + parameter,
                      fmt::format("expected a value, found {}", describe(item)));
        axis.values.emplace_back(std::move(*value), item.source());
      }
    } else {
      auto value = scalar_value(node);
      if (!value)
        report.fail(node.source(), prefix + parameter,
                    fmt::format("expected a value or a list of values, found {}", describe(node)));
      axis.values.emplace_back(std::move(*value), node.source());
    }
    entry.axes.push_back(std::move(axis));
  }
  // Declared parameters in declaration order, then the user's by name (the order of
  // ParameterSet::resolve).
  std::sort(entry.axes.begin(), entry.axes.end(), [&](const auto& a, const auto& b) {
    const auto rank_a = std::find(known.begin(), known.end(), a.name) - known.begin();
    const auto rank_b = std::find(known.begin(), known.end(), b.name) - known.begin();
    return rank_a != rank_b ? rank_a < rank_b : a.name < b.name;
  });
  // Every value once, with the first of the other lists (a choice of the grid): a value out of
  // range or listed twice is found here, before the entry is expanded.
  const std::vector<std::size_t> first(entry.axes.size(), 0);
  resolve_choice(report, section, entry, first);
  for (std::size_t a = 0; a < entry.axes.size(); ++a) {
    std::set<std::string> labels;
    for (std::size_t v = 0; v < entry.axes[a].values.size(); ++v) {
      auto at = first;
      at[a] = v;
      const auto label = resolve_choice(report, section, entry, at).label();
      if (!labels.insert(label).second)
        report.fail(entry.axes[a].values[v].second, prefix + entry.axes[a].name,
                    fmt::format("'{}' is listed twice", label));
    }
  }
  return entry;
}

// Every combination of an entry's lists, the first parameter varying slowest.
void expand_plugin_entry(const Reporter& report, std::string_view section, const PluginEntry& entry,
                         std::vector<PluginChoice>& out) {
  for_each_combination(entry, [&](const std::vector<std::size_t>& at) {
    out.push_back(resolve_choice(report, section, entry, at));
  });
}

}  // namespace

PluginAxis read_plugins(const Reporter& report, const toml::table& root, std::string_view section,
                        const PluginCatalogue& plugins, std::optional<std::string> default_name) {
  PluginAxis axis{std::string(section), root.get(section), {}};
  if (!axis.node) {
    if (!default_name)
      report.fail({}, section,
                  fmt::format("missing: add at least one [[{}]] table with a name (known: {})",
                              section, fmt::join(plugins.names, ", ")));
    const auto& info = *plugins.find(*default_name);
    PluginEntry entry{*default_name, &info.parameters, {}, {}, {}};
    if (info.user_parameters) entry.user_parameters = &*info.user_parameters;
    axis.entries.push_back(std::move(entry));
    return axis;
  }
  auto add_entry = [&](const toml::node& item) {
    if (!item.is_table())
      report.fail(item.source(), section,
                  fmt::format("expected a table ([[{}]]), found {}", section, describe(item)));
    axis.entries.push_back(read_plugin_entry(report, *item.as_table(), section, plugins));
  };
  if (const auto* array = axis.node->as_array()) {
    for (const auto& item : *array) add_entry(item);
  } else {
    add_entry(*axis.node);
  }
  return axis;
}

std::vector<PluginChoice> first_choices(const Reporter& report, const PluginAxis& axis) {
  std::vector<PluginChoice> out;
  for (const auto& entry : axis.entries)
    out.push_back(resolve_choice(report, axis.section, entry,
                                 std::vector<std::size_t>(entry.axes.size(), 0)));
  return out;
}

std::vector<PluginChoice> expand_plugins(const Reporter& report, const PluginAxis& axis) {
  std::vector<PluginChoice> out;
  for (const auto& entry : axis.entries) expand_plugin_entry(report, axis.section, entry, out);
  if (!axis.node) return out;
  std::set<std::string> seen;
  for (const auto& choice : out)
    if (!seen.insert(choice.label()).second)
      report.fail(axis.node->source(), axis.section,
                  fmt::format("'{}' is listed twice", choice.label()));
  return out;
}

void check_instances(const Reporter& report, const toml::table& root, const PluginAxis& axis,
                     const std::function<void(const PluginChoice&, const PluginEntry&)>& make) {
  const std::string_view section = axis.section;
  for (const auto& entry : axis.entries)
    for_each_combination(entry, [&](const std::vector<std::size_t>& at) {
      const auto choice = resolve_choice(report, section, entry, at);
      try {
        make(choice, entry);
      } catch (const StudyError&) {
        throw;  // located already (by `make`)
      } catch (const ParameterError& e) {
        report.fail(parameter_location(entry, at, e.parameter()),
                    fmt::format("{}.{}", section, e.parameter()),
                    fmt::format("{}: {}", choice.given_label(), e.what()));
      } catch (const std::exception& e) {
        report.fail(root.get(section) ? root.get(section)->source() : toml::source_region{},
                    section, fmt::format("{}: {}", choice.given_label(), e.what()));
      }
    });
}

// `plugins = ["path.so", ...]`: plugin modules, relative to the study file's directory, loaded
// before any plugin name in the file is looked up.
void load_study_plugins(const Reporter& report, const toml::table& root) {
  const auto* node = root.get("plugins");
  if (!node) return;
  const auto* array = node->as_array();
  if (!array)
    report.fail(node->source(), "plugins",
                fmt::format("expected an array of plugin files, found {}", describe(*node)));
  const auto directory = std::filesystem::path(report.source()).parent_path();
  for (const auto& item : *array) {
    if (!item.is_string())
      report.fail(item.source(), "plugins",
                  fmt::format("expected a plugin file name, found {}", describe(item)));
    std::filesystem::path file(item.as_string()->get());
    if (file.is_relative()) file = directory / file;
    try {
      load_plugin(file);
    } catch (const PluginError& e) {
      report.fail(item.source(), "plugins", e.what());
    }
  }
}

}  // namespace rkhs::detail
