#include "rkhs/report/plots.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <variant>

#include "rkhs/core/printable.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/rates/theory.hpp"

namespace rkhs {

namespace {

// A gnuplot string expression showing `text` as written: every text command and key using it
// says `noenhanced`, so '_' and '^' are not sub- and superscripts. Text from a study file is
// never given to gnuplot as it stands: gnuplot runs `backquoted` commands and expands @macros in
// double-quoted strings (and in the bare command line), so the text goes into single-quoted
// strings, where gnuplot substitutes and escapes nothing and a quote is written twice. Line
// breaks join the lines' strings with "\n" ('a'."\n".'b'); other control characters and bytes
// that are not UTF-8 become '?' (a terminal or SVG would otherwise receive them).
std::string gp_text(std::string_view text) {
  std::string out = "'";
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      out += "'.\"\\n\".'";
      ++i;
      continue;
    }
    if (c == '\t') {
      out += ' ';
      ++i;
      continue;
    }
    if (c < 0x20 || c == 0x7f) {
      out += '?';
      ++i;
      continue;
    }
    if (c < 0x80) {
      out += c == '\'' ? std::string("''") : std::string(1, static_cast<char>(c));
      ++i;
      continue;
    }
    const std::size_t length = utf8_sequence_length(text.substr(i));
    if (length == 0 || (length == 2 && c == 0xc2 &&
                        static_cast<unsigned char>(text[i + 1]) < 0xa0)) {  // or a C1 control
      out += '?';
      i += length == 0 ? 1 : 2;
      continue;
    }
    out += text.substr(i, length);
    i += length;
  }
  return out + "'";
}

// `items` joined by `separator`, broken into lines of about `width` characters (gnuplot does
// not wrap); an item longer than a line is broken at its spaces.
std::string wrapped(const std::vector<std::string>& items, std::size_t width,
                    std::string_view separator = ", ") {
  std::string out, line;
  auto end_line = [&](std::string_view tail) {
    out += line;
    out += tail;
    out += '\n';
    line.clear();
  };
  for (const auto& item : items) {
    if (!line.empty() && line.size() + separator.size() + item.size() > width)
      end_line(separator.substr(0, separator.find_last_not_of(' ') + 1));
    if (!line.empty()) line += separator;
    std::size_t start = 0;
    while (start < item.size()) {
      auto space = item.find(' ', start);
      if (space == std::string::npos) space = item.size();
      if (start > 0 && line.size() + space - start > width) {  // within the item
        line.pop_back();                                       // its space
        end_line("");
      }
      line += item.substr(start, space - start);
      if (space < item.size()) line += ' ';
      start = space + 1;
    }
  }
  return out + line;
}

std::string header(std::string_view title, std::string_view xlabel, std::string_view ylabel,
                   bool logx, bool logy) {
  return fmt::format(
      "set title {} noenhanced\nset xlabel {} noenhanced\nset ylabel {} noenhanced\n{}{}set grid\n"
      "set key noenhanced\nset datafile missing 'nan'\n",
      gp_text(title), gp_text(xlabel), gp_text(ylabel), logx ? "set logscale x\n" : "",
      logy ? "set logscale y\nset format y '10^{%L}'\n" : "");
}

// A value a logarithmic axis can show.
bool usable_on_log_axis(double v) {
  return std::isfinite(v) && v > 0;
}

// The extent of the values an axis shows.
struct Extent {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void add(double v) {
    low = std::min(low, v);
    high = std::max(high, v);
  }
  bool empty() const { return !(low <= high); }
};

// The margin a logarithmic axis leaves around `extent`: a factor of (high / low)^share, at
// least `least` and at most `most` (never a whole decade: the data fill the plot).
double log_margin(const Extent& extent, double share, double least, double most) {
  return std::clamp(std::pow(extent.high / extent.low, share), least, most);
}
constexpr double x_share = 0.03, x_least = 1.03, x_most = 1.3;
constexpr double y_share = 0.05, y_least = 1.1, y_most = 2.0;

// "set xrange [a:b]" for a logarithmic axis over `extent` with its margin. An axis spanning
// less than about two and a half decades gets labelled tics at 1, 2 and 5 times the powers of
// ten, one of less than a decade at every digit (the decades alone would leave it with one or
// two labels, or none).
std::string log_range(const char* axis, const Extent& extent, bool is_x) {
  if (extent.empty()) return "";
  const double m = is_x ? log_margin(extent, x_share, x_least, x_most)
                        : log_margin(extent, y_share, y_least, y_most);
  const double low = extent.low / m, high = extent.high * m;
  auto out = fmt::format("set {}range [{}:{}]\n", axis, format_real(low), format_real(high));
  if (high / low > 300) return out;
  // Within a decade, every digit; within two and a half, 1, 2 and 5.
  const std::vector<int> mantissas =
      high / low < 10 ? std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9} : std::vector<int>{1, 2, 5};
  std::string tics;
  for (int decade = static_cast<int>(std::floor(std::log10(low))) - 1;
       decade <= static_cast<int>(std::ceil(std::log10(high))); ++decade)
    for (int mantissa : mantissas) {
      const double tic = decade < 0 ? mantissa / std::pow(10.0, -decade)  // 0.005, not 0.0050..01
                                    : mantissa * std::pow(10.0, decade);
      if (tic >= low && tic <= high)
        tics += fmt::format("{}{}", tics.empty() ? "" : ", ", format_real(tic));
    }
  return out + fmt::format("set {}tics ({})\nset format {} '%g'\n", axis, tics, axis);
}

// A figure's size in inches.
struct Figure {
  double width = 0, height = 0;
};

// The SVG's canvas, in pixels per inch of the figure (report.html shows it at this size).
constexpr double svg_pixels_per_inch = 150;
// The lines' and points' size in the PDF, relative to gnuplot's (the PNG and SVG scale alike).
constexpr double line_scale = 0.7, point_scale = 0.5;

// The script that renders `drawing` (every setting and plot command; the data blocks come
// first, outside) to <stem>.svg, <stem>.png and <stem>.pdf in the current directory: the PDF
// on a page of the figure's size in inches with text of style.font_points points, the PNG its
// raster at style.png_dpi and the SVG at svg_pixels_per_inch (fonts, lines and points scaled
// with the resolution, gnuplot's cairo terminals counting 72 points to the inch: the three look
// alike).
std::string rendered(const std::string& stem, Figure figure, const PlotStyle& style,
                     const std::string& data, const std::string& drawing) {
  auto pixels = [](double inches, double per_inch) {
    return static_cast<int>(std::lround(inches * per_inch));
  };
  const double svg = svg_pixels_per_inch / 72, png = style.png_dpi / 72.0;
  const auto font = format_real(style.font_points);
  auto scale = [](double factor) { return fmt::format("{:.4g}", factor); };
  return data +
         fmt::format(
             "do for [ext in \"svg png pdf\"] {{\n"
             "reset\n"
             "if (ext eq \"svg\") {{ set terminal svg size {0},{1} dynamic enhanced font "
             "'sans,{6}' fontscale {7} linewidth {8} }}\n"
             "if (ext eq \"png\") {{ set terminal pngcairo size {2},{3} enhanced font 'sans,{6}' "
             "fontscale {9} linewidth {10} pointscale {11} }}\n"
             "if (ext eq \"pdf\") {{ set terminal pdfcairo size {4}in,{5}in enhanced font "
             "'sans,{6}' linewidth {12} pointscale {13} }}\n"
             "set output '{14}.'.ext\n"
             "{15}"
             "unset output\n"
             "}}\n",
             pixels(figure.width, svg_pixels_per_inch), pixels(figure.height, svg_pixels_per_inch),
             pixels(figure.width, style.png_dpi), pixels(figure.height, style.png_dpi),
             format_real(figure.width), format_real(figure.height), font, scale(svg),
             scale(svg * line_scale), scale(png), scale(png * line_scale), scale(png * point_scale),
             scale(line_scale), scale(point_scale), stem, drawing);
}

