#pragma once
// Internal to the verify layer: the judgements verification.cpp combines into verdicts (the
// interval rule, constant series, model expectations), the text of fits for the "found" line,
// and the quasi-uniformity of a group's centres. Defined in judgement.cpp.

#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rkhs/verify/verification.hpp"

namespace rkhs::verify_detail {

inline constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
// Quasi-uniformity, as far as a finite study can tell: the fill distance decays like n^-1/d and
// the mesh ratio h / q neither grows nor shrinks, both within this slope.
inline constexpr double quasi_uniform_slack = 0.1;

// A rate for messages: 2 decimals from 1 up, 3 below 1, 3 significant digits below 0.01.
std::string num(double v);

std::string interval_text(const RateInterval& i);

std::string_view model_text(RateModel model);

Verdict worst(Verdict a, Verdict b);

struct Judgement {
  Verdict verdict;
  std::string reason;
};

// The interval rule of verification.hpp.
Judgement judge_interval(const RateFit* fit, const RateInterval& accepted);

// The values a theory bounds (TheoryRate::values_below): every usable value (not failed, not
// flagged) among the `inside` ones below `bound`. A value within its floor of the bound is not
// known to exceed it; a non-finite one makes the verdict inconclusive.
Judgement judge_values_below(const MetricSeries& series, const std::vector<bool>& inside,
                             double bound);

// The rates a constant series allows under `model`: every line within its band over its points,
// slopes up to w = 2 band / |value| per span of ln x (power law) or of n (exponential).
// +inf for a constant of value 0 with a band, or a span of 0.
double constant_rate_width(const MetricSeries& series, RateModel model);

// A rate verdict on a constant series: the rates its band allows, [-w, w], against the
// accepted interval (the same rule as a CI: within passes, outside fails, across is open).
Judgement judge_constant_rate(const MetricSeries& series, RateModel model,
                              const RateInterval& accepted);

// A model expectation (also the first half of an analytic theory).
Judgement judge_model(const SeriesAnalysis& analysis, RateModel required);

// Fit, CI, window and exclusions of one model of a series, for the "found" line.
std::string describe_fit(const MetricSeries& series, const ModelAnalysis& analysis);

// The power law with its pre-asymptotic term, when the verdict judges it ("" otherwise).
std::string describe_bend(const MetricSeries& series, const ModelAnalysis& analysis);

// The points a fit of one model left out, and the notes of the series, as "; ..." clauses.
std::string exclusions(const MetricSeries& series, const ModelAnalysis& analysis);

// Whether the centres of a group are quasi-uniform, judged from the trials' fill and separation
// distances: the sentence for the "expected" line, and whether the theory can be converted.
// `dimension`: d of the kernel's domain (KernelProperties::dimension).
std::pair<bool, std::string> quasi_uniformity(int dimension, const StudyDefinition& study,
                                              const std::vector<TrialSpec>& trials,
                                              const std::vector<TrialResult>& results,
                                              const MetricSeries& series);

// reference = { ... }: judges `series` against e.reference's published values at the n where
// `inside` holds (reference_judgement.cpp); `flags[k]` are the flags of the series' k-th trial,
// joined, for the message on a value that is no number. Sets o.expected, found, reason,
// verdict, window_points and effectivity_min / effectivity_max (the ratios' range).
void judge_reference(const Expectation& e, const MetricSeries& series,
                     const std::vector<bool>& inside, const std::vector<std::string>& flags,
                     ExpectationOutcome& o);

}  // namespace rkhs::verify_detail
