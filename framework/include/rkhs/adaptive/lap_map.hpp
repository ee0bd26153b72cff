#pragma once
// The lap map of an adaptive trial (docs/model.md, "the lap map"). With s(t) = (v t) mod L the
// coupled system z' = J(t) z + g(t) is linear and periodic in t with period T = L / v, so one
// lap is an affine map
//   z((k + 1) T) = Phi z(k T) + c,
// Phi the monodromy matrix (the states after one lap that start at the columns of I, forcing
// off) and c the state after one lap from z = 0 (forcing on). Both come from one integration
// of the dimension() + 1 columns [I | 0] over one lap, with shared Radau IIA steps and
// structured stage solves. N laps are then the N-th power of the augmented matrix
//   [ Phi  c ]
//   [  0   1 ],
// applied through its binary powers, and laps = "limit" is its fixed point.

#include <Eigen/Dense>
#include <cstdint>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "rkhs/adaptive/adaptive.hpp"

namespace rkhs {

struct LapMap {
  Eigen::MatrixXd monodromy;  ///< Phi, dimension() x dimension()
  Eigen::VectorXd offset;     ///< c
  IntegrationStats stats;     ///< of the one lap integrated (all columns share its steps)
  std::size_t rhs_evaluations = 0;       ///< the system's, spent on this map
  std::size_t jacobian_evaluations = 0;  ///< likewise
};

/// Lap maps shared by the trials of one run that differ only in their lap count (a laps
/// axis): the first trial that asks for a key computes the map, trials asking for the same key
/// meanwhile wait for it, later ones reuse it. The map is deterministic and carries its own
/// cost (stats, evaluations), so sharing changes no result. Thread-safe; an exception of the
/// computation reaches every trial that asked for the key.
class LapMapCache {
 public:
  /// A map from the cache, and whether this call computed it (false: another call did, and
  /// the caller's system has not been integrated for it).
  struct Found {
    std::shared_ptr<const LapMap> map;
    bool computed_here = false;
  };
  /// The map under `key`: computed by `compute` on the first call, waited for by calls that
  /// come while it is computed, shared afterwards. An exception of `compute` reaches every
  /// call for that key.
  Found find_or_compute(const std::string& key, const std::function<LapMap()>& compute);

 private:
  std::mutex mutex_;
  std::map<std::string, std::shared_future<std::shared_ptr<const LapMap>>> maps_;
};

/// Integrates one lap [0, lap_time] of `system` for the columns [I | 0]: Radau IIA (order 5)
/// at the tolerances given, landing on `breakpoints` (times in (0, lap_time) where phi(s(t))
/// or f(s(t)) have kinks). Throws std::runtime_error as Integrator::integrate does.
LapMap compute_lap_map(AdaptiveSystem& system, double lap_time,
                       std::span<const double> breakpoints, double atol, double rtol,
                       std::int64_t max_steps);

/// The augmented map's binary powers A^(2^k), k = 0..63, computed once (64 squarings of a
/// (dimension() + 1)^2 matrix); advance() then costs O(bits of N x dimension()^2).
class LapPowers {
 public:
  explicit LapPowers(const LapMap& map);
  /// The state after `laps` laps from z0.
  Eigen::VectorXd advance(const Eigen::VectorXd& z0, std::uint64_t laps) const;

 private:
  std::vector<Eigen::MatrixXd> powers_;
};

/// The periodic steady state: the fixed point z* = Phi z* + c reached from z0. Directions in
/// which one lap changes nothing (eigenvalue 1 of Phi: coefficients that the path never
/// excites, e.g. the null space of a singular Gram matrix) keep their initial value: z* - z0 is
/// the minimum-norm solution of (I - Phi)(z* - z0) = Phi z0 + c - z0, singular values of
/// I - Phi below `cutoff` (relative to the largest, at least 1) counted as zero.
struct PeriodicLimit {
  Eigen::VectorXd state;              ///< z*
  std::size_t unexcited_directions;   ///< singular values of I - Phi counted as zero
  double spectral_radius;             ///< of the learning block of Phi (xhat, alpha), its
                                      ///< eigenvalues within `cutoff` of 1 left out
  double slowest_time_constant_laps;  ///< -1 / ln(spectral_radius)
  /// First-order bound on the error of spectral_radius from an error `map_error ||Phi||_2` in
  /// Phi: `map_error ||Phi||_2 / s` with `s = |y^T x| / (|x| |y|)` the condition of the
  /// eigenvalue that attains it (x, y its right and left eigenvectors; Wilkinson). NaN when no
  /// eigenvalue is left (radius 0).
  double spectral_radius_uncertainty;
};
PeriodicLimit periodic_limit(const LapMap& map, const Eigen::VectorXd& z0,
                             Eigen::Index plant_dimension, double cutoff, double map_error);

}  // namespace rkhs
