// Convergence plots: per metric, every series against n or h on log axes with its fitted rate
// and band, constant series as their value, theory slopes, split into panels and parts
// (rkhs/report/plots.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "plot_parts.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs::plot_detail {

namespace {

constexpr std::size_t most_curves_per_panel = 8;
constexpr std::size_t most_panels_per_file = 12;
constexpr double panel_inches = 3.2;  // one panel of a grid, square

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
  out.plugin_axes = identity.plugin_axes;
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

// The curves of `metric`: one per series with a value a log axis can show, on the axis its
// reported model is fitted against, with the kernel's theory slope where it has one.
std::vector<Curve> convergence_curves(const RunRecord& run, const std::string& metric,
                                      PlotPlan& plan) {
  std::vector<Curve> curves;
  for (const auto& series : run.rates) {
    if (series.metric != metric || series.trials.empty()) continue;
    if (std::none_of(series.values.begin(), series.values.end(), usable_on_log_axis)) continue;
    Curve curve;
    curve.series = &series;
    const bool in_n =
        series.analysis.reported == RateModel::exponential || run.study.abscissa == Abscissa::n;
    curve.x = in_n ? series.n : series.abscissa;
    // The theory slope (power-law theories from the kernel's metadata) on the same axis.
    if (const auto& theory = series.theory.rate; theory && theory->model == RateModel::power_law &&
                                                 in_n == (run.study.abscissa == Abscissa::n))
      curve.theory_slope = run.study.abscissa == Abscissa::n
                               ? -theory->h_exponent / theory->dimension
                               : theory->h_exponent;
    else if (series.theory.kernel_unavailable)  // e.g. from a plugin not loaded: said, not drawn
      plan.notes.push_back(fmt::format("convergence_{}: no theory line for kernel {}: {}", metric,
                                       run.trials[series.trials.front()].kernel.label(),
                                       series.theory.why_none));
    curves.push_back(std::move(curve));
  }
  return curves;
}

// How a metric's curves are laid out: what tells them apart (groups that differ only in axes
// the metric does not depend on, such as the power function and the target, made one curve),
// the panels that keep each plot readable, and each curve's colour.
struct Layout {
  Identity identity;
  std::vector<std::size_t> chosen;               ///< the factors that split the curves into panels
  std::vector<std::size_t> others;               ///< the factors the curves of a panel differ in
  std::vector<std::vector<std::size_t>> panels;  ///< curves, in order of first appearance
  /// A curve keeps its colour in every panel when the curves' identities within panels are
  /// few enough (the same road class is the same colour everywhere); otherwise colours by
  /// position.
  std::map<std::vector<std::string>, std::size_t> colour_of;
  bool colour_by_identity = false;

  std::vector<std::string> values_of(std::size_t c, const std::vector<std::size_t>& factors) const {
    std::vector<std::string> out;
    for (auto f : factors) out.push_back(identity.values[c][f]);
    return out;
  }
  // The line type (1 to palette_size) of curve `c`, the `position`-th of its panel.
  std::size_t line_type(std::size_t c, std::size_t position) const {
    return 1 + (colour_by_identity ? colour_of.at(values_of(c, others)) : position) % palette_size;
  }
};

Layout layout_curves(const RunRecord& run, std::vector<Curve>& curves) {
  Layout layout;
  std::vector<const TrialSpec*> groups;
  for (const auto& curve : curves) groups.push_back(&run.trials[curve.series->trials.front()]);
  layout.identity = merge_identical(curves, identify(groups));
  const auto& identity = layout.identity;
  layout.chosen = panel_factors(identity, most_curves_per_panel);
  for (std::size_t f = 0; f < identity.factors.size(); ++f)
    if (std::find(layout.chosen.begin(), layout.chosen.end(), f) == layout.chosen.end())
      layout.others.push_back(f);
  std::map<std::vector<std::string>, std::size_t> index;
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const auto key = layout.values_of(c, layout.chosen);
    if (!index.contains(key)) {
      index[key] = layout.panels.size();
      layout.panels.emplace_back();
    }
    layout.panels[index[key]].push_back(c);
  }
  for (std::size_t c = 0; c < curves.size(); ++c)
    layout.colour_of.emplace(layout.values_of(c, layout.others), layout.colour_of.size());
  layout.colour_by_identity = layout.colour_of.size() <= palette_size;
  return layout;
}

// What a metric's plots show over all their panels: one x and y range for every panel and
// part (the values plotted; the axes add a margin) and the line styles that appear.
struct Contents {
  Extent xs, ys;
  std::vector<std::string> style_lines;
};

