// Targets' derivatives f'(s): the closed forms of sine, iso8608 and csv (linear and cubic
// interpolation) against formulas and against central differences of f, the right-hand slope at
// a csv sample, and TargetFunction's default difference for a target without a closed form.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "rkhs/approx/target.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/targets/iso8608.hpp"

using namespace rkhs;
namespace fs = std::filesystem;

namespace {

std::unique_ptr<TargetFunction> make_target(const std::string& name,
                                            std::map<std::string, ParameterValue> given,
                                            const Domain& domain) {
  const auto* entry = target_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

// (f(s + h) - f(s - h)) / 2h with h = 1e-5 m: truncation h^2 |f'''| / 6, for the smooth pieces
// tested here far below the tolerances used.
double central_difference(const TargetFunction& f, double s, double h = 1e-5) {
  return (f(s + h) - f(s - h)) / (2 * h);
}

// A fresh data root holding one profile file.
class ProfileFile {
 public:
  ProfileFile(const std::string& name, const std::string& text)
      : root_(fs::temp_directory_path() / ("rkhs_target_derivatives_" + name)) {
    fs::remove_all(root_);
    fs::create_directories(root_);
    std::ofstream(root_ / (name + ".csv"), std::ios::binary) << text;
    set_data_root(root_);
  }
  ~ProfileFile() {
    set_data_root({});
    std::error_code ignored;
    fs::remove_all(root_, ignored);
  }

 private:
  fs::path root_;
};

// Samples at uneven spacing on [0, 11]; elevation a smooth function plus a bump.
const std::vector<double> sample_u = {0.0, 1.0, 2.5, 4.0, 4.5, 6.0, 8.0, 10.0, 11.0};
double sample_z(double u) {
  return 0.1 * std::sin(0.7 * u) + (u == 4.5 ? 0.05 : 0.0);
}
std::string profile_text() {
  std::string text = "u,z\n";
  for (double u : sample_u) {
    char line[64];
    std::snprintf(line, sizeof line, "%.17g,%.17g\n", u, sample_z(u));
    text += line;
  }
  return text;
}

}  // namespace

TEST_CASE("sine target: f' in closed form", "[target][derivative]") {
  const Domain track{25.0, true};
  const auto f = make_target("sine", {{"amplitude", 2.0}, {"cycles", 3.0}, {"phase", 0.4}}, track);
  CHECK(f->has_exact_derivative());
  const double k = 2 * std::numbers::pi * 3.0 / 25.0;
  for (double s : {0.0, 1.3, 7.7, 12.5, 24.9}) {
    INFO("s = " << s);
    CHECK(f->slope(s) == Approx(2.0 * k * std::cos(k * s + 0.4)).margin(1e-14));
    CHECK(f->slope(s) == Approx(central_difference(*f, s)).margin(1e-8));
  }
  // The span form and the single-point form agree.
  const std::vector<double> points{0.5, 3.0, 9.0};
  std::vector<double> slopes(points.size());
  f->derivative(points, slopes);
  for (std::size_t m = 0; m < points.size(); ++m) CHECK(slopes[m] == f->slope(points[m]));
}

TEST_CASE("iso8608 target: f' is the harmonics' sum differentiated term by term",
          "[target][derivative][iso8608]") {
  const Domain track{2 * std::numbers::pi * 4, true};
  for (const char* amplitudes : {"deterministic", "random"}) {
    const auto f = make_target(
        "iso8608",
        {{"amplitudes", std::string(amplitudes)}, {"n_max", 2.0}, {"seed", std::int64_t{7}}},
        track);
    CHECK(f->has_exact_derivative());
    // The closed form of one harmonic: z = a cos(w s) + b sin(w s), z' = w (b cos - a sin).
    Harmonics one;
    one.k = {3};
    one.cosine = {0.2};
    one.sine = {-0.1};
    const double w = 2 * std::numbers::pi * 3 / track.length;
    CHECK(one.slope(1.1, track.length) ==
          Approx(w * (-0.1 * std::cos(w * 1.1) - 0.2 * std::sin(w * 1.1))).epsilon(1e-14));
    double scale = 0;
    for (double s = 0; s < track.length; s += 0.37) scale = std::max(scale, std::abs(f->slope(s)));
    REQUIRE(scale > 0);
    for (double s = 0.05; s < track.length; s += 0.37) {
      INFO(amplitudes << " s = " << s);
      CHECK(std::abs(f->slope(s) - central_difference(*f, s)) <= 1e-7 * scale);
    }
  }
}

TEST_CASE("csv target, linear interpolation: f' is the chord slope, right-hand at samples",
          "[target][derivative][csv_road]") {
  const ProfileFile file("linear", profile_text());
  for (bool periodic : {false, true}) {
    const Domain domain{10.0, periodic};
    // On the closed track the profile must close: detrend the chord (its slope is subtracted).
    const auto f = make_target(
        "csv", {{"file", std::string("linear.csv")}, {"detrend", std::string("linear")}}, domain);
    CHECK(f->has_exact_derivative());
    const double trend = (sample_z(10.0) - sample_z(0.0)) / 10.0;
    for (std::size_t i = 0; i + 1 < sample_u.size() && sample_u[i + 1] <= 10.0; ++i) {
      const double chord =
          (sample_z(sample_u[i + 1]) - sample_z(sample_u[i])) / (sample_u[i + 1] - sample_u[i]) -
          trend;
      const double middle = 0.5 * (sample_u[i] + sample_u[i + 1]);
      INFO((periodic ? "track" : "interval") << ", piece from u = " << sample_u[i]);
      CHECK(f->slope(middle) == Approx(chord).margin(1e-12));
      CHECK(f->slope(middle) == Approx(central_difference(*f, middle)).margin(1e-9));
      // At the sample that starts the piece: the right-hand derivative.
      CHECK(f->slope(sample_u[i]) == Approx(chord).margin(1e-12));
    }
    const double last_chord = (sample_z(10.0) - sample_z(8.0)) / 2.0 - trend;
    const double first_chord = (sample_z(1.0) - sample_z(0.0)) / 1.0 - trend;
    if (periodic)  // s = L is s = 0: the first piece's slope
      CHECK(f->slope(10.0) == Approx(first_chord).margin(1e-12));
    else  // the section ends at L: the left-hand slope
      CHECK(f->slope(10.0) == Approx(last_chord).margin(1e-12));
  }
}

TEST_CASE("csv target, cubic interpolation: f' of the natural spline is continuous",
          "[target][derivative][csv_road]") {
  const ProfileFile file("cubic", profile_text());
  const Domain interval{10.0, false};
  const auto f = make_target(
      "csv", {{"file", std::string("cubic.csv")}, {"interpolation", std::string("cubic")}},
      interval);
  CHECK(f->has_exact_derivative());
  for (double s = 0.013; s < 10.0; s += 0.21) {
    INFO("s = " << s);
    CHECK(f->slope(s) == Approx(central_difference(*f, s)).margin(1e-8));
  }
  // C1 at the inner samples: the slopes just left and right of a sample agree.
  for (std::size_t i = 1; i + 1 < sample_u.size() && sample_u[i] < 10.0; ++i) {
    INFO("sample u = " << sample_u[i]);
    CHECK(f->slope(sample_u[i] - 1e-9) == Approx(f->slope(sample_u[i])).margin(1e-7));
  }
}

namespace {

// A target without a closed-form derivative: f(s) = exp(sin s).
class PlainTarget final : public TargetFunction {
 public:
  void evaluate(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m) out[m] = std::exp(std::sin(points[m]));
  }
};

}  // namespace

TEST_CASE("TargetFunction's default derivative is a central difference with step 1e-6 m",
          "[target][derivative]") {
  const PlainTarget f;
  CHECK_FALSE(f.has_exact_derivative());
  CHECK(TargetFunction::derivative_step == 1e-6);
  for (double s : {0.0, 0.7, 3.0, 24.0, 1000.0}) {
    const double exact = std::cos(s) * std::exp(std::sin(s));
    INFO("s = " << s);
    // Error bound of the header: h^2 |f'''| / 6 + eps |f| / h, here below 1e-9.
    CHECK(f.slope(s) == Approx(exact).margin(1e-9));
  }
}