// The figure's size: [plot] size when given, else `automatic`.
Figure sized(const PlotStyle& style, Figure automatic) {
  return style.width_inches > 0 ? Figure{style.width_inches, style.height_inches} : automatic;
}

// About how many characters of the figure's text fit across `inches` (gnuplot does not wrap).
std::size_t characters_across(double inches, const PlotStyle& style) {
  return static_cast<std::size_t>(std::max(10.0, inches * 72 / (0.7 * style.font_points)));
}

// The height of `lines` lines of text, in inches.
double text_height(std::size_t lines, const PlotStyle& style) {
  return static_cast<double>(lines) * 1.35 * style.font_points / 72;
}

// Colour-blind safe colours (Okabe and Ito, without yellow) with a point type each, filled and
// hollow (flagged values), so that curves stay apart in grey print too.
constexpr int palette_size = 8;
constexpr const char* palette[palette_size] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                               "#E69F00", "#56B4E9", "#000000", "#8C564B"};
constexpr int filled_point[palette_size] = {7, 5, 9, 11, 13, 15, 7, 5};
std::string line_types() {
  std::string out;
  for (int i = 0; i < palette_size; ++i)
    out += fmt::format("set linetype {} lc rgb '{}' lw 1.5 pt {} ps 0.8\n", i + 1, palette[i],
                       filled_point[i]);
  return out;
}

// ---- What varies among the trials of a plot -------------------------------------------------

// The plugin axes of a trial, in the order of trials.csv's columns.
using PluginAxis = std::pair<const char*, PluginChoice TrialSpec::*>;
constexpr PluginAxis plugin_axes[] = {
    {"kernel", &TrialSpec::kernel},        {"target", &TrialSpec::target},
    {"centres", &TrialSpec::centres},      {"projection", &TrialSpec::projection},
    {"plant", &TrialSpec::plant},          {"law", &TrialSpec::law},
    {"integrator", &TrialSpec::integrator}};

// The identity of each of a set of trials split into factors, the axes whose values differ
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
};

// The text of `factors` of one trial: "name=value" pairs separated by commas, except that a
// plugin's own parameters follow it after a space ("kernel=bspline degree=1, class=A").
std::string identity_text(const Identity& identity, std::size_t trial,
                          const std::vector<std::size_t>& factors) {
  std::string out;
  std::string_view last_axis;
  for (auto f : factors) {
    const auto& value = identity.values[trial][f];
    if (value.empty()) continue;
    if (!out.empty())
      out += identity.owner[f] != std::string::npos && identity.axes[f] == last_axis ? " " : ", ";
    out += value;
    last_axis = identity.axes[f];
  }
  return out;
}

Identity identify(const std::vector<const TrialSpec*>& trials) {
  Identity out;
  out.values.resize(trials.size());
  std::vector<std::pair<std::string, std::size_t>> parameter_factors;  // (parameter, factor)
  auto add_factor = [&](const std::string& name, const std::string& axis, std::size_t owner) {
    out.factors.push_back(name);
    out.axes.push_back(axis);
    out.owner.push_back(owner);
    return out.factors.size() - 1;
  };
  for (const auto& axis_and_member : plugin_axes) {
    // Named copies, not structured bindings: clang 14 cannot capture those in a lambda.
    const auto axis = axis_and_member.first;
    const auto member = axis_and_member.second;
    std::vector<std::string> names;
    for (const auto* trial : trials)
      if (const auto& name = ((*trial).*member).name;
          std::find(names.begin(), names.end(), name) == names.end())
        names.push_back(name);
    if (names.size() == 1 && names.front().empty()) continue;  // an axis the study has not
    // The parameters of each plugin of the axis, in order, with their distinct values.
    auto spread = [&](const std::string& name) {
      std::vector<std::pair<std::string, std::vector<std::string>>> parameters;
      for (const auto* trial : trials) {
        const auto& choice = (*trial).*member;
        if (choice.name != name) continue;
        for (const auto& parameter_and_value : choice.parameters.values()) {
          const auto& parameter = parameter_and_value.first;
          const auto& value = parameter_and_value.second;
          auto it = std::find_if(parameters.begin(), parameters.end(),
                                 [&](const auto& p) { return p.first == parameter; });
          if (it == parameters.end()) it = parameters.insert(parameters.end(), {parameter, {}});
          if (const auto text = format_value(value);
              std::find(it->second.begin(), it->second.end(), text) == it->second.end())
            it->second.push_back(text);
        }
      }
      return parameters;
    };
    // The parameters that differ within a plugin, in order of first appearance; the others
    // are constants, of the axis (one plugin) or of their plugin.
    std::vector<std::string> differing;
    std::map<std::string, std::vector<std::string>> differing_in;
    std::string single = std::string(axis) + "=" + names.front();
    for (const auto& name : names) {
      std::string constant;
      for (const auto& [parameter, values] : spread(name)) {
        if (values.size() == 1) {
          (((names.size() == 1 ? single : constant) += ' ') += parameter) += "=" + values.front();
          continue;
        }
        differing_in[name].push_back(parameter);
        if (std::find(differing.begin(), differing.end(), parameter) == differing.end())
          differing.push_back(parameter);
      }
      if (names.size() > 1 && !constant.empty()) out.constants.push_back(name + ":" + constant);
    }
    if (names.size() == 1) out.constants.push_back(single);
    std::size_t plugin = std::string::npos;
    if (names.size() > 1) {
      plugin = add_factor(axis, axis, std::string::npos);
      for (std::size_t t = 0; t < trials.size(); ++t)
        out.values[t].push_back(std::string(axis) + "=" + ((*trials[t]).*member).name);
    }
    for (const auto& parameter : differing) {
      parameter_factors.emplace_back(parameter, add_factor(parameter, axis, plugin));
      for (std::size_t t = 0; t < trials.size(); ++t) {
        const auto& choice = (*trials[t]).*member;
        std::string text;
        const auto& own = differing_in[choice.name];
        if (std::find(own.begin(), own.end(), parameter) != own.end())
          for (const auto& [name, value] : choice.parameters.values())
            if (name == parameter) text = format_value(value);
        out.values[t].push_back(text);
      }
    }
  }
  // A parameter factor is named by its parameter ("class"), or by its column of trials.csv
  // ("target_seed") when two axes share the parameter name.
  for (const auto& parameter_and_factor : parameter_factors) {
    const auto& parameter = parameter_and_factor.first;
    const auto f = parameter_and_factor.second;
    const bool shared = std::count_if(parameter_factors.begin(), parameter_factors.end(),
                                      [&](const auto& p) { return p.first == parameter; }) > 1;
    std::string name = parameter;
    if (shared && out.axes[f] != "kernel") {
      name = out.axes[f];  // (operator+ here trips GCC 12's -Wrestrict false positive)
      name += '_';
      name += parameter;
    }
    out.factors[f] = name;
    for (auto& values : out.values)
      if (!values[f].empty()) values[f] = name + "=" + values[f];
  }
  // Laps, nested just outside n.
  std::vector<std::string> laps;
  for (const auto* trial : trials)
    if (trial->laps) {
      if (const auto text = "laps=" + laps_text(*trial->laps);
          std::find(laps.begin(), laps.end(), text) == laps.end())
        laps.push_back(text);
    }
  if (laps.size() == 1) out.constants.push_back(laps.front());
  if (laps.size() > 1) {
    add_factor("laps", "laps", std::string::npos);
    for (std::size_t t = 0; t < trials.size(); ++t)
      out.values[t].push_back("laps=" + laps_text(*trials[t]->laps));
  }
  return out;
}

