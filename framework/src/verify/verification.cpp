#include "rkhs/verify/verification.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/study/trial_grid.hpp"
#include "rkhs/rates/theory.hpp"
#include "rkhs/verify/expectation_cases.hpp"

namespace rkhs {
namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
// Quasi-uniformity, as far as a finite study can tell: the fill distance decays like n^-1/d and
// the mesh ratio h / q neither grows nor shrinks, both within this slope.
constexpr double quasi_uniform_slack = 0.1;

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

struct Judgement {
  Verdict verdict;
  std::string reason;
};

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

// The rates a constant series allows under `model`: every line within its band over its points,
// slopes up to w = 2 band / |value| per span of ln x (power law) or of n (exponential).
// +inf for a constant of value 0 with a band, or a span of 0.
double constant_rate_width(const MetricSeries& series, RateModel model) {
  const auto& constant = *series.analysis.constant;
  const auto first = constant.points.front(), last = constant.points.back();
  const double span = model == RateModel::power_law
                          ? std::fabs(std::log(series.abscissa[last] / series.abscissa[first]))
                          : std::fabs(series.n[last] - series.n[first]);
  const double relative = constant.relative_band();
  if (relative == 0.0) return 0.0;
  return span > 0.0 && std::isfinite(relative) ? 2.0 * relative / span
                                               : std::numeric_limits<double>::infinity();
}

// A rate verdict on a constant series: the rates its band allows, [-w, w], against the
// accepted interval (the same rule as a CI: within passes, outside fails, across is open).
Judgement judge_constant_rate(const MetricSeries& series, RateModel model,
                              const RateInterval& accepted) {
  const double w = constant_rate_width(series, model);
  const auto allowed = fmt::format("the rates its band allows, [{}, {}],", num(0.0 - w), num(w));
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
  if (series.constant()) {
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

// Advice: pairwise rates that move by more than this in all over the last points are still
// moving; a fill distance exponent within this fraction of -1/d is n^(-1/d) (as
// quasi_uniform_slack).
constexpr double still_moving = 0.05;
constexpr double fill_exponent_slack = 0.1;

class Verifier {
 public:
  Verifier(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
           const std::vector<TrialResult>& results, const std::vector<MetricSeries>& rates)
      : study_(study), trials_(trials), results_(results), rates_(rates) {
    for (auto& c : expectation_cases(study_, trials_))
      cases_.emplace(std::pair(c.expectation, c.group), std::move(c));
  }

  std::vector<ExpectationOutcome> run() const {
    std::vector<ExpectationOutcome> out;
    for (const auto& expectation : study_.expectations)
      for (std::size_t s = 0; s < rates_.size(); ++s) {
        const auto& series = rates_[s];
        if (series.metric != expectation.metric || series.trials.empty() ||
            !expectation.selects(trials_[series.trials.front()]))
          continue;
        const auto start = std::chrono::steady_clock::now();
        out.push_back(judge(expectation, s));
        out.back().seconds +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
    return out;
  }

 private:
  ExpectationOutcome judge(const Expectation& e, std::size_t s) const {
    // An expectation with its own window judges the series refitted on it.
    std::optional<MetricSeries> windowed;
    if (!e.window.empty()) {
      windowed = rates_[s];
      fit_series(*windowed, e.window);
    }
    const auto& series = windowed ? *windowed : rates_[s];
    ExpectationOutcome o;
    o.expectation = &e;
    o.series = s;
    o.group = trials_[series.trials.front()].group_key;
    const auto& test_case = cases_.at(std::pair(&e, o.group));
    o.group_label = test_case.group_label;
    o.name = test_case.name;
    for (auto t : series.trials) o.seconds += results_[t].seconds;
    o.rate = o.ci_low = o.ci_high = o.accepted_low = o.accepted_high = not_a_number;
    o.effectivity_min = o.effectivity_max = not_a_number;
    switch (e.kind) {
      case ExpectationKind::rate: judge_rate(e, series, o); break;
      case ExpectationKind::theory: judge_theory(e, series, o); break;
      case ExpectationKind::model: judge_model_expectation(e, series, o); break;
      case ExpectationKind::bound: judge_bound(e, series, o); break;
      case ExpectationKind::constant:
        judge_constant(e, series, o);
        break;
    }
    if (o.verdict != Verdict::pass && e.kind != ExpectationKind::bound &&
        e.kind != ExpectationKind::constant && !series.constant())
      o.advice =
          verdict_advice(series, o.window_points, study_.abscissa, fill_distance_scaling(series));
    note_missing_excitation(series, o);
    return o;
  }

  // How the fill distance of the series' trials scales with n; nullopt when the study does not
  // measure it or fewer than 2 trials have it.
  std::optional<FillDistanceScaling> fill_distance_scaling(const MetricSeries& series) const {
    const auto& all = study_.all_metrics();
    if (std::find(all.begin(), all.end(), "fill_distance") == all.end()) return std::nullopt;
    const auto h_index = study_.metric_index("fill_distance");
    std::vector<double> n, h;
    for (auto t : series.trials) {
      const auto& r = results_[t];
      if (!r.ok || !(r.metrics[h_index] > 0) || !std::isfinite(r.metrics[h_index])) continue;
      n.push_back(static_cast<double>(trials_[t].n));
      h.push_back(r.metrics[h_index]);
    }
    const auto fit = fit_power_law(n, h);
    if (!fit) return std::nullopt;
    return FillDistanceScaling{fit->rate, fit->std_error, study_.domain.dimension};
  }

  // Theorem 3.3 needs persistence of excitation: a verdict on a series whose trials the path
  // does not excite (flag not_persistently_excited) says so, and that fhat need not converge.
  void note_missing_excitation(const MetricSeries& series, ExpectationOutcome& o) const {
    std::size_t unexcited = 0;
    double directions = 0;
    for (auto t : series.trials) {
      const auto& flags = results_[t].flags;
      if (std::find(flags.begin(), flags.end(), "not_persistently_excited") == flags.end())
        continue;
      ++unexcited;
      // The flag is an adaptive trial's, whose table has unexcited_dimension.
      directions =
          std::max(directions, results_[t].metrics[study_.metric_index("unexcited_dimension")]);
    }
    if (unexcited == 0) return;
    o.reason += fmt::format(
        "; persistence of excitation fails in {} of {} trials (the path leaves up to {} "
        "directions of the law's space unexcited, pe_level = 0): Theorem 3.3 does not apply, and "
        "fhat need not converge to f where the path does not go",
        unexcited, series.trials.size(), format_real(directions));
  }

  std::string axis_name() const { return study_.abscissa == Abscissa::n ? "ln n" : "ln h"; }

  // The fit a verdict on `analysis`'s model judges: the bend's for a bending power law.
  static const RateFit* judged_fit(const MetricSeries& series, const ModelAnalysis& analysis) {
    if (analysis.model == RateModel::power_law) return series.analysis.power_law_rate_fit();
    return analysis.fit ? &*analysis.fit : nullptr;
  }

  // The interval rule on the judged fit, or on the rates a constant series allows.
  static Judgement judge_series(const MetricSeries& series, const ModelAnalysis& analysis,
                                const RateInterval& accepted) {
    if (series.constant()) return judge_constant_rate(series, analysis.model, accepted);
    return judge_interval(judged_fit(series, analysis), accepted);
  }

  void record_fit(const MetricSeries& series, const ModelAnalysis& analysis,
                  ExpectationOutcome& o) const {
    if (const auto& constant = series.analysis.constant) {
      const double w = constant_rate_width(series, analysis.model);
      o.rate = 0.0;
      o.ci_low = 0.0 - w;
      o.ci_high = w;
      o.window_points = constant->points.size();
      o.window_from = trials_[series.trials[constant->points.front()]].n;
      o.window_to = trials_[series.trials[constant->points.back()]].n;
    } else if (const auto* fit = judged_fit(series, analysis)) {
      o.rate = fit->rate;
      o.ci_low = fit->ci_low;
      o.ci_high = fit->ci_high;
      o.window_points = fit->points;
      if (!fit->used.empty()) {
        o.window_from = trials_[series.trials[fit->used.front()]].n;
        o.window_to = trials_[series.trials[fit->used.back()]].n;
      }
    }
    o.found = describe_fit(series, analysis) + exclusions(series, analysis) +
              describe_bend(series, analysis);
  }

  // rate = { at_least = "reference" }: the accepted interval is derived from the reference
  // metric's power-law fit in the same group: "at least as fast" means beyond its CI's inner
  // end (its upper end for a decreasing series, its lower end for an increasing one) less the
  // tolerance. Empty with the reason when the reference has no usable fit.
  std::optional<RateInterval> derived_interval(const Expectation& e, const MetricSeries& series,
                                               std::string& why) const {
    for (const auto& other : rates_) {
      if (other.metric != e.rate_reference || other.group != series.group) continue;
      const auto& fit = other.analysis.analysis(RateModel::power_law).fit;
      if (!fit || fit->points < 3 || !std::isfinite(fit->ci_low) || !std::isfinite(fit->ci_high)) {
        why = fmt::format("{} has no rate with a CI to compare with (fewer than 3 usable points)",
                          e.rate_reference);
        return std::nullopt;
      }
      if (fit->rate < 0) {
        why = fmt::format("{} decreases at {} [{}, {}]", e.rate_reference, num(fit->rate),
                          num(fit->ci_low), num(fit->ci_high));
        return RateInterval{-std::numeric_limits<double>::infinity(), fit->ci_high + e.tolerance};
      }
      why = fmt::format("{} increases at {} [{}, {}]", e.rate_reference, num(fit->rate),
                        num(fit->ci_low), num(fit->ci_high));
      return RateInterval{fit->ci_low - e.tolerance, std::numeric_limits<double>::infinity()};
    }
    why = fmt::format("no series of {} in this group", e.rate_reference);
    return std::nullopt;
  }

  void judge_rate(const Expectation& e, const MetricSeries& series, ExpectationOutcome& o) const {
    const auto& analysis = series.analysis.analysis(e.model);
    if (!e.rate_reference.empty()) {
      std::string why;
      const auto interval = derived_interval(e, series, why);
      record_fit(series, analysis, o);
      if (!interval) {
        o.expected = fmt::format("a rate at least as fast as {}'s against {}", e.rate_reference,
                                 axis_name());
        o.verdict = Verdict::inconclusive;
        o.reason = why;
        return;
      }
      o.accepted_low = interval->low;
      o.accepted_high = interval->high;
      o.expected = fmt::format("at least as fast as {} against {} ({}; tolerance {}): {}",
                               e.rate_reference, axis_name(), why, num(e.tolerance),
                               interval_text(*interval));
      auto [verdict, reason] = judge_series(series, analysis, *interval);
      o.verdict = verdict;
      o.reason = reason;
      return;
    }
    o.accepted_low = e.interval.low;
    o.accepted_high = e.interval.high;
    const auto against = e.model == RateModel::exponential ? std::string("n (exponential model)")
                                                           : axis_name();
    o.expected = e.expected ? fmt::format("rate {} +- {} against {}, i.e. {}", num(*e.expected),
                                          num(e.tolerance), against, interval_text(e.interval))
                            : fmt::format("{} against {}", interval_text(e.interval), against);
    record_fit(series, analysis, o);
    auto [verdict, reason] = judge_series(series, analysis, e.interval);
    o.verdict = verdict;
    o.reason = reason;
  }

  void judge_theory(const Expectation& e, const MetricSeries& series, ExpectationOutcome& o) const {
    const auto& trial = trials_[series.trials.front()];
    std::string why;
    const auto theory = theory_rate(
        e.metric, kernel_properties(trial.kernel.name, trial.kernel.parameters, study_.domain), &why);
    if (!theory) {  // the parser rejects this; kept for studies built in code
      o.verdict = Verdict::inconclusive;
      o.expected = "theory";
      o.reason = why;
      return;
    }
    if (theory->model == RateModel::exponential) {
      const auto& analysis = series.analysis.exponential;
      const RateInterval sign = theory->direction < 0
                                    ? RateInterval{-std::numeric_limits<double>::infinity(), 0.0}
                                    : RateInterval{0.0, std::numeric_limits<double>::infinity()};
      o.accepted_low = sign.low;
      o.accepted_high = sign.high;
      o.expected = fmt::format("theory: {}: the exponential model fits better than a power law "
                               "and its rate is {} 0",
                               theory->statement, theory->direction < 0 ? "<" : ">");
      record_fit(series, analysis, o);
      const auto model = judge_model(series.analysis, RateModel::exponential);
      auto sign_judgement = judge_series(series, analysis, sign);
      if (!series.constant() && analysis.fit && analysis.fit->points >= 3 &&
          std::isfinite(analysis.fit->ci_low))
        sign_judgement.reason = fmt::format(
              "its {:.4g}% CI [{}, {}] {}", 100.0 * analysis.fit->confidence, num(analysis.fit->ci_low),
              num(analysis.fit->ci_high),
              sign_judgement.verdict == Verdict::pass
                  ? (theory->direction < 0 ? "lies below 0" : "lies above 0")
                  : sign_judgement.verdict == Verdict::fail ? "lies on the wrong side of 0"
                                                            : "contains 0");
      o.verdict = worst(model.verdict, sign_judgement.verdict);
      o.reason = model.reason + "; " + sign_judgement.reason;
      return;
    }
    const auto [uniform, uniformity] =
        quasi_uniformity(theory->dimension, study_, trials_, results_, series);
    // Against ln h a statement in the fill distance needs no quasi-uniformity; against ln n,
    // or stated in the separation distance, it does.
    const bool any_centres =
        study_.abscissa == Abscissa::fill_distance && theory->holds_for_any_centres;
    // For scattered centres an attained order holds up to constants that change with the
    // configuration from one n to the next, which a slope over a finite range cannot test:
    // only its upper bound (at least as fast as h^a) is judged then.
    auto judged = *theory;
    const bool upper_only = any_centres && !uniform && theory->sharp;
    if (upper_only) judged.sharp = false;
    double slope = 0.0;
    const auto interval = theory_interval(judged, study_.abscissa, e.tolerance, &slope);
    o.accepted_low = interval.low;
    o.accepted_high = interval.high;
    const std::string conversion =
        study_.abscissa == Abscissa::n
            ? fmt::format("slope {} against ln n for quasi-uniform centres (h ~ n^-1/d; measured: {})",
                          num(slope), uniformity)
        : any_centres
            ? fmt::format("slope {} against ln h, for any centres (a bound in the fill distance; "
                          "measured: {}){}",
                          num(slope), uniformity,
                          upper_only ? "; the centres are not quasi-uniform, so the attained "
                                       "order's constants vary with the configuration and only "
                                       "its upper bound is judged"
                                     : "")
            : fmt::format("slope {} against ln h for quasi-uniform centres (the theory is stated "
                          "in the separation distance q, which is h only for them; measured: {})",
                          num(slope), uniformity);
    o.expected = fmt::format("theory: {}, {}; {}; accepted: {} (tolerance {})", theory->statement,
                             theory->sharp ? "order attained" : "an upper bound (faster passes)",
                             conversion, interval_text(interval), num(e.tolerance));
    const auto& analysis = series.analysis.power_law;
    record_fit(series, analysis, o);
    auto [verdict, reason] = judge_series(series, analysis, interval);
    o.verdict = verdict;
    o.reason = reason;
    if (!uniform && !any_centres) {  // the rates above hold for quasi-uniform centres only
      o.verdict = Verdict::inconclusive;
      o.reason = fmt::format("the centres are not quasi-uniform ({}), so the theory's rate does "
                             "not apply (the fit alone: {})",
                             uniformity, reason);
    }
  }

  void judge_model_expectation(const Expectation& e, const MetricSeries& series,
                               ExpectationOutcome& o) const {
    o.expected = fmt::format("the {} describes the series better (ΔAIC >= 2)", model_text(e.model));
    record_fit(series, series.analysis.analysis(e.model), o);
    auto [verdict, reason] = judge_model(series.analysis, e.model);
    o.verdict = verdict;
    o.reason = reason;
  }

  // The n an expectation judges pointwise: its window (n_from, n_to, last), else every n.
  static std::vector<bool> window_members(const Expectation& e, const MetricSeries& series) {
    std::vector<bool> inside(series.trials.size(), true);
    std::size_t kept = 0;
    for (std::size_t k = series.trials.size(); k-- > 0;) {
      const double n = series.n[k];
      inside[k] = (!e.window.n_from || n >= *e.window.n_from) &&
                  (!e.window.n_to || n <= *e.window.n_to) &&
                  (!e.window.last || kept < *e.window.last);
      kept += inside[k];
    }
    return inside;
  }

  // constant = true: the series is constant (detect_constant); constant = { value, within }:
  // every usable value lies within value +- (within + its floor).
  void judge_constant(const Expectation& e, const MetricSeries& series,
                      ExpectationOutcome& o) const {
    record_fit(series, series.analysis.power_law, o);
    if (!e.constant.value) {
      o.expected = fmt::format("{} constant in n (within its floors or {} % of its value)",
                               e.metric, format_real(100.0 * series.constant_within));
      std::size_t usable = 0;
      for (std::size_t k = 0; k < series.values.size(); ++k)
        usable += !series.failed[k] && !series.flagged[k] && std::isfinite(series.values[k]);
      if (series.constant()) {
        o.verdict = Verdict::pass;
        o.reason = "its values lie within the band";
      } else if (usable < 3) {
        o.verdict = Verdict::inconclusive;
        o.reason = fmt::format("{} usable point{}: telling a constant needs at least 3", usable,
                               usable == 1 ? "" : "s");
      } else {
        o.verdict = Verdict::fail;
        o.reason = "it varies with n beyond its floors and the relative band";
      }
      return;
    }
    const double value = *e.constant.value;
    o.expected = fmt::format(
        "{} = {} {} at every n", e.metric, format_real(value),
        e.constant.within > 0 ? "± " + format_real(e.constant.within) + " (plus each value's floor)"
                              : std::string("within each value's floor"));
    const auto inside = window_members(e, series);
    std::size_t used = 0, failed = 0, flagged = 0, non_finite = 0, worst_n = 0;
    double worst = -1.0, worst_excess = -std::numeric_limits<double>::infinity();
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (std::size_t k = 0; k < series.values.size(); ++k) {
      if (!inside[k]) continue;
      if (series.failed[k]) {
        ++failed;
        continue;
      }
      if (series.flagged[k]) {
        ++flagged;
        continue;
      }
      const double y = series.values[k];
      if (!std::isfinite(y)) {
        ++non_finite;
        continue;
      }
      const double floor =
          k < series.floors.size() && series.floors[k] > 0 ? series.floors[k] : 0.0;
      const double allowed =
          e.constant.within + floor + 4.0 * std::numeric_limits<double>::epsilon() * std::fabs(y);
      const double deviation = std::fabs(y - value);
      ++used;
      low = std::min(low, y);
      high = std::max(high, y);
      if (deviation - allowed > worst_excess) {
        worst_excess = deviation - allowed;
        worst = deviation;
        worst_n = static_cast<std::size_t>(series.n[k]);
      }
    }
    o.window_points = used;
    std::vector<std::string> left_out;
    if (failed) left_out.push_back(fmt::format("{} failed", failed));
    if (flagged) left_out.push_back(fmt::format("{} flagged at a floor", flagged));
    if (non_finite) left_out.push_back(fmt::format("{} non-finite", non_finite));
    std::string excluded;
    for (const auto& part : left_out) excluded += (excluded.empty() ? "" : ", ") + part;
    if (non_finite || used == 0) {
      o.verdict = Verdict::inconclusive;
      o.reason = non_finite ? fmt::format("{} value{} not finite: no verdict on it", non_finite,
                                          non_finite == 1 ? " is" : "s are")
                            : fmt::format("no usable value ({})", excluded);
      return;
    }
    o.found =
        fmt::format("{} from {} to {} at {} of {} n{}; {}", e.metric, format_real(low),
                    format_real(high), used, series.trials.size(),
                    excluded.empty() ? std::string() : " (left out: " + excluded + ")", o.found);
    o.verdict = worst_excess > 0.0 ? Verdict::fail : Verdict::pass;
    o.reason = worst_excess > 0.0
                   ? fmt::format("it deviates from {} by {:.3g} at n = {}, {:.3g} beyond the band",
                                 format_real(value), worst, worst_n, worst_excess)
                   : "every usable value lies within the band";
  }

  void judge_bound(const Expectation& e, const MetricSeries& series, ExpectationOutcome& o) const {
    const auto metric_index = study_.metric_index(e.metric);
    const bool has_by = !e.bound.by.empty(), has_times = !e.bound.times.empty();
    const auto by_index = has_by ? study_.metric_index(e.bound.by) : 0;
    const auto times_index = has_times ? study_.metric_index(e.bound.times) : 0;
    auto flagged = [this](const TrialResult& r, const std::string& metric) {
      const auto flag = excluding_flag(study_.kind, metric);
      return !metric.empty() && !flag.empty() &&
             std::find(r.flags.begin(), r.flags.end(), flag) != r.flags.end();
    };
    std::string rhs = has_by && e.bound.constant == 1.0 ? std::string() : format_real(e.bound.constant);
    for (const auto* factor : {&e.bound.by, &e.bound.times}) {
      if (factor->empty()) continue;
      if (!rhs.empty()) rhs += " * ";
      rhs += *factor;
    }
    o.expected = fmt::format("{} <= {} at every n", e.metric, rhs);
    // The lower end of a bracket, relative to the upper: effectivity >= at_least / constant.
    const double lowest = e.bound.at_least ? *e.bound.at_least / e.bound.constant : 0.0;
    if (e.bound.at_least) {
      std::string lower = format_real(*e.bound.at_least);
      for (const auto* factor : {&e.bound.by, &e.bound.times})
        if (!factor->empty()) lower += " * " + *factor;
      o.expected = fmt::format("{} <= {} <= {} at every n", lower, e.metric, rhs);
    }
    double low = std::numeric_limits<double>::infinity(), high = -low;
    std::size_t used = 0, at_max = 0, at_min = 0, skipped = 0;
    std::size_t failed_trials = 0, flagged_values = 0, unusable_values = 0, non_finite = 0;
    const auto inside = window_members(e, series);
    // Each usable n's effectivity and its floor (the relative floors of its factors, added).
    struct Point {
      double effectivity, floor;
      std::size_t n;
    };
    std::vector<Point> points;
    auto relative_floor = [](const TrialResult& r, std::size_t index) {
      const double floor = index < r.floors.size() ? r.floors[index] : 0.0;
      const double value = std::fabs(r.metrics[index]);
      return floor > 0.0 && value > 0.0 ? floor / value : 0.0;
    };
    for (std::size_t k = 0; k < series.trials.size(); ++k) {
      if (!inside[k]) continue;
      const auto t = series.trials[k];
      const auto& r = results_[t];
      const double value = r.metrics[metric_index];
      const double bound = e.bound.constant * (has_by ? r.metrics[by_index] : 1.0) *
                           (has_times ? r.metrics[times_index] : 1.0);
      const bool any_flag = flagged(r, e.metric) || flagged(r, e.bound.by) ||
                            (has_times && flagged(r, e.bound.times));
      const bool usable = r.ok && !any_flag && std::isfinite(value) && value >= 0 &&
                          std::isfinite(bound) && bound > 0;
      if (!usable) {
        ++skipped;
        if (!r.ok) ++failed_trials;
        else if (any_flag) ++flagged_values;
        else ++unusable_values;
        if (r.ok && !any_flag && !(std::isfinite(value) && std::isfinite(bound))) ++non_finite;
        continue;
      }
      const double effectivity = value / bound;
      const double floor = effectivity * (relative_floor(r, metric_index) +
                                          (has_by ? relative_floor(r, by_index) : 0.0) +
                                          (has_times ? relative_floor(r, times_index) : 0.0));
      points.push_back({effectivity, floor, trials_[t].n});
      ++used;
      low = std::min(low, effectivity);
      high = std::max(high, effectivity);
    }
    // Where the extremes are: the first n whose effectivity reaches the extreme within the two
    // floors, so that ties are decided only beyond the floors (the same n on every processor).
    double high_floor = 0.0, low_floor = 0.0;
    for (const auto& p : points) {
      if (p.effectivity == high) high_floor = std::max(high_floor, p.floor);
      if (p.effectivity == low) low_floor = std::max(low_floor, p.floor);
    }
    for (auto it = points.rbegin(); it != points.rend(); ++it) {
      if (it->effectivity + it->floor >= high - high_floor) at_max = it->n;
      if (it->effectivity - it->floor <= low + low_floor) at_min = it->n;
    }
    o.window_points = used;
    std::vector<std::string> left_out;
    if (failed_trials) left_out.push_back(fmt::format("{} failed", failed_trials));
    if (flagged_values) left_out.push_back(fmt::format("{} flagged at a floor", flagged_values));
    if (unusable_values)
      left_out.push_back(fmt::format("{} with a non-finite or non-positive value", unusable_values));
    std::string excluded;
    for (const auto& part : left_out) excluded += (excluded.empty() ? "" : ", ") + part;
    if (used == 0) {
      o.verdict = Verdict::inconclusive;
      o.found = fmt::format("no n where {} and its bound are usable ({})", e.metric, excluded);
      o.reason = "nothing to check";
      return;
    }
    o.effectivity_min = low;
    o.effectivity_max = high;
    o.found = fmt::format("effectivity {} / bound from {:.3g} to {:.3g} (largest at n = {}), at {} "
                          "of {} n{}{}",
                          e.metric, low, high, at_max, used, series.trials.size(),
                          skipped ? fmt::format(" (left out: {})", excluded) : std::string(),
                          e.window.empty() ? std::string()
                                           : fmt::format(" (window set by {})", e.window.text()));
    // Beyond the bound by more than the effectivity's floor: a value within its floor of the
    // bound is not known to exceed it.
    const bool above = high - high_floor > 1.0, below = low + low_floor < lowest;
    o.verdict = above || below ? Verdict::fail : Verdict::pass;
    if (above)
      o.reason = fmt::format("the bound is exceeded by a factor {:.3g} at n = {}", high, at_max);
    else if (below)
      o.reason = fmt::format("below the lower bound at n = {}: {} is {:.3g} times it", at_min,
                             e.metric, low / lowest);
    else
      o.reason = "the bound holds at every usable n";
    // Never a pass over a value that is no number: the bound is not known to hold there.
    if (o.verdict == Verdict::pass && non_finite > 0) {
      o.verdict = Verdict::inconclusive;
      o.reason = fmt::format(
          "{} value{} of {} or its bound not finite in trials reported ok: the "
          "bound is not known to hold there",
          non_finite, non_finite == 1 ? "" : "s", e.metric);
    }
  }

  const StudyDefinition& study_;
  const std::vector<TrialSpec>& trials_;
  const std::vector<TrialResult>& results_;
  const std::vector<MetricSeries>& rates_;
  std::map<std::pair<const Expectation*, std::string>, ExpectationCase> cases_;
};

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

std::vector<ExpectationOutcome> verify_expectations(const StudyDefinition& study,
                                                    const std::vector<TrialSpec>& trials,
                                                    const std::vector<TrialResult>& results,
                                                    const std::vector<MetricSeries>& rates) {
  return Verifier(study, trials, results, rates).run();
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
