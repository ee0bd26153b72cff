// The outcomes of expectations as verdicts, case outcomes, counts, an exit code and text
// (verification.hpp). verification.cpp judges the expectations.
#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "judgement.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

using verify_detail::interval_text;

namespace {

// Advice: pairwise rates that move by more than this in all over the last points are still
// moving; a fill distance exponent within this fraction of -1/d is n^(-1/d) (as
// quasi_uniform_slack).
constexpr double still_moving = 0.05;
constexpr double fill_exponent_slack = 0.1;

}  // namespace

std::string verdict_advice(const MetricSeries& series, std::size_t window_points, Abscissa abscissa,
                           const std::optional<FillDistanceScaling>& fill) {
  std::vector<std::string> clauses;
  const auto largest_n = [&] {
    return series.n.empty() ? std::string("the largest") : format_real(series.n.back());
  };
  if (window_points < 3)
    clauses.push_back(
        fmt::format("the fit window has {} point{} and a verdict needs at least 3: "
                    "add n beyond {}",
                    window_points, window_points == 1 ? "" : "s", largest_n()));
  if (abscissa == Abscissa::n && fill && fill->dimension > 0) {
    const double expected = -1.0 / fill->dimension;
    const double off = std::fabs(fill->exponent - expected);
    if (off > fill_exponent_slack / fill->dimension &&
        (!std::isfinite(fill->std_error) || off > fill->std_error))
      clauses.push_back(fmt::format("h ~ n^{:.2f}, not n^{:.2f}: fit against h (abscissa = \"h\")",
                                    fill->exponent, expected));
  }
  // The trailing finite pairwise rates, at most 3.
  std::vector<double> last;
  for (auto k = series.pairwise.size(); k-- > 0 && last.size() < 3;) {
    if (!std::isfinite(series.pairwise[k])) break;
    last.insert(last.begin(), series.pairwise[k]);
  }
  if (last.size() >= 2) {
    bool climbs = true, falls = true;
    for (std::size_t k = 1; k < last.size(); ++k) {
      climbs = climbs && last[k] > last[k - 1];
      falls = falls && last[k] < last[k - 1];
    }
    if ((climbs || falls) && std::fabs(last.back() - last.front()) > still_moving)
      clauses.push_back(fmt::format("pairwise rates still {} {:.2f} -> {:.2f}: extend n beyond {}",
                                    climbs ? "climb" : "fall", last.front(), last.back(),
                                    largest_n()));
  }
  std::string out;
  for (const auto& clause : clauses) out += (out.empty() ? "" : "; ") + clause;
  return out;
}

std::string_view verdict_name(Verdict verdict) {
  switch (verdict) {
    case Verdict::pass: return "PASS";
    case Verdict::fail: return "FAIL";
    default: return "INCONCLUSIVE";
  }
}

CaseOutcome case_outcome(const ExpectationOutcome& outcome) {
  const bool xfail = outcome.expectation && !outcome.expectation->xfail.empty();
  switch (outcome.verdict) {
    case Verdict::pass:
      return xfail ? CaseOutcome::xpassed : CaseOutcome::passed;
    case Verdict::fail:
      return xfail ? CaseOutcome::xfailed : CaseOutcome::failed;
    default:
      return CaseOutcome::inconclusive;
  }
}

std::string_view case_outcome_name(CaseOutcome outcome) {
  switch (outcome) {
    case CaseOutcome::passed:
      return "PASS";
    case CaseOutcome::failed:
      return "FAIL";
    case CaseOutcome::xfailed:
      return "XFAIL";
    case CaseOutcome::xpassed:
      return "XPASS";
    default:
      return "INCONCLUSIVE";
  }
}

std::string_view case_outcome_id(CaseOutcome outcome) {
  switch (outcome) {
    case CaseOutcome::passed:
      return "passed";
    case CaseOutcome::failed:
      return "failed";
    case CaseOutcome::xfailed:
      return "xfailed";
    case CaseOutcome::xpassed:
      return "xpassed";
    default:
      return "inconclusive";
  }
}

VerdictCounts& VerdictCounts::operator+=(const VerdictCounts& other) {
  passed += other.passed;
  failed += other.failed;
  inconclusive += other.inconclusive;
  xfailed += other.xfailed;
  xpassed += other.xpassed;
  deselected += other.deselected;
  return *this;
}

VerdictCounts count_verdicts(const std::vector<ExpectationOutcome>& outcomes) {
  VerdictCounts counts;
  for (const auto& o : outcomes) {
    switch (case_outcome(o)) {
      case CaseOutcome::passed:
        ++counts.passed;
        break;
      case CaseOutcome::failed:
        ++counts.failed;
        break;
      case CaseOutcome::xfailed:
        ++counts.xfailed;
        break;
      case CaseOutcome::xpassed:
        ++counts.xpassed;
        break;
      case CaseOutcome::inconclusive:
        ++counts.inconclusive;
        break;
    }
  }
  return counts;
}

