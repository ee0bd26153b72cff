#include "rkhs/kernel/kernel.hpp"

#include <fmt/format.h>

#include "rkhs/core/parameters.hpp"

namespace rkhs {

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
