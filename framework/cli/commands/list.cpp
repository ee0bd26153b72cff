// `rkhs-study list [KIND]`: the registered plugins of every kind (plugin_kinds.hpp) with their
// parameters, and the metrics.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <type_traits>

#include "commands/commands.hpp"
#include "commands/options.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/run/run.hpp"

namespace rkhs::cli {

namespace {

std::string describe_parameter(const ParameterSpec& spec) {
  std::string detail =
      "default " + (spec.default_doc.empty() ? format_value(spec.default_value) : spec.default_doc);
  if (spec.type == ParameterType::choice)
    detail += fmt::format("; one of {}", fmt::join(spec.choices, ", "));
  else if (spec.type == ParameterType::real || spec.type == ParameterType::integer)
    if (const auto range = describe_range(spec); range != "any number") detail += "; " + range;
  return fmt::format("    {:<14} {} ({})", spec.name, spec.doc, detail);
}

// "[declares] ...": the properties() of the plugin made with its default parameters, in words;
// "unavailable" with the reason when it cannot be made.
template <class Entry, class Describe>
void print_declared(const Entry& entry, Describe describe, std::ostream& out) {
  try {
    out << fmt::format(
        "    [declares] {}\n",
        describe(entry.factory(ParameterSet::resolve(entry.info.parameters, {}))->properties()));
  } catch (const std::exception& e) {
    out << fmt::format("    [declares] unavailable: {}\n", e.what());
  }
}

template <class RegistryType>
void list_registry(const RegistryType& registry, std::ostream& out) {
  out << registry.kind() << " plugins:\n";
  for (const auto& name : registry.names()) {
    const auto& info = registry.find(name)->info;
    out << fmt::format("  {:<10} {}\n", name, info.doc);
    for (const auto& spec : info.parameters) out << describe_parameter(spec) << "\n";
    if (info.user_parameters) {  // any other key: a parameter the user names
      const auto& spec = *info.user_parameters;
      const auto range = describe_range(spec);
      out << fmt::format("    {:<14} {} ({}{})\n", spec.name, spec.doc, type_name(spec.type),
                         range == "any number" ? "" : "; " + range);
    }
    if constexpr (std::is_same_v<RegistryType, KernelRegistry>) {
      // A kernel's facts are its properties() (one source), shown for the default parameters
      // on a periodic track of length 1.
      try {
        out << fmt::format("    [properties at the defaults] {}\n",
                           describe_properties(kernel_properties(
                               name, ParameterSet::resolve(info.parameters, {}), Domain{})));
      } catch (const std::exception& e) {
        out << fmt::format("    [properties at the defaults] unavailable: {}\n", e.what());
      }
    }
    // What a projection declares (its contract test checks each claim), and what an integrator
    // does per step (the scheduler's cost estimate reads it).
    if constexpr (std::is_same_v<RegistryType, ProjectionRegistry>)
      print_declared(*registry.find(name), describe_projection, out);
    if constexpr (std::is_same_v<RegistryType, IntegratorRegistry>)
      print_declared(*registry.find(name), describe_integrator, out);
    for (const auto& [key, value] : info.traits) out << fmt::format("    [{}] {}\n", key, value);
  }
  out << "\n";
}

}  // namespace

int command_list(const std::string& kind) {
  const bool all = kind.empty();
  for_each_plugin_kind([&](auto plugin_kind) {
    using Kind = decltype(plugin_kind);
    if (all || kind == Kind::singular || kind == Kind::plural)
      list_registry(Kind::registry(), std::cout);
  });
  if (all || kind == "metric" || kind == "metrics") {
    // One row per metric of each kind's catalogue (rkhs/approx/metrics.hpp, MetricInfo);
    // columns are separated by at least two spaces (docs/metrics.md, "The catalogue", is
    // checked against this listing).
    for (const auto* study_kind : study_kind_table()) {
      std::cout << "metrics (" << study_kind->name() << " trials):\n";
      const auto row = [](auto name, auto unit, auto floor, auto nan, auto grid, auto theory,
                          auto flag) {
        return fmt::format("  {:<28}  {:<16}  {:<15}  {:<3}  {:<4}  {:<21}  {}\n", name, unit,
                           floor, nan, grid, theory, flag);
      };
      std::cout << row("metric", "unit", "floor", "NaN", "grid", "theory", "flag");
      for (const auto& metric : study_kind->metrics())
        std::cout << row(metric.name, metric.unit, floor_rule_name(metric.floor),
                         metric.may_be_nan ? "yes" : "no", metric.on_grid ? "yes" : "no",
                         theory_law_name(metric.theory),
                         metric.flag.empty() ? std::string_view("-") : metric.flag);
    }
  }
  if (const auto plugins = loaded_plugins(); all && !plugins.empty()) {
    std::cout << "\nplugin modules:\n";
    for (const auto& p : plugins)
      std::cout << fmt::format("  {:<10} {} (built against rkhs-study {})\n", p.name,
                               p.file.string(), p.rkhs_study_version);
  }
  return exit_ok;
}

Command add_list_command(CLI::App& app, SessionOptions& session) {
  // The kinds `list` accepts come from the table of plugin kinds (plugin_kinds.hpp).
  std::string kinds;
  std::vector<std::string> accepts;
  for (const auto& name : plugin_kind_names()) {
    kinds += (kinds.empty() ? "" : ", ") + name.singular;
    accepts.push_back(name.singular);
    if (name.plural != name.singular) accepts.push_back(name.plural);
  }
  accepts.insert(accepts.end(), {"metric", "metrics"});
  auto kind = std::make_shared<std::string>();
  auto* list = app.add_subcommand("list", "list plugins (" + kinds + ") or metrics");
  list->add_option("kind", *kind, kinds + " or metrics (default: all)")
      ->check(CLI::IsMember(accepts));
  add_plugin_option(*list, session);
  return {list, {}, [kind](pipeline::Executor&) { return command_list(*kind); }};
}

}  // namespace rkhs::cli
