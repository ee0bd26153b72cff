// The `csv` target: every malformed file is refused with its file:line:column, interpolation
// is exact on piecewise-linear data, detrending closes the loop, the data root resolves files.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "rkhs/core/data_root.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/targets/csv_road.hpp"

using namespace rkhs;
namespace fs = std::filesystem;

namespace {

// A fresh directory used as the data root for the duration of a test.
class DataDirectory {
 public:
  explicit DataDirectory(const std::string& name)
      : path_(fs::temp_directory_path() / ("rkhs_csv_road_" + name)) {
    fs::remove_all(path_);
    fs::create_directories(path_);
    set_data_root(path_);
  }
  ~DataDirectory() {
    set_data_root({});
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  // Writes a fixture file and returns its full path as the road reports it.
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
    return (path_ / name).string();
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::unique_ptr<TargetFunction> road(std::map<std::string, ParameterValue> given,
                                     Domain domain = {10.0, false}) {
  const auto* entry = target_registry().find("csv");
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

std::string error_of(std::map<std::string, ParameterValue> given, Domain domain = {10.0, false}) {
  try {
    road(std::move(given), domain);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

std::string fmt_line(double u, double z) {
  char line[80];
  std::snprintf(line, sizeof line, "%.17g,%.17g,ok\n", u, z);
  return line;
}

// A profile u = 0, step, ..., to written as "u,z" lines.
std::string profile(double (*z)(double), double step = 0.5, double to = 10.0) {
  std::string text = "u,z\n";
  for (int i = 0; i * step <= to + 1e-12; ++i) {
    char line[64];
    std::snprintf(line, sizeof line, "%.17g,%.17g\n", i * step, z(i * step));
    text += line;
  }
  return text;
}

}  // namespace

TEST_CASE("csv road: each malformed file is refused with file:line:column", "[csv_road]") {
  const DataDirectory data("malformed");
  const std::string named_columns = "arc_length_column";

  SECTION("missing file: says where it looked") {
    CHECK(error_of({{"file", std::string("absent.csv")}}) ==
          "data file 'absent.csv' not found (looked at " + (data.path() / "absent.csv").string() +
              ", in the data root from --data-dir; set the data root with --data-dir DIR or "
              "RKHS_STUDY_DATA)");
  }
  SECTION("more fields than the columns read: a decimal comma is not a silent zero") {
    // "2,131593" with a decimal comma splits into 2 and 131593 in a two-column file.
    const auto comma = data.write("comma.csv", "u_m,z_m\n0.0000,2.131593\n0.0900,0,243774178082\n");
    CHECK(error_of({{"file", std::string("comma.csv")}}) ==
          comma +
              ":3:10: 3 fields where line 1 has 2 (u_m, z_m): a decimal comma (0,5 for 0.5) "
              "or a delimiter inside a number?");
    // The same with the columns named: the header still says how many fields a line has.
    CHECK_THAT(error_of({{"file", std::string("comma.csv")},
                         {"arc_length_column", std::string("u_m")},
                         {"elevation_column", std::string("z_m")}}),
               Catch::StartsWith(comma + ":3:10: 3 fields where line 1 has 2"));
    // Without a header the first line sets the number of fields.
    const auto plain = data.write("plain3.csv", "0,2.5\n1,2,5\n");
    CHECK(error_of({{"file", std::string("plain3.csv")}, {"header", false}}) ==
          plain +
              ":2:5: 3 fields where line 1 has 2: a decimal comma (0,5 for 0.5) or a "
              "delimiter inside a number?");
    // A file with a third column, read with the default columns: the study must say which.
    const auto wide = data.write("wide.csv", "u,z,quality\n0,1,ok\n10,1,ok\n");
    CHECK(error_of({{"file", std::string("wide.csv")}}) ==
          wide +
              ":1:1: the header has 3 fields and the study reads two (arc length from column "
              "1, elevation from column 2, the defaults): name both in the [[target]] entry "
              "(arc_length_column, elevation_column) to read this file");
    const auto decimal_commas = data.write("commas.csv", "0,0,5\n10,1,5\n");
    CHECK_THAT(error_of({{"file", std::string("commas.csv")}, {"header", false}}),
               Catch::StartsWith(decimal_commas + ":1:1: the first line has 3 fields"));
    // Named columns: the rest is read past, and said once.
    const auto f = road({{"file", std::string("wide.csv")},
                         {"arc_length_column", std::string("u")},
                         {"elevation_column", std::string("z")}});
    CHECK(f->notes() ==
          std::vector<std::string>{wide + ": column 3 (quality) not read (arc length: column 1, "
                                          "elevation: column 2)"});
    data.write("two.csv", "u_m,z_m\n0,1\n10,1\n");
    CHECK(road({{"file", std::string("two.csv")}})->notes().empty());
  }
  SECTION("missing column by name, with a suggestion") {
    const auto file = data.write("columns.csv", "u_m,z_m\n0,1\n10,1\n");
    CHECK(error_of(
              {{"file", std::string("columns.csv")}, {"elevation_column", std::string("z_mm")}}) ==
          file +
              ":1:1: no column 'z_mm' (elevation) in the header (columns: u_m, z_m; did you mean "
              "'z_m'?)");
    CHECK(error_of({{"file", std::string("columns.csv")},
                    {"arc_length_column", std::string("distance")}}) ==
          file + ":1:1: no column 'distance' (arc length) in the header (columns: u_m, z_m)");
  }
  SECTION("missing column by number, in the header and in a data line") {
    const auto file = data.write("short_line.csv", "0,1\n0.5\n");
    CHECK(error_of({{"file", std::string("short_line.csv")}, {"header", false}}) ==
          file + ":2:4: no elevation (column 2): the line has 1 field");
    const auto header = data.write("header.csv", "u,z\n0,1\n");
    CHECK(error_of({{"file", std::string("header.csv")}, {"elevation_column", std::string("3")}}) ==
          header + ":1:4: no column 3 (elevation): the header has 2 columns");
  }
  SECTION("non-numeric value") {
    const auto file = data.write("text.csv", "u,z\n0,1\n0.5,abc\n");
    CHECK(error_of({{"file", std::string("text.csv")}}) ==
          file + ":3:5: elevation: 'abc' is not a number");
    const auto trailing = data.write("trailing.csv", "u,z\n0,1\n0.5x,2\n");
    CHECK(error_of({{"file", std::string("trailing.csv")}}) ==
          trailing + ":3:1: arc length: '0.5x' is not a number");
    const auto empty = data.write("empty_field.csv", "u,z\n0,1\n0.5, \n");
    CHECK(error_of({{"file", std::string("empty_field.csv")}}) ==
          empty + ":3:6: elevation: empty field, expected a number");
  }
  SECTION("NaN and infinity") {
    const auto file = data.write("nan.csv", "u,z\n0,1\n0.5,NaN\n");
    CHECK(error_of({{"file", std::string("nan.csv")}}) ==
          file + ":3:5: elevation is NaN (every sample needs a value)");
    const auto arc = data.write("nan_arc.csv", "u,z\n0,1\nnan,2\n");
    CHECK(error_of({{"file", std::string("nan_arc.csv")}}) ==
          arc + ":3:1: arc length is NaN (every sample needs a value)");
    const auto inf = data.write("inf.csv", "u,z\n0,1\n1,-inf\n");
    CHECK(error_of({{"file", std::string("inf.csv")}}) == inf + ":3:3: elevation is infinite");
  }
  SECTION("arc length decreasing or duplicated") {
    const auto decreasing = data.write("decreasing.csv", "u,z\n0,1\n0.2,1\n0.1,1\n");
    CHECK(error_of({{"file", std::string("decreasing.csv")}}) ==
          decreasing +
              ":4:1: arc length 0.1 is less than 0.2 on line 3 (arc length must be strictly "
              "increasing)");
    const auto duplicated = data.write("duplicated.csv", "u,z\n0,1\n0.1,1\n0.1,2\n");
    CHECK(error_of({{"file", std::string("duplicated.csv")}}) ==
          duplicated +
              ":4:1: arc length 0.1 repeats line 3 (arc length must be strictly increasing)");
  }
  SECTION("fewer than 2 samples") {
    const auto one = data.write("one.csv", "u,z\n0,1\n");
    CHECK(error_of({{"file", std::string("one.csv")}}) ==
          one + ":2:1: 1 sample: a profile needs at least 2");
    const auto none = data.write("none.csv", "");
    CHECK(error_of({{"file", std::string("none.csv")}}) ==
          none + ":1:1: the file is empty (expected a header line)");
    const auto header_only = data.write("header_only.csv", "u,z\n");
    CHECK(error_of({{"file", std::string("header_only.csv")}}) ==
          header_only + ":1:1: 0 samples: a profile needs at least 2");
  }
  SECTION("profile shorter than the track") {
    const auto file = data.write("short.csv", "u,z\n0,1\n5,2\n9.99,1\n");
    CHECK(error_of({{"file", std::string("short.csv")}}) ==
          file +
              ":4:1: the profile is shorter than the track: it covers arc length 0 m to 9.99 m, "
              "the track needs 10 m");
    const auto long_enough = data.write("long.csv", "u,z\n0,1\n12,1\n");
    CHECK(
        error_of({{"file", std::string("long.csv")}, {"start", 2.5}}) ==
        long_enough +
            ":3:1: the profile is shorter than the track: it covers arc length 0 m to 12 m, "
            "the track needs 10 m (start = 2.5 m: the track runs from arc length 2.5 m to 12.5 m)");
    // A section whose end is beyond the largest double (start + L infinite) was accepted: the
    // comparison with the profile's end is false for an infinite end (found while writing
    // the csv_road fuzz harness).
    CHECK(error_of({{"file", std::string("long.csv")}, {"start", 1e308}}, {1e308, false}) ==
          long_enough +
              ":3:1: the profile is shorter than the track: it covers arc length 0 m to 12 m, "
              "the track needs 1e+308 m (start = 1e+308 m: the track runs from arc length 1e+308 "
              "m to inf m)");
  }
  SECTION("a closed track needs a profile that closes") {
    const auto file = data.write("open.csv", "u,z\n0,1\n10,1.5\n");
    CHECK(error_of({{"file", std::string("open.csv")}}, {10.0, true}) ==
          file +
              ": the profile does not close on the track: elevation 1 m at s = 0 and 1.5 m at "
              "s = L = 10 m; set detrend = \"linear\" (remove the trend between the end points) "
              "or make the domain an interval ([domain] periodic = false)");
    CHECK_NOTHROW(road({{"file", std::string("open.csv")}, {"detrend", std::string("linear")}},
                       {10.0, true}));
    CHECK_NOTHROW(road({{"file", std::string("open.csv")}}, {10.0, false}));
  }
  SECTION("a column name without a header is a parameter error") {
    data.write("plain.csv", "0,1\n10,1\n");
    try {
      road({{"file", std::string("plain.csv")},
            {"header", false},
            {named_columns, std::string("u")}});
      FAIL("no error");
    } catch (const ParameterError& e) {
      CHECK(e.parameter() == "arc_length_column");
      CHECK(std::string(e.what()) ==
            "arc_length_column = \"u\" is a column name, but header = false: give a column number "
            "(from 1)");
    }
    // Column numbers: from 1, and within a size_t (one beyond was read as 0, found by
    // the csv_road fuzz harness: "columns are numbered from 1").
    CHECK(error_of({{"file", std::string("plain.csv")}, {named_columns, std::string("0")}}) ==
          "arc_length_column = \"0\": columns are numbered from 1");
    CHECK(error_of({{"file", std::string("plain.csv")},
                    {named_columns, std::string("99999999999999999999")}}) ==
          "arc_length_column = \"99999999999999999999\": column number too large");
  }
}

TEST_CASE("csv road: linear interpolation is exact on piecewise-linear data", "[csv_road]") {
  const DataDirectory data("linear");
  // Non-uniform samples of a piecewise-linear function with kinks at the samples. Dyadic
  // values, so that the exact interpolant is representable and is compared without tolerance.
  const std::vector<double> u{0.0, 0.75, 1.125, 2.5, 4.0, 4.0625, 6.25, 8.0, 9.25, 10.0};
  const std::vector<double> z{0.0, 0.3125, -0.1875, 0.125, 0.125, 0.875, -0.375, 0.0, 0.25, 0.0};
  std::string text = "# a comment line\nposition,height,quality\n";
  for (std::size_t i = 0; i < u.size(); ++i) text += fmt_line(u[i], z[i]);
  data.write("pl.csv", text);
  const auto f = road({{"file", std::string("pl.csv")},
                       {"arc_length_column", std::string("position")},
                       {"elevation_column", std::string("height")},
                       {"restart_at_samples", false}},
                      {10.0, true});
  for (std::size_t i = 0; i + 1 < u.size(); ++i) {
    CHECK((*f)(u[i]) == z[i]);
    for (double t : {0.125, 0.5, 0.875}) {
      const double s = u[i] + t * (u[i + 1] - u[i]);
      CHECK((*f)(s) == (1 - t) * z[i] + t * z[i + 1]);
    }
  }
  // Periodic: s and s + L agree, and s = L is s = 0.
  CHECK((*f)(10.0) == (*f)(0.0));
  CHECK((*f)(12.5) == (*f)(2.5));
  // The seam is a kink, and (by default) so is every sample.
  CHECK(f->kink_points() == std::vector<double>{0.0});
  const auto with_samples = road({{"file", std::string("pl.csv")},
                                  {"arc_length_column", std::string("position")},
                                  {"elevation_column", std::string("height")},
                                  {"restart_at_samples", true}},
                                 {10.0, true});
  CHECK(with_samples->kink_points() ==
        std::vector<double>{0.0, 0.75, 1.125, 2.5, 4.0, 4.0625, 6.25, 8.0, 9.25});
}

TEST_CASE("csv road: units, column numbers, delimiters and subranges", "[csv_road]") {
  const DataDirectory data("options");
  // Millimetres, semicolons, no header, columns given by number (elevation first).
  data.write("mm.csv", "5;0\n-3;2500\n7;10000\n");
  const auto mm = road({{"file", std::string("mm.csv")},
                        {"header", false},
                        {"delimiter", std::string(";")},
                        {"arc_length_column", std::string("2")},
                        {"elevation_column", std::string("1")},
                        {"arc_length_units", std::string("mm")},
                        {"elevation_units", std::string("mm")}});
  CHECK((*mm)(0.0) == Approx(0.005).epsilon(1e-14));
  CHECK((*mm)(2.5) == Approx(-0.003).epsilon(1e-14));
  CHECK((*mm)(5.0) == Approx(-0.003 + 0.01 / 3).epsilon(1e-14));
  CHECK((*mm)(10.0) == Approx(0.007).epsilon(1e-14));
  // Tabs, CRLF line ends, quoted header names, a profile starting at 100 m, a subrange.
  data.write("tabs.csv", "\"u\"\t\"z\"\r\n100\t0\r\n110\t10\r\n120\t0\r\n");
  const auto sub = road({{"file", std::string("tabs.csv")},
                         {"delimiter", std::string("tab")},
                         {"arc_length_column", std::string("u")},
                         {"elevation_column", std::string("z")},
                         {"start", 5.0}});
  CHECK((*sub)(0.0) == Approx(5.0));   // arc length 105 m
  CHECK((*sub)(5.0) == Approx(10.0));  // 110 m
  CHECK((*sub)(10.0) == Approx(5.0));  // 115 m
}

TEST_CASE("csv road: detrending closes the loop", "[csv_road]") {
  const DataDirectory data("detrend");
  // A rough profile on a slope: 0.3 + 0.05 u + bumps; the ends differ by 0.5 m.
  data.write("slope.csv", profile(
                              [](double u) {
                                return 0.3 + 0.05 * u + 0.01 * std::sin(7 * u) +
                                       0.02 * std::cos(3 * u * u);
                              },
                              0.01));
  const Domain track{10.0, true};
  const auto f =
      road({{"file", std::string("slope.csv")}, {"detrend", std::string("linear")}}, track);
  // Closed: the values at s = 0 and s -> L meet, both 0 (|f'| < 2 here, so within 2e-9 at
  // 1e-9 from the seam; without detrending the gap is 0.5 m).
  CHECK(std::abs((*f)(0.0)) <= 1e-15);
  CHECK(std::abs((*f)(10.0 - 1e-9)) < 2e-9);
  CHECK(std::abs((*f)(-1e-9)) < 2e-9);
  // And f is the profile minus the chord between its end points.
  const double z0 = 0.3 + 0.02, z1 = 0.3 + 0.5 + 0.01 * std::sin(70.0) + 0.02 * std::cos(300.0);
  for (double s : {0.0, 1.0, 3.33, 7.5}) {
    const double u = std::round(s * 100) / 100;  // a sample
    const double z = 0.3 + 0.05 * u + 0.01 * std::sin(7 * u) + 0.02 * std::cos(3 * u * u);
    CHECK((*f)(u) == Approx(z - (z0 + (z1 - z0) * u / 10)).margin(1e-14));
  }
  // `mean` removes the mean (it does not close the loop: an interval domain).
  const Domain interval{10.0, false};
  const auto centred =
      road({{"file", std::string("slope.csv")}, {"detrend", std::string("mean")}}, interval);
  const auto points = interval.uniform_points(100001);
  std::vector<double> values(points.size());
  centred->evaluate(points, values);
  double integral = 0;
  for (std::size_t m = 0; m + 1 < points.size(); ++m)
    integral += 0.5 * (values[m] + values[m + 1]) * 1e-4;
  CHECK(std::abs(integral) < 1e-6);
}

TEST_CASE("csv road: cubic interpolation", "[csv_road]") {
  const DataDirectory data("cubic");
  data.write("line.csv", profile([](double u) { return 0.2 - 0.03 * u; }, 0.37, 10.4));
  const auto line =
      road({{"file", std::string("line.csv")}, {"interpolation", std::string("cubic")}});
  for (double s : {0.0, 0.1, 3.14159, 9.99})
    CHECK((*line)(s) == Approx(0.2 - 0.03 * s).margin(1e-14));
  // On smooth data the spline is far closer than linear interpolation, and it interpolates.
  data.write("sine.csv", profile([](double u) { return std::sin(u); }, 0.25));
  const auto cubic =
      road({{"file", std::string("sine.csv")}, {"interpolation", std::string("cubic")}});
  const auto linear = road({{"file", std::string("sine.csv")}});
  double cubic_error = 0, linear_error = 0;
  for (double s = 1.0; s < 9.0; s += 0.01) {
    cubic_error = std::max(cubic_error, std::abs((*cubic)(s)-std::sin(s)));
    linear_error = std::max(linear_error, std::abs((*linear)(s)-std::sin(s)));
  }
  CHECK(cubic_error < 1e-4);
  CHECK(linear_error > 5e-3);
  CHECK((*cubic)(2.5) == Approx(std::sin(2.5)).margin(1e-15));
}

TEST_CASE("csv road: provenance is the file's SHA-256", "[csv_road]") {
  const DataDirectory data("provenance");
  const auto file = data.write("p.csv", "u,z\n0,0\n10,0\n");
  const auto f = road({{"file", std::string("p.csv")}});
  CHECK(f->data_provenance() == "sha256:" + sha256_file(file));
  CHECK(f->data_provenance() == "sha256:" + sha256_hex("u,z\n0,0\n10,0\n"));
  data.write("p.csv", "u,z\n0,0\n10,1e-9\n");
  CHECK(road({{"file", std::string("p.csv")}})->data_provenance() != f->data_provenance());
}

TEST_CASE("csv road: from text, as from the file with that text", "[csv_road]") {
  const DataDirectory data("from_text");
  const std::string text = "# profile\nu;z\n0;0\n2.5;1\n5;-1\n10;0.5\n";
  const auto file = data.write("t.csv", text);
  const std::map<std::string, ParameterValue> given{{"file", std::string("t.csv")},
                                                    {"delimiter", std::string(";")},
                                                    {"interpolation", std::string("cubic")}};
  const auto* entry = target_registry().find("csv");
  REQUIRE(entry);
  const auto parameters = ParameterSet::resolve(entry->info.parameters, given);
  const Domain domain{10.0, false};
  const auto from_file = road(given, domain);
  // The file is not looked for: `file` names it, the text stands in for it.
  const auto from_text = csv_road_from_text(parameters, domain, text, "in memory");
  CHECK(from_text->data_provenance() == from_file->data_provenance());
  CHECK(from_text->kink_points() == from_file->kink_points());
  for (double s : {0.0, 1.0, 2.5, 4.0, 7.5, 10.0}) CHECK((*from_text)(s) == (*from_file)(s));
  // Errors name the text as they name the file; an empty text is an empty file, and a line
  // with a NUL byte ends there (here: a blank line 3).
  auto text_error = [&](std::string_view csv) {
    try {
      csv_road_from_text(parameters, domain, csv, "in memory");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  CHECK(text_error("u;z\n0;0\n5;x\n") == "in memory:3:3: elevation: 'x' is not a number");
  data.write("t.csv", "u;z\n0;0\n5;x\n");
  CHECK(error_of(given, domain) == file + ":3:3: elevation: 'x' is not a number");
  CHECK(text_error("") == "in memory:1:1: the file is empty (expected a header line)");
  CHECK(text_error(std::string_view("u;z\n0;0\n\0", 9)) ==
        "in memory:3:1: 1 sample: a profile needs at least 2");
  // Lines as fast-cpp-csv-parser's reader split them: a byte-order mark and CRLF line ends are
  // accepted, a line ends at a NUL byte, and has fewer than 2^24 bytes.
  const auto windows = csv_road_from_text(
      parameters, domain, "\xEF\xBB\xBF# profile\r\nu;z\r\n0;0\r\n2.5;1\r\n5;-1\r\n10;0.5",
      "in memory");
  const auto nul = csv_road_from_text(
      parameters, domain, std::string_view("u;z\n0;0\n2.5;1\0;2\n5;-1\n10;0.5\n", 30), "in memory");
  for (double s : {1.0, 4.0, 7.5}) {
    CHECK((*windows)(s) == (*from_file)(s));
    CHECK((*nul)(s) == (*from_file)(s));
  }
  CHECK(text_error("u;z\n0;0\n10;0" + std::string(std::size_t{1} << 24, ' ') + "\n") ==
        "in memory:3:1: the line is longer than 16777215 bytes");
  CHECK(text_error("u;z\n0;0\n10;0" + std::string((std::size_t{1} << 24) - 5, ' ') + "\n") ==
        "(no error)");
}

TEST_CASE("data root: --data-dir, then RKHS_STUDY_DATA, then studies/data", "[csv_road]") {
  set_data_root({});
  const char* saved = std::getenv("RKHS_STUDY_DATA");
  const std::string saved_value = saved ? saved : "";
  ::unsetenv("RKHS_STUDY_DATA");
  CHECK(data_root().origin == "default");
  CHECK(data_root().directory == (fs::current_path() / "studies" / "data").lexically_normal());
  ::setenv("RKHS_STUDY_DATA", "/tmp/from_environment", 1);
  CHECK(data_root().origin == "RKHS_STUDY_DATA");
  CHECK(data_root().directory == fs::path("/tmp/from_environment"));
  set_data_root("relative/dir");
  CHECK(data_root().origin == "--data-dir");
  CHECK(data_root().directory == (fs::current_path() / "relative" / "dir").lexically_normal());
  set_data_root({});
  CHECK(data_root().origin == "RKHS_STUDY_DATA");
  CHECK_THROWS_WITH(
      resolve_data_file("x/y.csv"),
      "data file 'x/y.csv' not found (looked at /tmp/from_environment/x/y.csv, in the "
      "data root from RKHS_STUDY_DATA, which does not exist; set the data root with "
      "--data-dir DIR or RKHS_STUDY_DATA)");
  ::unsetenv("RKHS_STUDY_DATA");
  CHECK_THROWS_WITH(resolve_data_file("/nowhere/z.csv"),
                    "data file '/nowhere/z.csv' not found (looked at /nowhere/z.csv)");
  if (saved) ::setenv("RKHS_STUDY_DATA", saved_value.c_str(), 1);
}
