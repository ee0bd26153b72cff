#include "judgement.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rkhs/rates/asymptotic.hpp"

namespace rkhs::verify_detail {

// A rate for messages: 2 decimals from 1 up, 3 below 1, 3 significant digits below 0.01.
std::string num(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (std::isnan(v)) return "nan";
  const double a = std::fabs(v);
  if (a >= 1.0) return fmt::format("{:.2f}", v);
  if (a >= 0.01 || a == 0.0) return fmt::format("{:.3f}", v);
  return fmt::format("{:.3g}", v);
}

std::string interval_text(const RateInterval& i) {
  if (std::isinf(i.low) && std::isinf(i.high)) return "any rate";
  if (std::isinf(i.low)) return fmt::format("rate <= {}", num(i.high));
  if (std::isinf(i.high)) return fmt::format("rate >= {}", num(i.low));
  return fmt::format("rate in [{}, {}]", num(i.low), num(i.high));
}

std::string_view model_text(RateModel model) {
  return model == RateModel::power_law ? "power law" : "exponential model";
}

Verdict worst(Verdict a, Verdict b) {
  if (a == Verdict::fail || b == Verdict::fail) return Verdict::fail;
  if (a == Verdict::inconclusive || b == Verdict::inconclusive) return Verdict::inconclusive;
  return Verdict::pass;
}

// The interval rule of verification.hpp.
Judgement judge_interval(const RateFit* fit, const RateInterval& accepted) {
  if (!fit) return {Verdict::inconclusive, "no fit: fewer than 2 usable points"};
  if (fit->points < 3 || !std::isfinite(fit->ci_low) || !std::isfinite(fit->ci_high))
    return {Verdict::inconclusive,
            fmt::format("only {} point{} in the window: a verdict needs at least 3", fit->points,
                        fit->points == 1 ? "" : "s")};
  const auto level = fmt::format("{:.4g}%", 100.0 * fit->confidence);
  if (fit->ci_low >= accepted.low && fit->ci_high <= accepted.high)
    return {Verdict::pass, fmt::format("the {} CI lies within the accepted interval", level)};
  if (fit->ci_high < accepted.low)
    return {Verdict::fail, fmt::format("the {} CI lies entirely below {}", level, num(accepted.low))};
  if (fit->ci_low > accepted.high)
    return {Verdict::fail, fmt::format("the {} CI lies entirely above {}", level, num(accepted.high))};
  const double width = fit->ci_high - fit->ci_low;
  if (width > accepted.high - accepted.low)
    return {Verdict::inconclusive,
            fmt::format("the {} CI is {} wide, wider than the accepted interval ({}): the series "
                        "scatters too much for this tolerance",
                        level, num(width), num(accepted.high - accepted.low))};
  const double edge = fit->ci_low < accepted.low ? accepted.low : accepted.high;
  return {Verdict::inconclusive, fmt::format("the {} CI straddles {}", level, num(edge))};
}

// A constant whose values agree within their floors: its band is round-off, which the verdicts
// do not print (it differs from one processor to another); they print the floors instead.
bool floor_bound(const ConstantSeries& constant) {
  return constant.within_floors && constant.floor > 0.0 && constant.value != 0.0;
}

// `value` to the digits `floor` leaves it ("1.0000000000" for 1 +- 2e-11).
std::string digits_of(double value, double floor) {
  const int digits =
      std::clamp(static_cast<int>(std::ceil(std::log10(std::fabs(value) / floor))), 1, 17);
  auto out = fmt::format("{:#.{}g}", value, digits);
  if (!out.empty() && out.back() == '.') out.pop_back();
  return out;
}

// The rates a constant series allows under `model`: every line within its band over its points,
// slopes up to w = 2 band / |value| per span of ln x (power law) or of n (exponential).
// +inf for a constant of value 0 with a band, or a span of 0.
double constant_rate_width(const MetricSeries& series, RateModel model) {
  const auto& constant = *series.analysis.constant;
  const auto first = constant.points.front(), last = constant.points.back();
  const double span = model == RateModel::power_law
                          ? std::fabs(std::log(series.abscissa[last] / series.abscissa[first]))
                          : std::fabs(series.n[last] - series.n[first]);
  // Within the values' floors the band is round-off: the floors bound what the values allow.
  const double relative = floor_bound(constant)
                              ? std::max(constant.band, constant.floor) / std::fabs(constant.value)
                              : constant.relative_band();
  if (relative == 0.0) return 0.0;
  return span > 0.0 && std::isfinite(relative) ? 2.0 * relative / span
                                               : std::numeric_limits<double>::infinity();
}

// A rate verdict on a constant series: the rates its band allows, [-w, w], against the
// accepted interval (the same rule as a CI: within passes, outside fails, across is open).
Judgement judge_constant_rate(const MetricSeries& series, RateModel model,
                              const RateInterval& accepted) {
  const double w = constant_rate_width(series, model);
  const auto allowed =
      floor_bound(*series.analysis.constant)
          ? fmt::format("the rates its floors allow, [{:.2g}, {:.2g}],", -w, w)
          : fmt::format("the rates its band allows, [{}, {}],", num(0.0 - w), num(w));
  if (-w >= accepted.low && w <= accepted.high)
    return {Verdict::pass,
            "the series is constant: " + allowed + " lie within the accepted interval"};
  if (w < accepted.low)
    return {Verdict::fail, fmt::format("the series is constant: {} lie entirely below {}", allowed,
                                       num(accepted.low))};
  if (-w > accepted.high)
    return {Verdict::fail, fmt::format("the series is constant: {} lie entirely above {}", allowed,
                                       num(accepted.high))};
  const double edge = -w < accepted.low ? accepted.low : accepted.high;
  return {Verdict::inconclusive,
          fmt::format("the series is constant: {} straddle {}", allowed, num(edge))};
}

// A model expectation (also the first half of an analytic theory).
Judgement judge_model(const SeriesAnalysis& analysis, RateModel required) {
  if (analysis.constant)
    return {Verdict::fail, fmt::format("the series is constant: neither the {} nor the other "
                                       "model describes it",
                                       model_text(required))};
  if (!analysis.preferred) return {Verdict::inconclusive, analysis.note};
  if (!analysis.decisive()) return {Verdict::inconclusive, analysis.note};
  if (*analysis.preferred == required)
    return {Verdict::pass, fmt::format("the {} fits better (ΔAIC = {:.1f})", model_text(required),
                                       analysis.evidence)};
  return {Verdict::fail, fmt::format("the {} fits better, not the {}",
                                     model_text(*analysis.preferred), model_text(required))};
}

// Fit, CI, window and exclusions of one model of a series, for the "found" line.
std::string describe_fit(const MetricSeries& series, const ModelAnalysis& analysis) {
  const auto& fit = analysis.fit;
  std::string out;
  if (series.constant() && floor_bound(*series.analysis.constant)) {
    const auto& constant = *series.analysis.constant;
    const double w = constant_rate_width(series, analysis.model);
    out = fmt::format(
        "constant {} within the values' floors (± {:.2g}) on n = {} ({} of {} points; the rates "
        "its floors allow: [{:.2g}, {:.2g}]{})",
        digits_of(constant.value, constant.floor), constant.floor,
        label_range(series.n, constant.points), constant.points.size(), series.trials.size(), -w, w,
        analysis.model == RateModel::exponential ? " per unit n" : "");
  } else if (series.constant()) {
    const double w = constant_rate_width(series, analysis.model);
    out = fmt::format("constant {} ({} of {} points; the rates its band allows: [{}, {}]{})",
                      series.analysis.constant->text(series.n),
                      series.analysis.constant->points.size(), series.trials.size(), num(0.0 - w),
                      num(w), analysis.model == RateModel::exponential ? " per unit n" : "");
  } else if (!fit) {
    out = fmt::format("{}: no fit ({})", model_text(analysis.model),
                      series.no_fit_reason.empty() ? "fewer than 2 usable points" : series.no_fit_reason);
  } else {
    const std::string per = analysis.model == RateModel::exponential ? " per unit n" : "";
    if (std::isfinite(fit->ci_low))
      out = fmt::format("{} rate {}{} ({:.4g}% CI [{}, {}])", model_text(analysis.model),
                        num(fit->rate), per, 100.0 * fit->confidence, num(fit->ci_low), num(fit->ci_high));
    else
      out = fmt::format("{} rate {}{} (no CI)", model_text(analysis.model), num(fit->rate), per);
    out += fmt::format(" on the window n = {} ({} of {} points)",
                       label_range(series.n, analysis.window.points), fit->points,
                       series.trials.size());
  }
  return out;
}

// The power law with its pre-asymptotic term, when the verdict judges it ("" otherwise).
std::string describe_bend(const MetricSeries& series, const ModelAnalysis& analysis) {
  const auto& a = series.analysis;
  if (analysis.model != RateModel::power_law || !a.bends()) return "";
  const auto& c = *a.corrected;
  return fmt::format(
      "; the pairwise rates bend monotonically, so the verdict judges C x^p (1 + D t^-q) on "
      "n = {} ({} points): rate {} ({:.4g}% CI [{}, {}]), q = {:.3g}, D = {:.3g} at n = {} "
      "(ΔAICc = {:.1f} over the straight line)",
      label_range(series.n, a.corrected_points), c.fit.points, num(c.fit.rate),
      100.0 * c.fit.confidence, num(c.fit.ci_low), num(c.fit.ci_high), c.order, c.correction,
      format_real(series.n[a.corrected_points.back()]), c.advantage);
}

std::string exclusions(const MetricSeries& series, const ModelAnalysis& analysis) {
  if (series.constant()) return series.note.empty() ? "" : "; " + series.note;
  std::vector<std::string> parts;
  if (!series.note.empty() && &analysis == &series.analysis.reported_analysis())
    parts.push_back(series.note);
  else if (!analysis.window.note.empty())
    parts.push_back(analysis.window.note);
  if (!series.analysis.note.empty()) parts.push_back(series.analysis.note);
  std::string out;
  for (const auto& p : parts) out += "; " + p;
  return out;
}

Judgement judge_values_below(const MetricSeries& series, const std::vector<bool>& inside,
                             double bound) {
  std::size_t used = 0, non_finite = 0, largest_at = 0, beyond = 0;
  double largest = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < series.values.size(); ++k) {
    if (!inside[k] || series.failed[k] || series.flagged[k]) continue;
    const double y = series.values[k];
    if (!std::isfinite(y)) {
      ++non_finite;
      continue;
    }
    const double floor = k < series.floors.size() && series.floors[k] > 0 ? series.floors[k] : 0.0;
    ++used;
    beyond += y - floor >= bound;
    if (y > largest) {
      largest = y;
      largest_at = static_cast<std::size_t>(series.n[k]);
    }
  }
  if (beyond)
    return {Verdict::fail, fmt::format("{} of {} values at or above {} beyond their floors "
                                       "(largest {} at n = {})",
                                       beyond, used, format_real(bound), num(largest), largest_at)};
  if (non_finite || used == 0)
    return {Verdict::inconclusive,
            non_finite ? fmt::format("{} value{} not finite: not known to lie below {}", non_finite,
                                     non_finite == 1 ? " is" : "s are", format_real(bound))
                       : fmt::format("no usable value to compare with {}", format_real(bound))};
  return {Verdict::pass, fmt::format("every usable value lies below {} (largest {} at n = {})",
                                     format_real(bound), num(largest), largest_at)};
}

