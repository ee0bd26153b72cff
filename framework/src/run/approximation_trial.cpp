// An approximation trial (rkhs/run/trial_kinds.hpp): the projection of the target onto the
// trial's space, measured on the evaluation grid; only the metrics the study asks for.
#include <exception>
#include <set>
#include <string>
#include <string_view>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/run/trial_cost.hpp"
#include "rkhs/run/trial_kinds.hpp"

namespace rkhs {
namespace {

double measure_approximation_trial(const TrialInputs& in, TrialResult& result) {
  const auto& study = in.study;
  const auto& trial = in.trial;
  const std::string_view projection =
      trial.projection.name.empty() ? default_projection : trial.projection.name;
  ApproximationMeasurement measured;
  if (projection == default_projection) {
    // Interpolation at the centres: one Gram factorisation serves the interpolant, the power
    // function (its norm ||I - Pi||_{H -> C}) and the operator, when asked for.
    measured = measure_approximation(in.kernel, in.target, in.centres, study.evaluation_points,
                                     study.solver, in.computed);
  } else {
    // An operator W, E measured by the framework, or a matrix-free projection measuring itself.
    const ProjectionRequest request{in.kernel, trial.n, in.centres, study.solver};
    measured = measure_projection_trial(projection, trial.projection.parameters, request, in.target,
                                        study.evaluation_points, in.computed);
  }
  result.metrics = std::move(measured.metrics).values();
  result.floors = std::move(measured.floors).values();
  result.solve_method = std::move(measured.solve_method);
  result.flags = std::move(measured.flags);
  return 0;
}

// Interpolation with a compactly supported kernel takes the sparse path when choose_sparse
// says so; a matrix-free projection predicts its own footprint (Projection::footprint, sparse
// when it gives one); everything else is dense.
TrialFootprint approximation_footprint(const StudyDefinition& study, const TrialSpec& trial) {
  TrialFootprint dense{trial_matrix_megabytes(trial.n, study.evaluation_points)};
  if (!(trial.projection.name.empty() || trial.projection.name == default_projection)) {
    try {
      const auto* entry = projection_registry().find(trial.projection.name);
      if (!entry) return dense;
      const auto kernel = make_kernel(trial.kernel.name, trial.kernel.parameters, study.domain);
      const auto predicted = entry->factory(trial.projection.parameters)
                                 ->footprint(*kernel, trial.n, study.evaluation_points);
      if (!predicted) return dense;
      return {predicted->megabytes, true, predicted->gram_nonzeros, predicted->factor_nonzeros,
              predicted->flops};
    } catch (const std::exception&) {
      return dense;  // the trial fails at once, with the reason
    }
  }
  if (study.solver.algebra == GramAlgebra::dense) return dense;
  try {
    const auto kernel = make_kernel(trial.kernel.name, trial.kernel.parameters, study.domain);
    if (!choose_sparse(*kernel, trial.n, study.solver,
                       work_needed<ApproximationMetric>(study.computed_metrics())))
      return dense;
    const auto factor = predict_sparse_factor(kernel->properties(), study.domain, trial.n);
    TrialFootprint sparse{sparse_trial_megabytes(factor.gram_nonzeros, factor.factor_nonzeros,
                                                 trial.n, study.evaluation_points),
                          true, factor.gram_nonzeros, factor.factor_nonzeros};
    // The factorisation, and a solve with L and one with L^T (the floors) per point solved:
    // every point, or about a hundred where the power function's sup comes from local bounds
    // (64 x 64 factorisations, one for about each centre, and a 64 x 64 solve per point).
    const auto points = static_cast<double>(study.evaluation_points);
    sparse.sparse_flops =
        factor.factor_flops + (floors_from_sample(trial.n, study.computed_metrics())
                                   ? 4.0 * factor.factor_nonzeros * 128.0 +
                                         1e5 * static_cast<double>(trial.n) + 8192.0 * points
                                   : 4.0 * factor.factor_nonzeros * points);
    return sparse;
  } catch (const std::exception&) {
    return dense;  // the trial fails at once, with the reason
  }
}

double approximation_cost(const StudyDefinition& study, const TrialSpec& trial,
                          std::set<std::string>*) {
  if (const auto footprint = approximation_footprint(study, trial); footprint.sparse)
    return footprint.sparse_flops;
  return approximation_trial_cost(trial.n, study.evaluation_points);
}

}  // namespace

const TrialKind approximation_trials{measure_approximation_trial, approximation_cost,
                                     approximation_footprint};

}  // namespace rkhs
