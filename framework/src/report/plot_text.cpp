// The text of gnuplot scripts: quoting, wrapped lines, logarithmic axes, the figure's
// terminals and sizes, line types and the key (rkhs/report/plots.cpp and the plot files beside it).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "plot_parts.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs::plot_detail {

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
                    std::string_view separator) {
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

// The margin a logarithmic axis leaves around `extent`: a factor of (high / low)^share, at
// least `least` and at most `most` (never a whole decade: the data fill the plot).
double log_margin(const Extent& extent, double share, double least, double most) {
  return std::clamp(std::pow(extent.high / extent.low, share), least, most);
}

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
constexpr const char* palette[palette_size] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                               "#E69F00", "#56B4E9", "#000000", "#8C564B"};
std::string line_types() {
  std::string out;
  for (int i = 0; i < palette_size; ++i)
    out += fmt::format("set linetype {} lc rgb '{}' lw 1.5 pt {} ps 0.8\n", i + 1, palette[i],
                       filled_point[i]);
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

}  // namespace rkhs::plot_detail
