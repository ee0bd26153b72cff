#pragma once
// Internal to the report layer: the parts of the plots (rkhs/report/plots.hpp) written in the
// files beside plots.cpp. plot_text.cpp writes gnuplot text (quoting, axes, figures, line types),
// plot_identity.cpp tells a plot's trials apart, convergence_plots.cpp and adaptive_plots.cpp
// write the scripts of each kind of plot.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/report/plots.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::plot_detail {

// ---- gnuplot text (plot_text.cpp) ------------------------------------------------------------

/// A gnuplot string expression showing `text` as written, safe for text from a study file:
/// single-quoted (gnuplot substitutes nothing there), line breaks joined with "\n", control
/// characters and bytes that are not UTF-8 as '?'. Commands using it say `noenhanced`.
std::string gp_text(std::string_view text);

/// `items` joined by `separator`, broken into lines of about `width` characters.
std::string wrapped(const std::vector<std::string>& items, std::size_t width,
                    std::string_view separator = ", ");

/// The title, axis labels, log scales, grid and key of a plain plot.
std::string header(std::string_view title, std::string_view xlabel, std::string_view ylabel,
                   bool logx, bool logy);

/// A value a logarithmic axis can show.
inline bool usable_on_log_axis(double v) {
  return std::isfinite(v) && v > 0;
}

/// The extent of the values an axis shows.
struct Extent {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void add(double v) {
    low = std::min(low, v);
    high = std::max(high, v);
  }
  bool empty() const { return !(low <= high); }
};

/// The margin a logarithmic axis leaves around `extent`: a factor of (high / low)^share, at
/// least `least` and at most `most`.
double log_margin(const Extent& extent, double share, double least, double most);
inline constexpr double x_share = 0.03, x_least = 1.03, x_most = 1.3;
inline constexpr double y_share = 0.05, y_least = 1.1, y_most = 2.0;

/// "set xrange [a:b]" for a logarithmic axis over `extent` with its margin, with labelled tics
/// between the decades when it spans few.
std::string log_range(const char* axis, const Extent& extent, bool is_x);

/// A figure's size in inches.
struct Figure {
  double width = 0, height = 0;
};
inline constexpr Figure single_figure{6, 4.5};  ///< one plot, without its title

/// The script that renders `drawing` (the data blocks first, outside) to <stem>.svg, .png and
/// .pdf in the current directory, alike at the figure's size and style's font and resolution.
std::string rendered(const std::string& stem, Figure figure, const PlotStyle& style,
                     const std::string& data, const std::string& drawing);

/// The figure's size: [plot] size when given, else `automatic`.
Figure sized(const PlotStyle& style, Figure automatic);

/// About how many characters of the figure's text fit across `inches` (gnuplot does not wrap).
std::size_t characters_across(double inches, const PlotStyle& style);

/// The height of `lines` lines of text, in inches.
double text_height(std::size_t lines, const PlotStyle& style);

/// Line types 1 to palette_size: colour-blind safe colours, each with a filled point type;
/// filled_point[i] - 1 is its hollow one (flagged values).
inline constexpr int palette_size = 8;
inline constexpr int filled_point[palette_size] = {7, 5, 9, 11, 13, 15, 7, 5};
std::string line_types();

/// The gnuplot commands that place the key at [plot] legend `position`.
std::string key_placement(std::string_view position);

// ---- What tells a plot's trials apart (plot_identity.cpp) ------------------------------------

/// The identity of each of a set of trials split into factors, the axes whose values differ
// among them: a plugin axis whose plugin differs gives a factor for the plugin
// ("kernel=bspline") and one per parameter that differs among the trials of one plugin
// ("degree=1"; empty for a trial of another plugin, or of one where it does not differ); a
// plugin axis with one plugin gives a factor per parameter that differs ("class=A"); laps one
// more. The constants are the text of everything the same for all ("target=iso8608 n_max=10",
// "bspline: J=8").
struct Identity {
  std::vector<std::string> factors;  ///< factor names, axis order
  std::vector<std::string> axes;     ///< the axis of each factor ("kernel", ..., "laps")
  /// The plugin factor a parameter factor belongs to (an axis with several plugins: a
  /// parameter means nothing without its plugin), or npos.
  std::vector<std::size_t> owner;
  std::vector<std::vector<std::string>> values;  ///< [trial][factor]: "name=value" or ""
  std::vector<std::string> constants;
  /// The plugin axes the trials' kind has ("kernel", ..., TrialSpec::plugin_choices()).
  std::vector<std::string> plugin_axes;
};

/// The text of `factors` of one trial: "name=value" pairs separated by commas, a plugin's own
/// parameters after it and a space ("kernel=bspline degree=1, class=A").
std::string identity_text(const Identity& identity, std::size_t trial,
                          const std::vector<std::size_t>& factors);

/// The identity of each of `trials`.
Identity identify(const std::vector<const TrialSpec*>& trials);

/// The factors whose values split `identity`'s trials into panels of at most `most` each (none
/// when all fit one plot): the fewest panels, then the fewest factors, then the earliest, a
/// parameter's plugin always with it.
std::vector<std::size_t> panel_factors(const Identity& identity, std::size_t most);

/// Short legend text for a group: the kernel, law and integrator names, and a lap count.
std::string legend(const TrialSpec& trial);

/// The constants of `identity` a short title names: each plugin every curve shares, by name, a
/// lap count, and which axes the curves are the same for.
std::string short_constants(const Identity& identity);

// ---- The scripts of each kind of plot --------------------------------------------------------

/// The convergence plots of `metric` (convergence_plots.cpp): one file, or parts of at most 12
/// panels, each panel at most 8 curves; a note in plan.notes when nothing can be drawn.
void convergence_scripts(const RunRecord& run, const std::string& metric, PlotPlan& plan);

/// Work-precision plots of a study with a reference integrator (adaptive_plots.cpp).
void work_precision_scripts(const RunRecord& run, PlotPlan& plan);

/// Per group of an adaptive study: the estimates at the snapshot laps against the road, and
/// |x - xhat| and V against time (adaptive_plots.cpp).
void time_series_scripts(const RunRecord& run, PlotPlan& plan);

}  // namespace rkhs::plot_detail
