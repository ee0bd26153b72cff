// [plot] of a study file (docs/study-files.md): how the convergence plots look; only the
// figures change (rkhs/study/study.hpp, PlotStyle).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "study_file_parts.hpp"

namespace rkhs::detail {

namespace {

// The longest text of a [plot] label or title (a label is a few words; gnuplot draws it on
// one line).
constexpr std::size_t max_plot_text = 300;

// A [plot] label or title: a string of at most max_plot_text bytes, one line.
std::string plot_text(const Reporter& report, const toml::node& node, const std::string& key) {
  if (!node.is_string())
    report.fail(node.source(), key,
                fmt::format("expected a string (gnuplot enhanced text), found {} ({})",
                            describe(node), show(node)));
  const std::string text = node.as_string()->get();
  if (text.size() > max_plot_text)
    report.fail(
        node.source(), key,
        fmt::format("is {} bytes long, at most {} are allowed", text.size(), max_plot_text));
  if (text.find_first_of("\r\n") != std::string::npos)
    report.fail(node.source(), key, "must be one line (found a line break)");
  return text;
}

// A [plot] number in [low, high].
double plot_number(const Reporter& report, const toml::node& node, const std::string& key,
                   double low, double high, std::string_view unit) {
  const auto value = real_of(node);
  if (!value || !(*value >= low && *value <= high))
    report.fail(node.source(), key,
                fmt::format("expected a number between {} and {}{}, found {}", format_real(low),
                            format_real(high), unit, show(node)));
  return *value;
}

}  // namespace

PlotStyle parse_plot(const Reporter& report, const toml::table& table,
                     const StudyDefinition& study) {
  check_keys(report, table, "plot.",
             {"metrics", "labels", "title", "size", "font_size", "legend", "png_dpi"});
  PlotStyle style;
  const auto& plotted = study.metrics;
  auto check_metric = [&](const toml::node& node, const std::string& metric,
                          const std::string& key) {
    if (std::find(plotted.begin(), plotted.end(), metric) != plotted.end()) return;
    const auto& all = metric_names(study.kind());
    report.fail(
        node.source(), key,
        std::find(all.begin(), all.end(), metric) == all.end()
            ? fmt::format("unknown metric '{}' {}", metric, with_suggestion(metric, plotted))
            : fmt::format("'{}' is not among study.metrics, so it has no plot (add it "
                          "there; study.metrics: {})",
                          metric, fmt::join(plotted, ", ")));
  };
  if (const auto* metrics = table.get("metrics")) {
    const auto* array = metrics->as_array();
    if (!array || array->empty())
      report.fail(metrics->source(), "plot.metrics",
                  fmt::format("expected a non-empty array of metric names, in the order to plot "
                              "them (of study.metrics: {})",
                              fmt::join(plotted, ", ")));
    for (const auto& item : *array) {
      if (!item.is_string())
        report.fail(item.source(), "plot.metrics",
                    fmt::format("expected a metric name, found {}", describe(item)));
      const std::string metric = item.as_string()->get();
      check_metric(item, metric, "plot.metrics");
      if (std::find(style.metrics.begin(), style.metrics.end(), metric) != style.metrics.end())
        report.fail(item.source(), "plot.metrics", fmt::format("'{}' is listed twice", metric));
      style.metrics.push_back(metric);
    }
  }
  if (const auto* labels = table.get("labels")) {
    const auto* map = labels->as_table();
    if (!map)
      report.fail(labels->source(), "plot.labels",
                  fmt::format("expected an inline table of metric = \"y axis label\" (e.g. "
                              "labels = {{ l2_error = \"L^2 error\" }}), found {}",
                              describe(*labels)));
    for (auto&& [key, value] : *map) {
      const std::string metric(key.str());
      const auto name = "plot.labels." + metric;
      check_metric(value, metric, name);
      style.labels[metric] = plot_text(report, value, name);
    }
  }
  if (const auto* title = table.get("title")) {
    if (const auto* flag = title->as_boolean()) {
      if (flag->get())
        report.fail(title->source(), "plot.title",
                    "expected a string, or false for no title (true is the default: leave the "
                    "key out)");
      style.title = std::string();
    } else {
      style.title = plot_text(report, *title, "plot.title");
    }
  }
  if (const auto* size = table.get("size")) {
    const auto* pair = size->as_array();
    if (!pair || pair->size() != 2)
      report.fail(
          size->source(), "plot.size",
          fmt::format("expected [width, height] in inches (e.g. [6, 4]), found {}", show(*size)));
    const char* axes[] = {"width", "height"};
    double inches[2];
    for (std::size_t i = 0; i < 2; ++i) {
      const auto& item = *pair->get(i);
      const auto value = real_of(item);
      if (!value || !(*value > 0 && *value <= PlotStyle::max_inches))
        report.fail(item.source(), "plot.size",
                    fmt::format("{}: expected inches, a number above 0 and at most {}, found {}",
                                axes[i], format_real(PlotStyle::max_inches), show(item)));
      inches[i] = *value;
    }
    style.width_inches = inches[0];
    style.height_inches = inches[1];
  }
  if (const auto* font = table.get("font_size"))
    style.font_points = plot_number(report, *font, "plot.font_size", PlotStyle::min_font_points,
                                    PlotStyle::max_font_points, " points");
  if (const auto* legend = table.get("legend")) {
    style.legend = get_string(report, table, "legend", "plot.", std::nullopt);
    const auto& known = PlotStyle::legend_positions();
    if (std::find(known.begin(), known.end(), style.legend) == known.end())
      report.fail(legend->source(), "plot.legend",
                  fmt::format("unknown position '{}' {}", style.legend,
                              with_suggestion(style.legend, known)));
  }
  if (const auto* dpi = table.get("png_dpi")) {
    style.png_dpi = static_cast<int>(get_whole_number(
        report, table, "png_dpi", "plot.", 150, PlotStyle::min_png_dpi, PlotStyle::max_png_dpi));
    const double inches = std::max(style.width_inches, style.height_inches);
    if (inches * style.png_dpi > PlotStyle::max_png_pixels)
      report.fail(dpi->source(), "plot.png_dpi",
                  fmt::format("{} dpi at {} inches makes a PNG of {} pixels a side, at most {} "
                              "are allowed: lower png_dpi or size",
                              style.png_dpi, format_real(inches),
                              format_real(std::round(inches * style.png_dpi)),
                              format_real(PlotStyle::max_png_pixels)));
  }
  return style;
}

}  // namespace rkhs::detail
