// An approximation trial (rkhs/run/trial_kinds.hpp): the projection of the target onto the
// trial's space, measured on the evaluation grid; only the metrics the study asks for.
#include <set>
#include <string>
#include <string_view>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/projection.hpp"
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
    measured = measure_projection_trial(projection, trial.projection.parameters, request,
                                        in.target, study.evaluation_points, in.computed);
  }
  result.metrics = std::move(measured.metrics).values();
  result.floors = std::move(measured.floors).values();
  result.solve_method = std::move(measured.solve_method);
  result.flags = std::move(measured.flags);
  return 0;
}

double approximation_cost(const StudyDefinition& study, const TrialSpec& trial,
                          std::set<std::string>*) {
  return approximation_trial_cost(trial.n, study.evaluation_points);
}

}  // namespace

const TrialKind approximation_trials{measure_approximation_trial, approximation_cost};

}  // namespace rkhs
