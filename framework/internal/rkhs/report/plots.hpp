#pragma once
// Plots of a finished run with gnuplot (SVG, PNG and PDF, no display needed).
//
// How every plot looks is the study's [plot] table's (PlotStyle, docs/study-files.md): the
// figure's size in inches (the PDF's page), its font size in points, the PNG's resolution
// (the PNG and SVG are rasters of the PDF: text, lines and points scaled alike); for the
// convergence plots also which metrics are plotted in which order, the y labels (default: the
// metric table's label, rkhs::metric_axis_label), the title (default: the study's name, the
// plugins every curve shares by name, and what the line styles mean) and where the key goes
// (default: below the x axis' label).
//
// Convergence plots, one figure per metric (convergence_<metric>): log-log points per group,
// the fitted rate as a dashed line drawn over the points, on its fit window, with its 95%
// confidence band (clipped to the fitted values, within a factor 2), the kernel's power-law theory
// slope as a dotted line over the same window through the fitted line at the window's geometric
// centre, flagged values hollow. The x and y ranges are the plotted values' with a small margin (at
// most 30% on x, a factor 2 on y); an axis of less than about two and a half decades gets labelled
// tics at 1, 2 and 5 times the powers of ten, one of less than a decade at every digit.
//   Legends name exactly the axes that differ among the curves of a panel, each curve with its
// rate: a plugin axis whose plugin differs is a factor ("kernel=bspline") with a factor per
// parameter that differs among that plugin's own groups, written after it ("kernel=bspline
// degree=1"); a plugin axis with one plugin gives a factor per parameter that differs
// ("class=A"); a laps axis one more. What every curve shares is said once, in the title. Groups
// that differ only in axes the metric does not depend on (their series equal wherever those
// axes alone change, e.g. the power function and the target) are one curve, and the title says
// "the same for every ...".
//   Small multiples: a metric with more than 8 curves is drawn as a grid of panels (gnuplot
// multiplot), one panel per value of the factors chosen so that no panel holds more than 8
// curves, with the fewest panels, then the fewest factors, then the earliest factors, a
// parameter always with its plugin (e.g. iso8608's l2_error: kernel and seed, 12 panels of 7
// road classes and wavinesses). Panel titles name the panel's values; x and y ranges are shared
// by all panels of a metric; a curve keeps its colour in every panel when the curves'
// identities within panels number 8 or fewer. The figure grows with the panels (3.2 x 3.2
// inches each, up to 4 columns) unless [plot] size fixes it; beyond 12 panels the figure is split
// into files convergence_<metric>_part1, _part2, ... of at most 12 panels.
//
// For adaptive studies: the estimate against the road at each snapshot lap and |x - xhat| and
// V against time, per group (titled by what sets the group apart); for adaptive studies with a
// reference integrator ([adaptive] reference), work-precision plots: per panel (every axis but
// the integrator and its tolerances), integration_error against each trial's wall time
// (work_precision_time_panelK; not deterministic) and against its steps
// (work_precision_steps_panelK), one line per integrator, points ordered by tolerance.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "rkhs/report/output.hpp"

namespace rkhs {

/// The plots of a run, before rendering: gnuplot scripts with their data inline, by output file
/// stem ("convergence_l2_error", ...), each rendering itself to <stem>.svg, <stem>.png and
/// <stem>.pdf in the current directory (no paths: a script is the same wherever the run
/// writes it; deterministic, except the work-precision time plots' wall times), and a note for each
/// plot left out because it would have nothing to show (a metric with no finite positive value in
/// any trial, a group whose trials all failed).
struct PlotPlan {
  std::vector<std::pair<std::string, std::string>> scripts;  ///< (stem, script)
  std::vector<std::string> notes;                            ///< "<stem>: not plotted: <why>"
};
PlotPlan plot_scripts(const RunRecord& run);

/// `metrics` in the order their convergence plots are shown: the errors first (a name with
/// "error" in it), then the other metrics, then the mesh quantities (fill_distance,
/// separation_distance), each part in the order given.
std::vector<std::string> convergence_plot_order(const std::vector<std::string>& metrics);

/// The metrics whose convergence plots a run of `study` draws, in order: [plot] metrics when
/// the study file gives them, else convergence_plot_order(study.metrics).
std::vector<std::string> plotted_metrics(const StudyDefinition& study);

/// What write_plots did. A plot that gnuplot could not render is a failure of that plot alone:
/// the others are still rendered.
struct PlotOutcome {
  std::vector<std::string> rendered;  ///< stems rendered to .svg, .png and .pdf
  std::vector<std::string> notes;     ///< plots left out, and why (PlotPlan::notes)
  std::vector<std::string> failures;  ///< "<stem>.gp: <gnuplot's own message>"; or that
                                      ///< gnuplot is not installed (then nothing is rendered)
  bool interrupted = false;  ///< stop_requested returned true: gnuplot killed, the rest not run
};

/// How long gnuplot may take, and when to stop it.
struct PlotOptions {
  /// One gnuplot process (one plot: SVG, PNG and PDF) may run this long; then it is killed and
  /// that plot fails ("did not finish within 120 s"). RKHS_STUDY_GNUPLOT_SECONDS, a positive
  /// number, replaces the default.
  double gnuplot_seconds = 120;
  /// Polled while gnuplot runs (every 20 ms); once it returns true gnuplot is killed and no
  /// further plot is rendered (PlotOutcome::interrupted). May be empty: never.
  std::function<bool()> stop_requested;
};

/// PlotOptions with gnuplot_seconds from RKHS_STUDY_GNUPLOT_SECONDS when that is a positive
/// number (else the default) and `stop_requested`.
PlotOptions plot_options(std::function<bool()> stop_requested);

/// Writes plots/<stem>.gp and renders plots/<stem>.svg, .png and .pdf with `gnuplot` (found on
/// PATH, run in plots/ by fork and exec, never through a shell), each plot on its own. First it
/// removes the files an earlier run listed in plots/.rkhs-study-manifest (and only those: a file
/// of the user's own in plots/ stays), then lists in the manifest every file this run may write.
/// Text from the study (names, labels, parameter values, file names) reaches the scripts only as
/// single-quoted gnuplot strings (no backquote substitution, no macros, no escapes), control
/// characters replaced. A failed plot keeps its script and its log (plots/<stem>.log). Throws
/// only when the plots folder cannot be written. gnuplot runs in a process group of its own,
/// which is killed (SIGKILL) when it runs past options.gnuplot_seconds or when
/// options.stop_requested returns true: a hanging gnuplot never keeps the command from ending.
PlotOutcome write_plots(const RunRecord& run, const std::filesystem::path& directory,
                        const PlotOptions& options = {});

}  // namespace rkhs
