#pragma once
// Plots of a finished run with gnuplot (SVG and PNG, no display needed): one convergence plot
// per metric (log-log points per group, the fitted rate as a line with its 95% confidence band,
// flagged values hollow), and for adaptive studies the estimate against the road at each
// snapshot lap and |x - xhat| and V against time, per group; for adaptive studies with a
// reference integrator ([adaptive] reference), work-precision plots: per panel (every axis but
// the integrator and its tolerances), integration_error against each trial's wall time
// (work_precision_time_panelK; not deterministic) and against its steps
// (work_precision_steps_panelK), one line per integrator, points ordered by tolerance.

#include <filesystem>
#include <string>
#include <vector>

#include "rkhs/report/output.hpp"

namespace rkhs {

/// The plots of a run, before rendering: gnuplot scripts with their data inline, by output file
/// stem ("convergence_l2_error", ...), and a note for each plot left out because it would have
/// nothing to show (a metric with no finite positive value in any trial, a group whose trials
/// all failed).
struct PlotPlan {
  std::vector<std::pair<std::string, std::string>> scripts;  ///< (stem, script)
  std::vector<std::string> notes;                            ///< "<stem>: not plotted: <why>"
};
PlotPlan plot_scripts(const RunRecord& run);

/// What write_plots did. A plot that gnuplot could not render is a failure of that plot alone:
/// the others are still rendered.
struct PlotOutcome {
  std::vector<std::string> rendered;  ///< stems rendered to .svg and .png
  std::vector<std::string> notes;     ///< plots left out, and why (PlotPlan::notes)
  std::vector<std::string> failures;  ///< "<stem>.gp: <gnuplot's own message>"; or that
                                      ///< gnuplot is not installed (then nothing is rendered)
};

/// Writes plots/<stem>.gp and renders plots/<stem>.svg and .png with `gnuplot` (found on PATH),
/// each plot on its own, after removing the plot files (.gp, .svg, .png, .log) an earlier run
/// left in plots/. A failed plot keeps its script and its log (plots/<stem>.log). Throws only
/// when the plots folder cannot be written.
PlotOutcome write_plots(const RunRecord& run, const std::filesystem::path& directory);

}  // namespace rkhs