int check_exit_code(const VerdictCounts& counts, const CheckPolicy& policy) {
  if (counts.failed > 0 || (policy.strict && (counts.inconclusive > 0 || counts.xpassed > 0)))
    return check_failed;
  if (counts.selected() == 0) return check_none_selected;
  if (counts.inconclusive > 0 && !policy.allow_inconclusive) return check_inconclusive;
  return check_passed;
}

std::string format_counts(const VerdictCounts& counts, const CheckPolicy& policy) {
  std::string out = fmt::format("{} passed, {} failed, {} inconclusive", counts.passed,
                                counts.failed, counts.inconclusive);
  if (counts.xfailed) out += fmt::format(", {} xfailed", counts.xfailed);
  if (counts.xpassed) out += fmt::format(", {} xpassed", counts.xpassed);
  if (counts.deselected) out += fmt::format(", {} deselected", counts.deselected);
  if (policy.strict && (counts.inconclusive || counts.xpassed))
    out += counts.xpassed && counts.inconclusive
               ? " (--strict: inconclusive and XPASS count as failed)"
           : counts.xpassed ? " (--strict: XPASS counts as failed)"
                            : " (--strict: inconclusive counts as failed)";
  else if (policy.allow_inconclusive && counts.inconclusive)
    out += " (--allow inconclusive: inconclusive does not fail the check)";
  return out;
}

std::string verdict_heading(const ExpectationOutcome& outcome) {
  return fmt::format("{:<12} {} ({})", case_outcome_name(case_outcome(outcome)), outcome.name,
                     outcome.expectation->location);
}

std::string verdict_numbers(const ExpectationOutcome& outcome) {
  const auto& o = outcome;
  const auto accepted = [&] {
    return interval_text(RateInterval{o.accepted_low, o.accepted_high});
  };
  if (o.expectation->kind == ExpectationKind::bound) {
    if (std::isnan(o.effectivity_max)) return std::string("no usable point");
    return fmt::format("effectivity up to {:.3g} against at most 1", o.effectivity_max);
  }
  if (o.expectation->kind == ExpectationKind::reference) {
    if (std::isnan(o.effectivity_max)) return std::string("no ratio");
    return fmt::format("ratio to the reference {:.4g} to {:.4g}", o.effectivity_min,
                       o.effectivity_max);
  }
  if (std::isnan(o.rate)) return std::string("no fit");
  // 3 significant digits: a rate of -0.99999 with its CI is "-1 [-1, -1]".
  std::string out = fmt::format("rate {:.3g}", o.rate + 0.0);
  if (std::isfinite(o.ci_low) && std::isfinite(o.ci_high))
    out += fmt::format(" [{:.3g}, {:.3g}]", o.ci_low + 0.0, o.ci_high + 0.0);
  if (!std::isnan(o.accepted_low) || !std::isnan(o.accepted_high)) out += " against " + accepted();
  return out;
}

std::string format_verdict_lines(const std::vector<ExpectationOutcome>& outcomes) {
  if (outcomes.empty()) return "no expectations\n";
  std::string out;
  for (const auto& o : outcomes) {
    out += verdict_heading(o) + ": " + verdict_numbers(o) + "\n";
    if (!o.advice.empty()) out += fmt::format("    advice: {}\n", o.advice);
  }
  return out + format_counts(count_verdicts(outcomes)) + "\n";
}

std::string format_verification(const std::vector<ExpectationOutcome>& outcomes,
                                const CheckPolicy& policy, std::size_t deselected) {
  std::string out;
  for (const auto& o : outcomes) {
    const auto& e = *o.expectation;
    out += verdict_heading(o) + "\n";
    out += fmt::format("    expected: {}\n", o.expected);
    out += fmt::format("    found:    {}\n", o.found);
    out += fmt::format("    verdict:  {}\n", o.reason);
    if (!o.advice.empty()) out += fmt::format("    advice:   {}\n", o.advice);
    if (!e.xfail.empty()) out += fmt::format("    xfail:    {}\n", e.xfail);
  }
  auto counts = count_verdicts(outcomes);
  counts.deselected = deselected;
  if (outcomes.empty())
    return deselected ? fmt::format("no expectation selected ({} deselected)\n", deselected)
                      : "no expectations to check (nothing verified)\n";
  return out + format_counts(counts, policy) + "\n";
}

}  // namespace rkhs
