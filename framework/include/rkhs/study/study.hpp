#pragma once
// Study definitions: a TOML file (docs/study-files.md) that declares axes (kernels with their
// parameters, n, targets, centre placements), the domain, the metrics and the solver; the trial
// grid is the Cartesian product of the axes.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/approx/metrics.hpp"
#include "rkhs/core/domain.hpp"
#include "rkhs/core/parameters.hpp"
#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/study/expectation.hpp"
#include "rkhs/study/study_kind.hpp"

namespace rkhs {

/// A bad study file. `what()` reads "file:line:column: key: what was found; what is allowed".
class StudyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One plugin with its resolved parameters.
struct PluginChoice {
  std::string name;
  ParameterSet parameters;
  /// `tier = "quick"` (or a list) in the entry: the tiers it belongs to; empty when unmarked.
  /// Not part of the label or the trial key.
  std::vector<std::string> tiers;
  /// "name p1=v1 p2=v2": the plugin part of a trial key.
  std::string label() const;
  /// "name p1=v1" with only the parameters the study file gave: how a message names the entry.
  std::string given_label() const;
};

/// What only an approximation trial has: nothing yet ([[projection]] is an axis of both kinds).
struct ApproximationTrialAxes {};

/// What only an adaptive trial has: its plant, learning law and integrator, and its lap count.
struct AdaptiveTrialAxes {
  PluginChoice plant;
  PluginChoice law;
  PluginChoice integrator;
  /// The trial's lap count when the study has a laps axis ([adaptive] laps = [10, 100,
  /// "limit"]): a positive number, +infinity for "limit". std::nullopt when laps is one value
  /// (AdaptiveStudyAxes::settings.laps applies, and nothing about laps is in the keys).
  std::optional<double> laps;
};

/// A trial's kind's own part: one alternative per StudyKind, in the enum's order (checked where
/// each kind is described, study/approximation_kind.cpp and study/adaptive_kind.cpp).
using TrialKindAxes = std::variant<ApproximationTrialAxes, AdaptiveTrialAxes>;

/// One point of the trial grid.
struct TrialSpec {
  std::size_t index = 0;  ///< position in the grid (the order of trials.csv)
  PluginChoice kernel;
  PluginChoice target;
  PluginChoice centres;
  /// Trials of a study with a [[projection]] axis (empty name otherwise: an approximation trial
  /// projects by interpolation at the centres, and nothing about it is in the keys).
  PluginChoice projection;
  /// What only its kind's trials have; its alternative is the kind of its study.
  TrialKindAxes kind_axes;
  std::size_t n = 0;
  std::string group_key;  ///< every axis but n: trials of a group form one convergence series
  std::string key;        ///< every axis: identifies the trial
  /// Hash of key (without its laps part: every lap count of a series has the same random
  /// centres): the seed of any randomness in the trial.
  std::uint64_t seed = 0;

  /// The kind of the study the trial is of: the alternative kind_axes holds.
  StudyKind kind() const noexcept { return static_cast<StudyKind>(kind_axes.index()); }
  /// The adaptive trial's own part; throws std::logic_error naming the kind for a trial of
  /// another kind.
  const AdaptiveTrialAxes& adaptive_axes() const;
  AdaptiveTrialAxes& adaptive_axes();
  /// The same, nullptr for a trial of another kind.
  const AdaptiveTrialAxes* adaptive_axes_if() const noexcept {
    return std::get_if<AdaptiveTrialAxes>(&kind_axes);
  }
  AdaptiveTrialAxes* adaptive_axes_if() noexcept {
    return std::get_if<AdaptiveTrialAxes>(&kind_axes);
  }
  /// The trial's plugin choices in the order of trials.csv's columns, each with its axis'
  /// name: "kernel", "target", "centres", "projection", then its kind's own ("plant", "law",
  /// "integrator"); an axis the study does not have is an empty choice.
  std::vector<std::pair<const char*, const PluginChoice*>> plugin_choices() const;
  std::vector<std::pair<const char*, PluginChoice*>> plugin_choices();
};

/// [limits]: what one trial may use (docs/study-files.md); a trial beyond them fails with the
/// reason, the rest of the study goes on.
struct StudyLimits {
  double trial_seconds = 0;          ///< a trial running longer fails (0: no limit)
  double matrix_megabytes = 2048;    ///< a trial whose dense matrices exceed this fails up front
  /// The trials running at once together stay within this many MB of predicted matrices
  /// (trial_footprint): a trial that would not fit waits for others to finish, a smaller one
  /// further down the order starts meanwhile, and a trial runs alone whatever its size (0: no
  /// limit).
  double memory_megabytes = 0;
};

/// "approximation", "adaptive": the name of `kind` (describe(kind).name()).
std::string_view study_kind_name(StudyKind kind) noexcept;

/// The kind `name` stands for; std::nullopt for an unknown name.
std::optional<StudyKind> study_kind_from_name(std::string_view name) noexcept;

/// [plot]: how the convergence plots look (docs/study-files.md). Only the figures change: no
/// number, no trial key, no table. Every field has a default that reads well.
struct PlotStyle {
  /// The metrics plotted, in this order (each one of StudyDefinition::metrics); empty: every
  /// metric of the study, the errors first (convergence_plot_order, rkhs/report/plots.hpp).
  std::vector<std::string> metrics;
  /// metric -> y axis label, gnuplot enhanced text ("L^2 error ||f - {/Symbol P}_n f||"); a
  /// metric not listed gets metric_axis_label().
  std::map<std::string, std::string> labels;
  /// The figure's title: std::nullopt for the default (the plugins every curve shares and the
  /// line styles), "" for none (title = false), else the text, gnuplot enhanced text.
  std::optional<std::string> title;
  /// The figure's size in inches (the PDF's page; PNG and SVG alike at png_dpi); 0: the default,
  /// 6 x 4.5 for one plot plus the title's lines, 3.2 x 3.2 per panel of a grid.
  double width_inches = 0, height_inches = 0;
  double font_points = 10;  ///< text size in points, at the figure's size
  /// Where the key goes: below (under the x axis' label), outside (right of the axes), top
  /// right, top left, bottom right, bottom left (inside the axes), none.
  std::string legend = "below";
  int png_dpi = 150;  ///< PNG pixels per inch (the SVG's canvas is the PNG's size)

