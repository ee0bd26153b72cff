#pragma once
// The kinds of plugin: the one table that everything which concerns "every kind" iterates.
//
// Each kind is a descriptor type:
//   using Product             the interface its plugins implement (AnyKernel, Plant, ...)
//   using Registry            Registry<Product, FactoryArgs...> (core/registry.hpp)
//   singular, plural          names: the registry's kind() (declared with the registry in its
//                             layer), the words `rkhs-study list` accepts
//   builtins                  the names every build of rkhs-study registers, sorted
//   registry()                the kind's registry (the accessor declared in the kind's layer)
// and PluginKinds lists them, in the order of `rkhs-study list` and of registration_errors().
//
// Who iterates the table (for_each_plugin_kind): the registries' definitions (their kind names),
// registration_errors(), missing_builtin_plugins(), freeze_registries(), plugin_kind_names()
// (builtins.hpp); the plugin loader's snapshot, comparison and roll-back of the registries
// (plugin_loader.cpp); `rkhs-study list` and its accepted kind names (cli).
//
// A new kind needs: its Registry accessor and kind name declared in its layer's header and the
// accessor defined in that layer (a function-local static: the layers hold when linked,
// tests/architecture/check_link_direction.py), a descriptor here, and its entry in PluginKinds.
// Nothing else lists the kinds.
//
// This header names the products of the kernel, approx and adaptive layers, so it lives in the
// plugin layer, above them; the generic registry and register_plugin<T>() are in core.

#include <concepts>
#include <iterator>
#include <string_view>
#include <tuple>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

struct KernelKind {
  using Product = AnyKernel;
  using Registry = KernelRegistry;
  static constexpr std::string_view singular = kernel_kind_name;
  static constexpr std::string_view plural = "kernels";
  static constexpr std::string_view builtins[] = {"bspline", "gaussian", "matern", "wendland"};
  static Registry& registry() { return kernel_registry(); }
};

struct CentresKind {
  using Product = CentrePlacement;
  using Registry = CentreRegistry;
  static constexpr std::string_view singular = centres_kind_name;
  static constexpr std::string_view plural = "centres";
  static constexpr std::string_view builtins[] = {"halton", "passes", "random", "uniform"};
  static Registry& registry() { return centre_registry(); }
};

struct TargetKind {
  using Product = TargetFunction;
  using Registry = TargetRegistry;
  static constexpr std::string_view singular = target_kind_name;
  static constexpr std::string_view plural = "targets";
  static constexpr std::string_view builtins[] = {"csv", "expression", "iso8608", "sine",
                                                  "surface_csv"};
  static Registry& registry() { return target_registry(); }
};

struct ProjectionKind {
  using Product = Projection;
  using Registry = ProjectionRegistry;
  static constexpr std::string_view singular = projection_kind_name;
  static constexpr std::string_view plural = "projections";
  static constexpr std::string_view builtins[] = {"interpolation", "l2_projection", "mra_level",
                                                  "multilevel", "quasi_interpolant"};
  static Registry& registry() { return projection_registry(); }
};

struct PlantKind {
  using Product = Plant;
  using Registry = PlantRegistry;
  static constexpr std::string_view singular = plant_kind_name;
  static constexpr std::string_view plural = "plants";
  static constexpr std::string_view builtins[] = {"duffing", "linear", "pendulum", "quarter_car",
                                                  "vehicle_surface"};
  static Registry& registry() { return plant_registry(); }
};

struct LawKind {
  using Product = LearningLaw;
  using Registry = LawRegistry;
  static constexpr std::string_view singular = law_kind_name;
  static constexpr std::string_view plural = "laws";
  static constexpr std::string_view builtins[] = {"gradient", "rkhs", "rkhs_embedding"};
  static Registry& registry() { return law_registry(); }
};

struct IntegratorKind {
  using Product = Integrator;
  using Registry = IntegratorRegistry;
  static constexpr std::string_view singular = integrator_kind_name;
  static constexpr std::string_view plural = "integrators";
  static constexpr std::string_view builtins[] = {"dopri5", "radau5", "rk4", "rk_fehlberg78",
                                                  "rodas4", "rosenbrock4"};
  static Registry& registry() { return integrator_registry(); }
};

/// The table.
using PluginKinds = std::tuple<KernelKind, CentresKind, TargetKind, ProjectionKind, PlantKind,
                               LawKind, IntegratorKind>;
inline constexpr std::size_t plugin_kind_count = std::tuple_size_v<PluginKinds>;

/// What a descriptor must declare (see the file comment).
template <class Kind>
concept PluginKindDescriptor = requires {
  typename Kind::Product;
  typename Kind::Registry;
  { Kind::singular } -> std::convertible_to<std::string_view>;
  { Kind::plural } -> std::convertible_to<std::string_view>;
  { Kind::registry() } -> std::same_as<typename Kind::Registry&>;
  std::size(Kind::builtins);
};
static_assert([]<class... Kinds>(std::tuple<Kinds...>*) {
  return (PluginKindDescriptor<Kinds> && ...);
}(static_cast<PluginKinds*>(nullptr)));

/// Calls visitor(Kind{}) for every kind, in table order (the descriptor is an empty value; use
/// decltype(kind) for its members).
template <class Visitor>
void for_each_plugin_kind(Visitor&& visitor) {
  std::apply([&](auto... kind) { (visitor(kind), ...); }, PluginKinds{});
}

}  // namespace rkhs
