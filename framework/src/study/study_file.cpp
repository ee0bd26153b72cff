// Study files read into a StudyDefinition (docs/study-files.md): every section, its keys and
// values checked, plugin names and parameters resolved against the registries.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "expectation_parser.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/state_dependent.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/core/input_file.hpp"
#include "rkhs/core/random.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/study/study.hpp"
#include "toml_reader.hpp"

namespace rkhs {

using namespace detail;

namespace {

// The largest n a study may ask for (no Gram matrix is anywhere near this size), and the
// most values of n one grid may list.
constexpr std::int64_t max_n = 1'000'000'000;
constexpr std::int64_t max_n_values = 100000;
// The longest study name (docs/study-files.md): it names the output folder, and file names
// are at most 255 bytes on common file systems.
constexpr std::size_t max_study_name = 100;
// [limits] trials when the file does not give it (docs/study-files.md).
constexpr std::uint64_t default_max_trials = 1'000'000;
// The largest [limits] trials: every trial of the grid is held in memory (its plugin choices
// and keys, about 1.7 KB: 10^6 trials took 1.7 GB), and a grid the count admits must be one
// that can be built (a 2^31-trial grid under trials = 1e15 ended in std::bad_alloc).
constexpr std::uint64_t max_max_trials = 10'000'000;

// n = [10, 20] | { from = 10, to = 100, step = 10 } | { from = 8, to = 1024, factor = 2 }.
// Ranges are counted before they are expanded, without overflow: bounds above max_n and more
// than max_n_values values are errors.
std::vector<std::size_t> parse_n(const Reporter& report, const toml::node& node) {
  std::vector<std::pair<std::int64_t, toml::source_region>> values;
  if (const auto* array = node.as_array()) {
    for (const auto& item : *array) {
      if (!item.is_integer())
        report.fail(item.source(), "grid.n",
                    fmt::format("expected integers, found {} ({})", describe(item), show(item)));
      values.emplace_back(item.as_integer()->get(), item.source());
    }
  } else if (const auto* range = node.as_table()) {
    check_keys(report, *range, "grid.n.", {"from", "to", "step", "factor"});
    auto integer = [&](std::string_view key) -> std::optional<std::int64_t> {
      const auto* v = range->get(key);
      if (!v) return std::nullopt;
      if (!v->is_integer())
        report.fail(v->source(), fmt::format("grid.n.{}", key),
                    fmt::format("expected an integer, found {} ({})", describe(*v), show(*v)));
      return v->as_integer()->get();
    };
    const auto from = integer("from"), to = integer("to"), step = integer("step"),
               factor = integer("factor");
    if (!from || !to) report.fail(range->source(), "grid.n", "a range needs 'from' and 'to'");
    if (step.has_value() == factor.has_value())
      report.fail(range->source(), "grid.n", "a range needs exactly one of 'step' or 'factor'");
    for (const char* key : {"from", "to"}) {
      const auto value = *integer(key);
      if (value < 1 || value > max_n)
        report.fail(range->get(key)->source(), fmt::format("grid.n.{}", key),
                    fmt::format("must be between 1 and {} (centres), found {}", max_n, value));
    }
    if (step && *step < 1)
      report.fail(range->get("step")->source(), "grid.n.step",
                  fmt::format("must be >= 1, found {}", *step));
    if (factor && *factor < 2)
      report.fail(range->get("factor")->source(), "grid.n.factor",
                  fmt::format("must be >= 2, found {}", *factor));
    if (*to < *from)
      report.fail(range->source(), "grid.n",
                  fmt::format("'to' ({}) is below 'from' ({})", *to, *from));
    // 1 <= from <= to <= max_n: neither the count nor the values can overflow.
    if (step) {
      const std::int64_t count = (*to - *from) / *step + 1;
      if (count > max_n_values)
        report.fail(range->source(), "grid.n",
                    fmt::format("{} values of n (from {} to {} in steps of {}), more than {}",
                                count, *from, *to, *step, max_n_values));
      for (std::int64_t i = 0; i < count; ++i)
        values.emplace_back(*from + i * *step, range->source());
    } else {
      for (std::int64_t v = *from;; v *= *factor) {
        values.emplace_back(v, range->source());
        if (v > *to / *factor) break;  // v * factor > to, computed without overflow
      }
    }
  } else {
    report.fail(node.source(), "grid.n",
                fmt::format("expected an array of integers or a range table "
                            "{{ from, to, step | factor }}, found {} ({})",
                            describe(node), show(node)));
  }
  if (values.empty()) report.fail(node.source(), "grid.n", "no values");
  std::vector<std::size_t> n;
  for (const auto& [v, where] : values) {
    if (v < 1 || v > max_n)
      report.fail(where, "grid.n",
                  fmt::format("must be between 1 and {} (centres), found {}", max_n, v));
    n.push_back(static_cast<std::size_t>(v));
  }
  std::sort(n.begin(), n.end());
  if (std::adjacent_find(n.begin(), n.end()) != n.end())
    report.fail(node.source(), "grid.n", "values must be distinct");
  return n;
}

// The grid's size counted from the file's lists, before any trial or plugin choice is built:
// the product of every axis (each the sum over its entries of the product of their parameter
// lists), saturating instead of overflowing.
std::uint64_t saturating_product(std::uint64_t a, std::uint64_t b) {
  std::uint64_t product = 0;
  return __builtin_mul_overflow(a, b, &product) ? std::numeric_limits<std::uint64_t>::max()
                                                : product;
}

struct GridFactor {
  std::string text;           // "60 kernels ([[kernel]] 'gaussian' at line 8: sigma 10 x nu 6)"
  std::uint64_t count = 1;    // of this axis
  std::uint64_t largest = 0;  // of its largest entry (or list)
  toml::source_region where;  // of that entry
  std::string key;            // of that entry: "kernel", "grid.n", "adaptive.laps"
};

// `[[section]]` entries: how many choices they expand to, without expanding them.
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

// Refuses a grid of more than `cap` trials before anything of it is built, at the entry or
// list that contributes most, naming the product and the lists that multiply to it.
void check_grid_size(const Reporter& report, const toml::table& root, StudyKind kind,
                     std::size_t n_count, const toml::node& n_node, std::uint64_t cap) {
  std::vector<GridFactor> factors{
      count_plugin_axis(root, "kernel", "kernel", "kernels"),
      count_plugin_axis(root, "target", "target", "targets"),
      count_plugin_axis(root, "centres", "centre placement", "centre placements")};
  if (root.get("projection"))
    factors.push_back(count_plugin_axis(root, "projection", "projection", "projections"));
  if (kind == StudyKind::adaptive) {
    factors.push_back(count_plugin_axis(root, "plant", "plant", "plants"));
    factors.push_back(count_plugin_axis(root, "law", "learning law", "learning laws"));
    factors.push_back(count_plugin_axis(root, "integrator", "integrator", "integrators"));
    const auto* adaptive = root.get("adaptive");
    const auto* laps =
        adaptive && adaptive->as_table() ? adaptive->as_table()->get("laps") : nullptr;
    if (laps && laps->as_array() && laps->as_array()->size() > 1) {
      const auto count = laps->as_array()->size();
      factors.push_back(
          {fmt::format("{} values of laps", count), count, count, laps->source(), "adaptive.laps"});
    }
  }
  factors.push_back({fmt::format("{} value{} of n", n_count, n_count == 1 ? "" : "s"), n_count,
                     n_count, n_node.source(), "grid.n"});
  std::uint64_t trials = 1;
  const GridFactor* largest = &factors.front();
  for (const auto& factor : factors) {
    trials = saturating_product(trials, factor.count);
    if (factor.largest > largest->largest) largest = &factor;
  }
  if (trials <= cap) return;
  std::vector<std::string> texts;
  for (const auto& factor : factors) texts.push_back(factor.text);
  report.fail(largest->where, largest->key,
              fmt::format("the grid has {} trials, more than [limits] trials = {}: {}; shorten "
                          "these lists, or raise [limits] trials",
                          trials == std::numeric_limits<std::uint64_t>::max()
                              ? std::string("more than 10^19")
                              : std::to_string(trials),
                          cap, fmt::join(texts, " x ")));
}

// A [[kernel]] / [[target]] / [[centres]] / ... entry read and checked (its name, its
// parameters' names, each value), not yet expanded: a name and parameters, each a value or an
// array of values (an axis).
struct PluginEntry {
  struct Axis {
    std::string name;
    std::vector<std::pair<ParameterValue, toml::source_region>> values;
  };
  std::string name;
  const std::vector<ParameterSpec>* specs = nullptr;
  std::vector<Axis> axes;  // declared parameters in declaration order, then the user's by name
  std::vector<std::string> tiers;
  toml::source_region where;
  const ParameterSpec* user_parameters = nullptr;  // PluginInfo::user_parameters
};

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

// Where the entry gives `parameter` in the combination `at`: its value, or the entry's table
// when the parameter took its default.
toml::source_region parameter_location(const PluginEntry& entry, const std::vector<std::size_t>& at,
                                       const std::string& parameter) {
  for (std::size_t a = 0; a < entry.axes.size(); ++a)
    if (entry.axes[a].name == parameter) return entry.axes[a].values[at[a]].second;
  return entry.where;
}

// The choice of `entry` with value at[a] of each axis a; fails at the value a ParameterError
// names.
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

// Calls visit(at) for every combination of an entry's lists (at[a]: the value of axis a), the
// first parameter varying slowest.
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

template <class RegistryType>
PluginEntry read_plugin_entry(const Reporter& report, const toml::table& table,
                              std::string_view section, const RegistryType& registry) {
  const std::string prefix = std::string(section) + ".";
  PluginEntry entry;
  entry.where = table.source();
  entry.name = get_string(report, table, "name", prefix, std::nullopt);
  const auto* plugin = registry.find(entry.name);
  if (!plugin)
    report.fail(table.get("name")->source(), prefix + "name",
                fmt::format("unknown {} '{}' {}", registry.kind(), entry.name,
                            with_suggestion(entry.name, registry.names())));
  entry.specs = &plugin->info.parameters;
  if (plugin->info.user_parameters) entry.user_parameters = &*plugin->info.user_parameters;
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
                  fmt::format("unknown parameter of {} '{}' {}", registry.kind(), entry.name,
                              known.empty() ? std::string("(it has none)")
                                            : with_suggestion(parameter, known)));
    if (!declared) {
      // A parameter the user names: its values must have the user parameters' type (a
      // misspelt declared parameter is said to be one, e.g. F = "..." for f).
      const auto& spec = *entry.user_parameters;
      const auto refuse = [&](const toml::node& value) {
        report.fail(
            value.source(), prefix + parameter,
            fmt::format("'{}' is not declared by {} '{}' {}, so it is one of the "
                        "{}'s own parameters, which must be {}: found {} ({})",
                        parameter, registry.kind(), entry.name,
                        known.empty() ? std::string("(it declares none)")
                                      : with_suggestion(parameter, known),
                        registry.kind(), type_name(spec.type), describe(value), show(value)));
      };
      if (auto why = check_user_parameter_name(parameter); !why.empty())
        report.fail(key.source(), prefix + parameter,
                    fmt::format("'{}' {} (a parameter of {} '{}' that it does not declare names "
                                "one of its own parameters)",
                                parameter, why, registry.kind(), entry.name));
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

// A plugin axis ([[kernel]], [[target]], ...) read and checked, expanded later (expand_plugins):
// everything cheap in a study file is checked before anything large is built.
struct PluginAxis {
  std::string section;
  const toml::node* node = nullptr;  // the section; nullptr: the default plugin
  std::vector<PluginEntry> entries;
};

template <class RegistryType>
PluginAxis read_plugins(const Reporter& report, const toml::table& root, std::string_view section,
                        const RegistryType& registry, std::optional<std::string> default_name) {
  PluginAxis axis{std::string(section), root.get(section), {}};
  if (!axis.node) {
    if (!default_name)
      report.fail({}, section,
                  fmt::format("missing: add at least one [[{}]] table with a name (known: {})",
                              section, fmt::join(registry.names(), ", ")));
    const auto& info = registry.find(*default_name)->info;
    PluginEntry entry{*default_name, &info.parameters, {}, {}, {}};
    if (info.user_parameters) entry.user_parameters = &*info.user_parameters;
    axis.entries.push_back(std::move(entry));
    return axis;
  }
  auto add_entry = [&](const toml::node& item) {
    if (!item.is_table())
      report.fail(item.source(), section,
                  fmt::format("expected a table ([[{}]]), found {}", section, describe(item)));
    axis.entries.push_back(read_plugin_entry(report, *item.as_table(), section, registry));
  };
  if (const auto* array = axis.node->as_array()) {
    for (const auto& item : *array) add_entry(item);
  } else {
    add_entry(*axis.node);
  }
  return axis;
}

// The first choice of each entry of `axis` (an outline of the axis: the same parameters).
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

// One lap count of [adaptive] laps: a finite number > 0, or "limit" (+infinity).
double parse_lap_count(const Reporter& report, const toml::node& node, bool in_list) {
  const auto allowed = in_list ? "a lap count > 0 or \"limit\" (the periodic steady state)"
                               : "a lap count > 0, \"limit\" (the periodic steady state) or an "
                                 "array of them";
  if (const auto* text = node.as_string()) {
    if (text->get() != "limit")
      report.fail(node.source(), "adaptive.laps",
                  fmt::format("found \"{}\", expected {}", text->get(), allowed));
    return std::numeric_limits<double>::infinity();
  }
  if (!node.is_number())
    report.fail(node.source(), "adaptive.laps",
                fmt::format("found {} ({}), expected {}", describe(node), show(node), allowed));
  const double laps = *real_of(node);
  if (!(laps > 0) || !std::isfinite(laps))
    report.fail(node.source(), "adaptive.laps",
                fmt::format("must be a finite number > 0 or \"limit\", found {}", show(node)));
  return laps;
}

struct AdaptiveSection {
  AdaptiveSettings settings;
  std::vector<double> laps_values;  // the laps axis; empty for one value
  PluginChoice reference;           // [adaptive] reference; empty name: none
};

// reference = { integrator = "radau5", rtol = 1e-11, atol = 1e-10 }: an integrator and its
// parameters (one value each, resolved against the integrator's declared parameters; those
// left out take the integrator's defaults, rtol and atol the reference's: 1e-11 and 1e-10).
PluginChoice parse_reference(const Reporter& report, const toml::node& node) {
  constexpr const char* key = "adaptive.reference";
  const auto* table = node.as_table();
  if (!table)
    report.fail(node.source(), key,
                fmt::format("expected an inline table {{ integrator = \"radau5\", rtol = 1e-11, "
                            "atol = 1e-10 }}, found {} ({})",
                            describe(node), show(node)));
  const auto* name_node = table->get("integrator");
  if (!name_node)
    report.fail(table->source(), key,
                fmt::format("missing 'integrator': the reference integrator's name (known: {})",
                            fmt::join(integrator_registry().names(), ", ")));
  if (!name_node->is_string())
    report.fail(name_node->source(), "adaptive.reference.integrator",
                fmt::format("expected an integrator name, found {} ({})", describe(*name_node),
                            show(*name_node)));
  const std::string name = name_node->as_string()->get();
  const auto* plugin = integrator_registry().find(name);
  if (!plugin)
    report.fail(name_node->source(), "adaptive.reference.integrator",
                fmt::format("unknown integrator '{}' {}", name,
                            with_suggestion(name, integrator_registry().names())));
  const auto& specs = plugin->info.parameters;
  std::vector<std::string> known;
  for (const auto& spec : specs) known.push_back(spec.name);
  std::map<std::string, ParameterValue> given;
  std::map<std::string, toml::source_region> where;
  for (auto&& [k, value] : *table) {
    const std::string parameter(k.str());
    if (parameter == "integrator") continue;
    const std::string qualified = std::string(key) + "." + parameter;
    if (std::find(known.begin(), known.end(), parameter) == known.end())
      report.fail(k.source(), qualified,
                  fmt::format("unknown parameter of integrator '{}' {}", name,
                              known.empty() ? std::string("(it has none)")
                                            : with_suggestion(parameter, known)));
    auto scalar = scalar_value(value);
    if (!scalar)
      report.fail(value.source(), qualified,
                  fmt::format("expected one value (a reference is not an axis), found {}",
                              describe(value)));
    given[parameter] = std::move(*scalar);
    where[parameter] = value.source();
  }
  // The reference's own defaults where the integrator declares rtol and atol.
  for (const auto& [parameter, fallback] : {std::pair<const char*, double>{"rtol", 1e-11},
                                            std::pair<const char*, double>{"atol", 1e-10}})
    if (std::find(known.begin(), known.end(), parameter) != known.end() &&
        !given.contains(parameter))
      given[parameter] = ParameterValue(fallback);
  try {
    return PluginChoice{name, ParameterSet::resolve(specs, given), {}};
  } catch (const ParameterError& e) {
    const auto found = where.find(e.parameter());
    report.fail(found != where.end() ? found->second : table->source(),
                std::string(key) + "." + e.parameter(), e.what());
  }
}

// `track_length` is the domain's length (a final time in laps, for snapshot_laps).
AdaptiveSection parse_adaptive(const Reporter& report, const toml::table& root,
                               double track_length) {
  AdaptiveSection section;
  AdaptiveSettings& settings = section.settings;
  const auto* table = optional_table(report, root, "adaptive");
  if (!table)
    report.fail({}, "adaptive",
                "missing [adaptive] table (speed = ..., laps = ... or final_time = ...)");
  check_keys(report, *table, "adaptive.",
             {"speed", "laps", "final_time", "q", "road", "snapshot_laps", "snapshot_points",
              "samples_per_lap", "engine", "lap_map_rtol", "lap_map_atol", "reference", "path"});
  settings.speed = get_number(report, *table, "speed", "adaptive.", 1.0, 0);

  // path = { from = a, to = b }: a shuttle back and forth between a and b (a lap is one round
  // trip); absent: laps around the track.
  if (const auto* path = table->get("path")) {
    const auto* range = path->as_table();
    if (!range)
      report.fail(path->source(), "adaptive.path",
                  fmt::format("expected {{ from = ..., to = ... }} (a shuttle between two points "
                              "of the track), found {}",
                              show(*path)));
    check_keys(report, *range, "adaptive.path.", {"from", "to"});
    for (const char* key : {"from", "to"})
      if (!range->contains(key))
        report.fail(path->source(), fmt::format("adaptive.path.{}", key),
                    "missing: a shuttle path needs both ends, { from = ..., to = ... }");
    const double from = get_number(report, *range, "from", "adaptive.path.", 0, -1e-300);
    const double to = get_number(report, *range, "to", "adaptive.path.", 0, 0);
    if (!(to > from) || to > track_length * (1 + 1e-12))
      report.fail(range->get("to")->source(), "adaptive.path.to",
                  fmt::format("found {}, expected a point after from = {} and at most the track's "
                              "length {}",
                              format_real(to), format_real(from), format_real(track_length)));
    settings.shuttle_from = from;
    settings.shuttle_length = std::min(to, track_length) - from;
  }

  const std::vector<std::string> engines{"automatic", "lap_map", "time_stepping"};
  const auto engine = get_string(report, *table, "engine", "adaptive.", std::string("automatic"));
  if (const auto found = adaptive_engine_from_name(engine))
    settings.engine = *found;
  else
    report.fail(table->get("engine")->source(), "adaptive.engine",
                fmt::format("unknown engine \"{}\" {}", engine, with_suggestion(engine, engines)));
  settings.lap_map_rtol =
      get_number(report, *table, "lap_map_rtol", "adaptive.", settings.lap_map_rtol, 0);
  settings.lap_map_atol =
      get_number(report, *table, "lap_map_atol", "adaptive.", settings.lap_map_atol, 0);

  // laps = 10 | "limit" | [10, 100, "limit"] (a list is an axis of the grid).
  const auto* laps_node = table->get("laps");
  std::vector<std::pair<double, const toml::node*>> lap_counts;
  if (!laps_node) {
    lap_counts.emplace_back(settings.laps, nullptr);
  } else if (const auto* array = laps_node->as_array()) {
    if (array->empty())
      report.fail(laps_node->source(), "adaptive.laps", "empty list of lap counts");
    for (const auto& item : *array)
      lap_counts.emplace_back(parse_lap_count(report, item, true), &item);
    std::stable_sort(lap_counts.begin(), lap_counts.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t i = 1; i < lap_counts.size(); ++i)
      if (lap_counts[i].first == lap_counts[i - 1].first)
        report.fail(lap_counts[i].second->source(), "adaptive.laps",
                    fmt::format("{} is listed twice; lap counts must be distinct",
                                laps_text(lap_counts[i].first)));
  } else {
    lap_counts.emplace_back(parse_lap_count(report, *laps_node, false), laps_node);
  }
  if (laps_node && table->contains("final_time")) {
    const auto limit = std::find_if(lap_counts.begin(), lap_counts.end(),
                                    [](const auto& c) { return std::isinf(c.first); });
    if (limit != lap_counts.end())
      report.fail(limit->second->source(), "adaptive.laps",
                  fmt::format("found \"limit\" together with final_time = {}: the periodic "
                              "limit has no final time; give laps = \"limit\" without "
                              "final_time, or a final time without laps",
                              show(*table->get("final_time"))));
    report.fail(table->source(), "adaptive", "give 'laps' or 'final_time', not both");
  }
  for (const auto& [laps, node] : lap_counts) {
    if (std::isinf(laps) && settings.engine == AdaptiveEngine::time_stepping)
      report.fail(node->source(), "adaptive.laps",
                  "found \"limit\" with engine = \"time_stepping\", which cannot step through "
                  "infinitely many laps; \"limit\" needs engine = \"automatic\" or \"lap_map\"");
    if (std::isfinite(laps) && laps != std::floor(laps) &&
        settings.engine == AdaptiveEngine::lap_map)
      report.fail(node->source(), "adaptive.laps",
                  fmt::format("found {} with engine = \"lap_map\", which advances whole laps; "
                              "give a whole number of laps, or engine = \"automatic\" or "
                              "\"time_stepping\"",
                              show(*node)));
  }
  if (laps_node && laps_node->is_array()) {
    settings.laps = std::numeric_limits<double>::quiet_NaN();  // each trial's: TrialSpec::laps
    for (const auto& [laps, node] : lap_counts) section.laps_values.push_back(laps);
  } else {
    settings.laps = lap_counts.front().first;
  }
  // Absent: 0 (the laps decide); given: a time > 0 (final_time = 0 ran the default laps).
  settings.final_time = get_number(report, *table, "final_time", "adaptive.", 0, 0);

  // The reference integrates every trial once more by time stepping: never with the lap map.
  if (const auto* reference = table->get("reference")) {
    section.reference = parse_reference(report, *reference);
    if (settings.engine == AdaptiveEngine::lap_map)
      report.fail(table->get("engine")->source(), "adaptive.engine",
                  "found \"lap_map\" with a reference: integration_error compares time stepping "
                  "with time stepping; use engine = \"automatic\" or \"time_stepping\" (a study "
                  "with a reference steps through time), or remove reference");
    for (const auto& [laps, node] : lap_counts)
      if (std::isinf(laps))
        report.fail(node->source(), "adaptive.laps",
                    "found \"limit\" with a reference, which integrates by time stepping and "
                    "cannot reach the periodic limit; give a number of laps or remove reference");
  }

  try {
    settings.q = WeightMatrix::parse(
        get_string(report, *table, "q", "adaptive.", std::string("identity")));
  } catch (const std::exception& e) {
    report.fail(table->get("q")->source(), "adaptive.q", e.what());
  }
  const auto road = get_string(report, *table, "road", "adaptive.", std::string("target"));
  if (road != "target" && road != "projection")
    report.fail(table->get("road")->source(), "adaptive.road",
                fmt::format("found \"{}\", expected \"target\" (f) or \"projection\" (Pi_n f, "
                            "a road in H_n)",
                            road));
  settings.projected_road = road == "projection";

  // A snapshot must be within the longest finite run: the laps (the largest finite value of a
  // laps axis) or final_time. A "limit" trial records every snapshot lap; a shorter trial of a
  // laps axis the ones it reaches (trial_adaptive_settings).
  std::optional<double> last_lap;
  std::string last_lap_text;
  if (settings.final_time > 0) {
    last_lap = settings.final_time / settings.lap_time(track_length);
    last_lap_text = fmt::format("final_time = {} s, {} laps", format_real(settings.final_time),
                                format_real(*last_lap));
  } else {
    for (const auto& [laps, node] : lap_counts)
      if (std::isfinite(laps)) {
        last_lap = laps;
        last_lap_text = fmt::format("laps = {}{}", laps_text(laps),
                                    lap_counts.size() > 1 ? ", the largest finite lap count" : "");
      }
  }
  if (const auto* laps = table->get("snapshot_laps")) {
    const auto* array = laps->as_array();
    if (!array)
      report.fail(laps->source(), "adaptive.snapshot_laps",
                  fmt::format("expected an array of lap numbers, found {}", describe(*laps)));
    for (const auto& item : *array) {
      const auto lap_number = real_of(item);
      if (!lap_number || *lap_number < 0)
        report.fail(item.source(), "adaptive.snapshot_laps",
                    fmt::format("expected a lap number >= 0, found {}", show(item)));
      const double lap = *lap_number;
      if (last_lap && lap > *last_lap * (1 + 1e-12))
        report.fail(item.source(), "adaptive.snapshot_laps",
                    fmt::format("found {}, after the end of the run ({}); snapshot laps must be "
                                "<= {}",
                                show(item), last_lap_text, format_real(*last_lap)));
      settings.snapshot_laps.push_back(lap);
    }
  }
  auto count = [&](std::string_view key, std::size_t fallback) {
    return static_cast<std::size_t>(
        get_whole_number(report, *table, key, "adaptive.", fallback, 1, 10000000));
  };
  settings.snapshot_points = count("snapshot_points", 0);
  settings.samples_per_lap = count("samples_per_lap", settings.samples_per_lap);
  return section;
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

// Every extent of the domain (length, 2 pi radius, each of lengths) lies in
// [Domain::min_extent, Domain::max_extent]; the reason, for messages.
bool in_extent_range(double extent) {
  return extent >= Domain::min_extent && extent <= Domain::max_extent;
}
constexpr const char* extent_range_reason =
    "beyond these the squared distances, volumes and spline knots computed on the domain leave "
    "the range of double";

bool valid_study_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  }) && name.front() != '.';
}

}  // namespace

