// Judging a `reference` expectation: a metric against published values, n by n
// (docs/verification.md, "Reference values").
#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "judgement.hpp"

namespace rkhs::verify_detail {

void judge_reference(const Expectation& e, const MetricSeries& series,
                     const std::vector<bool>& inside, const std::vector<std::string>& flags,
                     ExpectationOutcome& o) {
  const auto& spec = e.reference;
  o.expected = fmt::format("{} / reference = 1 ± {} at every n of the reference ({})", e.metric,
                           format_real(spec.within), spec.text());
  std::size_t used = 0, failed = 0, not_judged = 0;
  double low = std::numeric_limits<double>::infinity(), high = -low;
  std::size_t low_n = 0, high_n = 0;
  double worst_excess = -std::numeric_limits<double>::infinity();
  std::string worst, unmeasurable;
  for (std::size_t r = 0; r < spec.n.size(); ++r) {
    std::size_t k = 0;
    while (k < series.n.size() && series.n[k] != static_cast<double>(spec.n[r])) ++k;
    if (k == series.n.size() || !inside[k]) {
      ++not_judged;
      continue;
    }
    if (series.failed[k]) {
      ++failed;
      continue;
    }
    const double y = series.values[k], reference = spec.values[r];
    // A value that is no number, or flagged as numerically meaningless, cannot be set beside a
    // published number: the reference is not reproduced there (the first such n is named).
    if (!std::isfinite(y) || series.flagged[k]) {
      if (unmeasurable.empty())
        unmeasurable = fmt::format(
            "at n = {} the measured value is {}{}, no number to set beside "
            "the reference's {} (line {})",
            spec.n[r], format_real(y), flags[k].empty() ? "" : " (flagged " + flags[k] + ")",
            format_real(reference), spec.lines[r]);
      continue;
    }
    const double ratio = y / reference;
    const double floor =
        k < series.floors.size() && series.floors[k] > 0 ? series.floors[k] / std::fabs(y) : 0.0;
    const double allowed = spec.within + floor * std::fabs(ratio) +
                           4.0 * std::numeric_limits<double>::epsilon() * std::fabs(ratio);
    ++used;
    if (ratio < low) low = ratio, low_n = spec.n[r];
    if (ratio > high) high = ratio, high_n = spec.n[r];
    if (std::fabs(ratio - 1.0) - allowed > worst_excess) {
      worst_excess = std::fabs(ratio - 1.0) - allowed;
      // Four digits, as the ratio: a measured value's last digits differ between processors.
      worst = fmt::format(
          "at n = {} {} is {:.4g} against the reference's {} (line {}): a ratio "
          "of {:.4g}",
          spec.n[r], e.metric, y, format_real(reference), spec.lines[r], ratio);
    }
  }
  o.window_points = used;
  if (used > 0) {
    o.effectivity_min = low;
    o.effectivity_max = high;
  }
  std::string left_out;
  if (failed) left_out += fmt::format("{} failed", failed);
  if (not_judged)
    left_out += fmt::format("{}{} outside the window", left_out.empty() ? "" : ", ", not_judged);
  const std::size_t measurable = spec.n.size() - failed - not_judged;
  o.found = used == 0 ? fmt::format("no finite value at the {} n of the reference", spec.n.size())
                      : fmt::format(
                            "ratio {} / reference from {:.4g} (n = {}) to {:.4g} (n = {}) "
                            "at {} of {} n",
                            e.metric, low, low_n, high, high_n, used, spec.n.size());
  if (!left_out.empty()) o.found += " (left out: " + left_out + ")";
  if (measurable == 0) {
    o.verdict = Verdict::inconclusive;
    o.reason = "nothing to compare: no trial at the reference's n gave a value";
  } else if (!unmeasurable.empty()) {
    o.verdict = Verdict::fail;
    o.reason = unmeasurable;
  } else if (worst_excess > 0.0) {
    o.verdict = Verdict::fail;
    o.reason = worst + ", beyond the tolerance";
  } else {
    o.verdict = Verdict::pass;
    o.reason = "every value agrees with the reference within the tolerance";
  }
}

}  // namespace rkhs::verify_detail
