#pragma once
// Helpers shared by the kernel tests: creating kernels through the registry, point sets, and the
// power function with a round-off tolerance.

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/plugin/kernel_contract.hpp"
#include "rkhs/core/parameters.hpp"

namespace rkhs::test {

using Given = std::map<std::string, ParameterValue>;

inline constexpr double epsilon = std::numeric_limits<double>::epsilon();
inline constexpr double pi = 3.14159265358979323846;
/// The paper's track: a circle of radius 4 m.
inline constexpr double track_length = 2 * pi * 4;

/// Creates `name` from the kernel registry with `given` parameters (others default).
inline std::unique_ptr<AnyKernel> make_registered_kernel(const std::string& name,
                                                         const Given& given, const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry != nullptr);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

/// The concrete kernel type K with `given` parameters, resolved against K's own declaration.
template <class K>
K make_kernel_of(const Given& given, const Domain& domain) {
  return K(ParameterSet::resolve(K::info().parameters, given), domain);
}

/// Point sets and the power function of the kernel contract (rkhs/plugin/kernel_contract.hpp).
inline std::vector<double> uniform_centres(std::size_t n, double length) {
  return nested_uniform_centres(n, length);
}
inline std::vector<double> scattered_points(std::size_t count, double length,
                                            double start = 0.1234) {
  return golden_ratio_points(count, length, start);
}
using PowerFunction = PowerFunctionSquared;
using ::rkhs::power_function_squared;

}  // namespace rkhs::test
