#pragma once
// Centre placements: where the n kernel sections phi_i = k(c_i, .) of H_n sit.

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs {

class CentrePlacement {
 public:
  virtual ~CentrePlacement() = default;
  /// Writes n = out.size() / d centres in the domain into `out` (the caller's storage), a flat
  /// point set of d = domain.dimension coordinates per centre (core/domain.hpp); in d = 1 sorted
  /// increasingly. `trial_seed` is derived from the trial's key (random placements seed from
  /// it, deterministic ones ignore it). Nothing crosses the plugin boundary but the values.
  /// A placement that cannot place n centres in this domain (a grid needs n = m^d; a
  /// one-dimensional placement in d > 1) throws std::invalid_argument saying why.
  virtual void place_into(const Domain& domain, std::uint64_t trial_seed,
                          std::span<double> out) const = 0;
  /// n centres (place_into, allocated on the caller's side): n d values.
  std::vector<double> place(std::size_t n, const Domain& domain, std::uint64_t trial_seed) const {
    std::vector<double> out(n * static_cast<std::size_t>(domain.dimension));
    place_into(domain, trial_seed, out);
    return out;
  }
};

using CentreRegistry = Registry<CentrePlacement>;
/// The centre-placement registry (defined in this layer, registries.cpp), named centres_kind_name.
inline constexpr std::string_view centres_kind_name = "centres";
CentreRegistry& centre_registry();

/// Registers placement type P (static info(), constructor from ParameterSet). Never throws; a
/// failure is recorded in centre_registry().errors() (register_plugin).
template <class P>
bool register_centre_placement() noexcept {
  return register_plugin<P>(centre_registry());
}

}  // namespace rkhs

#define RKHS_REGISTER_CENTRES(Type) \
  RKHS_REGISTRAR(rkhs_centres_registered_, ::rkhs::register_centre_placement<Type>())