// The factors (indices into identity.factors) whose values split `identity`'s trials into
// panels of at most `most` each: none when all fit one plot; otherwise the set giving the
// fewest panels, then the one with fewer factors, then the one of earlier factors, a
// parameter's plugin always with it. Every set of factors is tried (up to 16 factors; beyond,
// factors are added greedily).
std::vector<std::size_t> panel_factors(const Identity& identity, std::size_t most) {
  const std::size_t k = identity.factors.size();
  if (identity.values.size() <= most || k == 0) return {};
  auto largest_panel = [&](const std::vector<std::size_t>& chosen, std::size_t* panels) {
    std::map<std::vector<std::string>, std::size_t> count;
    for (const auto& values : identity.values) {
      std::vector<std::string> key;
      for (auto f : chosen) key.push_back(values[f]);
      ++count[key];
    }
    std::size_t largest = 0;
    for (const auto& [key, n] : count) largest = std::max(largest, n);
    if (panels) *panels = count.size();
    return largest;
  };
  if (k > 16) {
    std::vector<std::size_t> chosen;
    while (largest_panel(chosen, nullptr) > most && chosen.size() < k) {
      std::size_t best = k, best_largest = std::numeric_limits<std::size_t>::max();
      for (std::size_t f = 0; f < k; ++f) {
        if (std::find(chosen.begin(), chosen.end(), f) != chosen.end()) continue;
        auto trial = chosen;
        trial.push_back(f);
        if (const auto largest = largest_panel(trial, nullptr); largest < best_largest) {
          best_largest = largest;
          best = f;
        }
      }
      chosen.push_back(best);
      if (const auto owner = identity.owner[best];
          owner != std::string::npos &&
          std::find(chosen.begin(), chosen.end(), owner) == chosen.end())
        chosen.push_back(owner);
    }
    std::sort(chosen.begin(), chosen.end());
    return chosen;
  }
  std::vector<std::size_t> best;
  std::size_t best_panels = std::numeric_limits<std::size_t>::max();
  for (std::size_t mask = 1; mask < (std::size_t{1} << k); ++mask) {
    std::vector<std::size_t> chosen;
    bool complete = true;  // a parameter with its plugin
    for (std::size_t f = 0; f < k; ++f)
      if (mask & (std::size_t{1} << f)) {
        chosen.push_back(f);
        if (const auto owner = identity.owner[f]; owner != std::string::npos)
          complete = complete && (mask & (std::size_t{1} << owner));
      }
    if (!complete) continue;
    std::size_t panels = 0;
    if (largest_panel(chosen, &panels) > most) continue;
    const bool better =
        panels < best_panels ||
        (panels == best_panels &&
         (chosen.size() < best.size() || (chosen.size() == best.size() && chosen < best)));
    if (better) {
      best = chosen;
      best_panels = panels;
    }
  }
  return best;
}

// Short legend text for a group: the plugin labels without the defaults' noise, and the lap
// count of a laps axis.
std::string legend(const TrialSpec& trial) {
  std::string out = trial.kernel.label();
  for (const auto* choice : {&trial.law, &trial.integrator})
    if (!choice->name.empty()) out += ", " + choice->name;
  if (trial.laps) out += ", laps=" + laps_text(*trial.laps);  // a laps axis: one curve per count
  return out;
}

