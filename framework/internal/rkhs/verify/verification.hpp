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
// An expectation marked `xfail = "reason"` is known not to hold: its fail is an XFAIL (does
// not fail `check`), its pass an XPASS (reported; a failure with --strict), as pytest's xfail.
//
// `check` exits 0 when every verdict is a pass, 1 when any is a fail (and, with --strict, when
// any is inconclusive or an XPASS), 3 when none fails but some are inconclusive (0 with
// --allow inconclusive), 5 when -k selected none of the expectations.

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
  std::string name;         ///< the test case's stable name (ExpectationCase::name)
  /// What the verdict cost: the wall time of the group's trials (as recorded when they ran,
  /// also for trials reused from the store) plus the time to judge it.
  double seconds = 0;
  Verdict verdict = Verdict::inconclusive;
  std::string expected;  ///< what was expected and where it comes from
  std::string found;     ///< what the study shows: fit, CI, window, exclusions, model choice
  std::string reason;    ///< why this verdict, one clause
  /// For a FAIL or INCONCLUSIVE verdict on a fitted rate: what the fit saw and what would
  /// decide it (verdict_advice), one line; "" for a pass or when the fit suggests nothing.
  std::string advice;
  // The judged numbers (NaN where they do not apply), for machine-readable reports.
  double rate = 0.0, ci_low = 0.0, ci_high = 0.0;
  double accepted_low = 0.0, accepted_high = 0.0;
  /// A bound: the effectivities metric / bound; a reference: the ratios metric / reference.
  double effectivity_min = 0.0, effectivity_max = 0.0;
  std::size_t window_points = 0;
  std::size_t window_from = 0, window_to = 0;  ///< n range of the window (0 when none)
};

// The fields of a judged expectation (an ExpectationOutcome with its Expectation) as one table,
// in the order summary.json writes them. The summary.json writer (summary_json.cpp), its reader
// (summary_verdicts.cpp, `rkhs-study report`) and the Python module's outcome dicts
// (python/src/module.cpp) all iterate it: adding a field is one row here.

/// What a field holds, and so how each writer and reader converts it.
enum class OutcomeFieldType {
  text,           ///< a string (`outcome_text` or `expectation_text`)
  optional_text,  ///< a string; null in summary.json when empty ("" in Python)
  number,         ///< a double (`number`): summary.json's json_number (null for NaN, "inf")
  seconds,        ///< a double (`number`) summary.json rounds to 0.1 ms
  verdict,        ///< ExpectationOutcome::verdict: "pass", ... in summary.json, verdict_name in
                  ///< Python
  kind,           ///< Expectation::kind, as expectation_kind_name names it
  window,         ///< {"from": n or null, "to": n or null, "points": count}: window_from,
                  ///< window_to (0 for null) and window_points
  outcome,        ///< case_outcome_id(case_outcome(o)): derived from the verdict, not read back
  summary,        ///< verdict_numbers(o): derived, not read back
};

/// One field: its key, its type, where it appears and the member that holds it (of the outcome,
/// or of its expectation: one expectation's fields are shared by the outcomes of its groups).
/// The derived types (verdict, kind, window, outcome, summary) name no member.
struct OutcomeField {
  /// Where a field appears: bits of `places`.
  static constexpr unsigned in_summary_json = 1u;  ///< summary.json (and read back from it)
  static constexpr unsigned in_python = 2u;        ///< the Python module's outcome dicts

  std::string_view key;
  OutcomeFieldType type;
  unsigned places = in_summary_json | in_python;
  std::string ExpectationOutcome::*outcome_text = nullptr;
  std::string Expectation::*expectation_text = nullptr;
  double ExpectationOutcome::*number = nullptr;

  bool in(unsigned place) const { return (places & place) != 0; }
  /// Held by the expectation (read once per expectation when summary.json is read back).
  bool of_expectation() const {
    return expectation_text != nullptr || type == OutcomeFieldType::kind;
  }
  /// The text of a text or optional_text field.
  const std::string& text(const ExpectationOutcome& o) const {
    return outcome_text ? o.*outcome_text : o.expectation->*expectation_text;
  }
};

