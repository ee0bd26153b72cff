#pragma once
// Convergence rates of a finished study: for each group (every axis but n) and each metric,
// the pairwise rates between successive n and a least-squares fit of ln(metric) against ln(n)
// (or ln h, as the study says). Failed trials and values flagged as numerically meaningless
// (singular Gram matrix for the condition number, round-off floors) are excluded from fits and
// the exclusion is said in the fit's note. The fit uses the asymptotic window only (no
// pre-asymptotic head, no floor; rkhs/rates/asymptotic.hpp), and both rate models are fitted: the
// reported one is the power law unless the exponential model fits decisively better.

#include <optional>
#include <string>
#include <vector>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/rates/rates.hpp"
#include "rkhs/rates/theory.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs {

/// What theory says about a series' metric for its group's kernel (rkhs/rates/theory.hpp),
/// worked out once when the series is formed and read by the plots and the theory expectations.
struct SeriesTheory {
  std::optional<TheoryRate> rate;  ///< empty when theory predicts nothing
  std::string why_none;            ///< why `rate` is empty ("" when it is not)
  /// The kernel could not be rebuilt from its name and parameters (a plugin not loaded when a
  /// results folder is read back): why_none holds the error.
  bool kernel_unavailable = false;
};

/// The theory for `metric` of `study` and `kernel`: only a metric whose catalogue row has a
/// theory law asks the kernel's properties (rkhs/kernel/kernel.hpp, kernel_properties).
SeriesTheory series_theory(const StudyDefinition& study, const PluginChoice& kernel,
                           std::string_view metric);

struct MetricSeries {
  std::string metric;
  std::size_t group = 0;                ///< index of the group (order of first appearance)
  std::vector<std::size_t> trials;      ///< trial indices, increasing n
  std::vector<double> abscissa;         ///< n or fill distance, per trial
  std::vector<double> n;                ///< n per trial (the exponential model's abscissa)
  std::vector<double> values;           ///< the metric, NaN for failed trials
  std::vector<double> floors;           ///< their floors (TrialResult::floors), NaN for none
  std::vector<bool> flagged;            ///< excluded from the fit as numerically meaningless
  std::vector<bool> failed;             ///< the trial failed (its value is not a measurement)
  std::string exclusion_flag;           ///< the flag behind `flagged` ("" when none applies)
  /// Size trials.size() - 1, NaN where undefined: the pairwise rates of the reported model
  /// (analysis.reported), power-law rates unless the exponential model is reported.
  std::vector<double> pairwise;
  /// The reported model's fit on its asymptotic window; empty for a constant series
  /// (analysis.constant), which is reported as its value and band instead.
  std::optional<RateFit> fit;
  SeriesAnalysis analysis;              ///< both models, their windows, the preferred one
  std::string note;                     ///< what was excluded and why ("" when nothing)
  std::string no_fit_reason;            ///< why there is no fit ("" when there is one)
  /// The relative band of a constant series (StudyDefinition::constant_within).
  double constant_within = default_constant_within;
  SeriesTheory theory;  ///< for the group's kernel (series_theory)

  /// The series does not vary with n: reported as analysis.constant, not as a rate.
  bool constant() const { return analysis.constant.has_value(); }
};

/// The flag that leaves a value of `metric` (a metric of a `kind` trial) out of rate fits, or ""
/// when none does: read from the kind's metric table (rkhs/approx/metrics.hpp,
/// rkhs/adaptive/metrics.hpp: `flag` where `flag_excludes_from_fits`).
std::string_view excluding_flag(StudyKind kind, std::string_view metric);

/// Series for every group and every metric of the study, groups in trial order, fitted on the
/// study's window (`[rates]`: StudyDefinition::rates_window; empty: the automatic one).
std::vector<MetricSeries> compute_rates(const StudyDefinition& study,
                                        const std::vector<TrialSpec>& trials,
                                        const std::vector<TrialResult>& results);

/// (Re)computes a series' analysis, fit, pairwise rates, note and no_fit_reason from its
/// abscissa, n, values, floors, flagged, failed and constant_within, on `window` (empty: the
/// automatic window). A constant series gets no fit; no_fit_reason then states its constant. An
/// [[expect]] table with its own window judges the series refitted this way.
void fit_series(MetricSeries& series, const FitWindow& window);

}  // namespace rkhs
