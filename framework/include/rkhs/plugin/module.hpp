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
//     int         rkhs_plugin_abi_version()          RKHS_PLUGIN_ABI_VERSION of its headers
//     const BuildConfiguration* rkhs_plugin_build_configuration()
//                                                    how it was compiled (build_configuration.hpp)
//     const char* rkhs_plugin_rkhs_study_version()   "0.1.0"
//     const char* rkhs_plugin_name()                 the module name (unique among loaded modules)
//     int         rkhs_plugin_register()             runs the module's recorded registrations
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
//   4. compares the module's build configuration (compiler, Eigen and its alignment,
//      vectorisation class, sanitizer, debug library: build_configuration.hpp) with its own:
//      different means refused, and the message names both configurations;
//   5. only then calls rkhs_plugin_register, and compares the registries (names and errors)
//      before and after to learn what the module registered and whether any of it was refused.
// The entry points use only C types (the configuration is a struct of ints), so steps 2 to 4
// are sound whatever the module was built with. A module compiled without RKHS_BUILDING_PLUGIN
// registers during step 1; the loader sees the registries change inside dlopen and refuses it,
// naming the cause.
//
// RKHS_PLUGIN_ABI_VERSION covers everything a plugin compiles into itself from the framework's
// headers: the layouts of PluginInfo, ParameterSpec, ParameterValue, ParameterSet, Domain,
// KernelProperties, SparseFeatures, Registry, Registry::Entry and BuildConfiguration, the virtual
// functions of AnyKernel, KernelBasis, CentrePlacement, TargetFunction, Plant, LearningLaw,
// Integrator and AdaptiveSystem, the module's entry points, and the signatures of the framework
// functions the headers call. Change any of them: increment it. What it cannot cover, how each
// side was compiled, is the build configuration of step 4.
//
// The boundary owns nothing across it. Eigen picks its allocator and alignment from build flags
// in inline code, so an Eigen object allocated by a module and freed by the framework (or the
// reverse) corrupts the heap whenever the two were built differently. So no virtual function of
// a plugin interface returns an owning object: results go into storage the caller owns and sized
// (AnyKernel::gram_into, cross_into, diagonal_into, CentrePlacement::place_into, the state of
// Integrator::integrate, an Eigen::Ref or std::span) or are handed to the caller's sink one value
// at a time (list_kink_points, TargetFunction::describe_provenance, list_notes); what a plugin
// makes (a kernel, a KernelBasis) is destroyed by its own virtual destructor, and references
// it returns (Plant::A(), AnyKernel::name()) are read, never freed, by the caller. The
// registration metadata (PluginInfo: std::string and std::vector) does move from the module into
// the registries: the standard allocator calls the process's one ::operator new and delete, the
// same on both sides once step 4 has matched the compiler and the debug library.

#include "rkhs/core/registry.hpp"
#include "rkhs/plugin/build_configuration.hpp"
#include "rkhs/version.hpp"  // RKHS_STUDY_VERSION, generated from the CMake project version

// 4: derivatives in KernelBasis, AnyKernel, TargetFunction
// 5: nothing owned crosses the boundary (*_into, sinks, Integrator state by Eigen::Ref), and the
//    build configuration entry point
// 6: AnyKernel::feature_basis, LearningLaw::coordinates and LearningLaw::require_kernel
// 7: LearningLaw::reference_resolution
// 8: PluginInfo::user_parameters, and ParameterSet::resolve's user parameters
// 9: Domain in R^d (dimension, width, height), AnyKernel::evaluate_point, flat point sets
// 10: state-dependent plants (Plant::readout, readout_offset, known_dynamics, period,
//     initial_state) and AdaptiveSystem's state read-out
// 11: AnyKernel::gradient_point and has_exact_gradient
// 12: KernelModel and its bases count their work (count_kernel_evaluations,
//     count_kernel_derivative_evaluations: core/work_counters.hpp)
// 13: Integrator::properties (IntegratorProperties: factorisations per step, structured stage
//     solves), which the trial scheduler reads instead of a trait string
#define RKHS_PLUGIN_ABI_VERSION 13

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
#define RKHS_PLUGIN_MODULE(name)                                                          \
  RKHS_PLUGIN_EXPORT int rkhs_plugin_abi_version() noexcept {                             \
    return RKHS_PLUGIN_ABI_VERSION;                                                       \
  }                                                                                       \
  RKHS_PLUGIN_EXPORT const ::rkhs::BuildConfiguration*                                    \
  rkhs_plugin_build_configuration() noexcept {                                            \
    static constexpr ::rkhs::BuildConfiguration configuration = RKHS_BUILD_CONFIGURATION; \
    return &configuration;                                                                \
  }                                                                                       \
  RKHS_PLUGIN_EXPORT const char* rkhs_plugin_rkhs_study_version() noexcept {              \
    return RKHS_STUDY_VERSION;                                                            \
  }                                                                                       \
  RKHS_PLUGIN_EXPORT const char* rkhs_plugin_name() noexcept {                            \
    return name;                                                                          \
  }                                                                                       \
  RKHS_PLUGIN_EXPORT int rkhs_plugin_register() noexcept {                                \
    return ::rkhs::plugin_detail::run_pending_registrations();                            \
  }
#endif
