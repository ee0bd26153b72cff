#pragma once
// The estimated cost of a trial, and the order in which trials are started: largest first, so
// that a long trial starts early instead of ending a run alone. The one estimate that both
// schedulers use: the local oneTBB scheduler (run_trials, rkhs/run/run.hpp) and the MPI runner
// (framework/mpi/, which hands trials out in largest_first_order).
//
// The estimate is relative, not seconds: it only has to rank the trials of one study (which all
// have the same kind and the same [adaptive] settings). In units of floating-point operations,
// up to constants that differ between machines:
//
//   every trial      n^3 + n^2 E             Gram factorisation, solves at the E evaluation points
//   adaptive trials  + laps_integrated x steps_per_lap x step_cost(N),   N = 2d + n
//
// where d is the plant's state dimension (the system is z = [x, xhat, alpha]), step_cost is
// N^3 + N^2 for an implicit integrator with dense stage solves (one LU of the N x N Jacobian
// per step), and N^2 for an explicit one or one with structured stage solves (right-hand sides
// with a dense learning map dominate), as the integrator declares them
// (Integrator::properties(), rkhs/adaptive/adaptive.hpp), and laps_integrated depends on the engine
// (adaptive_engine_for): the horizon in laps (laps, or final_time v / L) when the trial steps
// through time, about N laps with a lap map (one lap of the state and its N sensitivities; the map
// is then iterated at a cost independent of the horizon). Steps per lap are taken as the same for
// every integrator (they depend on tolerances and stiffness, which the estimate does not model).

#include <cstddef>
#include <string>
#include <vector>

#include "rkhs/study/study.hpp"

namespace rkhs {

/// What the estimate of an adaptive trial depends on.
struct AdaptiveTrialShape {
  std::size_t n = 0;                ///< centres (coefficients alpha)
  std::size_t plant_dimension = 1;  ///< d
  double laps = 0;                  ///< the horizon in laps: final time x speed / track length
  bool implicit_integrator = true;  ///< one LU factorisation of the (2d + n) system per step
  bool structured_solves = false;   ///< ... unless its stage solves use the structure (O(N))
  /// The engine: the lap map (one lap with its 2d + n sensitivities, then the lap's affine map
  /// iterated), or stepping through every lap (false); the choice of measure_adaptive
  /// (adaptive_engine_for).
  bool lap_map = false;
};

/// The dense matrices of a trial with `n` centres and `evaluation_points` points, in MiB: the
/// Gram matrix (three n x n: itself, its factor or eigenvectors, a working copy) and the cross
/// matrix with its derivative (two n x E).
double trial_matrix_megabytes(std::size_t n, std::size_t evaluation_points) noexcept;

/// The matrices a trial holds at its peak, predicted from the study alone before anything is
/// built, on the path the trial will take. run_trial fails a trial above
/// limits.matrix_megabytes before it builds anything, and `validate` names such trials from
/// this alone.
struct TrialFootprint {
  double megabytes = 0;
  /// An approximation trial on the sparse path (a compactly supported kernel; `[linear_algebra]
  /// solver`): its Gram matrix's and Cholesky factor's predicted nonzeros. Dense otherwise
  /// (trial_matrix_megabytes).
  bool sparse = false;
  double gram_nonzeros = 0, factor_nonzeros = 0;
  /// The predicted flops of the sparse factorisation and of the solves at the evaluation points.
  double sparse_flops = 0;
  /// "dense: 3 n x n and 2 n x E matrices", "sparse: 1.2e+08 nonzeros in G, 3.4e+09 in its
  /// Cholesky factor (predicted)": what the estimate counts, for messages.
  std::string describe() const;
};

/// The footprint of `trial` of `study` (the kind's own, trial_kinds.hpp). Never throws for a
/// trial of study.trials(): a trial whose kernel cannot be made is estimated dense (it fails
/// at once).
TrialFootprint trial_footprint(const StudyDefinition& study, const TrialSpec& trial);

/// The sparse path's peak memory, MiB, from its predicted nonzeros (sparse_gram.hpp): the Gram
/// matrix with its assembly, CHOLMOD's permuted copy of its upper triangle and its supernodal
/// factor, the sparse cross matrix of a chunk of evaluation points with its assembly (about
/// gram_nonzeros / n nonzeros per point, at most about 2^23 in a chunk) and the dense blocks of
/// the solves.
double sparse_trial_megabytes(double gram_nonzeros, double factor_nonzeros, std::size_t n,
                              std::size_t evaluation_points) noexcept;

/// The estimate of an approximation trial with `n` centres and `evaluation_points` points.
double approximation_trial_cost(std::size_t n, std::size_t evaluation_points) noexcept;

/// The estimate of an adaptive trial of `shape` with `evaluation_points` points.
double adaptive_trial_cost(const AdaptiveTrialShape& shape, std::size_t evaluation_points) noexcept;

/// The shape of adaptive trial `trial` of `study`: its plant's dimension (1 when the plant
/// cannot be made: the trial then fails at once), its horizon, whether its integrator is
/// implicit (an integrator that does not say is taken as implicit), whether its stage solves
/// are structured, and its engine.
AdaptiveTrialShape adaptive_trial_shape(const StudyDefinition& study, const TrialSpec& trial);

/// The estimated cost of `trial` of `study` (see the file comment): relative, not seconds;
/// increasing in n and, for adaptive trials stepped through time, in the horizon. Never throws
/// for a trial of study.trials().
double estimated_trial_cost(const StudyDefinition& study, const TrialSpec& trial);

/// The trial's key without its lap count: what identifies its lap map among the trials of a
/// run (trials on a laps axis share one, rkhs/adaptive/lap_map.hpp).
std::string lap_map_key(const TrialSpec& trial);

/// The positions of `trials` ordered by estimated cost, largest first (ties keep grid order):
/// the order in which both schedulers start trials. Of the trials that share a lap map, the
/// first in grid order carries the map's cost and the others only their own laps, so the maps
/// are computed first and, on several threads, not twice at once.
std::vector<std::size_t> largest_first_order(const StudyDefinition& study,
                                             const std::vector<TrialSpec>& trials);

}  // namespace rkhs