// The constants of `identity` that a short title names: each plugin every curve shares, by
// name ("kernel=matern", not its parameters nor an expression target's formula), a lap count,
// and which axes the curves are the same for.
std::string short_constants(const Identity& identity) {
  std::vector<std::string> names;
  for (const auto& constant : identity.constants) {
    const auto equals = constant.find('=');
    const auto axis = constant.substr(0, equals);
    const bool plugin = std::any_of(std::begin(plugin_axes), std::end(plugin_axes),
                                    [&](const PluginAxis& a) { return axis == a.first; });
    if (equals != std::string::npos && (plugin || axis == "laps"))
      names.push_back(constant.substr(0, constant.find(' ')));
    else if (constant.starts_with("the same for every"))
      names.push_back(constant);
  }
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

// The gnuplot commands that place the key at [plot] legend `position`
// (PlotStyle::legend_positions). Outside the axes it lies below the x axis' label or right of
// the axes, never over a label; inside, on an opaque box.
std::string key_placement(std::string_view position) {
  const std::string common = "noenhanced Left reverse samplen 2.5 spacing 1.1";
  if (position == "none") return "unset key\n";
  if (position == "outside") return fmt::format("set key {} outside right top vertical\n", common);
  if (position == "below")
    return fmt::format("set key {} outside below center horizontal\n", common);
  return fmt::format("set key {} inside {} opaque box\n", common, position);
}

// ---- Convergence plots ------------------------------------------------------------------------

constexpr std::size_t most_curves_per_panel = 8;
constexpr std::size_t most_panels_per_file = 12;
constexpr Figure single_figure{6, 4.5};  // one plot, inches, without its title
constexpr double panel_inches = 3.2;     // one panel of a grid, square

// One group's series of a metric as plotted: x is n or h (n for an exponential fit).
struct Curve {
  const MetricSeries* series = nullptr;
  std::vector<double> x;
  std::optional<double> theory_slope;  ///< the kernel's power-law theory against x
};

std::string rate_text(const RateFit& fit) {
  return fmt::format("rate {:.3g}{}", fit.rate,
                     fit.model == RateModel::exponential ? " (exp in n)" : "");
}

// The data blocks of curve `c`: $cC (x, unflagged value, flagged value), $fC (the fit on its
// window: x, fit, band low, band high), $tC (the theory slope through the fit at the window's
// geometric centre, over the window).
std::string curve_data(const Curve& curve, std::size_t c) {
  const auto& series = *curve.series;
  const auto& x = curve.x;
  std::string data = fmt::format("$c{} << EOD\n", c);
  for (std::size_t k = 0; k < series.trials.size(); ++k) {
    const double v = series.values[k];
    const bool usable = usable_on_log_axis(v);
    data += fmt::format("{} {} {}\n", format_real(x[k]),
                        usable && !series.flagged[k] ? format_real(v) : "nan",
                        usable && series.flagged[k] ? format_real(v) : "nan");
  }
  data += "EOD\n";
  // A constant series: its value over its points, shaded its band (on a log axis: positive).
  if (const auto& constant = series.analysis.constant) {
    if (!(constant->value > 0.0)) return data;
    data += fmt::format("$f{} << EOD\n", c);
    for (auto k : {constant->points.front(), constant->points.back()})
      data += fmt::format(
          "{} {} {} {}\n", format_real(x[k]), format_real(constant->value),
          format_real(std::max(constant->value - constant->band, 0.5 * constant->value)),
          format_real(constant->value + constant->band));
    return data + "EOD\n";
  }
  const auto& fit = series.fit;
  if (!fit || fit->used.empty()) return data;
  const bool exponential = fit->model == RateModel::exponential;
  auto u_of = [&](double xi) { return exponential ? xi : std::log(xi); };
  // The fit in log space pivots about the mean of the fitted points; the band spans the slopes
  // of the confidence interval about the same pivot, clipped to the values of the fitted points
  // (with the y axis' margin): a wide interval on few points must not swamp the plot.
  double mean_u = 0, mean_y = 0;
  Extent values;
  for (auto k : fit->used) {
    mean_u += u_of(x[k]);
    mean_y += std::log(series.values[k]);
    values.add(series.values[k]);
  }
  mean_u /= static_cast<double>(fit->used.size());
  mean_y /= static_cast<double>(fit->used.size());
  const double margin = log_margin(values, y_share, y_least, y_most);
  const double floor = values.low / margin, ceiling = values.high * margin;
  auto clip = [&](double v) { return std::clamp(v, floor, ceiling); };
  const double first = x[fit->used.front()], last = x[fit->used.back()];
  const bool band = std::isfinite(fit->ci_low) && std::isfinite(fit->ci_high);
  data += fmt::format("$f{} << EOD\n", c);
  for (int i = 0; i <= 20; ++i) {
    const double t = i / 20.0;
    const double xi = exponential
                          ? first + t * (last - first)
                          : std::exp(std::log(first) + t * (std::log(last) - std::log(first)));
    auto at = [&](double slope) { return std::exp(mean_y + slope * (u_of(xi) - mean_u)); };
    const double lo = band ? std::min(at(fit->ci_low), at(fit->ci_high)) : at(fit->rate);
    const double hi = band ? std::max(at(fit->ci_low), at(fit->ci_high)) : at(fit->rate);
    data += fmt::format("{} {} {} {}\n", format_real(xi), format_real(at(fit->rate)),
                        format_real(clip(lo)), format_real(clip(hi)));
  }
  data += "EOD\n";
  if (curve.theory_slope) {
    // Through the fitted line at the window's geometric centre, over the window: where the
    // series is asymptotic, not through its first (pre-asymptotic) point.
    const double centre = std::sqrt(first * last);
    const double anchor = std::exp(mean_y + fit->rate * (u_of(centre) - mean_u));
    data += fmt::format("$t{} << EOD\n", c);
    for (double xi : {first, last})
      data += fmt::format("{} {}\n", format_real(xi),
                          format_real(anchor * std::pow(xi / centre, *curve.theory_slope)));
    data += "EOD\n";
  }
  return data;
}

// Merges the curves that differ only in axes the metric does not depend on, and returns
// `identity` (of every curve) reduced to the curves kept. A factor is such an axis when some
// curves differ in it alone and every such pair has the same series (abscissa, values and
// flags): the power function does not depend on the target, say. Merged curves must have the
// same series, or nothing is merged. The title then says the curves are the same for every
// value of the factors left out; a factor that no longer differs among the curves kept becomes
// a constant of the title.
Identity merge_identical(std::vector<Curve>& curves, const Identity& identity) {
  const std::size_t count = curves.size(), factors = identity.factors.size();
  std::vector<std::string> text(count);
  for (std::size_t c = 0; c < count; ++c) {
    const auto& series = *curves[c].series;
    for (std::size_t k = 0; k < series.trials.size(); ++k)
      text[c] += fmt::format("{} {} {};", format_real(curves[c].x[k]),
                             format_real(series.values[k]), static_cast<int>(series.flagged[k]));
  }
  std::vector<bool> irrelevant(factors, false);
  for (std::size_t f = 0; f < factors; ++f) {
    bool pairs = false, same = true;
    for (std::size_t a = 0; a < count && same; ++a)
      for (std::size_t b = a + 1; b < count && same; ++b) {
        bool only_f = identity.values[a][f] != identity.values[b][f];
        for (std::size_t g = 0; g < factors && only_f; ++g)
          if (g != f && identity.values[a][g] != identity.values[b][g]) only_f = false;
        if (!only_f) continue;
        pairs = true;
        same = text[a] == text[b];
      }
    irrelevant[f] = pairs && same;
  }
  if (std::none_of(irrelevant.begin(), irrelevant.end(), [](bool b) { return b; })) return identity;
  std::map<std::vector<std::string>, std::size_t> kept_of;  // relevant values -> curve kept
  std::vector<std::size_t> kept;
  for (std::size_t c = 0; c < count; ++c) {
    std::vector<std::string> key;
    for (std::size_t f = 0; f < factors; ++f)
      if (!irrelevant[f]) key.push_back(identity.values[c][f]);
    const auto [it, fresh] = kept_of.emplace(key, kept.size());
    if (fresh)
      kept.push_back(c);
    else if (text[kept[it->second]] != text[c])
      return identity;  // the axis matters somewhere after all
  }
  Identity out;
  out.constants = identity.constants;
  out.values.resize(kept.size());
  std::vector<std::string> same_for;
  std::vector<std::size_t> index(factors, std::string::npos);  // old factor -> new
  for (std::size_t f = 0; f < factors; ++f) {
    if (irrelevant[f]) {
      same_for.push_back(identity.factors[f]);
      continue;
    }
    std::set<std::string> seen;
    for (auto c : kept) seen.insert(identity.values[c][f]);
    if (seen.size() == 1) {
      if (!seen.begin()->empty()) out.constants.push_back(*seen.begin());
      continue;
    }
    index[f] = out.factors.size();
    out.factors.push_back(identity.factors[f]);
    out.axes.push_back(identity.axes[f]);
    const auto owner = identity.owner[f];
    out.owner.push_back(owner == std::string::npos ? owner : index[owner]);
    for (std::size_t k = 0; k < kept.size(); ++k)
      out.values[k].push_back(identity.values[kept[k]][f]);
  }
  std::string same = "the same for every ";
  for (std::size_t i = 0; i < same_for.size(); ++i)
    same += (i == 0 ? "" : i + 1 == same_for.size() ? " and " : ", ") + same_for[i];
  out.constants.push_back(same);
  std::vector<Curve> remaining;
  for (auto c : kept) remaining.push_back(std::move(curves[c]));
  curves = std::move(remaining);
  return out;
}

void convergence_scripts(const RunRecord& run, const std::string& metric, PlotPlan& plan) {
  std::vector<Curve> curves;
  for (const auto& series : run.rates) {
    if (series.metric != metric || series.trials.empty()) continue;
    if (std::none_of(series.values.begin(), series.values.end(), usable_on_log_axis)) continue;
    Curve curve;
    curve.series = &series;
    const bool in_n =
        series.analysis.reported == RateModel::exponential || run.study.abscissa == Abscissa::n;
    curve.x = in_n ? series.n : series.abscissa;
    // The theory slope (power-law theories from the kernel's metadata) on the same axis, for a
    // metric whose catalogue row has a theory law.
    const auto* row = run.study.kind_descriptor().find_metric(metric);
    if (row && row->theory != TheoryLaw::none) {
      const auto& trial = run.trials[series.trials.front()];
      try {
        const auto theory = theory_rate(
            *row, kernel_properties(trial.kernel.name, trial.kernel.parameters, run.study.domain));
        if (theory && theory->model == RateModel::power_law &&
            in_n == (run.study.abscissa == Abscissa::n))
          curve.theory_slope = run.study.abscissa == Abscissa::n
                                   ? -theory->h_exponent / theory->dimension
                                   : theory->h_exponent;
      } catch (const std::exception& e) {
        // A kernel that cannot be rebuilt here (e.g. from a plugin not loaded): said, not drawn.
        plan.notes.push_back(fmt::format("convergence_{}: no theory line for kernel {}: {}", metric,
                                         trial.kernel.label(), e.what()));
      }
    }
    curves.push_back(std::move(curve));
  }
  if (curves.empty()) {
    plan.notes.push_back(fmt::format(
        "convergence_{}: not plotted: no trial has a finite positive {} (a log axis needs one)",
        metric, metric));
    return;
  }

  // What tells the curves apart (groups that differ only in axes the metric does not depend
  // on, such as the power function and the target, made one curve), and the panels that keep
  // each plot readable.
  std::vector<const TrialSpec*> groups;
  for (const auto& curve : curves) groups.push_back(&run.trials[curve.series->trials.front()]);
  const auto identity = merge_identical(curves, identify(groups));
  const auto chosen = panel_factors(identity, most_curves_per_panel);
  std::vector<std::size_t> others;  // the factors the curves of a panel differ in
  for (std::size_t f = 0; f < identity.factors.size(); ++f)
    if (std::find(chosen.begin(), chosen.end(), f) == chosen.end()) others.push_back(f);
  auto values_of = [&](std::size_t c, const std::vector<std::size_t>& factors) {
    std::vector<std::string> out;
    for (auto f : factors) out.push_back(identity.values[c][f]);
    return out;
  };
  std::vector<std::vector<std::size_t>> panels;  // curves, in order of first appearance
  {
    std::map<std::vector<std::string>, std::size_t> index;
    for (std::size_t c = 0; c < curves.size(); ++c) {
      const auto key = values_of(c, chosen);
      if (!index.contains(key)) {
        index[key] = panels.size();
        panels.emplace_back();
      }
      panels[index[key]].push_back(c);
    }
  }
  // A curve keeps its colour in every panel when the curves' identities within panels are few
  // enough (the same road class is the same colour everywhere); otherwise colours by position.
  std::map<std::vector<std::string>, std::size_t> colour_of;
  for (std::size_t c = 0; c < curves.size(); ++c)
    colour_of.emplace(values_of(c, others), colour_of.size());
  const bool colour_by_identity = colour_of.size() <= palette_size;

  // One x and y range for every panel and part of the metric: the values plotted, with a margin.
  Extent xs, ys;
  bool any_flagged = false, any_band = false, any_theory = false, any_constant = false;
  for (const auto& curve : curves) {
    const auto& series = *curve.series;
    for (std::size_t k = 0; k < series.trials.size(); ++k)
      if (usable_on_log_axis(series.values[k])) {
        xs.add(curve.x[k]);
        ys.add(series.values[k]);
        any_flagged = any_flagged || series.flagged[k];
      }
    any_band = any_band || (series.fit && !series.fit->used.empty());
    any_constant =
        any_constant || (series.analysis.constant && series.analysis.constant->value > 0);
    any_theory = any_theory || (curve.theory_slope && series.fit && !series.fit->used.empty());
  }
  const bool against_n = run.study.abscissa == Abscissa::n;
  std::vector<std::string> style_lines;
  style_lines.push_back("points: values");
  if (any_flagged) style_lines.push_back("hollow: flagged, not fitted");
  if (any_band) style_lines.push_back("dashed: fitted rate on its window, shaded its 95% band");
  if (any_constant)
    style_lines.push_back("const: a series constant on its window, shaded its band");
  if (any_theory) style_lines.push_back("dotted: theory slope");
  const auto shared = short_constants(identity);

  const std::size_t parts = (panels.size() + most_panels_per_file - 1) / most_panels_per_file;
  for (std::size_t part = 0; part < parts; ++part) {
    const std::size_t begin = part * most_panels_per_file;
    const std::size_t end = std::min(panels.size(), begin + most_panels_per_file);
    const std::size_t count = end - begin;
    const bool grid = panels.size() > 1;
    // Two panel factors that make a full grid: rows by the first, columns by the second.
    std::size_t columns = std::min<std::size_t>(
        4, static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(count)))));
    if (chosen.size() == 2 && parts == 1) {
      std::set<std::string> first, second;
      for (std::size_t c = 0; c < curves.size(); ++c) {
        first.insert(identity.values[c][chosen[0]]);
        second.insert(identity.values[c][chosen[1]]);
      }
      if (first.size() * second.size() == count && second.size() <= 4) columns = second.size();
    }
    const std::size_t rows = (count + columns - 1) / columns;
    const auto& style = run.study.plot;
    std::string title;
    if (!style.title) {
      // The plugins every curve shares, by name (their parameters are in the tables), and
      // what the line styles mean.
      std::vector<std::string> title_lines{
          fmt::format("{}{}{}", run.study.name, shared.empty() ? "" : ": " + shared,
                      parts > 1 ? fmt::format(" (part {} of {})", part + 1, parts) : "")};
      const auto automatic_width =
          grid ? static_cast<double>(columns) * panel_inches : single_figure.width;
      title_lines.push_back(wrapped(
          style_lines, characters_across(sized(style, {automatic_width, 0}).width, style), "; "));
      for (const auto& line : title_lines) title += (title.empty() ? "" : "\n") + line;
    }
    const auto title_line_count =
        style.title && style.title->empty()
            ? 0
            : static_cast<std::size_t>(std::count(title.begin(), title.end(), '\n') + 1);
    const auto figure = sized(
        style, grid ? Figure{static_cast<double>(columns) * panel_inches,
                             static_cast<double>(rows) * panel_inches +
                                 text_height(title_line_count + 1, style)}
                    : Figure{single_figure.width,
                             single_figure.height + text_height(title_line_count + 1, style)});
    // The title as a gnuplot string: the user's in enhanced text, ours as written.
    const auto title_command =
        style.title
            ? (style.title->empty() ? std::string("''") : gp_text(*style.title) + " enhanced")
            : gp_text(title) + " noenhanced";
    const auto ylabel = style.labels.contains(metric) ? style.labels.at(metric)
                                                      : metric_axis_label(run.study.kind, metric);

    std::string data, drawing = line_types();
    drawing += fmt::format(
        "set xlabel {} enhanced\nset ylabel {} enhanced\nset logscale xy\n"
        "set format y '10^{{%L}}'\nset grid\nset datafile missing 'nan'\n{}{}{}",
        gp_text(against_n ? "n" : "fill distance h (m)"), gp_text(ylabel), log_range("x", xs, true),
        log_range("y", ys, false), key_placement(style.legend));
    if (grid)
      drawing += fmt::format("set multiplot layout {},{} rowsfirst title {}\n", rows, columns,
                             title_command);
    for (std::size_t p = begin; p < end; ++p) {
      const auto& members = panels[p];
      // Legend: the factors that differ within the panel; the rest names the panel.
      std::vector<std::size_t> legend_factors, title_factors;
      for (std::size_t f = 0; f < identity.factors.size(); ++f) {
        std::set<std::string> seen;
        for (auto c : members) seen.insert(identity.values[c][f]);
        const bool panel = std::find(chosen.begin(), chosen.end(), f) != chosen.end();
        (panel || seen.size() == 1 ? title_factors : legend_factors).push_back(f);
      }
      const double plot_width = grid ? figure.width / static_cast<double>(columns) : figure.width;
      drawing +=
          grid ? fmt::format(
                     "set title {} noenhanced\n",
                     gp_text(wrapped({identity_text(identity, members.front(), title_factors)},
                                     characters_across(plot_width, style))))
               : fmt::format("set title {}\n", title_command);
      std::string bands, fits, points, theories;
      std::set<std::string> theory_titles;
      std::size_t longest = 0;  // characters of the longest key entry
      for (std::size_t position = 0; position < members.size(); ++position) {
        const auto c = members[position];
        const auto& curve = curves[c];
        const auto& series = *curve.series;
        data += curve_data(curve, c);
        const std::size_t lt =
            1 + (colour_by_identity ? colour_of.at(values_of(c, others)) : position) % palette_size;
        auto label = identity_text(identity, c, legend_factors);
        const auto& constant = series.analysis.constant;
        const bool fitted =
            (series.fit && !series.fit->used.empty()) || (constant && constant->value > 0.0);
        if (constant)
          label += (label.empty() ? "" : ": ") + fmt::format("const {:.4g}", constant->value);
        else if (fitted)
          label += (label.empty() ? "" : ": ") + rate_text(*series.fit);
        if (label.empty()) label = metric;
        longest = std::max(longest, label.size());
        // Unflagged values (the key's entry), then flagged ones hollow; a series whose every
        // value is flagged has its entry on the hollow points (gnuplot skips an empty column).
        bool unflagged = false, flagged = false;
        for (std::size_t k = 0; k < series.trials.size(); ++k)
          if (usable_on_log_axis(series.values[k]))
            (series.flagged[k] ? flagged : unflagged) = true;
        if (unflagged)
          points += fmt::format("$c{0} using 1:2 with linespoints lt {1} title {2}, ", c, lt,
                                gp_text(label));
        if (flagged)
          points += fmt::format("$c{} using 1:3 with points lt {} pt {} {}, ", c, lt,
                                filled_point[lt - 1] - 1,
                                unflagged ? std::string("notitle") : "title " + gp_text(label));
        if (!fitted) continue;
        bands += fmt::format(
            "$f{} using 1:3:4 with filledcurves fc lt {} fs transparent solid 0.15 noborder "
            "notitle, ",
            c, lt);
        fits += fmt::format("$f{} using 1:2 with lines lt {} dt 2 lw 1.2 notitle, ", c, lt);
        if (curve.theory_slope && !constant) {
          const auto text = fmt::format("theory slope {:.3g}", *curve.theory_slope);
          theories += fmt::format("$t{} using 1:2 with lines lc rgb '#505050' dt 3 lw 1.5 {}, ", c,
                                  theory_titles.insert(text).second ? "title " + gp_text(text)
                                                                    : std::string("notitle"));
        }
      }
      // The fitted lines over the data, the theory slopes over both.
      auto plot = bands + points + fits + theories;
      plot.erase(plot.size() - 2);
      // Two key columns when two entries fit side by side (with their samples, about 6
      // characters), else one.
      drawing +=
          fmt::format("set key maxcols {}\nplot {}\n",
                      2 * (longest + 6) < characters_across(plot_width, style) ? 2 : 1, plot);
    }
    if (grid) drawing += "unset multiplot\n";
    const auto stem = parts == 1 ? "convergence_" + metric
                                 : fmt::format("convergence_{}_part{}", metric, part + 1);
    plan.scripts.emplace_back(stem, rendered(stem, figure, style, data, drawing));
  }
}

