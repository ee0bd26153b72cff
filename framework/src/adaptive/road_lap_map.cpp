// The lap map engine of a road trial (RoadTrial::run_lap_map, road_trial.hpp; docs/model.md,
// "the lap map"): one lap integrated once as the affine map z -> Phi z + c, N laps as its N-th
// power or the limit as its fixed point, and the floors of what its powers give.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "rkhs/core/cancellation.hpp"
#include "road_trial.hpp"

namespace rkhs {

namespace {

// The smallest N >= 0 with distance(N) <= fraction distance(0), found by doubling and then
// bisection (it assumes distance(N) stays below the fraction once it is there, as it does
// for the contracting learning dynamics). Empty when not reached by `cap` laps (or 2^62).
template <class Distance>
std::optional<std::uint64_t> laps_within(Distance&& distance, double fraction, std::uint64_t cap) {
  const double target = fraction * distance(0);
  if (!(target > 0)) return 0;
  std::uint64_t high = 1;
  while (distance(high) > target) {
    if (high >= cap || high >= (std::uint64_t{1} << 62)) return std::nullopt;
    high *= 2;
  }
  std::uint64_t low = high / 2;  // distance(low) > target, or low = 0
  while (high - low > 1) {
    const std::uint64_t middle = low + (high - low) / 2;
    (distance(middle) > target ? low : high) = middle;
  }
  return high;
}

// The most laps whose powers of the lap map still say something about the limit: 50 time
// constants of its slowest excited mode (e^-50 = 2e-22 of what it had), and at least 2 m laps
// (a nilpotent part of an m x m map is gone after m). Beyond them what is left of
// fhat - fhat(limit) is the map's own error along its unexcited directions (eigenvalues 1 up
// to lap_map_rtol) raised to the power of the lap count, which overflows: persistence of
// excitation's unexcited paths gave 2.9e17 laps and a sampled state error of +inf. 2^62 for a
// map that does not contract (no finite time constant).
std::uint64_t meaningful_laps(double slowest_time_constant_laps, Eigen::Index dimension) {
  constexpr auto most = std::uint64_t{1} << 62;
  if (!std::isfinite(slowest_time_constant_laps)) return most;
  const double laps =
      std::max(50.0 * slowest_time_constant_laps, 2.0 * static_cast<double>(dimension));
  return laps >= static_cast<double>(most) ? most : static_cast<std::uint64_t>(std::ceil(laps));
}

// Lap numbers 2 .. laps - 2 at which the lap map's state is sampled: every lap up to 200 laps,
// beyond that about 50 per decade (rounded to whole laps).
std::vector<std::uint64_t> lap_boundaries(std::uint64_t laps) {
  std::vector<std::uint64_t> out;
  if (laps < 4) return out;
  const std::uint64_t last = laps - 2;
  if (last <= 200) {
    for (std::uint64_t k = 2; k <= last; ++k) out.push_back(k);
    return out;
  }
  for (double x = std::log10(2.0); x <= std::log10(static_cast<double>(last)); x += 0.02) {
    const auto k = static_cast<std::uint64_t>(std::llround(std::pow(10.0, x)));
    if (out.empty() || k > out.back()) out.push_back(std::min(k, last));
  }
  if (out.back() != last) out.push_back(last);
  return out;
}

// z after `laps` laps of `map` perturbed by its tolerance `rtol` (the limit for laps = 0: the
// trial's laps = "limit"), entry by entry with alternating signs: the spread under a
// perturbation of its inputs, a sample rather than a bound (1 / (1 - rho) times the tolerance
// bounds it but is orders of magnitude too pessimistic along the slow learning mode).
Eigen::VectorXd perturbed_state(const LapMap& map, const Eigen::VectorXd& z0, Eigen::Index d,
                                double rtol, bool limit, std::uint64_t laps) {
  LapMap perturbed = map;
  for (Eigen::Index j = 0; j < perturbed.monodromy.cols(); ++j)
    for (Eigen::Index i = 0; i < perturbed.monodromy.rows(); ++i)
      perturbed.monodromy(i, j) *= 1.0 + ((i + j) % 2 ? -1.0 : 1.0) * rtol;
  for (Eigen::Index i = 0; i < perturbed.offset.size(); ++i)
    perturbed.offset(i) *= 1.0 + (i % 2 ? -1.0 : 1.0) * rtol;
  if (limit) return periodic_limit(perturbed, z0, d, 100 * rtol, rtol).state;
  // N laps by squaring, one power at a time (no table of powers: no more memory than the map
  // itself).
  Eigen::VectorXd z = z0;
  Eigen::MatrixXd power = perturbed.monodromy;
  Eigen::VectorXd shift = perturbed.offset;  // z -> power z + shift is the map to the 2^k
  for (std::uint64_t left = laps; left != 0; left >>= 1) {
    if (left & 1u) z = (power * z + shift).eval();
    if (left > 1) {
      shift = (power * shift + shift).eval();
      power = (power * power).eval();
    }
  }
  return z;
}

}  // namespace

// Samples: the first lap and, for N laps, the last lap integrated with the study's integrator
// from the state the map gives (the last lap's end checks the map: lap_map_residual), and the
// lap boundaries in between from the map.
void RoadTrial::run_lap_map(LapMapCache* lap_maps, const std::string& key) {
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  const auto kink_times = path_kink_times(settings, domain, kinks);
  auto compute = [&] {
    return compute_lap_map(*system, lap_time, kink_times, settings.lap_map_atol,
                           settings.lap_map_rtol, std::numeric_limits<std::int64_t>::max());
  };
  bool computed_here = true;
  if (lap_maps) {
    auto found = lap_maps->find_or_compute(key, compute);
    lap_map = std::move(found.map);
    computed_here = found.computed_here;
  } else {
    lap_map = std::make_shared<const LapMap>(compute());
  }
  // A map computed by another trial: its cost is this trial's too (deterministic counts).
  if (!computed_here) {
    reused_rhs_evaluations = lap_map->rhs_evaluations;
    reused_jacobian_evaluations = lap_map->jacobian_evaluations;
  }
  stats.steps += lap_map->stats.steps;
  stats.rejected_steps += lap_map->stats.rejected_steps;
  stats.segments += lap_map->stats.segments;
  check_cancelled();
  const LapPowers powers(*lap_map);
  const Eigen::VectorXd z0 = z;
  const auto limit =
      periodic_limit(*lap_map, z0, d, 100 * settings.lap_map_rtol, settings.lap_map_rtol);
  metrics[M::learning_spectral_radius] = limit.spectral_radius;
  radius_uncertainty = limit.spectral_radius_uncertainty;
  metrics[M::slowest_time_constant_laps] = limit.slowest_time_constant_laps;
  metrics[M::unexcited_directions] = static_cast<double>(limit.unexcited_directions);
  for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i)
    if (settings.limit() || settings.snapshot_laps[i] <= settings.laps)  // the ones reached
      snapshot(i, powers.advance(z0, static_cast<std::uint64_t>(settings.snapshot_laps[i])).data());
  // Laps until fhat is within 1% (in L2 on the evaluation grid) of its limit.
  auto distance_to_limit = [&](std::uint64_t laps) {
    const Eigen::VectorXd state = powers.advance(z0, laps);
    const Eigen::VectorXd gap = on_grid(state.tail(coefficients) - limit.state.tail(coefficients));
    return domain.l2_norm(
        std::span<const double>(gap.data(), static_cast<std::size_t>(gap.size())));
  };
  const std::uint64_t laps_cap = meaningful_laps(limit.slowest_time_constant_laps, m);
  const auto laps_to_limit = laps_within(distance_to_limit, 0.01, laps_cap);
  if (laps_to_limit)
    metrics[M::laps_to_limit] = static_cast<double>(*laps_to_limit);
  else
    out.flags.push_back("laps_to_limit_unresolved");

