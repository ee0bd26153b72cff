#pragma once
// Plugin registries: one per kind of plugin (kernel, centres, target, ...).
//
// A registry maps a plugin name to its metadata and a factory. Built-in plugins register
// themselves from a namespace-scope registrar object defined by a RKHS_REGISTER_* macro; such
// registrations run during static initialisation, so `add` never throws: a duplicate name or an
// invalid declaration is recorded and reported by `errors()` once `main` runs (see
// registration_errors in plugin/builtins.hpp). Registries are function-local statics (no static
// initialisation order problem) and are frozen before trials start: after `freeze()` they are
// only read, so worker threads read them without locking.
//
// This header is generic: it knows no kind of plugin. The kinds (which registries exist, their
// names, what they make) are listed once, in plugin/plugin_kinds.hpp.

#include <algorithm>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rkhs/core/parameters.hpp"

namespace rkhs {

/// What a plugin declares about itself: shown by `rkhs-study list`, checked by the parser.
struct PluginInfo {
  std::string name;                        ///< lower-case identifier used in study files
  std::string doc;                         ///< one line
  std::vector<ParameterSpec> parameters;   ///< in the order they are printed and keyed
  std::vector<std::pair<std::string, std::string>> traits;  ///< kind-specific facts, for `list`
  /// Set when the plugin also takes parameters the user names: every other key of its study-file
  /// table is one (e.g. the constants `a = 2`, `k = [1, 2]` of an expression target), checked
  /// against this spec's type and range (ParameterSet::resolve). Its name is what `list` prints
  /// for them ("<name>"), its doc what it says of them; its default is never used. Such
  /// parameters are like declared ones everywhere else: a list is an axis of the grid, each is
  /// a column of trials.csv and a selector of [[expect]] tables.
  std::optional<ParameterSpec> user_parameters = std::nullopt;
};

/// Levenshtein distance, for "did you mean" suggestions.
std::size_t edit_distance(std::string_view a, std::string_view b);

/// The closest of `candidates` to `name` when it is close enough to be a likely misspelling,
/// otherwise an empty string.
std::string closest_name(std::string_view name, const std::vector<std::string>& candidates);

template <class Product, class... FactoryArgs>
class Registry {
 public:
  using Factory =
      std::function<std::unique_ptr<Product>(const ParameterSet&, FactoryArgs...)>;
  struct Entry {
    PluginInfo info;
    Factory factory;
  };

  explicit Registry(std::string kind) : kind_(std::move(kind)) {}
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  /// Registers a plugin. Never throws. Returns false (and records why) when the name is empty
  /// or taken, a parameter declaration is invalid, or the registry is frozen.
  bool add(PluginInfo info, Factory factory) noexcept {
    try {
      std::lock_guard lock(mutex_);
      std::string problem;
      if (frozen_) problem = "registered after the registry was frozen";
      else if (info.name.empty()) problem = "empty plugin name";
      else if (entries_.contains(info.name)) problem = "duplicate name";
      else if (!factory) problem = "no factory";
      for (const auto& spec : info.parameters) {
        if (!problem.empty()) break;
        if (auto why = validate_spec(spec); !why.empty())
          problem = "parameter '" + spec.name + "': " + why;
      }
      if (problem.empty() && info.user_parameters) {
        if (auto why = validate_spec(*info.user_parameters); !why.empty())
          problem = "user parameters: " + why;
      }
      if (!problem.empty()) {
        errors_.push_back(kind_ + " plugin '" + info.name + "': " + problem);
        return false;
      }
      auto name = info.name;
      entries_.emplace(std::move(name), Entry{std::move(info), std::move(factory)});
      return true;
    } catch (...) {
      // Out of memory during start-up: nothing sensible can be recorded.
      return false;
    }
  }

  /// The entry named `name`, or nullptr.
  const Entry* find(std::string_view name) const noexcept {
    auto it = entries_.find(name);
    return it == entries_.end() ? nullptr : &it->second;
  }

  /// Registered names, sorted.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [name, entry] : entries_) out.push_back(name);
    return out;
  }