Contents contents_of(const std::vector<Curve>& curves) {
  Contents out;
  bool any_flagged = false, any_band = false, any_theory = false, any_constant = false;
  for (const auto& curve : curves) {
    const auto& series = *curve.series;
    for (std::size_t k = 0; k < series.trials.size(); ++k)
      if (usable_on_log_axis(series.values[k])) {
        out.xs.add(curve.x[k]);
        out.ys.add(series.values[k]);
        any_flagged = any_flagged || series.flagged[k];
      }
    any_band = any_band || (series.fit && !series.fit->used.empty());
    any_constant =
        any_constant || (series.analysis.constant && series.analysis.constant->value > 0);
    any_theory = any_theory || (curve.theory_slope && series.fit && !series.fit->used.empty());
  }
  out.style_lines.push_back("points: values");
  if (any_flagged) out.style_lines.push_back("hollow: flagged, not fitted");
  if (any_band) out.style_lines.push_back("dashed: fitted rate on its window, shaded its 95% band");
  if (any_constant)
    out.style_lines.push_back("const: a series constant on its window, shaded its band");
  if (any_theory) out.style_lines.push_back("dotted: theory slope");
  return out;
}

// The key and plot commands of one panel, its curves `members` labelled by `legend_factors`;
// their data blocks are appended to `data`. `key_characters`: how many characters fit across.
std::string panel_plot(const std::string& metric, const std::vector<Curve>& curves,
                       const Layout& layout, const std::vector<std::size_t>& members,
                       const std::vector<std::size_t>& legend_factors, std::size_t key_characters,
                       std::string& data) {
  std::string bands, fits, points, theories;
  std::set<std::string> theory_titles;
  std::size_t longest = 0;  // characters of the longest key entry
  for (std::size_t position = 0; position < members.size(); ++position) {
    const auto c = members[position];
    const auto& curve = curves[c];
    const auto& series = *curve.series;
    data += curve_data(curve, c);
    const std::size_t lt = layout.line_type(c, position);
    auto label = identity_text(layout.identity, c, legend_factors);
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
      if (usable_on_log_axis(series.values[k])) (series.flagged[k] ? flagged : unflagged) = true;
    if (unflagged)
      points +=
          fmt::format("$c{0} using 1:2 with linespoints lt {1} title {2}, ", c, lt, gp_text(label));
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
      theories += fmt::format(
          "$t{} using 1:2 with lines lc rgb '#505050' dt 3 lw 1.5 {}, ", c,
          theory_titles.insert(text).second ? "title " + gp_text(text) : std::string("notitle"));
    }
  }
  // The fitted lines over the data, the theory slopes over both.
  auto plot = bands + points + fits + theories;
  plot.erase(plot.size() - 2);
  // Two key columns when two entries fit side by side (with their samples, about 6
  // characters), else one.
  return fmt::format("set key maxcols {}\nplot {}\n", 2 * (longest + 6) < key_characters ? 2 : 1,
                     plot);
}

}  // namespace

void convergence_scripts(const RunRecord& run, const std::string& metric, PlotPlan& plan) {
  auto curves = convergence_curves(run, metric, plan);
  if (curves.empty()) {
    plan.notes.push_back(fmt::format(
        "convergence_{}: not plotted: no trial has a finite positive {} (a log axis needs one)",
        metric, metric));
    return;
  }
  const Layout layout = layout_curves(run, curves);
  const auto& identity = layout.identity;
  const auto& chosen = layout.chosen;
  const auto& panels = layout.panels;
  const Contents contents = contents_of(curves);
  const bool against_n = run.study.abscissa == Abscissa::n;
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
      title_lines.push_back(
          wrapped(contents.style_lines,
                  characters_across(sized(style, {automatic_width, 0}).width, style), "; "));
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
                                                      : metric_axis_label(run.study.kind(), metric);

    std::string data, drawing = line_types();
    drawing += fmt::format(
        "set xlabel {} enhanced\nset ylabel {} enhanced\nset logscale xy\n"
        "set format y '10^{{%L}}'\nset grid\nset datafile missing 'nan'\n{}{}{}",
        gp_text(against_n ? "n" : "fill distance h (m)"), gp_text(ylabel),
        log_range("x", contents.xs, true), log_range("y", contents.ys, false),
        key_placement(style.legend));
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
      drawing += panel_plot(metric, curves, layout, members, legend_factors,
                            characters_across(plot_width, style), data);
    }
    if (grid) drawing += "unset multiplot\n";
    const auto stem = parts == 1 ? "convergence_" + metric
                                 : fmt::format("convergence_{}_part{}", metric, part + 1);
    plan.scripts.emplace_back(stem, rendered(stem, figure, style, data, drawing));
  }
}

}  // namespace rkhs::plot_detail
