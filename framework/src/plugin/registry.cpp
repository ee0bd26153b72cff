// The checks over the registries of every kind of plugin. Everything here iterates the table of
// kinds (plugin_kinds.hpp); each registry is defined in the layer that declares it.
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"

namespace rkhs {

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
