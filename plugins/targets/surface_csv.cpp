// The `surface_csv` target: a measured road surface z(u, v) on a regular grid, read from a CSV
// file below the data root (docs/roads.md, "Road surfaces in 2-D"); f on a box of d = 2 is the
// bilinear interpolant of the grid, x1 along the road (u) and x2 across it (v).
//
// The file is the grid itself (tools/crg_to_surface_csv.py writes it from an OpenCRG file):
//   u_m\v_m,-1.00,-0.98,...       a label, then the lateral offsets v_j (metres, increasing)
//   0.00,2.131593,2.130018,...    u_i (metres, increasing), then z(u_i, v_j) (metres)
// Lines that are blank or start with '#' are skipped. Both axes must be equally spaced (to
// 1e-6 of the spacing): the interpolant finds its cell by division. Every value must be a
// finite number; a missing sample is an error at its line and column (the tool fills them).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "rkhs/approx/target.hpp"
#include "rkhs/core/csv_text.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/core/sha256.hpp"

namespace rkhs {
namespace {

class SurfaceCsv final : public TargetFunction {
 public:
  static PluginInfo info() {
    auto file = text_parameter("file", "",
                               "the grid CSV, relative to the data root (--data-dir, "
                               "RKHS_STUDY_DATA or studies/data/)");
    file.default_doc = "none: required";
    auto u_start = real_parameter("u_start", 0.0, "the grid's u at x1 = 0, metres");
    u_start.default_doc = "the grid's first u";
    auto v_start = real_parameter("v_start", 0.0, "the grid's v at x2 = 0, metres");
    v_start.default_doc = "the grid's first v";
    return {"surface_csv",
            "a road surface z(u, v) on a regular grid from CSV, bilinear between samples (d = 2: "
            "x1 = u - u_start along the road, x2 = v - v_start across it)",
            {file, u_start, v_start,
             choice_parameter("detrend", "none",
                              "subtract nothing, or the mean of the samples on the domain",
                              {"none", "mean"})},
            {{"provenance", "sha256 of the file, recorded with every trial"}}};
  }

  SurfaceCsv(const ParameterSet& p, const Domain& domain) {
    if (domain.dimension != 2)
      throw std::invalid_argument(fmt::format(
          "target 'surface_csv' is a surface z(u, v): it needs a domain of d = 2 (lengths = "
          "[along, across]); this domain has d = {}",
          domain.dimension));
    if (domain.periodic)
      throw std::invalid_argument(
          "target 'surface_csv': a measured surface is not periodic; make the domain a box "
          "([domain] periodic = false)");
    if (!p.given("file"))
      throw ParameterError("file",
                           "parameter 'file' is required: the grid CSV, e.g. file = "
                           "\"belgian_block/surface_2cm.csv\"");
    const auto path = resolve_data_file(p.text("file"));
    file_ = printable(path.string());
    auto in = csv_text::open_file(path, file_);
    Sha256 digest;
    csv_text::Lines lines(in, file_, &digest);
    read(lines);
    provenance_ = "sha256:" + digest.hex_digest();

    u0_ = p.given("u_start") ? p.real("u_start") : u_first_;
    v0_ = p.given("v_start") ? p.real("v_start") : v_first_;
    const double u_last = u_first_ + du_ * static_cast<double>(rows_ - 1);
    const double v_last = v_first_ + dv_ * static_cast<double>(columns_ - 1);
    const double slack = 1e-9 * std::max({1.0, std::abs(u_last), std::abs(v_last)});
    if (u0_ < u_first_ - slack || u0_ + domain.length > u_last + slack || v0_ < v_first_ - slack ||
        v0_ + domain.width > v_last + slack)
      throw std::invalid_argument(fmt::format(
          "{}: the grid covers u in [{}, {}] m and v in [{}, {}] m; the domain needs u in "
          "[{}, {}] m and v in [{}, {}] m (u_start, v_start and the domain's lengths)",
          file_, format_real(u_first_), format_real(u_last), format_real(v_first_),
          format_real(v_last), format_real(u0_), format_real(u0_ + domain.length), format_real(v0_),
          format_real(v0_ + domain.width)));
    length_ = domain.length;
    width_ = domain.width;
    if (p.choice("detrend") == "mean") offset_ = mean_on_domain();
  }

  void evaluate(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < out.size(); ++m)
      out[m] = at(points[2 * m], points[2 * m + 1]) - offset_;
  }
  void derivative(std::span<const double>, std::span<double>) const override {
    throw std::logic_error("the surface target has no derivative along a track (d = 2)");
  }
  void describe_provenance(const std::function<void(std::string_view)>& sink) const override {
    sink(provenance_);
  }

 private:
  // The bilinear interpolant at domain point (x1, x2), clamped to the domain.
  double at(double x1, double x2) const {
    const double a = (u0_ + std::clamp(x1, 0.0, length_) - u_first_) / du_;
    const double b = (v0_ + std::clamp(x2, 0.0, width_) - v_first_) / dv_;
    const auto i = std::min(static_cast<std::size_t>(std::max(a, 0.0)), rows_ - 2);
    const auto j = std::min(static_cast<std::size_t>(std::max(b, 0.0)), columns_ - 2);
    const double s = std::clamp(a - static_cast<double>(i), 0.0, 1.0);
    const double t = std::clamp(b - static_cast<double>(j), 0.0, 1.0);
    const double* row = z_.data() + i * columns_;
    const double* next = row + columns_;
    return (1 - s) * ((1 - t) * row[j] + t * row[j + 1]) +
           s * ((1 - t) * next[j] + t * next[j + 1]);
  }