// Whether the centres of a group are quasi-uniform, judged from the trials' fill and separation
// distances: the sentence for the "expected" line, and whether the theory can be converted.
// `dimension`: d of the kernel's domain (KernelProperties::dimension).
std::pair<bool, std::string> quasi_uniformity(int dimension, const StudyDefinition& study,
                                              const std::vector<TrialSpec>& trials,
                                              const std::vector<TrialResult>& results,
                                              const MetricSeries& series) {
  const auto& all = study.all_metrics();
  if (std::find(all.begin(), all.end(), "fill_distance") == all.end() ||
      std::find(all.begin(), all.end(), "separation_distance") == all.end())
    return {false, "fill and separation distances are not measured"};
  const auto h_index = study.metric_index("fill_distance");
  const auto q_index = study.metric_index("separation_distance");
  std::vector<double> n, h, ratio;
  for (auto t : series.trials) {
    const auto& r = results[t];
    const double hv = r.metrics[h_index], qv = r.metrics[q_index];
    if (!r.ok || !(hv > 0) || !(qv > 0) || !std::isfinite(hv) || !std::isfinite(qv)) continue;
    n.push_back(static_cast<double>(trials[t].n));
    h.push_back(hv);
    ratio.push_back(hv / qv);
  }
  const auto h_fit = fit_power_law(n, h);
  const auto ratio_fit = fit_power_law(n, ratio);
  if (!h_fit || !ratio_fit) return {false, "too few trials to measure the fill distance"};
  const bool ok = std::fabs(h_fit->rate + 1.0 / dimension) <= quasi_uniform_slack &&
                  std::fabs(ratio_fit->rate) <= quasi_uniform_slack;
  return {ok, fmt::format("fill distance h ~ n^{:.2f}, mesh ratio h/q ~ n^{:.2f}",
                          h_fit->rate + 0.0, std::fabs(ratio_fit->rate) < 5e-3 ? 0.0 : ratio_fit->rate)};
}

}  // namespace rkhs::verify_detail
