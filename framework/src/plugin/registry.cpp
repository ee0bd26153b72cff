// The registries of every kind of plugin, and the checks over all of them. Everything here
// iterates the table of kinds (plugin_kinds.hpp).
#include "rkhs/core/registry.hpp"

#include <algorithm>

#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"

namespace rkhs {

namespace {

// A kind's registry, named by its table entry. A function-local static: constructed on first
// use, whatever the order in which the registrars of different translation units run.
template <PluginKindDescriptor Kind>
typename Kind::Registry& registry_of_kind() {
  static typename Kind::Registry registry{std::string(Kind::singular)};
  return registry;
}

}  // namespace

// The accessors declared in each kind's layer (kernel.hpp, centres.hpp, ...).
KernelRegistry& kernel_registry() {
  return registry_of_kind<KernelKind>();
}
CentreRegistry& centre_registry() {
  return registry_of_kind<CentresKind>();
}
TargetRegistry& target_registry() {
  return registry_of_kind<TargetKind>();
}
ProjectionRegistry& projection_registry() {
  return registry_of_kind<ProjectionKind>();
}
PlantRegistry& plant_registry() {
  return registry_of_kind<PlantKind>();
}
LawRegistry& law_registry() {
  return registry_of_kind<LawKind>();
}
IntegratorRegistry& integrator_registry() {
  return registry_of_kind<IntegratorKind>();
}

std::unique_ptr<AnyKernel> make_kernel(std::string_view name, const ParameterSet& parameters,
                                       const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  if (!entry) throw std::invalid_argument("unknown kernel '" + std::string(name) + "'");
  return entry->factory(parameters, domain);
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  // Optimal string alignment: insertions, deletions, substitutions and adjacent transpositions.
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::string closest_name(std::string_view name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const auto& candidate : candidates) {
    const auto d = edit_distance(name, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  // Likely a misspelling: at most a third of the longer name differs (and at least one edit
  // is always allowed).
  const std::size_t allowed = std::max<std::size_t>(1, std::max(name.size(), best.size()) / 3);
  return best_distance <= allowed ? best : std::string{};
}

std::vector<std::string> registration_errors() {
  std::vector<std::string> all;
  for_each_plugin_kind([&](auto kind) {
    const auto errors = decltype(kind)::registry().errors();
    all.insert(all.end(), errors.begin(), errors.end());
  });
  return all;
}

std::vector<std::string> missing_builtin_plugins() {
  std::vector<std::string> missing;
  for_each_plugin_kind([&](auto kind) {
    using Kind = decltype(kind);
    for (const auto name : Kind::builtins)
      if (!Kind::registry().find(name))
        missing.push_back(std::string(Kind::singular) + " '" + std::string(name) + "'");
  });
  return missing;
}

void freeze_registries() {
  for_each_plugin_kind([](auto kind) { decltype(kind)::registry().freeze(); });
}

std::vector<PluginKindName> plugin_kind_names() {
  std::vector<PluginKindName> names;
  for_each_plugin_kind([&](auto kind) {
    using Kind = decltype(kind);
    names.push_back({std::string(Kind::singular), std::string(Kind::plural)});
  });
  return names;
}

}  // namespace rkhs
