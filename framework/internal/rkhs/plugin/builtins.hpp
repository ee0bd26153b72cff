#pragma once
// Start-up checks over all registries, and the names of the kinds of plugin. Every function here
// iterates the table of plugin kinds (plugin_kinds.hpp); this header does not include it, so
// that callers need not see every product type.

#include <string>
#include <vector>

namespace rkhs {

/// Every registration error recorded so far, in all registries, kind by kind in table order: a
/// refused `add` ("kernel plugin 'x': duplicate name") or a plugin whose info() threw
/// ("kernel registration failed: <type>: <what()>").
std::vector<std::string> registration_errors();

/// Built-in names missing from the registries ("kernel 'gaussian'", ...): non-empty only when a
/// linker dropped a plugin's object file.
std::vector<std::string> missing_builtin_plugins();

/// Freezes every registry (call before trials run on worker threads).
void freeze_registries();

/// The name of a kind of plugin: singular ("kernel", the registry's kind()) and plural
/// ("kernels"; "centres" is both).
struct PluginKindName {
  std::string singular;
  std::string plural;
};
/// Every kind, in table order.
std::vector<PluginKindName> plugin_kind_names();

}  // namespace rkhs