  // The mean of the samples whose (u, v) lie on the domain.
  double mean_on_domain() const {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < rows_; ++i) {
      const double u = u_first_ + du_ * static_cast<double>(i) - u0_;
      if (u < -1e-9 || u > length_ + 1e-9) continue;
      for (std::size_t j = 0; j < columns_; ++j) {
        const double v = v_first_ + dv_ * static_cast<double>(j) - v0_;
        if (v < -1e-9 || v > width_ + 1e-9) continue;
        sum += z_[i * columns_ + j];
        ++count;
      }
    }
    return count ? sum / static_cast<double>(count) : 0.0;
  }

  // A finite number in `field` of line `line`, or an error at its line and column naming what
  // `describe()` says it is (called only then).
  template <class Describe>
  double number(const csv_text::Field& field, unsigned line, const Describe& describe) const {
    const auto parsed = csv_text::parse_number(field.text);
    if (!parsed)
      throw std::invalid_argument(fmt::format("{}:{}:{}: {}: '{}' is not a number", file_, line,
                                              field.column, describe(), printable(field.text)));
    const double value = *parsed;
    if (!std::isfinite(value))
      throw std::invalid_argument(fmt::format(
          "{}:{}:{}: {} is {} (every sample needs a finite value; tools/crg_to_surface_csv.py "
          "fills missing samples)",
          file_, line, field.column, describe(), printable(field.text)));
    return value;
  }

  // The spacing of `values`, which must increase in equal steps (each within 1e-6 of the first
  // step), or an error at the first value that does not, naming the axis.
  static double spacing(const std::vector<double>& values, const std::vector<unsigned>& lines,
                        const std::vector<std::size_t>& columns, const std::string& file,
                        std::string_view axis) {
    const double first = values[1] - values[0];
    for (std::size_t k = 1; k < values.size(); ++k) {
      const double gap = values[k] - values[k - 1];
      if (!(gap > 0) || std::abs(gap - first) > 1e-6 * std::abs(first))
        throw std::invalid_argument(fmt::format(
            "{}:{}:{}: {} = {} after {}: the grid's {} must increase in equal steps (the first "
            "is {} m)",
            file, lines[k], columns[k], axis, format_real(values[k]), format_real(values[k - 1]),
            axis, format_real(first)));
    }
    // The mean step: the grid's extent over its cells, without the rounding of the first gap.
    return (values.back() - values.front()) / static_cast<double>(values.size() - 1);
  }

  void read(csv_text::Lines& lines) {
    std::vector<double> v, u;
    std::vector<unsigned> v_lines, u_lines;
    std::vector<std::size_t> v_columns, u_columns;
    while (const auto line = lines.next()) {
      if (csv_text::blank_or_comment(*line)) continue;
      const auto fields = csv_text::split(*line, ',');
      if (v.empty()) {  // the header: a label, then the v of every column
        if (fields.size() < 3)
          throw std::invalid_argument(fmt::format(
              "{}:{}:1: the header has {} field(s); expected a label and at least 2 lateral "
              "offsets v",
              file_, lines.number(), fields.size()));
        for (std::size_t f = 1; f < fields.size(); ++f) {
          v.push_back(number(fields[f], lines.number(), [] { return "lateral offset v"; }));
          v_lines.push_back(lines.number());
          v_columns.push_back(fields[f].column);
        }
        continue;
      }
      if (fields.size() != v.size() + 1)
        throw std::invalid_argument(fmt::format(
            "{}:{}:1: {} fields, expected {} (u and one elevation per lateral offset of the "
            "header)",
            file_, lines.number(), fields.size(), v.size() + 1));
      u.push_back(number(fields[0], lines.number(), [] { return "u"; }));
      u_lines.push_back(lines.number());
      u_columns.push_back(fields[0].column);
      for (std::size_t f = 1; f < fields.size(); ++f)
        z_.push_back(number(fields[f], lines.number(), [&] {
          return fmt::format("elevation z at v = {}", format_real(v[f - 1]));
        }));
    }
    if (v.empty() || u.size() < 2)
      throw std::invalid_argument(
          fmt::format("{}: {} row(s) of samples; a surface needs a header and at least 2 rows",
                      file_, u.size()));
    dv_ = spacing(v, v_lines, v_columns, file_, "v");
    du_ = spacing(u, u_lines, u_columns, file_, "u");
    rows_ = u.size();
    columns_ = v.size();
    u_first_ = u.front();
    v_first_ = v.front();
  }

  std::string file_, provenance_;
  std::vector<double> z_;  // row-major: z(u_i, v_j) at i * columns_ + j
  std::size_t rows_ = 0, columns_ = 0;
  double u_first_ = 0, v_first_ = 0, du_ = 1, dv_ = 1;
  double u0_ = 0, v0_ = 0, length_ = 0, width_ = 0, offset_ = 0;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_TARGET(rkhs::SurfaceCsv)