namespace outcome_field_detail {
using enum OutcomeFieldType;
using O = ExpectationOutcome;
using E = Expectation;
inline constexpr unsigned summary_json_only = OutcomeField::in_summary_json;
inline constexpr unsigned python_only = OutcomeField::in_python;
// clang-format off
inline constexpr OutcomeField fields[] = {
    {.key = "name",             .type = text,          .outcome_text = &O::name},
    {.key = "expectation_name", .type = optional_text, .places = summary_json_only, .expectation_text = &E::name},
    {.key = "metric",           .type = text,          .expectation_text = &E::metric},
    {.key = "kind",             .type = kind,          .places = summary_json_only},
    {.key = "location",         .type = text,          .expectation_text = &E::location},
    {.key = "group",            .type = text,          .outcome_text = &O::group},
    {.key = "group_label",      .type = text,          .outcome_text = &O::group_label},
    {.key = "verdict",          .type = verdict},
    {.key = "outcome",          .type = outcome},
    {.key = "xfail",            .type = optional_text, .expectation_text = &E::xfail},
    {.key = "summary",          .type = summary,       .places = python_only},
    {.key = "rate",             .type = number,        .number = &O::rate},
    {.key = "ci_low",           .type = number,        .number = &O::ci_low},
    {.key = "ci_high",          .type = number,        .number = &O::ci_high},
    {.key = "accepted_low",     .type = number,        .number = &O::accepted_low},
    {.key = "accepted_high",    .type = number,        .number = &O::accepted_high},
    {.key = "effectivity_min",  .type = number,        .number = &O::effectivity_min},
    {.key = "effectivity_max",  .type = number,        .number = &O::effectivity_max},
    {.key = "window",           .type = window,        .places = summary_json_only},
    {.key = "expected",         .type = text,          .outcome_text = &O::expected},
    {.key = "found",            .type = text,          .outcome_text = &O::found},
    {.key = "reason",           .type = text,          .outcome_text = &O::reason},
    {.key = "advice",           .type = optional_text, .outcome_text = &O::advice},
    {.key = "seconds",          .type = seconds,       .number = &O::seconds},
};
// clang-format on
}  // namespace outcome_field_detail

/// Every field, in summary.json's order (which the Python dicts keep, after their "study").
inline constexpr const auto& outcome_fields = outcome_field_detail::fields;

/// Judges every expectation of `study` on every group it selects, in file order. `rates` is
/// compute_rates(study, trials, results). Never throws for study results (bad values give
/// inconclusive or failing verdicts with their reason); std::bad_alloc aside.
std::vector<ExpectationOutcome> verify_expectations(const StudyDefinition& study,
                                                    const std::vector<TrialSpec>& trials,
                                                    const std::vector<TrialResult>& results,
                                                    const std::vector<MetricSeries>& rates);

/// How the fill distance of a group's trials scales with n: h ~ n^exponent, fitted over every
/// usable trial, and the dimension d whose quasi-uniform exponent is -1/d.
struct FillDistanceScaling {
  double exponent = 0.0;
  double std_error = 0.0;  ///< of the exponent; NaN with 2 points
  int dimension = 1;
};

/// The advice of a FAIL or INCONCLUSIVE verdict on `series`, one line ("" when none applies),
/// its clauses joined by "; " in this order:
/// - fewer than 3 points in the fit window (`window_points`): "the fit window has 2 points
///   (n = 64..128) and a verdict needs at least 3: add n beyond 128";
/// - against n (`abscissa`), with `fill` measured: the fill distance's exponent differs from
///   -1/d by more than its standard error and by more than 10% of 1/d: "h ~ n^-0.57, not
///   n^-0.50: fit against h (abscissa = \"h\")";
/// - the last pairwise rates (up to 3, at least 2, finite) still move one way by more than 0.05
///   in all: "pairwise rates still climb 0.90 -> 1.46: extend n beyond 576" ("fall" when they
///   decrease).
/// Never throws except std::bad_alloc.
std::string verdict_advice(const MetricSeries& series, std::size_t window_points, Abscissa abscissa,
                           const std::optional<FillDistanceScaling>& fill);

