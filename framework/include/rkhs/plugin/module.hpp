#pragma once
// What a plugin module (a shared library loaded at run time) declares about itself.
//
// A plugin module is one or more .cpp files that register kernels (or centre placements,
// targets, plants, learning laws, integrators) with the same macros as the built-ins, compiled
// with RKHS_BUILDING_PLUGIN defined and linked against librkhs_study (the CMake package does
// both: rkhs_study_add_plugin(name file.cpp) or target_link_libraries(name PRIVATE
// rkhs_study::plugin)). Exactly one of its files says
//
//     #include "rkhs/plugin/module.hpp"
//     RKHS_PLUGIN_MODULE("my_kernels")
//
// which defines the module's extern "C" entry points:
//
//     int         rkhs_plugin_abi_version()   RKHS_PLUGIN_ABI_VERSION of the headers it was built
//     with const char* rkhs_plugin_rkhs_study_version()   "0.1.0" const char* rkhs_plugin_name()
//     the module name (unique among loaded modules) int         rkhs_plugin_register()      runs
//     the module's recorded registrations
//
// The ordering problem, and how it is solved. A shared module's static initialisers run inside
// dlopen, before the loader can call anything in it. If registrations ran there, a module built
// against another layout of PluginInfo, ParameterSpec or AnyKernel would write into the registry
// before its ABI version could be checked. So in a plugin build RKHS_REGISTER_* only records the
// registration (registrar.hpp), and the loader
//   1. dlopens the file with RTLD_LAZY | RTLD_LOCAL (lazy, so that a module whose framework
//      functions no longer exist still loads far enough to tell its ABI version);
//   2. looks up rkhs_plugin_abi_version: missing means "not an rkhs-study plugin";
//   3. compares it with its own RKHS_PLUGIN_ABI_VERSION: different means refused, and the message
//      names both ABI versions and both rkhs-study versions;
//   4. only then calls rkhs_plugin_register, and compares the registries (names and errors)
//      before and after to learn what the module registered and whether any of it was refused.
// The entry points use only C types, so step 2 and 3 are sound whatever the module was built
// with. A module compiled without RKHS_BUILDING_PLUGIN registers during step 1; the loader sees
// the registries change inside dlopen and refuses it, naming the cause.
//
// RKHS_PLUGIN_ABI_VERSION covers everything a plugin compiles into itself from the framework's
// headers: the layouts of PluginInfo, ParameterSpec, ParameterValue, ParameterSet, Domain,
// KernelProperties, SparseFeatures, Registry and Registry::Entry, the virtual functions of
// AnyKernel, KernelBasis, CentrePlacement, TargetFunction, Plant, LearningLaw, Integrator and
// AdaptiveSystem, and the signatures of the framework
// functions the headers call. Change any of them: increment it. It assumes what any C++ shared
// library assumes of its clients: the same compiler family and standard library, and no
// layout-changing library mode (a _GLIBCXX_DEBUG plugin is not compatible with a normal build).

#include "rkhs/core/registry.hpp"
#include "rkhs/version.hpp"  // RKHS_STUDY_VERSION, generated from the CMake project version

#define RKHS_PLUGIN_ABI_VERSION 4  // 4: derivatives in KernelBasis, AnyKernel, TargetFunction

#define RKHS_PLUGIN_EXPORT extern "C" [[gnu::visibility("default"), gnu::used]]

#if !defined(RKHS_BUILDING_PLUGIN)
#define RKHS_PLUGIN_MODULE(name)                                               \
  static_assert(false,                                                         \
                "RKHS_PLUGIN_MODULE: compile every source of the module with " \
                "RKHS_BUILDING_PLUGIN defined (rkhs_study_add_plugin() and "   \
                "rkhs_study::plugin do), so that its registrations wait for the ABI check");
#else
/// Declares the module `name` (a string literal; the name of the module, not of its kernels).
/// Use once per module, at namespace scope.
#define RKHS_PLUGIN_MODULE(name)                                             \
  RKHS_PLUGIN_EXPORT int rkhs_plugin_abi_version() noexcept {                \
    return RKHS_PLUGIN_ABI_VERSION;                                          \
  }                                                                          \
  RKHS_PLUGIN_EXPORT const char* rkhs_plugin_rkhs_study_version() noexcept { \
    return RKHS_STUDY_VERSION;                                               \
  }                                                                          \
  RKHS_PLUGIN_EXPORT const char* rkhs_plugin_name() noexcept {               \
    return name;                                                             \
  }                                                                          \
  RKHS_PLUGIN_EXPORT int rkhs_plugin_register() noexcept {                   \
    return ::rkhs::plugin_detail::run_pending_registrations();               \
  }
#endif