namespace {

// The metrics measured on the evaluation grid s_m = m L / M: sups and L2 norms over the domain.
bool measured_on_grid(std::string_view metric) {
  static constexpr std::string_view grid_metrics[] = {"power_function_sup",
                                                      "power_function_floor",
                                                      "l2_error",
                                                      "sup_error",
                                                      "error_floor",
                                                      "interpolant_l2_error",
                                                      "interpolant_sup_error",
                                                      "gap_to_projection",
                                                      "l2_projection_l2_error",
                                                      "l2_projection_sup_error",
                                                      "gap_to_l2_projection"};
  return std::find(std::begin(grid_metrics), std::end(grid_metrics), metric) !=
         std::end(grid_metrics);
}

// Can the evaluation grid measure what the grid metrics mean? Sups and L2 norms over the domain
// are taken on M points; with M <= n the grid is no finer than the centres (uniform centres with
// n a multiple of M are all on it), so it sees the power function and the error at or next to
// the centres, where they vanish, and reports round-off as if it were the result: refused. With
// fewer than 4 points per centre spacing the sups may miss the peaks between centres: warned.
void check_evaluation_grid(const Reporter& report, const toml::table& header,
                           StudyDefinition& study) {
  std::vector<std::string> on_grid;
  for (const auto& metric : study.metrics)
    if (measured_on_grid(metric)) on_grid.push_back(metric);
  if (on_grid.empty() || study.n_values.empty()) return;
  const std::size_t largest_n = study.n_values.back();
  // In d > 1: per axis, the grid's m points against the centres' n^(1/d) (4 per centre spacing
  // asks for 4^d n grid points); in d = 1 simply M against n.
  const int d = study.domain.dimension;
  const std::size_t per_axis = study.domain.points_per_axis(study.evaluation_points);
  const double centres_per_axis = std::pow(static_cast<double>(largest_n), 1.0 / d);
  const std::size_t points = study.evaluation_points;
  const double spacing = std::pow(4.0, d);
  if (d > 1) {
    const auto* node = header.get("evaluation_points");
    const auto where = node ? node->source() : header.source();
    const std::string given = node ? "" : " (the default)";
    const auto advised =
        static_cast<std::size_t>(std::ceil(spacing * static_cast<double>(largest_n)));
    if (static_cast<double>(per_axis) <= centres_per_axis)
      report.fail(where, "study.evaluation_points",
                  fmt::format("{} evaluation points{} ({} per axis of d = {}) for up to n = {} "
                              "centres ({:.4g} per axis): the grid is no finer than the centres, "
                              "so {} would be measured at or next to the centres, where they "
                              "vanish (round-off), not over the domain; use evaluation_points "
                              ">= {} (4 per centre spacing on every axis) or leave these metrics "
                              "out of study.metrics",
                              points, given, per_axis, d, largest_n, centres_per_axis,
                              fmt::join(on_grid, ", "), advised));
    if (static_cast<double>(per_axis) < 4.0 * centres_per_axis)
      study.warnings.push_back(report.locate(
          where, "study.evaluation_points",
          fmt::format("warning: {} evaluation points{} ({} per axis) give fewer than 4 per "
                      "centre spacing for n = {}: {} are taken on the grid and may miss the "
                      "peaks between centres; evaluation_points >= {} avoids it",
                      points, given, per_axis, largest_n, fmt::join(on_grid, ", "), advised)));
    return;
  }
  const auto* node = header.get("evaluation_points");
  const auto where = node ? node->source() : header.source();
  const std::string given = node ? "" : " (the default)";
  if (points <= largest_n)
    report.fail(
        where, "study.evaluation_points",
        fmt::format("{} evaluation points{} for up to n = {} centres: the grid is no finer than "
                    "the centres, so {} would be measured at or next to the centres, where they "
                    "vanish (round-off), not over the domain; use evaluation_points >= {} (4 per "
                    "centre spacing) or leave these metrics out of study.metrics",
                    points, given, largest_n, fmt::join(on_grid, ", "), 4 * largest_n));
  if (points < 4 * largest_n)
    study.warnings.push_back(report.locate(
        where, "study.evaluation_points",
        fmt::format("warning: {} evaluation points{} give fewer than 4 per centre spacing for "
                    "n > {}: {} are taken on the grid and may miss the peaks between centres; "
                    "evaluation_points >= {} avoids it",
                    points, given, points / 4, fmt::join(on_grid, ", "), 4 * largest_n)));
}

}  // namespace

