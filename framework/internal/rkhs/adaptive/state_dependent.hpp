#pragma once
// Adaptive trials of state-dependent plants (docs/model.md section 18): f is a function of the
// plant's read-out y = C x + y0 in the study's domain Omega (p = d read-out coordinates: [0, L]
// or the circle of that length in d = 1, a box or a torus in d = 2, 3), learnt along the
// trajectory the plant itself follows:
//
//   x'     = A x    + h(t, x) + B f(y)
//   xhat'  = A xhat + h(t, x) + B fhat(y),   fhat = sum_i alpha_i k(c_i, .)
//   alpha' = Gamma^-1 phi(y) B^T P (x - xhat)              (gradient law)
//          = Gamma^-1 G^-1 phi(y) B^T P (x - xhat)         (rkhs law)
//
// The system is nonlinear (f(y) and phi(y) depend on x), so there is no lap map: the trial steps
// through time with the study's integrator, and implicit integrators use the exact Jacobian
// (kernel and target derivatives in y) with dense stage solves. One lap is one period of the
// plant's forcing (Plant::period), or the final time for a plant without one.
//
// Where the trajectory goes decides what is learnt. Over the second half of the run:
//   the visited set    in d = 1, [min y, max y] over the samples; in d > 1 (a read-out of d
//                      coordinates, y = C x + y0 in a box or torus) the points within the
//                      centres' fill distance h_X of the polyline through the sampled
//                      read-outs (visited_neighbourhood): the kernel's sections reach about that
//                      far from where data was seen. path_l2_error is the L2 error there,
//                      off_path_l2_error on the rest of Omega;
//   the excitation     E = mean over the samples of phi(y) phi(y)^T, the time average of the
//                      rectangle rule in time (adaptive.samples_per_lap sets its resolution):
//                      pe_level = lambda_min of E a = lambda G a and unexcited_dimension its
//                      eigenvalues at round-off (rkhs/adaptive/excitation.hpp); a trajectory
//                      that leaves directions unexcited is flagged not_persistently_excited.
// A read-out outside [0, L] on an interval (outside the box in d > 1) by more than 1e-6 of the
// extent is flagged readout_left_domain (f and the kernel sections are evaluated there, by
// extension). In d > 1
// the gradient of f in the exact Jacobian is a central difference (step 1e-6 of each axis'
// extent), that of Pi_n f (adaptive.road = "projected") the sections' closed-form gradients;
// estimate snapshots (profiles along d = 1) are not taken.

#include <span>
#include <string>
#include <vector>

#include "rkhs/adaptive/adaptive.hpp"

namespace rkhs {

/// measure_adaptive for a plant with plant.state_dependent(): the same metrics, with the
/// visited set of the trajectory as the path. Throws std::invalid_argument for a plant whose
/// read-out has other than d = domain.dimension coordinates, snapshots in d > 1, settings the
/// state-dependent trial cannot run (laps = "limit" or the lap map, a shuttle path, no lap
/// length: a plant without a period and no final_time; a law in feature coordinates), and
/// std::runtime_error for a failed integration.
AdaptiveMeasurement measure_state_dependent(
    const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
    const class Plant& plant, const class LearningLaw& law, const Integrator& integrator,
    const AdaptiveSettings& settings, std::size_t evaluation_points,
    const struct SolverOptions& solver, const Integrator* reference = nullptr);

/// For each point of `points` (flat: d = domain.dimension values each), whether it lies within
/// `reach` of the polyline through `path` (flat, its consecutive points joined by straight
/// segments; one point: a ball). On a periodic domain each segment and each distance is taken
/// with the shortest representatives of the coordinate differences (Domain::difference), which
/// assumes segments shorter than half of every period. The visited set of a read-out in d > 1.
std::vector<bool> visited_neighbourhood(const Domain& domain, std::span<const double> path,
                                        std::span<const double> points, double reach);

/// The reason `settings` (with a plant of period `period`) cannot run a state-dependent trial,
/// or an empty string. Study files are checked with it before anything runs.
std::string state_dependent_settings_error(const AdaptiveSettings& settings, double period);

}  // namespace rkhs
