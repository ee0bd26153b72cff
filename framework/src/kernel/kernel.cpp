#include "rkhs/kernel/kernel.hpp"

#include <fmt/format.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "rkhs/core/parameters.hpp"

namespace rkhs {

KernelRegistry& kernel_registry() {
  // Constructed on first use, whatever the order in which the registrars of the built-in and
  // loaded plugins run.
  static KernelRegistry registry{std::string(kernel_kind_name)};
  return registry;
}

std::unique_ptr<AnyKernel> make_kernel(std::string_view name, const ParameterSet& parameters,
                                       const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  if (!entry) throw std::invalid_argument("unknown kernel '" + std::string(name) + "'");
  return entry->factory(parameters, domain);
}

KernelProperties kernel_properties(std::string_view name, const ParameterSet& parameters,
                                   const Domain& domain) {
  return make_kernel(name, parameters, domain)->properties();
}

std::string describe_properties(const KernelProperties& p) {
  std::string out = p.positive_definite ? "positive definite" : "positive semidefinite";
  if (p.analytic)
    out += ", analytic";
  else if (p.sobolev_order)
    out += fmt::format(", Sobolev order tau = {}", format_real(*p.sobolev_order));
  else
    out += ", no smoothness declared";
  out += p.support_radius > 0 ? fmt::format(", support radius {}", format_real(p.support_radius))
                              : std::string(", global support");
  out += p.stationary ? ", stationary" : ", not stationary";
  if (p.periodic) out += ", periodic";
  return out + fmt::format(", d = {}", p.dimension);
}

}  // namespace rkhs