// ---- Work precision ---------------------------------------------------------------------------

// The tolerances a line of a work-precision plot runs through (the integrator's other
// parameters make other lines).
bool is_tolerance(std::string_view parameter) {
  return parameter == "rtol" || parameter == "atol" || parameter == "step";
}

// Where a point lies along its line: the relative tolerance (or rk4's step), loosest first.
double looseness(const PluginChoice& integrator) {
  for (const char* name : {"rtol", "step"})
    for (const auto& [parameter, value] : integrator.parameters.values())
      if (parameter == name) {
        if (const auto* real = std::get_if<double>(&value)) return *real;
        if (const auto* integer = std::get_if<std::int64_t>(&value))
          return static_cast<double>(*integer);
      }
  return 0;
}

// The integrator without its tolerances: one line of a work-precision plot.
std::string line_key(const PluginChoice& integrator) {
  std::string out = integrator.name;
  for (const auto& [parameter, value] : integrator.parameters.values())
    if (!is_tolerance(parameter) && integrator.parameters.given(parameter))
      out += " " + parameter + "=" + format_value(value);
  return out;
}

// Work-precision plots (DiffEqDevTools' WorkPrecisionSet) of a study with a reference
// integrator: per panel (every axis but the integrator and its tolerances, n included), the
// integration_error of each trial against its wall time and against its steps, one line per
// integrator, its points ordered from the loosest tolerance to the tightest.
void work_precision_scripts(const RunRecord& run, PlotPlan& plan) {
  const auto error_index = run.study.metric_index("integration_error");
  const auto steps_index = run.study.metric_index("steps");
  std::vector<std::string> panels;
  std::map<std::string, std::vector<std::size_t>> members;  // panel -> trials
  for (const auto& trial : run.trials) {
    std::string panel = fmt::format("kernel={} | target={} | centres={} | plant={} | law={}",
                                    trial.kernel.label(), trial.target.label(),
                                    trial.centres.label(), trial.plant.label(), trial.law.label());
    if (trial.laps) panel += " | laps=" + laps_text(*trial.laps);
    panel += fmt::format(" | n={}", trial.n);
    if (!members.contains(panel)) panels.push_back(panel);
    members[panel].push_back(trial.index);
  }
  for (std::size_t p = 0; p < panels.size(); ++p) {
    // Lines in the order their integrators first appear; points by decreasing tolerance.
    std::vector<std::string> lines;
    std::map<std::string, std::vector<std::size_t>> points;
    Extent seconds, steps, errors;
    for (auto index : members[panels[p]]) {
      const auto& result = run.results[index];
      if (!result.ok || !usable_on_log_axis(result.metrics[error_index]) ||
          !usable_on_log_axis(result.seconds))
        continue;
      const auto key = line_key(run.trials[index].integrator);
      if (!points.contains(key)) lines.push_back(key);
      points[key].push_back(index);
      seconds.add(result.seconds);
      if (usable_on_log_axis(result.metrics[steps_index])) steps.add(result.metrics[steps_index]);
      errors.add(result.metrics[error_index]);
    }
    const auto& first = run.trials[members[panels[p]].front()];
    const auto time_stem = fmt::format("work_precision_time_panel{}", p + 1);
    const auto steps_stem = fmt::format("work_precision_steps_panel{}", p + 1);
    if (lines.empty()) {
      for (const auto& stem : {time_stem, steps_stem})
        plan.notes.push_back(fmt::format(
            "{}: not plotted: no trial of panel {} ({}) has a finite positive integration_error",
            stem, p + 1, panels[p]));
      continue;
    }
    std::string data, plot_time, plot_steps;
    for (std::size_t l = 0; l < lines.size(); ++l) {
      auto& indices = points[lines[l]];
      std::stable_sort(indices.begin(), indices.end(), [&](std::size_t a, std::size_t b) {
        return looseness(run.trials[a].integrator) > looseness(run.trials[b].integrator);
      });
      // seconds, steps, integration_error, tolerance
      data += fmt::format("$line{} << EOD\n", l);
      for (auto index : indices)
        data += fmt::format("{} {} {} {}\n", format_real(run.results[index].seconds),
                            format_real(run.results[index].metrics[steps_index]),
                            format_real(run.results[index].metrics[error_index]),
                            format_real(looseness(run.trials[index].integrator)));
      data += "EOD\n";
      const auto title = gp_text(lines[l]);
      for (const auto& [plot, column] : {std::pair<std::string*, int>{&plot_time, 1},
                                         std::pair<std::string*, int>{&plot_steps, 2}})
        *plot += fmt::format(
            "{}$line{} using {}:3 with linespoints pt 7 lc {} title {}, $line{} using {}:3:(sprintf"
            "('%g', $4)) with labels offset char 0.6,0.6 font ',8' tc lt {} notitle",
            plot->empty() ? "" : ", ", l, column, l + 1, title, l, column, l + 1);
    }
    const auto where = fmt::format("{}, {}, n = {}{}", first.kernel.label(), first.law.name,
                                   first.n, first.laps ? ", laps=" + laps_text(*first.laps) : "");
    std::string tolerances;
    for (const auto& [parameter, value] : run.study.reference.parameters.values())
      if (is_tolerance(parameter)) tolerances += " " + parameter + "=" + format_value(value);
    const auto title = fmt::format("work precision: {}; reference {}{}", where,
                                   run.study.reference.name, tolerances);
    const std::string ylabel = "integration error (relative L2 of fhat(T))";
    plan.scripts.emplace_back(
        time_stem,
        rendered(time_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                 line_types() +
                     header(title,
                            fmt::format("wall time of the trial, s (not deterministic: machine, "
                                        "load, {} threads); labels: rtol",
                                        run.threads),
                            ylabel, true, true) +
                     log_range("x", seconds, true) + log_range("y", errors, false) +
                     "set key outside below\nplot " + plot_time + "\n"));
    plan.scripts.emplace_back(
        steps_stem,
        rendered(steps_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                 line_types() + header(title, "accepted steps; labels: rtol", ylabel, true, true) +
                     log_range("x", steps, true) + log_range("y", errors, false) +
                     "set key outside below\nplot " + plot_steps + "\n"));
  }
}

}  // namespace