  Eigen::VectorXd first = z0;
  integrate(first, adaptive_breakpoints(settings, domain, 0.0, lap_time, kinks,
                                        integrator.restarts_at_kinks(), /*snapshots=*/false));
  const std::uint64_t laps = settings.limit()
                                 ? std::max<std::uint64_t>(2, laps_to_limit.value_or(laps_cap))
                                 : static_cast<std::uint64_t>(settings.laps);
  for (std::uint64_t k : lap_boundaries(laps))
    sample(static_cast<double>(k) * lap_time, powers.advance(z0, k).data());
  if (settings.limit()) {
    z = limit.state;
  } else {
    z = powers.advance(z0, laps);
    if (laps >= 2) {
      // The system is periodic: the last lap is integrated over [0, T] (at t near N T the
      // spacing of doubles would be coarser than the plant's transients need) and its samples
      // are shifted to where they belong.
      Eigen::VectorXd last = powers.advance(z0, laps - 1);
      const double start = static_cast<double>(laps - 1) * lap_time;
      const std::size_t first_sample = out.samples.size();
      integrate(last, adaptive_breakpoints(settings, domain, 0.0, lap_time, kinks,
                                           integrator.restarts_at_kinks(), /*snapshots=*/false));
      for (std::size_t k = first_sample; k < out.samples.size(); ++k) out.samples[k].t += start;
      metrics[M::lap_map_residual] = (last - z).norm() / std::max(z.norm(), 1e-300);
    } else {
      metrics[M::lap_map_residual] = (first - z).norm() / std::max(z.norm(), 1e-300);
    }
  }
  std::sort(out.samples.begin(), out.samples.end(),
            [](const auto& a, const auto& b) { return a.t < b.t; });
  // The floor of what the map's powers or limit give: the same state from the perturbed map.
  lap_map_spread = perturbed_state(*lap_map, z0, d, settings.lap_map_rtol, settings.limit(),
                                   settings.limit() ? 0 : laps) -
                   z;
}

}  // namespace rkhs
