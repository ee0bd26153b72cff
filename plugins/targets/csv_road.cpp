// The `csv` target: a measured road profile (arc length, elevation) read from a CSV file below
// the data root (docs/roads.md; docs/model.md section 6). The file is read a block at a time
// (csv_text::Lines, the line limit applied as it is read) and parsed as it is read; a text is
// parsed the same way (csv_road_from_text, rkhs/targets/csv_road.hpp): lines and fields are
// split here, so that every error can name the file's own line and column.
#include "rkhs/targets/csv_road.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>

#include "rkhs/core/csv_text.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/core/sha256.hpp"

namespace rkhs {
namespace {

using csv_text::blank_or_comment;
using csv_text::Field;
using csv_text::Lines;
using csv_text::split;

// A column chosen by header name or by 1-based number.
struct ColumnChoice {
  std::string parameter;  // "arc_length_column" or "elevation_column"
  std::string role;       // "arc length" or "elevation"
  std::string given;
  std::optional<std::size_t> number;  // 1-based, when `given` is all digits
};

ColumnChoice column_choice(const ParameterSet& p, const std::string& parameter,
                           const std::string& role, bool header) {
  ColumnChoice choice{parameter, role, p.text(parameter), std::nullopt};
  const auto& g = choice.given;
  if (g.empty())
    throw ParameterError(parameter,
                         fmt::format("{} is empty: give a column name or number", parameter));
  if (std::all_of(g.begin(), g.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    std::size_t number = 0;
    if (std::from_chars(g.data(), g.data() + g.size(), number).ec != std::errc())
      throw ParameterError(parameter,
                           fmt::format("{} = \"{}\": column number too large", parameter, g));
    if (number < 1)
      throw ParameterError(parameter,
                           fmt::format("{} = \"{}\": columns are numbered from 1", parameter, g));
    choice.number = number;
  } else if (!header) {
    throw ParameterError(parameter, fmt::format("{} = \"{}\" is a column name, but header = false: "
                                                "give a column number (from 1)",
                                                parameter, g));
  }
  return choice;
}

double unit_scale(const std::string& units) {
  return units == "mm" ? 1e-3 : 1.0;
}

/// Natural cubic spline second derivatives through (u_i, z_i).
std::vector<double> natural_spline(const std::vector<double>& u, const std::vector<double>& z) {
  const std::size_t n = u.size();
  std::vector<double> second(n, 0.0);
  if (n < 3) return second;
  // Tridiagonal system for the interior second derivatives (Thomas algorithm).
  std::vector<double> diagonal(n, 0.0), rhs(n, 0.0), upper(n, 0.0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double h0 = u[i] - u[i - 1], h1 = u[i + 1] - u[i];
    const double lower = h0 / 6;
    diagonal[i] = (h0 + h1) / 3;
    upper[i] = h1 / 6;
    rhs[i] = (z[i + 1] - z[i]) / h1 - (z[i] - z[i - 1]) / h0;
    if (i > 1) {
      const double factor = lower / diagonal[i - 1];
      diagonal[i] -= factor * upper[i - 1];
      rhs[i] -= factor * rhs[i - 1];
    }
  }
  for (std::size_t i = n - 2; i >= 1; --i) {
    second[i] = (rhs[i] - upper[i] * second[i + 1]) / diagonal[i];
    if (i == 1) break;
  }
  return second;
}

class CsvRoad final : public TargetFunction {
 public:
  static PluginInfo info() {
    auto file = text_parameter("file", "",
                               "CSV file, relative to the data root (--data-dir, RKHS_STUDY_DATA, "
                               "default studies/data/) or absolute");
    file.default_doc = "none: required";
    return {
        "csv",
        "measured road profile (arc length, elevation) from a CSV file below the data root",
        {file,
         text_parameter("arc_length_column", "1",
                        "arc-length column: a header name or a number counted from 1"),
         text_parameter("elevation_column", "2",
                        "elevation column: a header name or a number counted from 1"),
         boolean_parameter("header", true, "the first line (after comments) names the columns"),
         choice_parameter("delimiter", ",", "field separator", {",", ";", "tab"}),
         choice_parameter("arc_length_units", "m", "units of the arc-length column", {"m", "mm"}),
         choice_parameter("elevation_units", "m", "units of the elevation column", {"m", "mm"}),
         real_parameter("start", 0.0,
                        "subrange: s = 0 lies this many metres after the first sample; the "
                        "track uses [first + start, first + start + L]",
                        0.0),
         choice_parameter("detrend", "none",
                          "none; linear: subtract the chord between the section's end "
                          "points (closes the loop, f(0) = f(L) = 0); mean: subtract the mean",
                          {"none", "linear", "mean"}),
         choice_parameter("interpolation", "linear",
                          "between samples: linear, or cubic (natural C2 spline)",
                          {"linear", "cubic"}),
         boolean_parameter("restart_at_samples", true,
                           "report every sample as a kink, so that an adaptive integrator "
                           "restarts there (linear interpolation only)")},
        {{"provenance", "sha256 of the file, recorded with every trial"}}};
  }

  // The file that `file` names below the data root.
  CsvRoad(const ParameterSet& p, const Domain& domain) : CsvRoad(p, domain, std::nullopt, {}) {}

  // `text` in place of the file, named `file_name` (csv_road_from_text); without `text`, the
  // file. The parameters are checked before the file is looked for.
  CsvRoad(const ParameterSet& p, const Domain& domain, std::optional<std::string_view> text,
          const std::string& file_name)
      : length_(domain.length),
        periodic_(domain.periodic),
        cubic_(p.choice("interpolation") == "cubic") {
    require_track(domain, "csv");
    const bool header = p.boolean("header");
    const auto arc = column_choice(p, "arc_length_column", "arc length", header);
    const auto elevation = column_choice(p, "elevation_column", "elevation", header);
    const std::string& delimiter_name = p.choice("delimiter");
    const char delimiter = delimiter_name == "tab" ? '\t' : delimiter_name[0];
    const auto read_lines = [&](Lines& lines) {
      read(lines, arc, elevation, header, delimiter, unit_scale(p.choice("arc_length_units")),
           unit_scale(p.choice("elevation_units")),
           p.given("arc_length_column") && p.given("elevation_column"));
    };
    std::string digest;
    if (text) {
      file_ = file_name;
      Lines lines(*text, file_);
      read_lines(lines);
      digest = sha256_hex(*text);
    } else {
      const auto path = resolve_data_file(p.text("file"));
      file_ = printable(path.string());
      auto in = csv_text::open_file(path, file_);
      Sha256 hash;
      Lines lines(in, file_, &hash);
      read_lines(lines);
      digest = hash.hex_digest();
    }
    if (cubic_) second_ = natural_spline(u_, z_);

    // The section of the profile on the track: [origin, origin + L].
    origin_ = u_.front() + p.real("start");
    const double end = origin_ + length_;
    // (An end beyond the largest double is infinite and would pass the comparison.)
    if (!std::isfinite(end) || end > u_.back() + 1e-9 * std::max(1.0, std::abs(end))) {
      const std::string section =
          p.real("start") > 0
              ? fmt::format(" (start = {} m: the track runs from arc length {} m to {} m)",
                            format_real(p.real("start")), format_real(origin_), format_real(end))
              : "";
      throw std::invalid_argument(fmt::format(
          "{}:{}:{}: the profile is shorter than the track: it covers arc length {} m to {} m, "
          "the track needs {} m{}",
          file_, lines_.back(), arc_columns_.back(), format_real(u_.front()),
          format_real(u_.back()), format_real(length_), section));
    }
    const double first = raw(origin_), last = raw(std::min(end, u_.back()));
    const auto& detrend = p.choice("detrend");
    if (detrend == "linear") {
      offset_ = first;
      slope_ = (last - first) / length_;
    } else if (detrend == "mean") {
      offset_ = section_mean();
    }
    if (periodic_ && detrend != "linear") {
      const double gap = last - first;
      if (std::abs(gap) > 1e-9 * std::max(1.0, std::max(std::abs(first), std::abs(last))))
        throw std::invalid_argument(fmt::format(
            "{}: the profile does not close on the track: elevation {} m at s = 0 and {} m at "
            "s = L = {} m; set detrend = \"linear\" (remove the trend between the end points) "
            "or make the domain an interval ([domain] periodic = false)",
            file_, format_real(first), format_real(last), format_real(length_)));
    }
    // Kinks: the seam of a closed track (slopes differ across s = L ~ 0), and, when asked for,
    // every sample inside the section (linear interpolation only; the spline is C2).
    if (periodic_) kinks_.push_back(0.0);
    if (p.boolean("restart_at_samples") && !cubic_)
      for (double u : u_)
        if (const double s = u - origin_; s > 0 && s < length_) kinks_.push_back(s);
    provenance_ = "sha256:" + digest;
  }

  void evaluate(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m) {
      double s = points[m];
      s = periodic_ ? std::fmod(s, length_) : std::clamp(s, 0.0, length_);
      if (s < 0) s += length_;
      out[m] = raw(origin_ + s) - offset_ - slope_ * s;
    }
  }
  /// The derivative of the interpolant (less the detrending slope), at points mapped into the
  /// domain as by evaluate(). At a sample, where a linear interpolant's slope jumps, the
  /// right-hand derivative (the piece that starts there); at s = L on an interval the left-hand
  /// one (the section ends there).
  void derivative(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m) {
      double s = points[m];
      s = periodic_ ? std::fmod(s, length_) : std::clamp(s, 0.0, length_);
      if (s < 0) s += length_;
      const bool at_end = !periodic_ && s == length_;
      out[m] = raw_slope(origin_ + s, at_end) - slope_;
    }
  }
  bool has_exact_derivative() const override { return true; }
  void describe_provenance(const std::function<void(std::string_view)>& sink) const override {
    sink(provenance_);
  }
  void list_notes(const std::function<void(std::string_view)>& sink) const override {
    for (const auto& note : notes_) sink(note);
  }
  void list_kink_points(const std::function<void(double)>& sink) const override {
    for (double s : kinks_) sink(s);
  }

