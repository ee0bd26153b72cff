#pragma once
// Loading plugin modules at run time (`--plugin PATH`, `plugins = [...]` in a study file,
// RKHS_STUDY_PLUGIN_PATH). How a module is checked before it may register anything is explained
// in plugin/module.hpp.
//
// A module is loaded at most once per process: loading the same file again (by any path that
// resolves to it) returns the first load. A module that fails any check is unloaded and leaves
// the registries as they were; its registration errors are reported by the PluginError, not by
// registration_errors(). Modules that loaded stay loaded (the registries hold their factories;
// only tests unload them, unload_plugin). Load plugins before the registries are frozen
// (freeze_registries()): a registration into a frozen registry is refused, and so is the module.

#include <filesystem>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rkhs {

/// A plugin module that could not be loaded. what() starts with the file's path and says why:
///   "<path>: plugin file not found"
///   "<path>: is a FIFO, not a plugin file (a shared library)"  (any file that is not regular,
///   refused by its type before it is opened: opening a FIFO would wait for a writer)
///   "<path>: not an rkhs-study plugin (not a complete shared library: 3000 bytes, its program
///   headers need 15736)"  (an ELF file whose headers or segments lie beyond its end, checked
///   before dlopen maps it: a truncated library was a SIGBUS inside dlopen)
///   "<path>: not an rkhs-study plugin (not a loadable shared library: <dlerror>)"
///   "<path>: not an rkhs-study plugin (it exports no rkhs_plugin_abi_version; ...)"
///   "<path>: built against plugin ABI 7 (rkhs-study 0.0.1), this rkhs-study 0.1.0 has plugin ABI
///   1; ..."
///   "<path>: built for gcc 12, Eigen 3.4.0 (alignment 32 bytes), AVX, no sanitizer, this
///   rkhs-study is built for gcc 12, Eigen 3.4.0 (alignment 16 bytes), SSE2, no sanitizer
///   (Eigen alignment ...; vectorisation AVX against SSE2); build the plugin with ..."
///   "<path>: duplicate plugin name 'x' (already loaded from <other path>)"
///   "<path>: kernel plugin 'gaussian': duplicate name"                       (a registry error)
///   "<path>: kernel plugin 'k': parameter 'c': default must be > 0"          (invalid metadata)
///   "<path>: kernel registration failed: my::Kernel: <what()>"           (its info() threw)
///   "<path>: registered nothing (...)", "<path>: registered plugins while loading, ..."
class PluginError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A module that loaded.
struct LoadedPlugin {
  std::filesystem::path file;      ///< canonical path
  /// SHA-256 (hex) of the file's bytes as it was loaded, read once per process (a module is
  /// loaded once): part of the identity of every trial that uses one of its plugins
  /// (run/trial_identity.hpp), so a rebuilt module re-runs its trials.
  std::string sha256;
  std::string name;                ///< RKHS_PLUGIN_MODULE(name)
  std::string rkhs_study_version;  ///< the rkhs-study it was built against
  int abi_version = 0;
  /// How it was compiled, in words (describe() of plugin/build_configuration.hpp): equal to this
  /// rkhs-study's, or it would not have loaded.
  std::string build_configuration;
  /// What it registered, sorted, per kind of plugin: keyed by the kind's singular name
  /// (plugin_kinds.hpp), every kind present.
  std::map<std::string, std::vector<std::string>, std::less<>> registered;
};

/// Loads a plugin module (see the file comment). Throws PluginError.
LoadedPlugin load_plugin(const std::filesystem::path& file);

/// Every module loaded so far, in load order.
std::vector<LoadedPlugin> loaded_plugins();

/// Removes what the module loaded from `file` registered and unloads it, so that a test leaves
/// the registries as it found them. Every object the module's factories created must have been
/// destroyed. Returns false when no module was loaded from `file`. Not for use during a run.
bool unload_plugin(const std::filesystem::path& file);

/// Records plugins a host registered at run time rather than a module (kernels, targets and
/// centre placements written in Python: python/src/plugins.cpp) as a module of their own:
/// `file` names their origin ("python:mymodule.MyKernel"), `sha256` is the hash of their source
/// and `registered` what they registered. Trials that use them are then keyed by that hash
/// (run/trial_identity.hpp: a changed Python kernel re-runs its trials) and `rkhs-study list`
/// shows them like a loaded module's plugins. Replaces an earlier record of the same `file`
/// (whose plugins the caller has removed or re-registered). Not for use during a run.
void record_host_plugins(LoadedPlugin plugin);

/// Removes the plugins of the host record `file` (record_host_plugins) from the registries and
/// forgets the record. Returns false when there is none. Not for use during a run.
bool forget_host_plugins(const std::filesystem::path& file);

/// The plugin files named by a RKHS_STUDY_PLUGIN_PATH value: entries separated by ':', each a
/// plugin file or a directory (every *.so directly in it, sorted by name); empty entries are
/// skipped. Throws PluginError for an entry that does not exist.
std::vector<std::filesystem::path> plugin_path_files(std::string_view value);

/// Loads every plugin named by the environment variable RKHS_STUDY_PLUGIN_PATH (nothing when it
/// is unset). Throws PluginError, prefixed "RKHS_STUDY_PLUGIN_PATH: ".
void load_plugins_from_environment();

}  // namespace rkhs