// The longest text of a [plot] label or title (a label is a few words; gnuplot draws it on
// one line).
constexpr std::size_t max_plot_text = 300;

// A [plot] label or title: a string of at most max_plot_text bytes, one line.
std::string plot_text(const Reporter& report, const toml::node& node, const std::string& key) {
  if (!node.is_string())
    report.fail(node.source(), key,
                fmt::format("expected a string (gnuplot enhanced text), found {} ({})",
                            describe(node), show(node)));
  const std::string text = node.as_string()->get();
  if (text.size() > max_plot_text)
    report.fail(
        node.source(), key,
        fmt::format("is {} bytes long, at most {} are allowed", text.size(), max_plot_text));
  if (text.find_first_of("\r\n") != std::string::npos)
    report.fail(node.source(), key, "must be one line (found a line break)");
  return text;
}

// A [plot] number in [low, high].
double plot_number(const Reporter& report, const toml::node& node, const std::string& key,
                   double low, double high, std::string_view unit) {
  const auto value = real_of(node);
  if (!value || !(*value >= low && *value <= high))
    report.fail(node.source(), key,
                fmt::format("expected a number between {} and {}{}, found {}", format_real(low),
                            format_real(high), unit, show(node)));
  return *value;
}

// [plot] (docs/study-files.md): metrics, labels, title, size, font_size, legend, png_dpi.
PlotStyle parse_plot(const Reporter& report, const toml::table& table,
                     const StudyDefinition& study) {
  check_keys(report, table, "plot.",
             {"metrics", "labels", "title", "size", "font_size", "legend", "png_dpi"});
  PlotStyle style;
  const auto& plotted = study.metrics;
  auto check_metric = [&](const toml::node& node, const std::string& metric,
                          const std::string& key) {
    if (std::find(plotted.begin(), plotted.end(), metric) != plotted.end()) return;
    const auto& all = metric_names(study.kind);
    report.fail(
        node.source(), key,
        std::find(all.begin(), all.end(), metric) == all.end()
            ? fmt::format("unknown metric '{}' {}", metric, with_suggestion(metric, plotted))
            : fmt::format("'{}' is not among study.metrics, so it has no plot (add it "
                          "there; study.metrics: {})",
                          metric, fmt::join(plotted, ", ")));
  };
  if (const auto* metrics = table.get("metrics")) {
    const auto* array = metrics->as_array();
    if (!array || array->empty())
      report.fail(metrics->source(), "plot.metrics",
                  fmt::format("expected a non-empty array of metric names, in the order to plot "
                              "them (of study.metrics: {})",
                              fmt::join(plotted, ", ")));
    for (const auto& item : *array) {
      if (!item.is_string())
        report.fail(item.source(), "plot.metrics",
                    fmt::format("expected a metric name, found {}", describe(item)));
      const std::string metric = item.as_string()->get();
      check_metric(item, metric, "plot.metrics");
      if (std::find(style.metrics.begin(), style.metrics.end(), metric) != style.metrics.end())
        report.fail(item.source(), "plot.metrics", fmt::format("'{}' is listed twice", metric));
      style.metrics.push_back(metric);
    }
  }
  if (const auto* labels = table.get("labels")) {
    const auto* map = labels->as_table();
    if (!map)
      report.fail(labels->source(), "plot.labels",
                  fmt::format("expected an inline table of metric = \"y axis label\" (e.g. "
                              "labels = {{ l2_error = \"L^2 error\" }}), found {}",
                              describe(*labels)));
    for (auto&& [key, value] : *map) {
      const std::string metric(key.str());
      const auto name = "plot.labels." + metric;
      check_metric(value, metric, name);
      style.labels[metric] = plot_text(report, value, name);
    }
  }
  if (const auto* title = table.get("title")) {
    if (const auto* flag = title->as_boolean()) {
      if (flag->get())
        report.fail(title->source(), "plot.title",
                    "expected a string, or false for no title (true is the default: leave the "
                    "key out)");
      style.title = std::string();
    } else {
      style.title = plot_text(report, *title, "plot.title");
    }
  }
  if (const auto* size = table.get("size")) {
    const auto* pair = size->as_array();
    if (!pair || pair->size() != 2)
      report.fail(
          size->source(), "plot.size",
          fmt::format("expected [width, height] in inches (e.g. [6, 4]), found {}", show(*size)));
    const char* axes[] = {"width", "height"};
    double inches[2];
    for (std::size_t i = 0; i < 2; ++i) {
      const auto& item = *pair->get(i);
      const auto value = real_of(item);
      if (!value || !(*value > 0 && *value <= PlotStyle::max_inches))
        report.fail(item.source(), "plot.size",
                    fmt::format("{}: expected inches, a number above 0 and at most {}, found {}",
                                axes[i], format_real(PlotStyle::max_inches), show(item)));
      inches[i] = *value;
    }
    style.width_inches = inches[0];
    style.height_inches = inches[1];
  }
  if (const auto* font = table.get("font_size"))
    style.font_points = plot_number(report, *font, "plot.font_size", PlotStyle::min_font_points,
                                    PlotStyle::max_font_points, " points");
  if (const auto* legend = table.get("legend")) {
    style.legend = get_string(report, table, "legend", "plot.", std::nullopt);
    const auto& known = PlotStyle::legend_positions();
    if (std::find(known.begin(), known.end(), style.legend) == known.end())
      report.fail(legend->source(), "plot.legend",
                  fmt::format("unknown position '{}' {}", style.legend,
                              with_suggestion(style.legend, known)));
  }
  if (const auto* dpi = table.get("png_dpi")) {
    style.png_dpi = static_cast<int>(get_whole_number(
        report, table, "png_dpi", "plot.", 150, PlotStyle::min_png_dpi, PlotStyle::max_png_dpi));
    const double inches = std::max(style.width_inches, style.height_inches);
    if (inches * style.png_dpi > PlotStyle::max_png_pixels)
      report.fail(dpi->source(), "plot.png_dpi",
                  fmt::format("{} dpi at {} inches makes a PNG of {} pixels a side, at most {} "
                              "are allowed: lower png_dpi or size",
                              style.png_dpi, format_real(inches),
                              format_real(std::round(inches * style.png_dpi)),
                              format_real(PlotStyle::max_png_pixels)));
  }
  return style;
}

