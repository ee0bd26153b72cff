#pragma once
// Centre placements: where the n kernel sections phi_i = k(c_i, .) of H_n sit.

#include <cstdint>
#include <memory>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs {

class CentrePlacement {
 public:
  virtual ~CentrePlacement() = default;
  /// n centres in the domain, sorted increasingly. `trial_seed` is derived from the trial's key
  /// (random placements seed from it, deterministic ones ignore it).
  virtual std::vector<double> place(std::size_t n, const Domain& domain,
                                    std::uint64_t trial_seed) const = 0;
};

using CentreRegistry = Registry<CentrePlacement>;
CentreRegistry& centre_registry();

/// Registers placement type P (static info(), constructor from ParameterSet).
template <class P>
bool register_centre_placement() noexcept {
  try {
    return centre_registry().add(P::info(), [](const ParameterSet& p) {
      return std::unique_ptr<CentrePlacement>(std::make_unique<P>(p));
    });
  } catch (...) {
    return false;
  }
}

}  // namespace rkhs

#define RKHS_REGISTER_CENTRES(Type) \
  RKHS_REGISTRAR(rkhs_centres_registered_, ::rkhs::register_centre_placement<Type>())
