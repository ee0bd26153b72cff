// Built-in centre placements: uniform (a grid in d > 1), random and Halton points, and points
// on straight passes across a plane.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "rkhs/approx/centres.hpp"
#include "rkhs/core/random.hpp"

namespace rkhs {
namespace {

// m with m^d == n, or an error naming the placement, n and d.
std::size_t grid_side(std::string_view placement, std::size_t n, int dimension) {
  auto power = [&](std::size_t m) {
    std::size_t out = 1;
    for (int a = 0; a < dimension; ++a) out *= m;
    return out;
  };
  // The largest m with m^d <= n (the rounded root, corrected by one either way).
  auto m = static_cast<std::size_t>(std::pow(static_cast<double>(n), 1.0 / dimension));
  while (power(m + 1) <= n) ++m;
  while (m > 0 && power(m) > n) --m;
  if (power(m) != n)
    throw std::invalid_argument(fmt::format(
        "centres '{}' in d = {} place a grid of m^{} centres; n = {} is not such a number "
        "(nearest: {}, {})",
        placement, dimension, dimension, n, power(m), power(m + 1)));
  return m;
}

/// c_i = (i + offset) L / n on a periodic domain (docs/model.md section 4 with offset 0);
/// c_i = i L / (n - 1) on an interval (end points included), the midpoint for n = 1.
class UniformCentres final : public CentrePlacement {
 public:
  static PluginInfo info() {
    return {"uniform",
            "equally spaced centres c_i = (i + offset) L / n (interval: end points included); "
            "in d > 1 the grid of m per axis, n = m^d",
            {real_parameter("offset", 0.0, "shift as a fraction of the spacing (periodic only)",
                            0.0, 1.0)},
            {{"deterministic", "yes"}}};
  }
  explicit UniformCentres(const ParameterSet& p) : offset_(p.real("offset")) {}

  void place_into(const Domain& domain, std::uint64_t, std::span<double> c) const override {
    if (domain.dimension > 1) return place_grid(domain, c);
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
  // d > 1: the tensor grid of m = n^(1/d) points per axis, each axis placed like the track or
  // the interval above; axis 1 varies fastest.
  void place_grid(const Domain& domain, std::span<double> c) const {
    const auto d = static_cast<std::size_t>(domain.dimension);
    const std::size_t n = c.size() / d;
    if (n == 0) return;
    const std::size_t m = grid_side("uniform", n, domain.dimension);
    auto coordinate = [&](std::size_t i, std::size_t axis) {
      const double extent = domain.extent(static_cast<int>(axis));
      if (domain.periodic)
        return (static_cast<double>(i) + offset_) * extent / static_cast<double>(m);
      if (m == 1) return 0.5 * extent;
      return i + 1 == m ? extent : static_cast<double>(i) * extent / static_cast<double>(m - 1);
    };
    for (std::size_t p = 0; p < n; ++p) {
      std::size_t rest = p;
      for (std::size_t a = 0; a < d; ++a) {
        c[p * d + a] = coordinate(rest % m, a);
        rest /= m;
      }
    }
  }

  double offset_;
};

/// n independent uniform points, sorted. The generator is seeded from the `seed` parameter and
/// n, so every kernel of a study sees the same centre set for the same (seed, n).
class RandomCentres final : public CentrePlacement {
 public:
  static PluginInfo info() {
    return {"random",
            "n independent uniformly distributed centres (sorted on a track), seeded from seed "
            "and n",
            {integer_parameter("seed", 1, "seed of the generator", 0, 1LL << 62)},
            {{"deterministic", "for a given seed and n"}}};
  }
  explicit RandomCentres(const ParameterSet& p)
      : seed_(static_cast<std::uint64_t>(p.integer("seed"))) {}

  void place_into(const Domain& domain, std::uint64_t, std::span<double> c) const override {
    if (domain.dimension > 1) {
      // n points of d coordinates, drawn point by point, not sorted.
      const auto d = static_cast<std::size_t>(domain.dimension);
      const std::size_t n = c.size() / d;
      Random random(
          hash_combine(hash64("centres/random"), hash_combine(seed_, hash_combine(n, d))));
      for (std::size_t i = 0; i < c.size(); ++i)
        c[i] = random.uniform() * domain.extent(static_cast<int>(i % d));
      return;
    }
    const std::size_t n = c.size();
    Random random(hash_combine(hash64("centres/random"), hash_combine(seed_, n)));
    for (auto& x : c) x = random.uniform() * domain.length;
    std::sort(c.begin(), c.end());
  }

