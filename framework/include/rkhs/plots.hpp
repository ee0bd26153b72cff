#pragma once
// Plots of a finished run with gnuplot (SVG and PNG, no display needed): one convergence plot
// per metric (log-log points per group, the fitted rate as a line with its 95% confidence band,
// flagged values hollow), and for adaptive studies the estimate against the road at each
// snapshot lap and |x - xhat| and V against time, per group.

#include <filesystem>
#include <string>
#include <vector>

#include "rkhs/output.hpp"

namespace rkhs {

/// gnuplot scripts with their data inline, by output file stem ("convergence_l2_error", ...).
std::vector<std::pair<std::string, std::string>> plot_scripts(const RunRecord& run);

/// Writes plots/<stem>.gp and renders plots/<stem>.svg and .png with `gnuplot` (found on PATH).
/// Returns the stems rendered. Throws std::runtime_error when gnuplot is missing or fails, saying
/// which script failed.
std::vector<std::string> write_plots(const RunRecord& run, const std::filesystem::path& directory);

}  // namespace rkhs