 private:
  // Reads every sample; throws std::invalid_argument "file:line:column: ..." for any problem.
  // The header (or, without one, the first data line) fixes the number of fields: a line with
  // more is refused (a decimal comma, "0,5", splits a number in two). A file with more columns
  // than the two it reads is refused unless `columns_given` (the study names both columns);
  // then the columns left out are noted once.
  void read(Lines& reader, const ColumnChoice& arc, const ColumnChoice& elevation, bool header,
            char delimiter, double arc_scale, double elevation_scale, bool columns_given) {
    std::size_t arc_index = arc.number ? *arc.number - 1 : 0;
    std::size_t elevation_index = elevation.number ? *elevation.number - 1 : 0;
    bool need_header = header;
    std::size_t width = 0;           // fields per line, from the first line
    unsigned width_line = 0;         // the line that set it
    std::vector<std::string> names;  // the header's column names (empty without a header)
    const auto set_width = [&](std::size_t count, unsigned line_number) {
      width = count;
      width_line = line_number;
      if (width <= 2) return;
      std::vector<std::string> unread;
      for (std::size_t k = 0; k < width; ++k)
        if (k != arc_index && k != elevation_index)
          unread.push_back(names.empty() ? fmt::format("{}", k + 1)
                                         : fmt::format("{} ({})", k + 1, printable(names[k])));
      if (!columns_given)
        throw std::invalid_argument(fmt::format(
            "{}:{}:1: the {} has {} fields and the study reads two (arc length from column {}, "
            "elevation from column {}, the defaults): name both in the [[target]] entry "
            "(arc_length_column, elevation_column) to read this file",
            file_, line_number, header ? "header" : "first line", width, arc_index + 1,
            elevation_index + 1));
      notes_.push_back(
          fmt::format("{}: column{} {} not read (arc length: column {}, "
                      "elevation: column {})",
                      file_, unread.size() == 1 ? "" : "s", fmt::join(unread, ", "), arc_index + 1,
                      elevation_index + 1));
    };
    while (const auto next = reader.next()) {
      const std::string_view line = *next;
      const unsigned line_number = reader.number();
      if (blank_or_comment(line)) continue;
      const auto fields = split(line, delimiter);
      if (need_header) {
        need_header = false;
        for (const auto& f : fields) names.emplace_back(f.text);
        auto locate = [&](const ColumnChoice& choice, std::size_t& index) {
          if (choice.number) {
            if (*choice.number > fields.size())
              throw std::invalid_argument(
                  fmt::format("{}:{}:{}: no column {} ({}): the header has {} column{}", file_,
                              line_number, line.size() + 1, *choice.number, choice.role,
                              fields.size(), fields.size() == 1 ? "" : "s"));
            return;
          }
          const auto it = std::find(names.begin(), names.end(), choice.given);
          if (it == names.end()) {
            std::string known;
            for (const auto& name : names) known += (known.empty() ? "" : ", ") + printable(name);
            const auto guess = printable(closest_name(choice.given, names));
            throw std::invalid_argument(
                fmt::format("{}:{}:1: no column '{}' ({}) in the header (columns: {}{})", file_,
                            line_number, printable(choice.given), choice.role, known,
                            guess.empty() ? "" : fmt::format("; did you mean '{}'?", guess)));
          }
          index = static_cast<std::size_t>(it - names.begin());
        };
        locate(arc, arc_index);
        locate(elevation, elevation_index);
        set_width(fields.size(), line_number);
        continue;
      }
      if (width == 0) set_width(fields.size(), line_number);
      if (fields.size() > width)
        throw std::invalid_argument(fmt::format(
            "{}:{}:{}: {} fields where line {} has {}{}: a decimal comma (0,5 for 0.5) or a "
            "delimiter inside a number?",
            file_, line_number, fields[width].column, fields.size(), width_line, width,
            names.empty()
                ? ""
                : fmt::format(" ({})", printable(fmt::format("{}", fmt::join(names, ", "))))));
      auto number = [&](std::size_t index, const ColumnChoice& choice) {
        if (index >= fields.size())
          throw std::invalid_argument(
              fmt::format("{}:{}:{}: no {} (column {}): the line has {} field{}", file_,
                          line_number, line.size() + 1, choice.role, index + 1, fields.size(),
                          fields.size() == 1 ? "" : "s"));
        const auto& field = fields[index];
        auto fail = [&](const std::string& what) {
          return std::invalid_argument(
              fmt::format("{}:{}:{}: {}", file_, line_number, field.column, what));
        };
        if (field.text.empty())
          throw fail(fmt::format("{}: empty field, expected a number", choice.role));
        const auto parsed = csv_text::parse_number(field.text);
        if (!parsed)
          throw fail(fmt::format("{}: '{}' is not a number", choice.role, printable(field.text)));
        const double value = *parsed;
        if (std::isnan(value))
          throw fail(fmt::format("{} is NaN (every sample needs a value)", choice.role));
        if (std::isinf(value)) throw fail(fmt::format("{} is infinite", choice.role));
        return std::pair{value, field.column};
      };
      const auto [u, u_column] = number(arc_index, arc);
      const auto [z, z_column] = number(elevation_index, elevation);
      const double position = u * arc_scale;
      if (!u_.empty() && !(position > u_.back())) {
        // Captured by copy: a lambda may not capture a structured binding in C++20 (clang).
        const auto fail = [&, column = u_column, given = u](const std::string& what) {
          return std::invalid_argument(
              fmt::format("{}:{}:{}: arc length {} {} (arc length must be strictly increasing)",
                          file_, line_number, column, format_real(given), what));
        };
        if (position == u_.back()) throw fail(fmt::format("repeats line {}", lines_.back()));
        throw fail(fmt::format("is less than {} on line {}", format_real(u_.back() / arc_scale),
                               lines_.back()));
      }
      u_.push_back(position);
      z_.push_back(z * elevation_scale);
      lines_.push_back(line_number);
      arc_columns_.push_back(u_column);
    }
    if (need_header)
      throw std::invalid_argument(
          fmt::format("{}:1:1: the file is empty (expected a header line)", file_));
    if (u_.size() < 2)
      throw std::invalid_argument(fmt::format("{}:{}:1: {} sample{}: a profile needs at least 2",
                                              file_, std::max(1u, reader.number()), u_.size(),
                                              u_.size() == 1 ? "" : "s"));
  }

