#pragma once
// Start-up checks over all registries.

#include <string>
#include <vector>

namespace rkhs {

/// Every registration error recorded during static initialisation, in all registries.
std::vector<std::string> registration_errors();

/// The names every build of rkhs-study must register, per kind (for the start-up self-check
/// and the registry test).
struct BuiltinNames {
  std::vector<std::string> kernels;
  std::vector<std::string> centres;
  std::vector<std::string> targets;
  std::vector<std::string> plants;
  std::vector<std::string> laws;
  std::vector<std::string> integrators;
};
const BuiltinNames& builtin_plugin_names();

/// Built-in names missing from the registries ("kernel 'gaussian'", ...): non-empty only when a
/// linker dropped a plugin's object file.
std::vector<std::string> missing_builtin_plugins();

/// Freezes every registry (call before trials run on worker threads).
void freeze_registries();

}  // namespace rkhs