  static constexpr double max_inches = 40;
  static constexpr double min_font_points = 4, max_font_points = 72;
  static constexpr int min_png_dpi = 50, max_png_dpi = 1200;
  static constexpr double max_png_pixels = 20000;  ///< per side: inches x png_dpi
  /// The accepted values of `legend`.
  static const std::vector<std::string>& legend_positions();
};

/// What only an approximation study has: nothing yet ([[projection]] is an axis of both kinds).
struct ApproximationStudyAxes {};

/// What only an adaptive study has: the [[plant]], [[law]] and [[integrator]] axes and the
/// [adaptive] section.
struct AdaptiveStudyAxes {
  std::vector<PluginChoice> plants, laws, integrators;
  AdaptiveSettings settings;  ///< [adaptive]
  /// [adaptive] laps given as a list: the values of the laps axis, in the file's order
  /// (+infinity for "limit"), nested just outside n. Empty when laps is one value, which is
  /// then settings.laps; with the axis, settings.laps is NaN and each trial's lap count is
  /// AdaptiveTrialAxes::laps (run_trial gives measure_adaptive the settings with it).
  std::vector<double> laps_values;
  /// [adaptive] reference = { integrator = "radau5", rtol = 1e-11, atol = 1e-10 }: the
  /// integrator (with its resolved parameters) every trial also integrates with, for
  /// integration_error; its trials step through time. An empty name: no reference.
  PluginChoice reference;
};

/// A study's kind's own part: one alternative per StudyKind, in the enum's order (checked where
/// each kind is described, study/approximation_kind.cpp and study/adaptive_kind.cpp).
using StudyKindAxes = std::variant<ApproximationStudyAxes, AdaptiveStudyAxes>;
static_assert(std::variant_size_v<StudyKindAxes> == std::variant_size_v<TrialKindAxes>);

/// The part of a study, and of a trial, of `kind` that only its kind has, with nothing set.
StudyKindAxes study_kind_axes(StudyKind kind);
TrialKindAxes trial_kind_axes(StudyKind kind);

struct StudyDefinition {
  std::string name;
  std::string description;
  std::string source;  ///< the file it was read from
  /// What only its kind's studies have; its alternative is the study's kind (kind()), the
  /// first kind of study_kind_table(), approximation, by default.
  StudyKindAxes kind_axes;
  Domain domain;
  std::vector<std::size_t> n_values;  ///< increasing, distinct
  /// [grid] tier_n: the values of n a tier runs (increasing, some of n_values); a tier it does not
  /// name runs them all (restrict_to_tier, rkhs/study/tiers.hpp).
  std::map<std::string, std::vector<std::size_t>, std::less<>> tier_n_values;
  std::size_t evaluation_points = 4096;
  std::vector<PluginChoice> kernels, targets, centres;
  /// [[projection]] entries (empty when the file has none): in an adaptive study each trial
  /// also runs the finite estimator of its projection (Theorem 4.1).
  std::vector<PluginChoice> projections;
  std::vector<std::string> metrics;  ///< the metrics written and fitted, in output order
  Abscissa abscissa = Abscissa::n;
  /// [rates]: the window every series is fitted on (empty: the automatic asymptotic window;
  /// rkhs/rates/asymptotic.hpp).
  FitWindow rates_window;
  /// [rates] constant_within: the relative band within which a series is reported as constant
  /// rather than as a rate (rkhs/rates/asymptotic.hpp, detect_constant).
  double constant_within = default_constant_within;
  SolverOptions solver;
  StudyLimits limits;
  std::vector<Expectation> expectations;  ///< [[expect]] tables (rkhs/study/expectation.hpp)
  /// What the file asks for that is valid but doubtful, as "file:line:column: key: why" (e.g. an
  /// evaluation grid too coarse for the largest n); `validate`, `run` and `check` print them.
  std::vector<std::string> warnings;
  PlotStyle plot;  ///< [plot]