  // The bytes of the file at `path` (file_).
  // The interpolant of the raw samples at arc length u (inside the profile).
  double raw(double u) const {
    const auto upper = std::upper_bound(u_.begin() + 1, u_.end() - 1, u);
    const std::size_t i = static_cast<std::size_t>(upper - u_.begin()) - 1;
    const double h = u_[i + 1] - u_[i];
    const double a = (u_[i + 1] - u) / h, b = (u - u_[i]) / h;
    double value = a * z_[i] + b * z_[i + 1];
    if (cubic_)
      value += ((a * a * a - a) * second_[i] + (b * b * b - b) * second_[i + 1]) * h * h / 6;
    return value;
  }

  // d/du of raw(u): on the piece [u_i, u_i+1) holding u (right-hand at a sample), or, with
  // `left`, on the piece (u_i, u_i+1] (left-hand).
  double raw_slope(double u, bool left) const {
    const auto bound = left ? std::lower_bound(u_.begin() + 1, u_.end() - 1, u)
                            : std::upper_bound(u_.begin() + 1, u_.end() - 1, u);
    const std::size_t i = static_cast<std::size_t>(bound - u_.begin()) - 1;
    const double h = u_[i + 1] - u_[i];
    double slope = (z_[i + 1] - z_[i]) / h;
    if (cubic_) {
      const double a = (u_[i + 1] - u) / h, b = (u - u_[i]) / h;
      slope += ((3 * b * b - 1) * second_[i + 1] - (3 * a * a - 1) * second_[i]) * h / 6;
    }
    return slope;
  }