 private:
  std::uint64_t seed_;
};

/// The Halton sequence: point i (i = skip + 1, ..., skip + n) has coordinate a equal to the
/// radical inverse of i in the a-th prime (2, 3, 5), scaled to the axis. A low-discrepancy set
/// whose first n points are nested in the first 2n: quasi-uniform (h ~ n^-1/d, mesh ratio
/// bounded by a constant for these bases). In d = 1 (the van der Corput sequence) the centres
/// are sorted like every placement's.
class HaltonCentres final : public CentrePlacement {
 public:
  static PluginInfo info() {
    return {"halton",
            "the first n points of the Halton sequence (bases 2, 3, 5), after `skip`",
            {integer_parameter("skip", 0, "points of the sequence left out before the first", 0,
                               1LL << 40)},
            {{"deterministic", "yes"}, {"nested", "the first n points are among the first 2n"}}};
  }
  explicit HaltonCentres(const ParameterSet& p)
      : skip_(static_cast<std::uint64_t>(p.integer("skip"))) {}

  /// The radical inverse of i in `base`: its digits mirrored about the radix point, in [0, 1).
  static double radical_inverse(std::uint64_t i, unsigned base) noexcept {
    double value = 0.0, scale = 1.0 / base;
    for (; i > 0; i /= base, scale /= base) value += static_cast<double>(i % base) * scale;
    return value;
  }

  void place_into(const Domain& domain, std::uint64_t, std::span<double> c) const override {
    static constexpr std::array<unsigned, Domain::max_dimension> bases{2, 3, 5};
    const auto d = static_cast<std::size_t>(domain.dimension);
    const std::size_t n = c.size() / d;
    for (std::size_t p = 0; p < n; ++p)
      for (std::size_t a = 0; a < d; ++a)
        c[p * d + a] =
            radical_inverse(skip_ + p + 1, bases[a]) * domain.extent(static_cast<int>(a));
    if (d == 1) std::sort(c.begin(), c.end());
  }

 private:
  std::uint64_t skip_;
};

/// The centres a vehicle places where it drove: `passes` straight passes along axis 1 of a box
/// or torus in d = 2, at lateral positions x2 equally spaced from `from` W to `to` W (one pass:
/// at `from` W), n / passes centres on each, placed along the pass like the track (periodic) or
/// the interval (end points included). Everything off the passes is far from every centre: the
/// fill distance stays at the largest lateral gap, and a study shows where f is not learned.
class PassCentres final : public CentrePlacement {
 public:
  static PluginInfo info() {
    return {"passes",
            "n centres on straight passes along axis 1 at equally spaced lateral positions "
            "(d = 2): where a vehicle drove",
            {integer_parameter("passes", 2, "number of passes; n must be a multiple of it", 1,
                               1 << 20),
             real_parameter("from", 0.25, "lateral position of the first pass, fraction of the "
                            "width", 0.0, 1.0),
             real_parameter("to", 0.75, "lateral position of the last pass, fraction of the width",
                            0.0, 1.0)},
            {{"deterministic", "yes"}}};
  }
  explicit PassCentres(const ParameterSet& p)
      : passes_(static_cast<std::size_t>(p.integer("passes"))),
        from_(p.real("from")),
        to_(p.real("to")) {
    if (to_ < from_)
      throw ParameterError("to", fmt::format("parameter 'to' ({}) must be at least 'from' ({})",
                                             format_real(to_), format_real(from_)));
  }

  void place_into(const Domain& domain, std::uint64_t, std::span<double> c) const override {
    if (domain.dimension != 2)
      throw std::invalid_argument(fmt::format(
          "centres 'passes' lie on passes across a plane: they need a domain of d = 2, this "
          "domain has d = {}",
          domain.dimension));
    const std::size_t n = c.size() / 2;
    if (n % passes_ != 0)
      throw std::invalid_argument(fmt::format(
          "centres 'passes' put n / passes centres on each of {} passes; n = {} is not a "
          "multiple of {}",
          passes_, n, passes_));
    const std::size_t per_pass = n / passes_;
    Domain along = domain;  // the pass as a track or an interval of length L
    along.dimension = 1;
    const auto positions = along.uniform_points(per_pass);
    for (std::size_t k = 0; k < passes_; ++k) {
      const double fraction =
          passes_ == 1 ? from_
                       : from_ + (to_ - from_) * static_cast<double>(k) /
                                     static_cast<double>(passes_ - 1);
      for (std::size_t i = 0; i < per_pass; ++i) {
        c[2 * (k * per_pass + i)] = positions[i];
        c[2 * (k * per_pass + i) + 1] = fraction * domain.width;
      }
    }
  }

 private:
  std::size_t passes_;
  double from_, to_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_CENTRES(rkhs::UniformCentres)
RKHS_REGISTER_CENTRES(rkhs::PassCentres)
RKHS_REGISTER_CENTRES(rkhs::RandomCentres)
RKHS_REGISTER_CENTRES(rkhs::HaltonCentres)