/// How an outcome counts, its verdict read with its expectation's xfail marker (pytest's
/// outcomes): a fail of an xfail expectation is xfailed, a pass xpassed; inconclusive stays.
enum class CaseOutcome { passed, failed, inconclusive, xfailed, xpassed };
CaseOutcome case_outcome(const ExpectationOutcome& outcome);

/// "PASS", "FAIL", "INCONCLUSIVE", "XFAIL", "XPASS" (the console's and JUnit's words).
std::string_view case_outcome_name(CaseOutcome outcome);
/// "passed", "failed", "inconclusive", "xfailed", "xpassed" (summary.json).
std::string_view case_outcome_id(CaseOutcome outcome);

struct VerdictCounts {
  std::size_t passed = 0, failed = 0, inconclusive = 0, xfailed = 0, xpassed = 0;
  std::size_t deselected = 0;  ///< cases `-k` left out (not judged)
  std::size_t selected() const { return passed + failed + inconclusive + xfailed + xpassed; }
  VerdictCounts& operator+=(const VerdictCounts& other);
};
/// The outcomes counted by case_outcome (deselected 0).
VerdictCounts count_verdicts(const std::vector<ExpectationOutcome>& outcomes);

/// How `check` reads the counts (its options).
struct CheckPolicy {
  bool strict = false;  ///< --strict: inconclusive and XPASS fail the check
  bool allow_inconclusive =
      false;  ///< --allow inconclusive: inconclusive does not (not with strict)
};

/// The exit codes of `rkhs-study check` for its verdicts (2 is bad input, 130 an interrupted run).
inline constexpr int check_passed = 0, check_failed = 1, check_inconclusive = 3,
                     check_none_selected = 5;

/// 1 any fail (strict: or any inconclusive or XPASS); else 5 when no case was judged: -k
/// deselected every one, or there was none (no [[expect]]), pytest's "no tests collected";
/// else 3 when some are inconclusive and they are not allowed; else 0.
int check_exit_code(const VerdictCounts& counts, const CheckPolicy& policy = {});

/// The line that names an outcome, as `check` and `run` print it: "OUTCOME      name
/// (file:line:column)", the outcome (case_outcome_name) padded to 12 characters.
std::string verdict_heading(const ExpectationOutcome& outcome);

/// The judged numbers in a few words: "rate 1.22 [1.18, 1.26] against rate in [1.40, 1.60]" (the
/// fitted rate and its CI to 3 significant digits against the accepted interval); for a bound
/// "effectivity up to 1.07 against at most 1"; "no fit" when nothing was fitted.
std::string verdict_numbers(const ExpectationOutcome& outcome);

/// The answer `run` ends with: per outcome verdict_heading, ": ", verdict_numbers, then
/// "    advice: ..." when it has advice; then the counts line (format_counts). "no expectations"
/// when `outcomes` is empty.
std::string format_verdict_lines(const std::vector<ExpectationOutcome>& outcomes);

/// The console report: per outcome verdict_heading with the expected / found / verdict (and
/// advice and xfail) lines below, then "N passed, M failed, K inconclusive" (and the
/// xfailed, xpassed and deselected counts when there are any).
std::string format_verification(const std::vector<ExpectationOutcome>& outcomes,
                                const CheckPolicy& policy = {}, std::size_t deselected = 0);

/// The counts line of format_verification: "2 passed, 1 failed, 0 inconclusive, 1 xfailed,
/// 3 deselected", with what --strict or --allow changed.
std::string format_counts(const VerdictCounts& counts, const CheckPolicy& policy = {});

}  // namespace rkhs