  const std::string& kind() const noexcept { return kind_; }
  /// Records a registration error that happened before `add` could be called (register_plugin:
  /// the plugin's info() threw). Never throws.
  void record_error(std::string message) noexcept {
    try {
      std::lock_guard lock(mutex_);
      errors_.push_back(std::move(message));
    } catch (...) {
      // Out of memory during start-up: nothing sensible can be recorded.
    }
  }
  std::vector<std::string> errors() const {
    std::lock_guard lock(mutex_);
    return errors_;
  }
  std::size_t error_count() const {
    std::lock_guard lock(mutex_);
    return errors_.size();
  }
  /// Removes and returns the errors recorded after the first `kept`: the plugin loader reports
  /// them as the failure of the module it was loading (which it then unloads), so they do not
  /// linger as start-up errors.
  std::vector<std::string> take_errors_after(std::size_t kept) {
    std::lock_guard lock(mutex_);
    if (kept >= errors_.size()) return {};
    std::vector<std::string> taken(errors_.begin() + static_cast<std::ptrdiff_t>(kept), errors_.end());
    errors_.resize(kept);
    return taken;
  }

  /// After this, `add` is refused: trials read the registry from several threads.
  void freeze() noexcept {
    std::lock_guard lock(mutex_);
    frozen_ = true;
  }
  /// Re-opens the registry (for run-time registration between studies; not during a run).
  void unfreeze() noexcept {
    std::lock_guard lock(mutex_);
    frozen_ = false;
  }
  /// Removes a plugin (used by tests that register temporary plugins). Returns whether it existed.
  bool remove(std::string_view name) {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(name);
    if (it == entries_.end()) return false;
    entries_.erase(it);
    return true;
  }

 private:
  std::string kind_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry, std::less<>> entries_;
  std::vector<std::string> errors_;
  bool frozen_ = false;
};

/// The name of type T as the compiler spells it ("rkhs::Gaussian"), for messages.
template <class T>
constexpr std::string_view type_name() noexcept {
  // GCC: "... type_name() [with T = rkhs::Gaussian; std::string_view = ...]",
  // Clang: "... type_name() [T = rkhs::Gaussian]".
  const std::string_view function = __PRETTY_FUNCTION__;
  const auto start = function.find("T = ");
  if (start == std::string_view::npos) return function;
  const auto name = function.substr(start + 4);
  return name.substr(0, name.find_first_of(";]"));
}

/// Registers plugin type T into `registry`: its metadata T::info() and a factory that makes
/// `Made(parameters, args...)` (Made is T itself, or a wrapper such as KernelModel<T>). The one
/// registration function behind every RKHS_REGISTER_* macro. Never throws: when info() throws,
/// the exception's message is recorded in the registry's errors() as
///   "<kind> registration failed: <type T>: <what()>"
/// and false is returned; every other refusal is recorded by `add` (see there).
template <class T, class Made = T, class Product, class... Args>
bool register_plugin(Registry<Product, Args...>& registry) noexcept {
  auto failed = [&](std::string_view what) {
    try {
      registry.record_error(registry.kind() + " registration failed: " +
                            std::string(type_name<T>()) + ": " + std::string(what));
    } catch (...) {
      // Out of memory during start-up: nothing sensible can be recorded.
    }
    return false;
  };
  try {
    PluginInfo info = T::info();
    return registry.add(std::move(info), [](const ParameterSet& parameters, Args... args) {
      return std::unique_ptr<Product>(
          std::make_unique<Made>(parameters, std::forward<Args>(args)...));
    });
  } catch (const std::exception& e) {
    return failed(e.what());
  } catch (...) {
    return failed("unknown exception");
  }
}

}  // namespace rkhs

#define RKHS_CONCAT_IMPL(a, b) a##b
#define RKHS_CONCAT(a, b) RKHS_CONCAT_IMPL(a, b)
/// A unique identifier per use within a translation unit.
#define RKHS_UNIQUE_NAME(prefix) RKHS_CONCAT(prefix, __COUNTER__)

// RKHS_REGISTRAR(prefix, call): what every RKHS_REGISTER_* macro expands to (immediate in the
// framework, deferred until the ABI check in a plugin module).
#include "rkhs/core/registrar.hpp"
