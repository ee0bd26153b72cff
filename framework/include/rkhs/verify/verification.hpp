#pragma once
// Verdicts on a finished study's expectations (rkhs/study/expectation.hpp), for `rkhs-study check`
// and CI. docs/verification.md defines every rule; in short, with [lo, hi] the accepted
// interval of a rate and [cl, ch] the fit's 95% confidence interval on its asymptotic window:
//
//   pass          lo <= cl and ch <= hi        (the whole CI is acceptable)
//   fail          ch < lo or cl > hi           (no value in the CI is acceptable)
//   inconclusive  otherwise, or fewer than 3 points in the window, or (theory) centres that
//                 are not quasi-uniform, or (model) a model choice that is not decisive.
//
// A bound metric <= C by [times] passes when every effectivity metric / (C by times) is <= 1
// and fails otherwise; without a usable point it is inconclusive.
//
// `check` exits 0 when every verdict is a pass, 1 when any is a fail (and, with --strict, when
// any is inconclusive), 3 when none fails but some are inconclusive.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/study/expectation.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/verify/study_rates.hpp"

namespace rkhs {

enum class Verdict { pass, fail, inconclusive };

/// "PASS", "FAIL", "INCONCLUSIVE".
std::string_view verdict_name(Verdict verdict);

/// The verdict of one expectation on one group it selects.
struct ExpectationOutcome {
  const Expectation* expectation = nullptr;  ///< points into StudyDefinition::expectations
  std::size_t series = 0;   ///< index of the judged MetricSeries (the expectation's metric)
  std::string group;        ///< the group's key (every axis but n)
  std::string group_label;  ///< the axes that tell this group from the study's others
  Verdict verdict = Verdict::inconclusive;
  std::string expected;  ///< what was expected and where it comes from
  std::string found;     ///< what the study shows: fit, CI, window, exclusions, model choice
  std::string reason;    ///< why this verdict, one clause
  // The judged numbers (NaN where they do not apply), for machine-readable reports.
  double rate = 0.0, ci_low = 0.0, ci_high = 0.0;
  double accepted_low = 0.0, accepted_high = 0.0;
  double effectivity_min = 0.0, effectivity_max = 0.0;  ///< bounds only
  std::size_t window_points = 0;
  std::size_t window_from = 0, window_to = 0;  ///< n range of the window (0 when none)
};

/// Judges every expectation of `study` on every group it selects, in file order. `rates` is
/// compute_rates(study, trials, results). Never throws for study results (bad values give
/// inconclusive or failing verdicts with their reason); std::bad_alloc aside.
std::vector<ExpectationOutcome> verify_expectations(const StudyDefinition& study,
                                                    const std::vector<TrialSpec>& trials,
                                                    const std::vector<TrialResult>& results,
                                                    const std::vector<MetricSeries>& rates);

struct VerdictCounts {
  std::size_t passed = 0, failed = 0, inconclusive = 0;
};
VerdictCounts count_verdicts(const std::vector<ExpectationOutcome>& outcomes);

/// 0 all pass (or nothing to check), 1 any fail (strict: or any inconclusive), 3 otherwise.
int check_exit_code(const VerdictCounts& counts, bool strict);

/// The console report: per outcome "VERDICT  #k metric, group (file:line:column)" with the
/// expected / found / verdict lines below, then "N passed, M failed, K inconclusive".
std::string format_verification(const std::vector<ExpectationOutcome>& outcomes, bool strict);

}  // namespace rkhs
