// Built-in centre placements: uniform and random.
#include "rkhs/approx/centres.hpp"

#include <algorithm>
#include <stdexcept>

#include "rkhs/core/random.hpp"

namespace rkhs {
namespace {

/// c_i = (i + offset) L / n on a periodic domain (docs/model.md section 4 with offset 0);
/// c_i = i L / (n - 1) on an interval (end points included), the midpoint for n = 1.
class UniformCentres final : public CentrePlacement {
 public:
  static PluginInfo info() {
    return {"uniform",
            "equally spaced centres c_i = (i + offset) L / n (interval: end points included)",
            {real_parameter("offset", 0.0, "shift as a fraction of the spacing (periodic only)",
                            0.0, 1.0)},
            {{"deterministic", "yes"}}};
  }
  explicit UniformCentres(const ParameterSet& p) : offset_(p.real("offset")) {}

  void place_into(const Domain& domain, std::uint64_t, std::span<double> c) const override {
    const std::size_t n = c.size();
    if (n == 0) return;
    if (!domain.periodic) {
      const auto points = domain.uniform_points(n);
      std::copy(points.begin(), points.end(), c.begin());
      return;
    }
    for (std::size_t i = 0; i < n; ++i)
      c[i] = (static_cast<double>(i) + offset_) * domain.length / static_cast<double>(n);
  }

 private:
  double offset_;
};

/// n independent uniform points, sorted. The generator is seeded from the `seed` parameter and
/// n, so every kernel of a study sees the same centre set for the same (seed, n).
class RandomCentres final : public CentrePlacement {
 public:
  static PluginInfo info() {
    return {"random",
            "n independent uniformly distributed centres, sorted (seeded from seed and n)",
            {integer_parameter("seed", 1, "seed of the generator", 0, 1LL << 62)},
            {{"deterministic", "for a given seed and n"}}};
  }
  explicit RandomCentres(const ParameterSet& p)
      : seed_(static_cast<std::uint64_t>(p.integer("seed"))) {}

  void place_into(const Domain& domain, std::uint64_t, std::span<double> c) const override {
    const std::size_t n = c.size();
    Random random(hash_combine(hash64("centres/random"), hash_combine(seed_, n)));
    for (auto& x : c) x = random.uniform() * domain.length;
    std::sort(c.begin(), c.end());
  }

 private:
  std::uint64_t seed_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_CENTRES(rkhs::UniformCentres)
RKHS_REGISTER_CENTRES(rkhs::RandomCentres)