std::vector<std::string> convergence_plot_order(const std::vector<std::string>& metrics) {
  auto rank = [](const std::string& metric) {
    if (metric.find("error") != std::string::npos) return 0;
    if (metric == "fill_distance" || metric == "separation_distance") return 2;
    return 1;
  };
  auto out = metrics;
  std::stable_sort(out.begin(), out.end(),
                   [&](const std::string& a, const std::string& b) { return rank(a) < rank(b); });
  return out;
}

std::vector<std::string> plotted_metrics(const StudyDefinition& study) {
  return study.plot.metrics.empty() ? convergence_plot_order(study.metrics) : study.plot.metrics;
}

PlotPlan plot_scripts(const RunRecord& run) {
  PlotPlan plan;
  auto& out = plan.scripts;
  for (const auto& metric : plotted_metrics(run.study)) convergence_scripts(run, metric, plan);
  if (!run.study.kind_descriptor().outputs().time_series_plots) return plan;
  if (!run.study.reference.name.empty()) work_precision_scripts(run, plan);

  // Per group: the estimates at each snapshot lap (largest n of the group) against the road,
  // and |x - xhat| and V against time for every n. Titled by what sets the group apart.
  std::map<std::string, std::vector<std::size_t>> groups;
  std::vector<std::string> order;
  for (const auto& trial : run.trials) {
    if (!groups.contains(trial.group_key)) order.push_back(trial.group_key);
    groups[trial.group_key].push_back(trial.index);
  }
  std::vector<const TrialSpec*> firsts;
  for (const auto& key : order) firsts.push_back(&run.trials[groups[key].front()]);
  const auto identity = identify(firsts);
  const auto grid = run.study.domain.uniform_points(run.study.adaptive.snapshot_points);
  for (std::size_t g = 0; g < order.size(); ++g) {
    const auto& members = groups[order[g]];
    const auto& last = run.results[members.back()];
    const auto& trial = run.trials[members.back()];
    std::vector<std::size_t> every(identity.factors.size());
    for (std::size_t f = 0; f < every.size(); ++f) every[f] = f;
    const auto name = identity_text(identity, g, every);
    const auto group_name = name.empty() ? legend(trial) : wrapped({name}, 100);
    if (last.ok && !last.snapshots.empty()) {
      std::string data = "$estimates << EOD\n";
      for (std::size_t m = 0; m < grid.size() && m < last.road.size(); ++m) {
        data += fmt::format("{} {}", format_real(grid[m]), format_real(last.road[m]));
        for (const auto& snapshot : last.snapshots)
          data += fmt::format(" {}", format_real(snapshot.estimate[m]));
        data += '\n';
      }
      data += "EOD\n";
      std::string plot = "$estimates using 1:2 with lines lw 2 lc 'black' title 'road f'";
      for (std::size_t i = 0; i < last.snapshots.size(); ++i)
        plot += fmt::format(
            ", $estimates using 1:{} with lines title {}", i + 3,
            gp_text(fmt::format("fhat after {} laps", format_real(last.snapshots[i].lap))));
      const auto stem = fmt::format("estimates_group{}", g + 1);
      out.emplace_back(
          stem, rendered(stem, sized(run.study.plot, single_figure), run.study.plot, data,
                         header(fmt::format("{} (n = {})", group_name, trial.n), "arc length s (m)",
                                "elevation (m)", false, false) +
                             "set autoscale xfix\nset key outside below\nplot " + plot + "\n"));
    } else if (!run.study.adaptive.snapshot_laps.empty()) {
      plan.notes.push_back(
          fmt::format("estimates_group{}: not plotted: the trial with the largest n of group {} {}",
                      g + 1, g + 1, last.ok ? "has no snapshot" : "failed"));
    }
    // |x - xhat| and V on log axes: only trials with a sample the axis can show.
    std::string data, plot_error, plot_v;
    Extent errors, lyapunov;
    for (std::size_t k = 0; k < members.size(); ++k) {
      const auto& result = run.results[members[k]];
      for (const auto& s : result.samples) {
        if (usable_on_log_axis(s.state_error)) errors.add(s.state_error);
        if (usable_on_log_axis(s.lyapunov)) lyapunov.add(s.lyapunov);
      }
      const auto shows = [&](auto value) {
        return std::any_of(result.samples.begin(), result.samples.end(),
                           [&](const TimeSample& s) { return usable_on_log_axis(value(s)); });
      };
      const auto title = gp_text(fmt::format("n = {}", run.trials[members[k]].n));
      if (shows([](const TimeSample& s) { return s.state_error; }))
        plot_error += fmt::format("{}$series{} using 1:2 with lines title {}",
                                  plot_error.empty() ? "" : ", ", k, title);
      if (shows([](const TimeSample& s) { return s.lyapunov; }))
        plot_v += fmt::format("{}$series{} using 1:3 with lines title {}",
                              plot_v.empty() ? "" : ", ", k, title);
      data += fmt::format("$series{} << EOD\n", k);
      for (const auto& s : result.samples)
        data += fmt::format("{} {} {}\n", format_real(s.t),
                            format_real(s.state_error > 0 ? s.state_error : NAN),
                            format_real(s.lyapunov > 0 ? s.lyapunov : NAN));
      data += "EOD\n";
    }
    const auto state_stem = fmt::format("state_error_group{}", g + 1);
    if (!plot_error.empty())
      out.emplace_back(
          state_stem,
          rendered(state_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                   header(group_name + ": |x - xhat|", "t (s)", "|x - xhat|", false, true) +
                       "set autoscale xfix\n" + log_range("y", errors, false) +
                       "set key outside right top\nplot " + plot_error + "\n"));
    else
      plan.notes.push_back(
          fmt::format("{}: not plotted: no trial of group {} has a positive |x - xhat| sample",
                      state_stem, g + 1));
    const auto lyapunov_stem = fmt::format("lyapunov_group{}", g + 1);
    if (!plot_v.empty())
      out.emplace_back(
          lyapunov_stem,
          rendered(lyapunov_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                   header(group_name + ": V", "t (s)", "V", false, true) + "set autoscale xfix\n" +
                       log_range("y", lyapunov, false) + "set key outside right top\nplot " +
                       plot_v + "\n"));
    else
      plan.notes.push_back(fmt::format(
          "{}: not plotted: no trial of group {} has a positive V sample", lyapunov_stem, g + 1));
  }
  return plan;
}

