// The registries of the adaptive layer's plugin kinds, defined where they are declared. Each is a
// function-local static: constructed on first use, whatever the order in which the registrars of
// the built-in and loaded plugins run.
#include <string>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/plant.hpp"

namespace rkhs {

PlantRegistry& plant_registry() {
  static PlantRegistry registry{std::string(plant_kind_name)};
  return registry;
}

LawRegistry& law_registry() {
  static LawRegistry registry{std::string(law_kind_name)};
  return registry;
}

IntegratorRegistry& integrator_registry() {
  static IntegratorRegistry registry{std::string(integrator_kind_name)};
  return registry;
}

}  // namespace rkhs
