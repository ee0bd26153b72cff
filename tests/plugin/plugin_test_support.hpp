#pragma once
// Plugin modules in tests: where the test build puts them, and loading one for a scope only, so
// that a test leaves the registries as it found them (other tests expect exactly the built-ins).
#include <filesystem>
#include <string>

#include "rkhs/plugin/plugin_loader.hpp"

namespace rkhs::test {

/// A module built by tests/plugin/CMakeLists.txt.
inline std::filesystem::path test_plugin(const std::string& name) {
  return std::filesystem::path(RKHS_TEST_PLUGIN_DIR) / (name + ".so");
}

/// Loads a plugin module; unloads it at the end of the scope. Declare it before any object the
/// module's factories create, so that those are destroyed first.
class ScopedPlugin {
 public:
  explicit ScopedPlugin(const std::filesystem::path& file) : plugin_(load_plugin(file)) {}
  ~ScopedPlugin() { unload_plugin(plugin_.file); }
  ScopedPlugin(const ScopedPlugin&) = delete;
  ScopedPlugin& operator=(const ScopedPlugin&) = delete;
  const LoadedPlugin& plugin() const noexcept { return plugin_; }

 private:
  LoadedPlugin plugin_;
};

}  // namespace rkhs::test