namespace {
// gnuplot's own complaint from its log: the lines that say what went wrong, joined.
std::string gnuplot_message(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, message;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t^") == std::string::npos) continue;  // blank or the caret line
    if (!message.empty()) message += " ";
    message += line.substr(line.find_first_not_of(" \t"));
  }
  return message.empty() ? "gnuplot exited with an error and said nothing" : message;
}

// The file gnuplot is run from: the first executable `gnuplot` on PATH, or nothing.
std::optional<std::filesystem::path> find_gnuplot() {
  const char* path = std::getenv("PATH");
  std::string_view rest = path && *path ? path : "/usr/local/bin:/usr/bin:/bin";
  while (true) {
    const auto colon = rest.find(':');
    const std::string directory(rest.substr(0, colon));
    const auto candidate = std::filesystem::path(directory.empty() ? "." : directory) / "gnuplot";
    if (::access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate))
      return candidate;
    if (colon == std::string_view::npos) return std::nullopt;
    rest.remove_prefix(colon + 1);
  }
}

// How a gnuplot process ended.
enum class GnuplotEnd { success, failed, timed_out, stopped };

// Runs `gnuplot <script>` in `folder` with its standard error to `log` (standard input and
// output /dev/null), directly (fork and exec: no shell sees a name), in a process group of its
// own. Polls it every 20 ms: past `options.gnuplot_seconds`, or once options.stop_requested
// returns true, the whole group is killed (gnuplot and anything it started).
GnuplotEnd run_gnuplot(const std::filesystem::path& gnuplot, const std::filesystem::path& folder,
                       const std::string& script, const std::string& log,
                       const PlotOptions& options) {
  const std::string program = gnuplot.string();
  const pid_t child = ::fork();
  if (child < 0) return GnuplotEnd::failed;
  if (child == 0) {
    // Only async-signal-safe calls from here on.
    ::setpgid(0, 0);
    if (::chdir(folder.c_str()) != 0) ::_exit(127);
    const int null = ::open("/dev/null", O_RDWR);
    const int err = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (null < 0 || err < 0) ::_exit(127);
    ::dup2(null, STDIN_FILENO);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    char* const argv[] = {const_cast<char*>("gnuplot"), const_cast<char*>(script.c_str()), nullptr};
    ::execv(program.c_str(), argv);
    ::_exit(127);
  }
  ::setpgid(child, child);  // as the child does: whichever runs first, the group exists
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(std::min(options.gnuplot_seconds, 1e9)));
  int status = 0;
  while (true) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (done == child) break;
    if (done < 0 && errno != EINTR) return GnuplotEnd::failed;
    const bool stop = options.stop_requested && options.stop_requested();
    if (stop || std::chrono::steady_clock::now() >= deadline) {
      ::kill(-child, SIGKILL);
      ::kill(child, SIGKILL);  // should it not have reached setpgid yet
      while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
      }
      return stop ? GnuplotEnd::stopped : GnuplotEnd::timed_out;
    }
    ::usleep(20'000);  // a signal (SIGTERM) ends the sleep early
  }
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? GnuplotEnd::success : GnuplotEnd::failed;
}