  // Mean of the interpolant over [origin, origin + L]: Simpson's rule on every piece between
  // samples (exact for linear and cubic pieces).
  double section_mean() const {
    const double end = origin_ + length_;
    std::vector<double> cuts{origin_};
    for (double u : u_)
      if (u > origin_ && u < end) cuts.push_back(u);
    cuts.push_back(end);
    double integral = 0;
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
      const double a = cuts[k], b = cuts[k + 1];
      integral += (b - a) / 6 * (raw(a) + 4 * raw(0.5 * (a + b)) + raw(b));
    }
    return integral / length_;
  }

  double length_;
  bool periodic_, cubic_;
  std::string file_, provenance_;
  std::vector<std::string> notes_;
  std::vector<double> u_, z_, second_;
  std::vector<unsigned> lines_;
  std::vector<std::size_t> arc_columns_;
  double origin_ = 0, offset_ = 0, slope_ = 0;
  std::vector<double> kinks_;
};

}  // namespace

std::unique_ptr<TargetFunction> csv_road_from_text(const ParameterSet& parameters,
                                                   const Domain& domain, std::string_view text,
                                                   const std::string& file_name) {
  return std::make_unique<CsvRoad>(parameters, domain, text, file_name);
}

}  // namespace rkhs

RKHS_REGISTER_TARGET(rkhs::CsvRoad)
