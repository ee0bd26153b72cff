// An adaptive trial (rkhs/run/trial_kinds.hpp): the estimator and its learning law driven by
// the plant (rkhs/adaptive/adaptive.hpp), with the finite estimator of the trial's projection
// beside it when the study has [[projection]] (Theorem 4.1), and the reference integration of
// integration_error when it has one.
#include <algorithm>
#include <memory>
#include <set>
#include <string>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/finite_to_infinite.hpp"
#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/reference_resolution.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/run/trial_cost.hpp"
#include "rkhs/run/trial_kinds.hpp"

namespace rkhs {
namespace {

double measure_adaptive_trial(const TrialInputs& in, TrialResult& result) {
  const auto& study = in.study;
  const auto& trial = in.trial;
  const auto& own = trial.adaptive_axes();
  const auto& study_reference = study.adaptive_axes().reference;
  const auto plant = plant_registry().find(own.plant.name)->factory(own.plant.parameters);
  const auto law = law_registry().find(own.law.name)->factory(own.law.parameters);
  const auto integrator =
      integrator_registry().find(own.integrator.name)->factory(own.integrator.parameters);
  // The reference integrator of integration_error, when the study has one.
  std::unique_ptr<Integrator> reference;
  if (!study_reference.name.empty())
    reference =
        integrator_registry().find(study_reference.name)->factory(study_reference.parameters);
  // rkhs_embedding with a kernel without features: H_N at the law's reference resolution
  // stands in for H (rkhs/adaptive/reference_resolution.hpp).
  std::unique_ptr<ReferenceResolvedKernel> resolved;
  if (law->coordinates() == LawCoordinates::features && in.kernel.feature_count() == 0 &&
      law->reference_resolution() > 0)
    resolved = std::make_unique<ReferenceResolvedKernel>(in.kernel, law->reference_resolution());
  const AnyKernel& law_kernel = resolved ? *resolved : in.kernel;
  // The study's settings with this trial's lap count (a laps axis).
  auto measured = measure_adaptive(law_kernel, in.target, in.centres, *plant, *law, *integrator,
                                   trial_adaptive_settings(study, trial), study.evaluation_points,
                                   study.solver, reference.get(), in.lap_maps,
                                   in.lap_maps ? lap_map_key(trial) : std::string());
  if (!trial.projection.name.empty()) {
    // Theorem 4.1: the finite estimator of the trial's projection beside the law's own
    // (infinite-dimensional) one, on the same breakpoints.
    const ProjectionRequest request{in.kernel, trial.n, in.centres, study.solver};
    const auto op = build_projection(trial.projection.name, trial.projection.parameters, request);
    check_cancelled();
    const auto gaps =
        measure_estimate_gaps(law_kernel, in.target, op, *plant, *law, *integrator,
                              trial_adaptive_settings(study, trial), study.evaluation_points);
    record_estimate_gaps(gaps, measured);
  }
  if (resolved) {
    const auto grid = study.domain.uniform_points(study.evaluation_points);
    measured.metrics[AdaptiveMetric::reference_norm_H_to_C] = resolved->norm_H_to_C(grid);
    measured.floors[AdaptiveMetric::reference_norm_H_to_C] =
        projection_norm_floor(in.kernel, law->reference_resolution(), grid);
  }
  // integration_error is the integrator's actual error, which follows its step sequence:
  // across processors and glibc's code paths it moved by up to a factor of 2 (1.07e-7
  // against 5.26e-8), so it is known to its order of magnitude (a floor of 0.9 times its
  // value, which flags nothing), and not below the reference's own tolerance (flagged).
  if (reference) {
    double& floor = measured.floors[AdaptiveMetric::integration_error];
    floor = 0.9 * measured.metrics[AdaptiveMetric::integration_error];
    for (const auto& [name, value] : study_reference.parameters.values())
      if (name == "rtol") floor = std::max(floor, study_reference.parameters.real(name));
  }
  result.metrics = std::move(measured.metrics).values();
  result.floors = std::move(measured.floors).values();
  result.solve_method = std::move(measured.solve_method);
  result.engine = measured.engine;
  result.flags = std::move(measured.flags);
  result.samples = std::move(measured.samples);
  result.road = std::move(measured.road);
  result.snapshots = std::move(measured.snapshots);
  return measured.reference_seconds;
}

// With `shared`: a lap map already counted for a trial ordered before (the same trial but for
// its lap count) is shared, and this trial integrates only its first and last laps.
double adaptive_cost(const StudyDefinition& study, const TrialSpec& trial,
                     std::set<std::string>* shared) {
  auto shape = adaptive_trial_shape(study, trial);
  if (shared && shape.lap_map && !shared->insert(lap_map_key(trial)).second) {
    shape.lap_map = false;
    shape.laps = 2;
  }
  return adaptive_trial_cost(shape, study.evaluation_points);
}

// Adaptive trials are dense.
TrialFootprint adaptive_footprint(const StudyDefinition& study, const TrialSpec& trial) {
  return {trial_matrix_megabytes(trial.n, study.evaluation_points)};
}

}  // namespace

const TrialKind adaptive_trials{measure_adaptive_trial, adaptive_cost, adaptive_footprint};

}  // namespace rkhs