constexpr const char* plot_extensions[] = {".svg", ".png", ".pdf"};
constexpr const char* manifest_name = ".rkhs-study-manifest";
constexpr std::string_view manifest_heading =
    "# rkhs-study: the files a run wrote in this folder; the next run removes these (and only "
    "these) before it writes its own\n";

// The names the manifest in `folder` lists: plain file names in the folder, no paths (a line
// that is not one is ignored).
std::vector<std::string> manifest_entries(const std::filesystem::path& folder) {
  std::ifstream in(folder / manifest_name);
  std::vector<std::string> names;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line.front() == '#' || line == "." || line == ".." ||
        line.find('/') != std::string::npos || line.find('\0') != std::string::npos ||
        line == manifest_name)
      continue;
    names.push_back(line);
  }
  return names;
}
}  // namespace

PlotOptions plot_options(std::function<bool()> stop_requested) {
  PlotOptions options;
  options.stop_requested = std::move(stop_requested);
  if (const char* text = std::getenv("RKHS_STUDY_GNUPLOT_SECONDS"); text && *text) {
    char* end = nullptr;
    const double seconds = std::strtod(text, &end);
    if (end && *end == '\0' && std::isfinite(seconds) && seconds > 0)
      options.gnuplot_seconds = seconds;
  }
  return options;
}

PlotOutcome write_plots(const RunRecord& run, const std::filesystem::path& directory,
                        const PlotOptions& options) {
  const auto folder = directory / "plots";
  std::filesystem::create_directories(folder);
  // The folder shows this run only: plots of an earlier run into the same directory (a metric
  // no longer plotted, a plot that fails now) must not be taken for this one's. Only the files
  // an earlier run listed in the manifest are removed: a file of the user's own stays.
  for (const auto& name : manifest_entries(folder)) {
    std::error_code error;
    const auto file = folder / name;
    if (std::filesystem::is_regular_file(std::filesystem::symlink_status(file, error)))
      std::filesystem::remove(file, error);
  }
  auto plan = plot_scripts(run);
  PlotOutcome outcome;
  outcome.notes = std::move(plan.notes);
  // Every file this run may write, listed before it writes any (a run that stops part-way
  // leaves a manifest that still names them).
  std::string manifest(manifest_heading);
  for (const auto& [stem, script] : plan.scripts)
    for (const char* extension : {".gp", ".svg", ".png", ".pdf", ".log"})
      manifest += stem + extension + "\n";
  write_file_atomically(folder / manifest_name, manifest);
  if (plan.scripts.empty()) return outcome;
  const auto gnuplot = find_gnuplot();
  if (!gnuplot) {
    outcome.failures.push_back(
        "gnuplot is not installed (not found on PATH): no plot was rendered (Debian: apt-get "
        "install gnuplot-nox; or run with --no-plots)");
    return outcome;
  }
  for (const auto& [stem, script] : plan.scripts) {
    const auto gp = folder / (stem + ".gp");
    const auto log = folder / (stem + ".log");
    try {
      write_file_atomically(gp, "# " + stem + ": run gnuplot " + stem +
                                    ".gp in this folder (writes " + stem +
                                    ".svg, .png and .pdf)\n" + script);
    } catch (const std::exception& e) {  // a full disk: this plot is not rendered
      outcome.failures.push_back(e.what());
      continue;
    }
    // In the plots folder: the script names its outputs without a path, so it is the same
    // wherever the run wrote it.
    const auto end = run_gnuplot(*gnuplot, folder, stem + ".gp", stem + ".log", options);
    if (end != GnuplotEnd::success) {
      outcome.failures.push_back(
          end == GnuplotEnd::timed_out
              ? fmt::format("{}: gnuplot did not finish within {} s and was killed", gp.string(),
                            options.gnuplot_seconds)
          : end == GnuplotEnd::stopped
              ? fmt::format("{}: gnuplot was killed: the command was interrupted", gp.string())
              : fmt::format("{}: {}", gp.string(), gnuplot_message(log)));
      for (const char* extension : plot_extensions)  // half-written images are not plots
        std::filesystem::remove(folder / (stem + extension));
      if (end == GnuplotEnd::stopped) {
        outcome.interrupted = true;
        break;
      }
      continue;
    }
    std::filesystem::remove(log);
    outcome.rendered.push_back(stem);
  }
  return outcome;
}

}  // namespace rkhs
