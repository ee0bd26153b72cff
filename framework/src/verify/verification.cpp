// Judging a study's expectations against its trials and rates (verification.hpp): the Verifier.
// The judgements it combines are judgement.cpp; verdicts, counts and their text verdicts.cpp.
#include "rkhs/verify/verification.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "judgement.hpp"
#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/study/trial_grid.hpp"
#include "rkhs/rates/theory.hpp"
#include "rkhs/verify/expectation_cases.hpp"

namespace rkhs {
namespace {

using namespace verify_detail;

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
      case ExpectationKind::reference: {
        std::vector<std::string> flags;
        for (auto t : series.trials) {
          std::string joined;
          for (const auto& flag : results_[t].flags) joined += (joined.empty() ? "" : ", ") + flag;
          flags.push_back(std::move(joined));
        }
        judge_reference(e, series, window_members(e, series), flags, o);
        break;
      }
    }
    if (o.verdict != Verdict::pass && e.kind != ExpectationKind::bound &&
        e.kind != ExpectationKind::constant && e.kind != ExpectationKind::reference &&
        !series.constant())
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
    const auto& theory = series.theory.rate;
    if (!theory) {  // the parser rejects this; a study built in code may still ask for it
      o.verdict = Verdict::inconclusive;
      o.expected = "theory";
      o.reason = series.theory.why_none;
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
            ? fmt::format(
                  "slope {} against ln n for quasi-uniform centres (h ~ n^-1/d; measured: {})",
                  num(slope), uniformity)
        : any_centres
            ? fmt::format(
                  "slope {} against ln h, for any centres (a bound in the fill distance; "
                  "measured: {}){}",
                  num(slope), uniformity,
                  upper_only ? "; the centres are not quasi-uniform, so the attained "
                               "order's constants vary with the configuration and only "
                               "its upper bound is judged"
                             : "")
            : fmt::format("slope {} against ln h for quasi-uniform centres ({}; measured: {})",
                          num(slope), theory->quasi_uniform_because, uniformity);
    o.expected = fmt::format("theory: {}, {}; {}; accepted: {} (tolerance {}){}", theory->statement,
                             theory->sharp ? "order attained" : "an upper bound (faster passes)",
                             conversion, interval_text(interval), num(e.tolerance),
                             theory->values_below ? fmt::format(", and every value below {}",
                                                                format_real(*theory->values_below))
                                                  : std::string());
    const auto& analysis = series.analysis.power_law;
    record_fit(series, analysis, o);
    auto [verdict, reason] = judge_series(series, analysis, interval);
    if (theory->values_below) {
      const auto values =
          judge_values_below(series, window_members(e, series), *theory->values_below);
      verdict = worst(verdict, values.verdict);
      reason += "; " + values.reason;
    }
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
      const auto flag = excluding_flag(study_.kind(), metric);
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

std::vector<ExpectationOutcome> verify_expectations(const StudyDefinition& study,
                                                    const std::vector<TrialSpec>& trials,
                                                    const std::vector<TrialResult>& results,
                                                    const std::vector<MetricSeries>& rates) {
  return Verifier(study, trials, results, rates).run();
}

}  // namespace rkhs
