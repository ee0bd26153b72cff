#pragma once
// The registrar behind every RKHS_REGISTER_* macro, and how it differs in a plugin module.
//
// In the rkhs_study library (built-in plugins) a registrar is a namespace-scope constant
// initialised by a noexcept registration call: the plugin registers while the library loads.
//
// In a plugin module (compiled with RKHS_BUILDING_PLUGIN defined, as rkhs_study_add_plugin()
// and the rkhs_study::plugin target do) the same macro only *records* the registration call in a
// list private to the module; nothing of the framework is touched while the module loads. The
// loader (plugin_loader.hpp) first checks the module's ABI version through an extern "C" entry
// point that uses no framework type, and only then asks the module to run the recorded calls
// (rkhs_plugin_register, defined by RKHS_PLUGIN_MODULE in plugin/module.hpp). A module built against an
// incompatible framework is therefore refused before any of its code builds a PluginInfo or calls
// into a registry whose layout it misunderstands.
//
// The list lives in a hidden inline function: one list per module, shared by all of the
// module's translation units, never merged with another module's (a default-visibility inline
// static would be a GNU "unique" symbol, shared process-wide).

namespace rkhs::plugin_detail {

/// A recorded registration: calls register_plugin<T>() (registry.hpp). Never throws.
using Registration = bool (*)() noexcept;

/// Registrations recorded by a plugin module, in static-initialisation order.
struct PendingRegistrations {
  static constexpr int capacity = 256;
  Registration calls[capacity];
  int count;
  bool overflow;  ///< more than `capacity` registrations: the module is refused
};

/// The module's list (zero-initialised at load time, before any dynamic initialiser runs).
[[gnu::visibility("hidden")]] inline PendingRegistrations& pending_registrations() noexcept {
  static PendingRegistrations pending;
  return pending;
}

/// Records `call` for later; the value initialises the registrar constant.
[[gnu::visibility("hidden")]] inline bool defer_registration(Registration call) noexcept {
  auto& pending = pending_registrations();
  if (pending.count == PendingRegistrations::capacity) {
    pending.overflow = true;
    return false;
  }
  pending.calls[pending.count++] = call;
  return true;
}

/// Runs the recorded registrations. Returns how many failed (their reasons, including the message
/// of an exception thrown by a plugin's info(), are in the registries' errors()), or -1 when the list overflowed. The list is kept: a module that
/// dlclose could not unmap (it stays resident, and its initialisers do not run again when it is
/// reopened) registers again from it.
[[gnu::visibility("hidden")]] inline int run_pending_registrations() noexcept {
  auto& pending = pending_registrations();
  if (pending.overflow) return -1;
  int failed = 0;
  for (int i = 0; i < pending.count; ++i)
    if (!pending.calls[i]()) ++failed;
  return failed;
}

}  // namespace rkhs::plugin_detail

#if defined(RKHS_BUILDING_PLUGIN)
/// A registrar in a plugin module: records the call (see above).
#define RKHS_REGISTRAR(prefix, ...)                                                             \
  namespace {                                                                                   \
  [[maybe_unused]] const bool RKHS_UNIQUE_NAME(prefix) =                                        \
      ::rkhs::plugin_detail::defer_registration([]() noexcept -> bool { return __VA_ARGS__; }); \
  }
#else
/// A registrar in the framework: registers during static initialisation.
#define RKHS_REGISTRAR(prefix, ...)                                   \
  namespace {                                                         \
  [[maybe_unused]] const bool RKHS_UNIQUE_NAME(prefix) = __VA_ARGS__; \
  }
#endif
