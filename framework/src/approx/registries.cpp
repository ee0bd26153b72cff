// The registries of the approx layer's plugin kinds, defined where they are declared. Each is a
// function-local static: constructed on first use, whatever the order in which the registrars of
// the built-in and loaded plugins run.
#include <string>

#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"

namespace rkhs {

CentreRegistry& centre_registry() {
  static CentreRegistry registry{std::string(centres_kind_name)};
  return registry;
}

TargetRegistry& target_registry() {
  static TargetRegistry registry{std::string(target_kind_name)};
  return registry;
}

ProjectionRegistry& projection_registry() {
  static ProjectionRegistry registry{std::string(projection_kind_name)};
  return registry;
}

}  // namespace rkhs
