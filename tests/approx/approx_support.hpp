#pragma once
// What tests of approximation trials build their cases from: the unit box or torus in R^d,
// Wendland's kernel of a given k and support radius, and a target written as an expression of
// x1, ..., xd.

#include <catch2/catch.hpp>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "rkhs/approx/target.hpp"
#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs::test {

using Given = std::map<std::string, ParameterValue>;

/// [0, 1]^d (d = 1, 2, 3), a torus when `periodic`.
inline Domain box(int dimension, bool periodic = false) {
  Domain d{1.0, periodic};
  d.dimension = dimension;
  d.width = 1.0;
  d.height = dimension == 3 ? 1.0 : 0.0;
  return d;
}

/// Wendland's phi_{d,k} with support radius `radius` on `domain`.
inline std::unique_ptr<AnyKernel> wendland(int k, double radius, const Domain& domain) {
  const auto* entry = kernel_registry().find("wendland");
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters,
                                              Given{{"k", std::int64_t{k}}, {"radius", radius}}),
                        domain);
}

/// The `expression` target f on `domain`.
inline std::unique_ptr<TargetFunction> expression(const std::string& f, const Domain& domain) {
  const auto* entry = target_registry().find("expression");
  REQUIRE(entry);
  return entry->factory(
      ParameterSet::resolve(entry->info.parameters, Given{{"f", f}},
                            entry->info.user_parameters ? &*entry->info.user_parameters : nullptr),
      domain);
}

}  // namespace rkhs::test
