#pragma once
// Theorem 4.1 measured (docs/model.md section 15, docs/theorems.md): the finite-dimensional
// estimator of a projection Pi_j beside the infinite-dimensional one, on the same plant.
//
//   infinite (H itself, feature coordinates: the rkhs_embedding law):
//     xhat' = A xhat + B fhat(s),        fhat' = Gamma^-1 k(s, .) b^T (x - xhat)
//   finite (H_j = range of Pi_j, Gamma_j = Gamma on H_j):
//     xhat_j' = A xhat_j + B (Pi_j^* fhat_j)(s),  fhat_j' = Gamma^-1 Pi_j k(s, .) b^T (x - xhat_j)
//
// (Pi_j^* fhat_j)(s) = (fhat_j, Pi_j k(s, .))_H: the function the finite estimator feeds the
// plant model. For an H-orthogonal Pi_j it is fhat_j itself and Gamma_j = Pi_j Gamma Pi_j^* is
// Gamma on H_j, the paper's eq. (4.1)-(4.2) exactly; for another projection Gamma_j is taken as
// Gamma on H_j, which keeps V_j = 1/2 e^T P e + Gamma/2 ||fhat_j - f_j||_H^2 non-increasing
// for a road f = Pi_j^* f_j.
//
// Coordinates: a in an H-orthonormal basis q = b L^-T of H_j (G_B = E^T K_YY E = L L^T). The
// coordinates of Pi_j k(s, .) are r(s) = L^T W k(S, s), so the finite estimator is the gradient
// law a' = Gamma^-1 r(s) b^T e_j with the basis r (xhat_j' uses r(s)^T a), the same coupled
// system as every adaptive trial (rkhs/adaptive/adaptive.hpp). Pi_j^* fhat_j has the feature
// coordinates Phi_S^T R^T a (R = L^T W, Phi_S the features at S), in the range of the features
// as beta is, so ||fhat - Pi_j^* fhat_j||_H = |beta - Phi_S^T R^T a| exactly.
//
// Both systems are integrated by the same integrator through the same breakpoints (the trial's
// samples, its snapshots and the kinks), each with its own copy of the plant: plant_gap is how
// far the two copies of x drift apart, the integration's share of every gap.

#include <cstddef>
#include <span>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/approx/projection.hpp"

namespace rkhs {

/// The gaps between the two estimators, sup over the breakpoints of [0, T].
struct EstimateGaps {
  double estimate_gap_H = 0;  ///< sup_t ||fhat(t) - Pi_j^* fhat_j(t)||_H
  double estimate_gap_C = 0;  ///< sup_t max over the evaluation grid of |fhat - Pi_j^* fhat_j|
  double state_gap = 0;       ///< sup_t |xhat(t) - xhat_j(t)|
  double plant_gap = 0;       ///< sup_t |x(t) - x_j(t)| (0 up to the integration's error)
  /// ||f - Pi_j^* fhat_j(T)|| in L2(Omega) on the evaluation grid.
  double projected_l2_error = 0;
  /// sup over the evaluation grid of ||(I - Pi_j)^* k(s, .)||_H = ||I - Pi_j||_{H -> C}.
  double projection_norm_H_to_C = 0;
  double projection_operator_norm = 0;  ///< ||Pi_j||_{H -> H}
  /// projection_norm_H_to_C is below its round-off floor sqrt(|S| eps max k(s, s)).
  bool projection_norm_at_floor = false;
  /// The gaps are within 10x the integration's own discrepancy: estimate_gap_H / sup_t |beta|
  /// <= 10 plant_gap / sup_t |x| (the two plant copies drift apart by the integration error).
  bool gaps_at_integration_floor = false;
  /// The floors of the values above (FloorRule; docs/metrics.md "Floors"): the gaps' from the
  /// integration, rtol (of settings.integrator_rtol, 0 when unknown) at the scale of the
  /// integrated state plus 10 times the plants' relative discrepancy; the norms' round-off.
  double estimate_gap_H_floor = 0, estimate_gap_C_floor = 0, state_gap_floor = 0,
         plant_gap_floor = 0, projected_l2_error_floor = 0, projection_norm_floor = 0,
         projection_operator_norm_floor = 0;
  std::size_t dimension = 0;    ///< dim H_j
  std::size_t breakpoints = 0;  ///< times at which the gaps were taken
};

/// Runs both estimators of the file comment for `op` (built for `kernel`) from z = 0 and
/// measures their gaps. `kernel` must have a finite feature map (H is then finite-dimensional
/// and the infinite estimator exact), or be a ReferenceResolvedKernel (H_N standing in for H:
/// the H gap is then taken over the sections at its centres and at S, with their Gram matrix); the
/// road is `target` (f); the time stepping is that of `settings` (its laps or final time,
/// samples_per_lap and snapshot laps; laps = "limit" is refused). Throws std::invalid_argument for
/// a kernel without features, a singular basis Gram G_B, or the limit; std::runtime_error when an
/// integration fails.
EstimateGaps measure_estimate_gaps(const AnyKernel& kernel, const TargetFunction& target,
                                   const ProjectionOperator& op, const class Plant& plant,
                                   const class LearningLaw& law, const Integrator& integrator,
                                   const AdaptiveSettings& settings, std::size_t evaluation_points);

/// Writes the gaps into the trial's metrics (the Theorem 4.1 rows of the adaptive table, with
/// gap_effectivity_* = gap / projection_norm_H_to_C) and its flags: projection_norm_at_floor,
/// estimate_gap_at_integration_floor.
void record_estimate_gaps(const EstimateGaps& gaps, AdaptiveMeasurement& out);

}  // namespace rkhs
