// The surface_csv target: a road surface z(u, v) on a regular grid, bilinear between samples,
// against closed forms (a bilinear surface is reproduced exactly) and the shipped Belgian block
// long sections; malformed grids are refused at their line and column.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "rkhs/approx/target.hpp"
#include "rkhs/core/data_root.hpp"
#include "study_data_support.hpp"

using namespace rkhs;
namespace fs = std::filesystem;

namespace {

class SurfaceDirectory {
 public:
  // One folder per process: ctest runs each test case as its own process, side by side.
  SurfaceDirectory()
      : path_(fs::temp_directory_path() / ("rkhs_surface_csv_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
    set_data_root(path_);
  }
  ~SurfaceDirectory() {
    set_data_root({});
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
    return (path_ / name).string();
  }

 private:
  fs::path path_;
};

Domain plane(double length, double width) {
  Domain d{length, false};
  d.dimension = 2;
  d.width = width;
  return d;
}

std::unique_ptr<TargetFunction> surface(std::map<std::string, ParameterValue> given,
                                        const Domain& domain) {
  const auto* entry = target_registry().find("surface_csv");
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

std::string error_of(std::map<std::string, ParameterValue> given, const Domain& domain) {
  try {
    surface(std::move(given), domain);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

// z = 1 + 2u - v + 3uv on u = 0, 0.5, 1, 1.5 and v = -1, 0, 1: bilinear, so its bilinear
// interpolant is itself.
std::string bilinear_grid() {
  std::string text = "# a bilinear surface\nu_m\\v_m,-1,0,1\n";
  for (const double u : {0.0, 0.5, 1.0, 1.5}) {
    text += std::to_string(u);
    for (const double v : {-1.0, 0.0, 1.0}) text += "," + std::to_string(1 + 2 * u - v + 3 * u * v);
    text += "\n";
  }
  return text;
}

}  // namespace

TEST_CASE("surface_csv reproduces a bilinear surface and shifts it to the domain",
          "[target][surface][rd]") {
  SurfaceDirectory data;
  const auto file = data.write("plane.csv", bilinear_grid());
  const auto f = surface({{"file", std::string("plane.csv")}, {"v_start", -0.5}}, plane(1.2, 1.5));
  CHECK(f->data_provenance().starts_with("sha256:"));
  const std::vector<double> points{0.0, 0.0, 0.3, 0.7, 1.2, 1.5, 0.77, 0.01};
  std::vector<double> values(4);
  f->evaluate(points, values);
  for (std::size_t m = 0; m < 4; ++m) {
    const double u = points[2 * m], v = points[2 * m + 1] - 0.5;
    CHECK(values[m] == Approx(1 + 2 * u - v + 3 * u * v).epsilon(1e-12));
  }
  // detrend = "mean": the mean of the samples on the domain (u <= 1.2, v in [-0.5, 1]:
  // u = 0, 0.5, 1 and v = 0, 1) is removed.
  const auto centred = surface(
      {{"file", std::string("plane.csv")}, {"v_start", -0.5}, {"detrend", std::string("mean")}},
      plane(1.2, 1.5));
  double mean = 0;
  for (const double u : {0.0, 0.5, 1.0})
    for (const double v : {0.0, 1.0}) mean += (1 + 2 * u - v + 3 * u * v) / 6;
  double value = 0;
  centred->evaluate(std::vector<double>{0.3, 0.7}, std::span<double>(&value, 1));
  CHECK(value == Approx(values[1] - mean).epsilon(1e-12));
}

TEST_CASE("surface_csv refuses what it cannot read, at its line and column",
          "[target][surface][rd]") {
  SurfaceDirectory data;
  const auto root = data.write("x", "");
  const std::string dir = fs::path(root).parent_path().string();
  data.write("nan.csv", "u,0,1\n0,1,2\n1,3,nan\n");
  CHECK(error_of({{"file", std::string("nan.csv")}}, plane(1, 1)) ==
        dir +
            "/nan.csv:3:5: elevation z at v = 1 is nan (every sample needs a finite value; "
            "tools/crg_to_surface_csv.py fills missing samples)");
  data.write("word.csv", "u,0,1\n0,1,2\n1,3,x\n");
  CHECK(error_of({{"file", std::string("word.csv")}}, plane(1, 1)) ==
        dir + "/word.csv:3:5: elevation z at v = 1: 'x' is not a number");
  data.write("short.csv", "u,0,1\n0,1,2\n1,3\n");
  CHECK(error_of({{"file", std::string("short.csv")}}, plane(1, 1)) ==
        dir +
            "/short.csv:3:1: 2 fields, expected 3 (u and one elevation per lateral offset of "
            "the header)");
  data.write("uneven.csv", "u,0,1,3\n0,1,2,3\n1,3,4,5\n");
  CHECK(error_of({{"file", std::string("uneven.csv")}}, plane(1, 1)) ==
        dir +
            "/uneven.csv:1:7: v = 3 after 1: the grid's v must increase in equal steps (the "
            "first is 1 m)");
  data.write("small.csv", "u,0,1\n0,1,2\n1,3,4\n");
  CHECK(error_of({{"file", std::string("small.csv")}}, plane(2, 1)) ==
        dir +
            "/small.csv: the grid covers u in [0, 1] m and v in [0, 1] m; the domain needs u in "
            "[0, 2] m and v in [0, 1] m (u_start, v_start and the domain's lengths)");
  CHECK_THAT(error_of({{"file", std::string("small.csv")}}, Domain{1.0, false}),
             Catch::Contains("it needs a domain of d = 2"));
  Domain torus = plane(1, 1);
  torus.periodic = true;
  CHECK_THAT(error_of({{"file", std::string("small.csv")}}, torus),
             Catch::Contains("a measured surface is not periodic"));
}

TEST_CASE("the shipped Belgian block surface holds the shipped long sections",
          "[target][surface][rd]") {
  // studies/data/belgian_block/surface_2cm.csv (tools/crg_to_surface_csv.py, 2 cm) and the
  // three long sections (1 cm) come from the same CRG file: along v = -0.5, 0, 0.5 the surface
  // equals the sections at every second sample.
  set_data_root(rkhs::testing::require_study_data());
  const auto* csv = target_registry().find("csv");
  const auto f =
      surface({{"file", std::string("belgian_block/surface_2cm.csv")}, {"v_start", -1.0}},
              plane(10.0, 2.0));
  for (const auto& [name, v] :
       std::vector<std::pair<std::string, double>>{{"long_section_v-0.50.csv", -0.5},
                                                   {"long_section_v+0.00.csv", 0.0},
                                                   {"long_section_v+0.50.csv", 0.5}}) {
    CAPTURE(name);
    const auto section = csv->factory(
        ParameterSet::resolve(csv->info.parameters, {{"file", "belgian_block/" + name}}),
        Domain{10.0, false});
    double worst = 0;
    for (int i = 0; i <= 500; ++i) {
      const double u = 0.02 * i;
      const std::vector<double> point{u, v + 1.0};
      double z = 0;
      f->evaluate(point, std::span<double>(&z, 1));
      worst = std::max(worst, std::abs(z - (*section)(u)));
    }
    CHECK(worst <= 1e-6);  // the files hold 6 decimals
  }
  set_data_root({});
}