  /// What this study's kind is: the alternative kind_axes holds.
  StudyKind kind() const noexcept { return static_cast<StudyKind>(kind_axes.index()); }
  /// The adaptive study's own part; throws std::logic_error naming the study's kind for a
  /// study of another kind.
  const AdaptiveStudyAxes& adaptive_axes() const;
  AdaptiveStudyAxes& adaptive_axes();
  /// The same, nullptr for a study of another kind.
  const AdaptiveStudyAxes* adaptive_axes_if() const noexcept {
    return std::get_if<AdaptiveStudyAxes>(&kind_axes);
  }
  AdaptiveStudyAxes* adaptive_axes_if() noexcept {
    return std::get_if<AdaptiveStudyAxes>(&kind_axes);
  }
  /// The study's plugin axes in the order of TrialSpec::plugin_choices(), each with its name
  /// ("kernel", ..., "projection", then its kind's own: "plant", "law", "integrator").
  std::vector<std::pair<const char*, const std::vector<PluginChoice>*>> plugin_axes() const;
  std::vector<std::pair<const char*, std::vector<PluginChoice>*>> plugin_axes();

  /// The Cartesian product kernels x targets x centres [x projections] [x plants x laws x
  /// integrators] [x laps] x n, n varying fastest.
  std::vector<TrialSpec> trials() const;

  /// What this study's kind is (rkhs/study/study_kind.hpp).
  const StudyKindDescriptor& kind_descriptor() const noexcept { return describe(kind()); }

  /// One axis of the trial grid: what it is called (singular and plural) and how many values
  /// it has. grid_axes() lists the axes this study's kind has, in the order trials() nests
  /// them (n last); the product of the counts is trials().size().
  struct GridAxis {
    const char* singular;
    const char* plural;
    std::size_t count;
  };
  std::vector<GridAxis> grid_axes() const;

  /// Every metric a trial of this study's kind measures (TrialResult::metrics is aligned with
  /// it), and the position of one of them (throws std::out_of_range for an unknown name).
  const std::vector<std::string>& all_metrics() const;
  std::size_t metric_index(std::string_view metric) const;
  /// The metrics of all_metrics() that every projection of the study computes (the
  /// interpolation projection's without [[projection]]: all but the matrix-free projections'
  /// own; a matrix-free projection's those it declares), in output order: what `metrics` may
  /// list and lists when the file names none.
  std::vector<std::string> computable_metrics() const;

  /// The metrics a trial of this study computes, by position in all_metrics(): for an
  /// approximation study `metrics`, with the fill distance when rates are fitted against h and
  /// the fill and separation distances when an expectation compares with theory (which judges
  /// the centres' quasi-uniformity); a trial then does only the work these need
  /// (MetricInfo::needs) and leaves the others NaN. Every metric for an adaptive study, whose
  /// trials compute all of them.
  MetricSelection computed_metrics() const;
  /// The names of computed_metrics(), in output order.
  std::vector<std::string> computed_metric_names() const;
  /// Why each metric computed beyond `metrics` is computed ("abscissa = \"h\"", "theory
  /// expectations (quasi-uniformity)"), each reason once, in the order of the rules above.
  std::vector<std::string> computed_metric_reasons() const;
};

/// A lap count as the laps column, the keys and messages print it: "limit" for +infinity, a
/// whole number without an exponent ("1000000"), any other number as format_real does ("2.5").
std::string laps_text(double laps);

/// The adaptive settings `trial` (of an adaptive study) runs with: the study's settings with the
/// trial's lap count when the study has a laps axis, keeping only the snapshot laps the trial
/// reaches, and time stepping when the study has a reference integrator (the reference is never
/// a lap map's).
AdaptiveSettings trial_adaptive_settings(const StudyDefinition& study, const TrialSpec& trial);

/// Every metric a trial of `kind` measures, in output order.
const std::vector<std::string>& metric_names(StudyKind kind);

/// How the floor of `metric` (a metric of a `kind` trial) is estimated (MetricInfo::floor);
/// FloorRule::exact for an unknown name.
FloorRule metric_floor_rule(StudyKind kind, std::string_view metric);

/// The y axis label of `metric` (a metric of a `kind` trial) in its plots: the metric table's
/// label (MetricInfo::label, gnuplot enhanced text) with the unit in parentheses when it is a
/// physical one (m, s, 1/s, laps); the name itself for an unknown metric.
std::string metric_axis_label(StudyKind kind, std::string_view metric);

/// Reads and validates a study file. Throws StudyError (file, line, column, key, found,
/// allowed, and a suggestion for misspelt names) for any problem.
StudyDefinition load_study(const std::filesystem::path& file);
/// The same from text; `source_name` is used in messages.
StudyDefinition parse_study(std::string_view text, const std::string& source_name);

}  // namespace rkhs
