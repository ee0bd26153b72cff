#pragma once
// Adaptive trials of state-dependent plants (docs/model.md section 18): f is a function of the
// plant's read-out y = c^T x + y0 in the study's domain Omega = [0, L] (or the circle of that
// length), learnt along the trajectory the plant itself follows:
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
//   the visited set    [min y, max y] over the samples: path_l2_error is the L2 error there,
//                      off_path_l2_error on the rest of Omega;
//   the excitation     E = mean over the samples of phi(y) phi(y)^T, the time average of the
//                      rectangle rule in time (adaptive.samples_per_lap sets its resolution):
//                      pe_level = lambda_min of E a = lambda G a and unexcited_dimension its
//                      eigenvalues at round-off (rkhs/adaptive/excitation.hpp); a trajectory
//                      that leaves directions unexcited is flagged not_persistently_excited.
// A read-out outside [0, L] on an interval is flagged readout_left_domain (f and the kernel
// sections are evaluated there, by extension).

#include <span>

#include "rkhs/adaptive/adaptive.hpp"

namespace rkhs {

/// measure_adaptive for a plant with plant.state_dependent(): the same metrics, with the
/// visited set of the trajectory as the path. Throws std::invalid_argument for settings the
/// state-dependent trial cannot run (laps = "limit" or the lap map, a shuttle path, no lap
/// length: a plant without a period and no final_time; a law in feature coordinates), and
/// std::runtime_error for a failed integration.
AdaptiveMeasurement measure_state_dependent(
    const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
    const class Plant& plant, const class LearningLaw& law, const Integrator& integrator,
    const AdaptiveSettings& settings, std::size_t evaluation_points,
    const struct SolverOptions& solver, const Integrator* reference = nullptr);

/// The reason `settings` (with a plant of period `period`) cannot run a state-dependent trial,
/// or an empty string. Study files are checked with it before anything runs.
std::string state_dependent_settings_error(const AdaptiveSettings& settings, double period);

}  // namespace rkhs
