#pragma once
// The run layer's part of a study kind's table entry (rkhs/study/study_kind.hpp): how a trial
// of the kind is measured, and what it is estimated to cost. run_trial does what every trial
// shares (limits, its kernel, target and centres, floors, the NaN and overflow checks, failure
// capture) and hands the rest to the kind; the schedulers order trials by the kind's cost.

#include <set>
#include <string>
#include <vector>

#include "rkhs/adaptive/lap_map.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/run/trial_cost.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs {

/// What a kind's measurement starts from: the trial, with what every trial builds first.
struct TrialInputs {
  const StudyDefinition& study;
  const TrialSpec& trial;
  const MetricSelection& computed;  ///< the metrics to compute (StudyDefinition::computed_metrics)
  const AnyKernel& kernel;
  const TargetFunction& target;
  const std::vector<double>& centres;  ///< placed by the trial's centre placement
  LapMapCache* lap_maps;               ///< shared by the trials of one run, or nullptr
};

struct TrialKind {
  /// Fills `result`'s metrics, floors, flags, solve method and the kind's own outputs (floors
  /// are raised to flags afterwards, by run_trial). Throws for a failed trial. Returns the
  /// seconds of work the trial's recorded time leaves out (a reference integration).
  double (*measure)(const TrialInputs& inputs, TrialResult& result);
  /// The estimated cost of `trial` in flops (rkhs/run/trial_cost.hpp). With `shared`, the keys
  /// of work shared by several trials (a lap map) already counted for trials ordered before it:
  /// the kind counts shared work once and adds the key.
  double (*cost)(const StudyDefinition& study, const TrialSpec& trial,
                 std::set<std::string>* shared);
  /// The matrices `trial` holds at its peak (rkhs/run/trial_cost.hpp), predicted before
  /// anything is built. Never throws for a trial of study.trials().
  TrialFootprint (*footprint)(const StudyDefinition& study, const TrialSpec& trial);
};

/// The entry of `kind`.
const TrialKind& trial_kind(StudyKind kind) noexcept;

/// The entries of the kinds this framework has (run/approximation_trial.cpp,
/// run/adaptive_trial.cpp).
extern const TrialKind approximation_trials;
extern const TrialKind adaptive_trials;

}  // namespace rkhs