StudyDefinition parse_study(std::string_view text, const std::string& source_name) {
  const Reporter report(source_name);
  toml::table root;
  check_toml_nesting(report, text);
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& error) {
    report.fail(error.source(), "", fmt::format("invalid TOML: {}", error.description()));
  }
  check_keys(
      report, root, "",
      {"study", "domain", "grid", "kernel", "target", "centres", "projection", "solver", "limits",
       "rates", "adaptive", "plant", "law", "integrator", "plugins", "expect", "plot"});
  load_study_plugins(report, root);

  StudyDefinition study;
  study.source = source_name;
  const auto* header = optional_table(report, root, "study");
  if (!header) report.fail({}, "study", "missing [study] table (with at least name = \"...\")");
  check_keys(report, *header, "study.",
             {"name", "description", "kind", "metrics", "abscissa", "evaluation_points"});
  study.name = get_string(report, *header, "name", "study.", std::nullopt);
  if (study.name.size() > max_study_name)
    report.fail(header->get("name")->source(), "study.name",
                fmt::format("is {} characters long, at most {} are allowed (it names the output "
                            "folder results/<name>/ and the files in it)",
                            study.name.size(), max_study_name));
  if (!valid_study_name(study.name))
    report.fail(header->get("name")->source(), "study.name",
                fmt::format("'{}' is not a valid name (letters, digits, '_', '-', '.'; it names "
                            "the output folder)",
                            study.name));
  study.description = get_string(report, *header, "description", "study.", std::string{});
  const auto kind = get_string(report, *header, "kind", "study.", std::string("approximation"));
  if (const auto known = study_kind_from_name(kind))
    study.kind = *known;
  else
    report.fail(header->get("kind")->source(), "study.kind",
                fmt::format("unknown study kind '{}' (known: approximation, adaptive)", kind));
  if (study.kind != StudyKind::adaptive)
    for (const char* section : {"adaptive", "plant", "law", "integrator"})
      if (const auto* node = root.get(section))
        report.fail(node->source(), section,
                    "only for adaptive studies: add kind = \"adaptive\" to [study]");
  const auto abscissa = get_string(report, *header, "abscissa", "study.", std::string("n"));
  if (abscissa == "n")
    study.abscissa = Abscissa::n;
  else if (abscissa == "h" || abscissa == "fill_distance")
    study.abscissa = Abscissa::fill_distance;
  else
    report.fail(header->get("abscissa")->source(), "study.abscissa",
                fmt::format("found \"{}\", expected \"n\" or \"h\" (fill distance)", abscissa));
  study.evaluation_points = static_cast<std::size_t>(
      get_whole_number(report, *header, "evaluation_points", "study.", 4096, 2, 100000000));

  const auto& all_metrics = metric_names(study.kind);
  if (const auto* metrics = header->get("metrics")) {
    const auto* array = metrics->as_array();
    if (!array || array->empty())
      report.fail(metrics->source(), "study.metrics",
                  fmt::format("expected a non-empty array of metric names (known: {})",
                              fmt::join(all_metrics, ", ")));
    std::set<std::string> chosen;
    for (const auto& item : *array) {
      if (!item.is_string())
        report.fail(item.source(), "study.metrics",
                    fmt::format("expected a metric name, found {}", describe(item)));
      const std::string metric = item.as_string()->get();
      if (std::find(all_metrics.begin(), all_metrics.end(), metric) == all_metrics.end())
        report.fail(
            item.source(), "study.metrics",
            fmt::format("unknown metric '{}' {}", metric, with_suggestion(metric, all_metrics)));
      chosen.insert(metric);
    }
    for (const auto& metric : all_metrics)  // output order is the canonical order
      if (chosen.contains(metric)) study.metrics.push_back(metric);
  } else {
    study.metrics = all_metrics;
  }

  const auto* domain = optional_table(report, root, "domain");
  if (!domain)
    report.fail({}, "domain",
                "missing [domain] table (length = ..., radius = ... or lengths = [...])");
  check_keys(report, *domain, "domain.", {"length", "radius", "lengths", "periodic"});
  const int given = int(domain->contains("length")) + int(domain->contains("radius")) +
                    int(domain->contains("lengths"));
  if (given != 1)
    report.fail(domain->source(), "domain",
                "give exactly one of 'length' (metres), 'radius' (a closed track of length "
                "2 pi radius) or 'lengths' (a box or torus in R^d: its extents in metres, e.g. "
                "lengths = [1.0, 1.0] for d = 2)");
  if (const auto* lengths = domain->get("lengths")) {
    const auto* list = lengths->as_array();
    if (!list || list->empty() || list->size() > std::size_t{Domain::max_dimension})
      report.fail(lengths->source(), "domain.lengths",
                  fmt::format("expected a list of 1 to {} extents in metres (one per axis), "
                              "found {}",
                              Domain::max_dimension, show(*lengths)));
    study.domain.dimension = static_cast<int>(list->size());
    for (std::size_t a = 0; a < list->size(); ++a) {
      const auto& item = *list->get(a);
      const auto value = real_of(item);
      if (!value)
        report.fail(item.source(), "domain.lengths",
                    fmt::format("axis {}: expected an extent in metres (a number between {} and "
                                "{}), found {}",
                                a + 1, format_real(Domain::min_extent),
                                format_real(Domain::max_extent), show(item)));
      if (!in_extent_range(*value))
        report.fail(item.source(), "domain.lengths",
                    fmt::format("axis {}: must be between {} and {} metres, found {} ({})", a + 1,
                                format_real(Domain::min_extent), format_real(Domain::max_extent),
                                show(item), extent_range_reason));
      (a == 0 ? study.domain.length : a == 1 ? study.domain.width : study.domain.height) = *value;
    }
  } else if (domain->contains("length")) {
    study.domain.length = real_of(*domain->get("length")).value_or(0);
    if (!in_extent_range(study.domain.length))
      report.fail(domain->get("length")->source(), "domain.length",
                  fmt::format("must be between {} and {} metres, found {} ({})",
                              format_real(Domain::min_extent), format_real(Domain::max_extent),
                              show(*domain->get("length")), extent_range_reason));
  } else {
    // The track's length 2 pi radius must lie in the extents' range.
    const double radius = real_of(*domain->get("radius")).value_or(0);
    study.domain.length = 2 * std::numbers::pi * radius;
    if (!in_extent_range(study.domain.length))
      report.fail(domain->get("radius")->source(), "domain.radius",
                  fmt::format("must be between {} and {} metres (the track's length, 2 pi "
                              "radius, between {} and {}), found {} ({})",
                              format_real(Domain::min_extent / (2 * std::numbers::pi)),
                              format_real(Domain::max_extent / (2 * std::numbers::pi)),
                              format_real(Domain::min_extent), format_real(Domain::max_extent),
                              show(*domain->get("radius")), extent_range_reason));
  }
  study.domain.periodic = get_bool(report, *domain, "periodic", "domain.", true);
  // An adaptive study in d > 1 learns f of a plant's read-out of d coordinates: every plant
  // must be state-dependent with such a read-out (checked with the plants below).

  const auto* grid = optional_table(report, root, "grid");
  if (!grid || !grid->contains("n"))
    report.fail(grid ? grid->source() : toml::source_region{}, "grid.n",
                "missing: the number of centres, e.g. n = { from = 10, to = 100, step = 10 }");
  check_keys(report, *grid, "grid.", {"n"});
  study.n_values = parse_n(report, *grid->get("n"));

  std::uint64_t max_trials = default_max_trials;
  if (const auto* limits = optional_table(report, root, "limits")) {
    check_keys(report, *limits, "limits.", {"trial_seconds", "matrix_megabytes", "trials"});
    study.limits.trial_seconds =
        get_number(report, *limits, "trial_seconds", "limits.", 0, -1e-300);
    study.limits.matrix_megabytes = get_number(report, *limits, "matrix_megabytes", "limits.",
                                               study.limits.matrix_megabytes, 0);
    max_trials =
        get_whole_number(report, *limits, "trials", "limits.", max_trials, 1, max_max_trials,
                         " (every trial of the grid is held in memory, about 1.7 KB each)");
  }
  // Before any plugin choice or trial is built: a short file can ask for billions of trials.
  check_grid_size(report, root, study.kind, study.n_values.size(), *grid->get("n"), max_trials);

  // The plugin axes are read and checked here and expanded once the rest of the file is
  // checked: a mistake anywhere is found before a large grid is built.
  std::vector<PluginAxis> axes{
      read_plugins(report, root, "kernel", kernel_registry(), std::nullopt),
      read_plugins(report, root, "target", target_registry(), std::string("sine")),
      read_plugins(report, root, "centres", centre_registry(), std::string("uniform"))};
  if (study.kind == StudyKind::adaptive) {
    axes.push_back(
        read_plugins(report, root, "plant", plant_registry(), std::string("quarter_car")));
    axes.push_back(read_plugins(report, root, "law", law_registry(), std::string("rkhs")));
    axes.push_back(read_plugins(report, root, "integrator", integrator_registry(),
                                std::string("rosenbrock4")));
    auto adaptive = parse_adaptive(report, root, study.domain.length);
    study.adaptive = std::move(adaptive.settings);
    study.laps_values = std::move(adaptive.laps_values);
    study.reference = std::move(adaptive.reference);
    if (study.adaptive.snapshot_points == 0)
      study.adaptive.snapshot_points = study.evaluation_points;
  }
  // [[projection]]: an axis only when the file has the section (a study without one projects
  // by interpolation at the centres, and its keys say nothing about projections).
  // In an adaptive study each trial also runs the finite estimator of its projection beside the
  // law's infinite-dimensional one (Theorem 4.1, rkhs/adaptive/finite_to_infinite.hpp).
  std::optional<PluginAxis> projections;
  if (root.get("projection"))
    projections = read_plugins(report, root, "projection", projection_registry(), std::nullopt);

  if (const auto* solver = optional_table(report, root, "solver")) {
    check_keys(report, *solver, "solver.", {"singular", "regularisation"});
    const auto policy =
        get_string(report, *solver, "singular", "solver.", std::string("pseudo_inverse"));
    if (policy == "pseudo_inverse")
      study.solver.singular = SingularPolicy::pseudo_inverse;
    else if (policy == "regularised")
      study.solver.singular = SingularPolicy::regularised;
    else if (policy == "fail")
      study.solver.singular = SingularPolicy::fail;
    else
      report.fail(
          solver->get("singular")->source(), "solver.singular",
          fmt::format("found \"{}\", expected \"pseudo_inverse\", \"regularised\" or \"fail\"",
                      policy));
    study.solver.regularisation =
        get_number(report, *solver, "regularisation", "solver.", 0, -1e-300);
  }

  if (const auto* rates = optional_table(report, root, "rates")) {
    auto keys = fit_window_keys;
    keys.push_back("constant_within");
    check_keys(report, *rates, "rates.", keys);
    study.rates_window = read_fit_window(report, *rates, "rates.", study);
    study.constant_within =
        get_number(report, *rates, "constant_within", "rates.", default_constant_within, -1e-300);
    if (!(study.constant_within < 1.0))
      report.fail(rates->get("constant_within")->source(), "rates.constant_within",
                  fmt::format("expected a relative band in [0, 1), found {}",
                              format_real(study.constant_within)));
  }

  if (const auto* plot = optional_table(report, root, "plot"))
    study.plot = parse_plot(report, *plot, study);

  check_evaluation_grid(report, *header, study);
  // Where each axis of `axes` goes, in the same order.
  static constexpr std::vector<PluginChoice> StudyDefinition::*axis_members[] = {
      &StudyDefinition::kernels, &StudyDefinition::targets, &StudyDefinition::centres,
      &StudyDefinition::plants,  &StudyDefinition::laws,    &StudyDefinition::integrators};
  // [[expect]] tables first against an outline of the grid (the first choice of each entry:
  // the same axis columns), then the axes expanded.
  for (std::size_t a = 0; a < axes.size(); ++a)
    study.*axis_members[a] = first_choices(report, axes[a]);
  if (projections) study.projections = first_choices(report, *projections);
  auto expectations = detail::read_expectations(root, study);
  for (std::size_t a = 0; a < axes.size(); ++a)
    study.*axis_members[a] = expand_plugins(report, axes[a]);
  if (projections) study.projections = expand_plugins(report, *projections);

  // Build every kernel and target once: a combination that is invalid only for this domain
  // (e.g. a non-periodic sine on a closed track) is an input error, not a failed trial. A
  // ParameterError is reported at the value of the parameter it names (at the entry when that
  // took its default), like the errors of the declarations; any other error at the section.
  auto check_instances = [&](const PluginAxis& axis, auto&& make) {
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
  };
  check_instances(axes[0], [&](const PluginChoice& c, const PluginEntry&) {
    kernel_registry().find(c.name)->factory(c.parameters, study.domain);
  });
  check_instances(axes[1], [&](const PluginChoice& c, const PluginEntry& entry) {
    const auto target = target_registry().find(c.name)->factory(c.parameters, study.domain);
    for (const auto& note : target->notes())
      study.warnings.push_back(report.locate(entry.where, "target", "note: " + note));
  });
  // In d > 1 every placement must place every n in this domain (a grid needs n = m^d): the n
  // it cannot place are reported at grid.n, all of them, each with the placement's reason.
  if (study.domain.dimension > 1)
    check_instances(axes[2], [&](const PluginChoice& c, const PluginEntry&) {
      const auto placement = centre_registry().find(c.name)->factory(c.parameters);
      std::vector<std::string> reasons;
      for (const auto n : study.n_values) {
        try {
          placement->place(n, study.domain, 0);
        } catch (const std::invalid_argument& e) {
          reasons.emplace_back(e.what());
        }
      }
      if (reasons.size() == 1)
        report.fail(grid->get("n")->source(), "grid.n",
                    fmt::format("centres {}: {}", c.given_label(), reasons[0]));
      if (reasons.size() > 1)
        report.fail(grid->get("n")->source(), "grid.n",
                    fmt::format("centres {}: {} values of n cannot be placed: {}", c.given_label(),
                                reasons.size(), fmt::join(reasons, "; ")));
    });
  // Every kernel with every projection and n: a projection that cannot be built for one (a
  // spline space of another kernel, an n that is not a level) is an input error.
  const PluginAxis none;  // an axis this study does not have: nothing to check
  const auto& projection_axis = projections ? *projections : none;
  check_instances(projection_axis, [&](const PluginChoice& c, const PluginEntry&) {
    const auto projection = projection_registry().find(c.name)->factory(c.parameters);
    const auto properties = projection->properties();
    for (const auto& k : study.kernels) {
      const auto kernel = kernel_registry().find(k.name)->factory(k.parameters, study.domain);
      if (!properties.requires_kernel.empty() && kernel->name() != properties.requires_kernel)
        throw std::invalid_argument(
            fmt::format("works with the {} kernel only, and the study pairs it with kernel '{}'",
                        properties.requires_kernel, k.label()));
      for (const auto n : study.n_values) {
        try {
          projection->check(*kernel, n);
        } catch (const std::invalid_argument& e) {
          throw std::invalid_argument(fmt::format("kernel '{}': {}", k.label(), e.what()));
        }
      }
    }
  });
  // Theorem 4.1 trials: the law is the infinite-dimensional estimator, the road is f.
  if (study.kind == StudyKind::adaptive && !study.projections.empty()) {
    const auto* node = root.get("projection");
    check_instances(axes[4], [&](const PluginChoice& c, const PluginEntry&) {
      const auto law = law_registry().find(c.name)->factory(c.parameters);
      if (law->coordinates() != LawCoordinates::features)
        throw std::invalid_argument(fmt::format(
            "with [[projection]] an adaptive study compares each projection's finite estimator "
            "with the infinite-dimensional one, which the law must be: found law '{}', expected "
            "\"rkhs_embedding\" (see docs/theorems.md)",
            c.label()));
    });
    if (study.adaptive.projected_road)
      report.fail(node->source(), "projection",
                  "with [[projection]] the road must be the target f (adaptive.road = "
                  "\"target\"): Theorem 4.1 compares two estimators of f");
    if (study.adaptive.limit() || std::any_of(study.laps_values.begin(), study.laps_values.end(),
                                              [](double laps) { return std::isinf(laps); }))
      report.fail(node->source(), "projection",
                  "with [[projection]] the gaps are taken along the integration: laps = "
                  "\"limit\" has none");
  }
  const auto& plants = study.kind == StudyKind::adaptive ? axes[3] : none;
  check_instances(plants, [&](const PluginChoice& c, const PluginEntry&) {
    const auto plant = plant_registry().find(c.name)->factory(c.parameters);
    const auto d = plant->A().rows();
    const auto Q = study.adaptive.q.for_dimension(d, "adaptive.q");
    solve_lyapunov(plant->A(), Q);
    const int dimension = study.domain.dimension;
    if (!plant->state_dependent() && dimension > 1)
      throw std::invalid_argument(fmt::format(
          "it drives f along a track (d = 1), and the domain has d = {}: a domain of d > 1 "
          "needs a plant whose f is a function of a read-out of {} coordinates of its state",
          dimension, dimension));
    if (plant->state_dependent()) {
      // f of the plant's state: a nonlinear system stepped through time on an interval or circle.
      AdaptiveSettings settings = study.adaptive;
      if (std::any_of(study.laps_values.begin(), study.laps_values.end(),
                      [](double laps) { return std::isinf(laps); }))
        settings.laps = std::numeric_limits<double>::infinity();
      if (const auto error = state_dependent_settings_error(settings, plant->period());
          !error.empty())
        throw std::invalid_argument(error);
      if (plant->readout().rows() != dimension)
        throw std::invalid_argument(fmt::format(
            "its read-out y = C x + y0 has {} coordinate{}, and f is a function on the domain of "
            "d = {}: they must agree",
            plant->readout().rows(), plant->readout().rows() == 1 ? "" : "s", dimension));
      if (dimension > 1 && !study.adaptive.snapshot_laps.empty())
        throw std::invalid_argument(
            "adaptive.snapshot_laps records profiles of the estimate along a domain of d = 1; "
            "remove it in d > 1");
      for (const auto& law_entry : axes[4].entries)
        for_each_combination(law_entry, [&](const std::vector<std::size_t>& at) {
          const auto law_choice = resolve_choice(report, "law", law_entry, at);
          const auto law = law_registry().find(law_choice.name)->factory(law_choice.parameters);
          if (law->coordinates() != LawCoordinates::centres)
            throw std::invalid_argument(fmt::format(
                "law '{}' learns in feature coordinates; a state-dependent plant learns in the "
                "span of the centres' sections (laws gradient and rkhs)",
                law_choice.label()));
        });
    }
  });
  detail::check_expectation_selections(root, study, expectations);
  study.expectations = std::move(expectations);
  return study;
}

StudyDefinition load_study(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_input_file(file, "study file", max_study_file_bytes);
  } catch (const InputFileError& error) {
    throw StudyError(error.what());
  }
  return parse_study(text, file.string());
}

}  // namespace rkhs
