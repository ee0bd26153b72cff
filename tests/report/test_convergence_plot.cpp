// Convergence plots of made-up results (no trial runs here): small multiples when a metric has
// more than 8 groups, legends that name exactly the axes that differ, ranges and confidence
// bands bounded by the data, the theory slope through the fit on its window, and rendering to
// SVG, PNG and PDF when gnuplot is installed (ci/setup installs it).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/plots.hpp"
#include "verify/synthetic_results.hpp"

using namespace rkhs;

namespace {

// Two B-spline degrees, sines of 3 amplitudes and 2 frequencies: 12 groups of l2_error.
const std::string twelve_groups = R"([study]
name = "panels"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 14, 20, 28, 40, 57, 80]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[target]]
name = "sine"
amplitude = [1.0, 2.0, 3.0]
cycles = [1, 2]
)";

// A power law in n with the degree as rate, scaled by amplitude and cycles, with a wobble that
// makes the fits' confidence bands finite and different per group.
double wobbly(const TrialSpec& trial, const std::string&) {
  const double n = static_cast<double>(trial.n);
  const double degree = static_cast<double>(trial.kernel.parameters.integer("degree"));
  const double amplitude = trial.target.parameters.real("amplitude");
  const double cycles = trial.target.parameters.real("cycles");
  return 0.1 * amplitude * cycles * std::pow(n, -degree) *
         (1 + 0.2 * std::sin(1.7 * n + amplitude + 3 * cycles));
}

struct Run : test::SyntheticResults {
  using SyntheticResults::SyntheticResults;
  RunRecord record() const {
    return RunRecord{study, trials, results, rates, 2, 0.0, "2026-01-01T00:00:00Z"};
  }
};

const std::string* script_of(const PlotPlan& plan, const std::string& stem) {
  for (const auto& [name, script] : plan.scripts)
    if (name == stem) return &script;
  return nullptr;
}

// The rows of data block $name (NaN for "nan").
std::vector<std::vector<double>> block(const std::string& script, const std::string& name) {
  std::vector<std::vector<double>> rows;
  const auto start = script.find("$" + name + " << EOD\n");
  if (start == std::string::npos) return rows;
  std::istringstream in(script.substr(start));
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line) && line != "EOD") {
    std::istringstream fields(line);
    std::vector<double> row;
    std::string field;
    while (fields >> field)
      row.push_back(field == "nan" ? std::numeric_limits<double>::quiet_NaN() : std::stod(field));
    rows.push_back(row);
  }
  return rows;
}

// The key titles of the data points' lines, by curve number.
std::map<int, std::string> curve_titles(const std::string& script) {
  std::map<int, std::string> out;
  const std::regex entry(R"re(\$c(\d+) using 1:2 with linespoints lt \d+ title '([^']*)')re");
  for (auto it = std::sregex_iterator(script.begin(), script.end(), entry);
       it != std::sregex_iterator(); ++it)
    out[std::stoi((*it)[1])] = (*it)[2];
  return out;
}

// [low, high] of `set <axis>range [low:high]`.
std::pair<double, double> range_of(const std::string& script, const std::string& axis) {
  const std::regex setting("set " + axis + R"(range \[([^:]+):([^\]]+)\])");
  std::smatch match;
  REQUIRE(std::regex_search(script, match, setting));
  return {std::stod(match[1]), std::stod(match[2])};
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

}  // namespace

TEST_CASE("convergence plot: more than 8 groups make panels, legends name what differs",
          "[report][plots][convergence]") {
  const Run run(twelve_groups, wobbly);
  const auto plan = plot_scripts(run.record());
  REQUIRE(plan.scripts.size() == 1);
  const auto* script = script_of(plan, "convergence_l2_error");
  REQUIRE(script);
  // 12 groups: two panels (by degree; r follows it), 6 curves each, side by side.
  CHECK_THAT(*script, Catch::Contains("set multiplot layout 1,2 rowsfirst title"));
  CHECK(count_of(*script, "\nplot ") == 2);
  CHECK_THAT(*script, Catch::Contains("set title 'degree=1, r=1' noenhanced"));
  CHECK_THAT(*script, Catch::Contains("set title 'degree=2, r=2' noenhanced"));
  CHECK_THAT(*script, Catch::Contains("unset multiplot"));
  // Each curve's key names its amplitude and frequency, nothing else, then its rate.
  const auto titles = curve_titles(*script);
  REQUIRE(titles.size() == 12);
  const std::regex legend(R"(amplitude=[123], cycles=[12]: rate -?[0-9.e-]+( \(exp in n\))?)");
  for (const auto& [curve, title] : titles) {
    INFO(title);
    CHECK(std::regex_match(title, legend));
  }
  // What all curves share is said once, in the title: the plugins by name.
  CHECK_THAT(*script, Catch::Contains("kernel=bspline,") && !Catch::Contains("J=8") &&
                          Catch::Contains("target=sine") && Catch::Contains("centres=uniform"));
  CHECK(count_of(*script, "target=sine") == 1);
  // The canvas grows with the panels: two 480-pixel panels.
  CHECK_THAT(*script, Catch::Contains("set terminal pngcairo size 960,"));
  // Rendered to SVG, PNG and PDF in the current folder.
  CHECK_THAT(*script, Catch::Contains("do for [ext in \"svg png pdf\"]"));
  CHECK_THAT(*script, Catch::Contains("set output 'convergence_l2_error.'.ext"));
}

TEST_CASE("convergence plot: 8 groups or fewer share one plot keyed by the axes that differ",
          "[report][plots][convergence]") {
  const Run run(R"([study]
name = "single"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 14, 20, 28, 40]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[target]]
name = "sine"
amplitude = 2.0
cycles = [1, 2]
)",
                wobbly);
  const auto plan = plot_scripts(run.record());
  REQUIRE(plan.scripts.size() == 1);
  const auto& script = plan.scripts.front().second;
  CHECK_THAT(script, !Catch::Contains("multiplot"));
  CHECK(count_of(script, "\nplot ") == 1);
  const auto titles = curve_titles(script);
  REQUIRE(titles.size() == 4);
  for (const auto& [curve, title] : titles) {
    INFO(title);
    CHECK(std::regex_match(
        title,
        std::regex(R"(degree=[12], r=[12], cycles=[12]: rate -?[0-9.e-]+( \(exp in n\))?)")));
  }
  CHECK_THAT(script, Catch::Contains("target=sine") && !Catch::Contains("amplitude=2"));
  // The key lies below the plot (and its x label), not over the data.
  CHECK_THAT(script, Catch::Contains("outside below center"));
}

TEST_CASE("convergence plot: several plugins of an axis are one legend factor",
          "[report][plots][convergence]") {
  const Run run(R"([study]
name = "kernels"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 20, 40, 80]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[kernel]]
name = "gaussian"
sigma = 1.0
)",
                [](const TrialSpec& trial, const std::string&) {
                  const double n = static_cast<double>(trial.n);
                  if (trial.kernel.name == "gaussian") return std::exp(-0.3 * n);
                  return std::pow(n,
                                  -static_cast<double>(trial.kernel.parameters.integer("degree")));
                });
  const auto plan = plot_scripts(run.record());
  REQUIRE(plan.scripts.size() == 1);
  const auto& script = plan.scripts.front().second;
  const auto titles = curve_titles(script);
  REQUIRE(titles.size() == 3);
  CHECK_THAT(titles.at(0), Catch::StartsWith("kernel=bspline degree=1 r=1: rate"));
  CHECK_THAT(titles.at(1), Catch::StartsWith("kernel=bspline degree=2 r=2: rate"));
  CHECK_THAT(titles.at(2), Catch::StartsWith("kernel=gaussian: rate"));
  // The title is short: the kernels' constant parameters are in the tables, not in it.
  CHECK_THAT(script, !Catch::Contains("n0=4") && !Catch::Contains("sigma=1"));
}

TEST_CASE("convergence plot: tight ranges, bands within the data, theory on the fit window",
          "[report][plots][convergence]") {
  // A fit window set by hand (n >= 20) and a few points, so that the confidence band is wide.
  const Run run(R"([study]
name = "bands"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 20, 28, 40]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[target]]
name = "sine"
amplitude = 1.0
cycles = 1
[rates]
n_from = 20
)",
                [](const TrialSpec& trial, const std::string& metric) {
                  // A pre-asymptotic head at n = 10 and a strong wobble in the window.
                  const double head = trial.n == 10 ? 30.0 : 1.0;
                  return head * wobbly(trial, metric) * (trial.n == 28 ? 3.0 : 1.0);
                });
  const auto record = run.record();
  const auto plan = plot_scripts(record);
  REQUIRE(plan.scripts.size() == 1);
  const auto& script = plan.scripts.front().second;
  REQUIRE(run.rates.size() == 2);

  // Ranges: the data's, with a margin of at most 30% on x and a factor 2 on y.
  double x_low = INFINITY, x_high = 0, y_low = INFINITY, y_high = 0;
  for (const auto& series : run.rates)
    for (std::size_t k = 0; k < series.values.size(); ++k) {
      x_low = std::min(x_low, series.n[k]);
      x_high = std::max(x_high, series.n[k]);
      y_low = std::min(y_low, series.values[k]);
      y_high = std::max(y_high, series.values[k]);
    }
  const auto [xa, xb] = range_of(script, "x");
  const auto [ya, yb] = range_of(script, "y");
  CHECK(xa < x_low);
  CHECK(xa >= x_low / 1.3);
  CHECK(xb > x_high);
  CHECK(xb <= x_high * 1.3);
  CHECK(ya < y_low);
  CHECK(ya >= y_low / 2);
  CHECK(yb > y_high);
  CHECK(yb <= y_high * 2);

  bool clipped = false;
  for (std::size_t c = 0; c < run.rates.size(); ++c) {
    INFO("curve " << c);
    const auto& series = run.rates[c];
    REQUIRE(series.fit);
    const auto& used = series.fit->used;
    REQUIRE(used.size() == 3);  // n = 20, 28, 40: the head is outside the window
    REQUIRE(used.front() == 1);
    double low = INFINITY, high = 0;
    for (auto k : used) {
      low = std::min(low, series.values[k]);
      high = std::max(high, series.values[k]);
    }
    // The band: over the fit window only, within the fitted values and the y axis' margin
    // (their span to the power 0.05, between 1.1 and 2).
    const double margin = std::clamp(std::pow(high / low, 0.05), 1.1, 2.0);
    const auto band = block(script, std::string(1, 'f') += std::to_string(c));
    REQUIRE(band.size() == 21);
    CHECK(band.front()[0] == Approx(series.n[used.front()]).epsilon(1e-12));
    CHECK(band.back()[0] == Approx(series.n[used.back()]).epsilon(1e-12));
    for (const auto& row : band) {
      CHECK(row[2] >= low / margin * (1 - 1e-12));
      CHECK(row[3] <= high * margin * (1 + 1e-12));
      CHECK(row[2] <= row[1]);
      CHECK(row[1] <= row[3]);
      clipped = clipped || row[2] == Approx(low / margin).epsilon(1e-12) ||
                row[3] == Approx(high * margin).epsilon(1e-12);
    }
    // The theory line (bspline: slope -degree against n) spans the window and passes through
    // the fitted line at the window's geometric centre.
    const auto theory = block(script, std::string(1, 't') += std::to_string(c));
    REQUIRE(theory.size() == 2);
    const double first = series.n[used.front()], last = series.n[used.back()];
    CHECK(theory[0][0] == Approx(first).epsilon(1e-12));
    CHECK(theory[1][0] == Approx(last).epsilon(1e-12));
    const double degree = c == 0 ? 1.0 : 2.0;
    CHECK(std::log(theory[1][1] / theory[0][1]) / std::log(last / first) ==
          Approx(-degree).epsilon(1e-12));
    const double centre = std::sqrt(first * last);
    const double fitted = std::exp(series.fit->intercept + series.fit->rate * std::log(centre));
    CHECK(std::sqrt(theory[0][1] * theory[1][1]) == Approx(fitted).epsilon(1e-10));
  }
  CHECK(clipped);  // the 3-point band reached the clip somewhere (or this case tests nothing)
}

TEST_CASE("convergence plot: more than 12 panels go to several files",
          "[report][plots][convergence]") {
  const Run run(R"([study]
name = "parts"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 20, 40]
[[kernel]]
name = "bspline"
degree = 1
[[target]]
name = "sine"
amplitude = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
cycles = [1, 2, 3, 4, 5, 6, 7, 8, 9]
)",
                wobbly);
  const auto plan = plot_scripts(run.record());
  // 81 groups: no factor alone leaves 8 curves per panel, so one panel per group, 12 a file.
  REQUIRE(plan.scripts.size() == 7);
  for (std::size_t part = 0; part < 7; ++part) {
    const auto& [stem, script] = plan.scripts[part];
    CHECK(stem == "convergence_l2_error_part" + std::to_string(part + 1));
    CHECK_THAT(script, Catch::Contains("(part " + std::to_string(part + 1) + " of 7)"));
    CHECK(count_of(script, "\nplot ") == (part < 6 ? 12u : 9u));
    CHECK_THAT(script,
               Catch::Contains(part < 6 ? "set multiplot layout 3,4" : "set multiplot layout 3,3"));
  }
}

TEST_CASE("convergence plots rendered: SVG, PNG and PDF", "[report][plots][convergence]") {
  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
    WARN("gnuplot is not installed: the convergence plots were not rendered");
    return;
  }
  const Run run(twelve_groups, wobbly);
  const auto directory = std::filesystem::temp_directory_path() / "rkhs_convergence_plot";
  std::filesystem::remove_all(directory);
  const auto outcome = write_plots(run.record(), directory);
  INFO((outcome.failures.empty() ? std::string() : outcome.failures.front()));
  CHECK(outcome.failures.empty());
  REQUIRE(outcome.rendered == std::vector<std::string>{"convergence_l2_error"});
  for (const char* extension : {".svg", ".png", ".pdf"}) {
    const auto file = directory / "plots" / (std::string("convergence_l2_error") + extension);
    INFO(file.string());
    REQUIRE(std::filesystem::exists(file));
    CHECK(std::filesystem::file_size(file) > 1000);
  }
  std::filesystem::remove_all(directory);
}

TEST_CASE("convergence plot: groups that differ only in axes the metric ignores are one curve",
          "[report][plots][convergence]") {
  // The value depends on the degree alone (as the power function ignores the target), except
  // that one group of degree 2 differs: the amplitude then matters, and nothing is merged.
  auto by_degree = [](const TrialSpec& trial, const std::string&) {
    return std::pow(static_cast<double>(trial.n),
                    -static_cast<double>(trial.kernel.parameters.integer("degree")));
  };
  const Run run(twelve_groups, by_degree);
  const auto plan = plot_scripts(run.record());
  REQUIRE(plan.scripts.size() == 1);
  const auto& script = plan.scripts.front().second;
  CHECK_THAT(script, !Catch::Contains("multiplot"));
  const auto titles = curve_titles(script);
  REQUIRE(titles.size() == 2);
  CHECK_THAT(titles.at(0), Catch::StartsWith("degree=1, r=1: rate -1"));
  CHECK_THAT(titles.at(1), Catch::StartsWith("degree=2, r=2: rate -2"));
  CHECK_THAT(script, Catch::Contains("the same for every amplitude and cycles"));

  const Run uneven(twelve_groups, [&](const TrialSpec& trial, const std::string& metric) {
    const bool odd = trial.target.parameters.real("amplitude") == 3.0 &&
                     trial.kernel.parameters.integer("degree") == 2;
    return by_degree(trial, metric) * (odd ? 2.0 : 1.0);
  });
  const auto uneven_plan = plot_scripts(uneven.record());
  REQUIRE(uneven_plan.scripts.size() == 1);
  CHECK(curve_titles(uneven_plan.scripts.front().second).size() == 6);  // degree x amplitude
  CHECK_THAT(uneven_plan.scripts.front().second, Catch::Contains("the same for every cycles"));
}

TEST_CASE("report.html embeds every part of a convergence figure", "[report][plots][convergence]") {
  const Run run(twelve_groups, wobbly);
  const auto plots = std::filesystem::temp_directory_path() / "rkhs_convergence_parts";
  std::filesystem::remove_all(plots);
  std::filesystem::create_directories(plots);
  for (int part = 1; part <= 2; ++part)
    std::ofstream(plots / ("convergence_l2_error_part" + std::to_string(part) + ".svg"))
        << "<svg xmlns=\"http://www.w3.org/2000/svg\"><text>part " << part << "</text></svg>";
  const auto page = html_report(run.record(), plots);
  CHECK(count_of(page, "alt=\"convergence of l2_error\"") == 2);
  std::filesystem::remove_all(plots);
}

TEST_CASE("convergence plot: a plugin's parameters go with it into panels and legends",
          "[report][plots][convergence]") {
  const Run run(R"([study]
name = "plugins"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 20, 40, 80]
[[kernel]]
name = "bspline"
degree = [1, 2, 3]
J = 8
[[kernel]]
name = "matern"
nu = [0.5, 1.5, 2.5]
[[target]]
name = "sine"
amplitude = [1.0, 2.0]
)",
                [](const TrialSpec& trial, const std::string&) {
                  const auto& kernel = trial.kernel;
                  const double order =
                      kernel.name == "bspline"
                          ? static_cast<double>(kernel.parameters.integer("degree"))
                          : kernel.parameters.real("nu") + 0.5;
                  return trial.target.parameters.real("amplitude") *
                         std::pow(static_cast<double>(trial.n), -order);
                });
  const auto plan = plot_scripts(run.record());
  REQUIRE(plan.scripts.size() == 1);
  const auto& script = plan.scripts.front().second;
  // 12 groups: one panel per kernel (degree or nu alone would not say which kernel).
  CHECK_THAT(script, Catch::Contains("set multiplot layout 1,2"));
  CHECK_THAT(script, Catch::Contains("set title 'kernel=bspline' noenhanced"));
  CHECK_THAT(script, Catch::Contains("set title 'kernel=matern' noenhanced"));
  const auto titles = curve_titles(script);
  REQUIRE(titles.size() == 12);
  for (const auto& [curve, title] : titles) {
    INFO(title);
    CHECK(std::regex_match(
        title, std::regex(curve < 6 ? R"(degree=([123]) r=\1, amplitude=[12]: rate -[0-9.]+)"
                                    : R"(nu=[0-9.]+, amplitude=[12]: rate -[0-9.]+)")));
  }
  // The title is short: the kernels' constant parameters are in the tables, not in it.
  CHECK_THAT(script, !Catch::Contains("n0=4") && !Catch::Contains("length_scale=1"));
}

TEST_CASE("convergence plot: [plot] sets metrics, labels, title, size, font, legend, resolution",
          "[report][plots][convergence][plot]") {
  const Run run(R"([study]
name = "styled"
metrics = ["l2_error", "sup_error", "fill_distance"]
[domain]
radius = 4.0
[grid]
n = [10, 14, 20, 28, 40]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[target]]
name = "sine"
[plot]
metrics = ["sup_error", "l2_error"]
labels = { l2_error = "L^2 error ||f - Π_n f||" }
title = "B-splines on a circle"
size = [3.5, 2.5]
font_size = 8
legend = "top right"
png_dpi = 300
)",
                wobbly);
  const auto plan = plot_scripts(run.record());
  // The metrics of [plot], in its order; fill_distance is not plotted.
  REQUIRE(plan.scripts.size() == 2);
  CHECK(plan.scripts[0].first == "convergence_sup_error");
  CHECK(plan.scripts[1].first == "convergence_l2_error");
  const auto& script = plan.scripts[1].second;
  // The label as given, in enhanced text (^ and _ raise and lower); sup_error's from the table.
  CHECK_THAT(script, Catch::Contains("set ylabel 'L^2 error ||f - Π_n f||' enhanced"));
  CHECK_THAT(plan.scripts[0].second, Catch::Contains("set ylabel 'sup-norm error' enhanced"));
  CHECK_THAT(script, Catch::Contains("set title 'B-splines on a circle' enhanced"));
  // 3.5 x 2.5 inches: the PDF's page, the PNG at 300 dpi, fonts of 8 points scaled alike.
  CHECK_THAT(script, Catch::Contains("set terminal pdfcairo size 3.5in,2.5in enhanced font "
                                     "'sans,8'"));
  CHECK_THAT(script, Catch::Contains("set terminal pngcairo size 1050,750 enhanced font "
                                     "'sans,8' fontscale 4.167"));
  CHECK_THAT(script, Catch::Contains("set key noenhanced Left reverse samplen 2.5 spacing 1.1 "
                                     "inside top right opaque box"));
  // The fitted lines are drawn after (over) the points.
  const auto points = script.find("with linespoints");
  const auto fits = script.find("with lines lt");
  REQUIRE(points != std::string::npos);
  REQUIRE(fits != std::string::npos);
  CHECK(points < fits);

  const auto untitled = Run(R"([study]
name = "untitled"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 14, 20, 28, 40]
[[kernel]]
name = "bspline"
degree = 1
[plot]
title = false
legend = "none"
)",
                            wobbly);
  const auto untitled_script = plot_scripts(untitled.record()).scripts.at(0).second;
  CHECK_THAT(untitled_script, Catch::Contains("set title ''\n"));
  CHECK_THAT(untitled_script, Catch::Contains("unset key\n"));

  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
    WARN("gnuplot is not installed: the PDF's size was not read back");
    return;
  }
  const auto directory = std::filesystem::temp_directory_path() / "rkhs_styled_plot";
  std::filesystem::remove_all(directory);
  const auto outcome = write_plots(run.record(), directory);
  INFO((outcome.failures.empty() ? std::string() : outcome.failures.front()));
  REQUIRE(outcome.failures.empty());
  // The PDF's page is the size asked for: 3.5 x 2.5 inches, 252 x 180 points.
  std::ifstream pdf(directory / "plots" / "convergence_l2_error.pdf", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(pdf)), std::istreambuf_iterator<char>());
  std::smatch box;
  REQUIRE(
      std::regex_search(bytes, box, std::regex(R"(/MediaBox \[ *0 0 ([0-9.]+) ([0-9.]+) *\])")));
  CHECK(std::stod(box[1]) == Approx(252).margin(0.5));
  CHECK(std::stod(box[2]) == Approx(180).margin(0.5));
  // The PNG at 300 dpi: 1050 x 750 pixels (IHDR's width and height, big-endian).
  std::ifstream png(directory / "plots" / "convergence_l2_error.png", std::ios::binary);
  unsigned char header[24] = {};
  png.read(reinterpret_cast<char*>(header), sizeof header);
  auto big_endian = [&](int at) {
    return (header[at] << 24) | (header[at + 1] << 16) | (header[at + 2] << 8) | header[at + 3];
  };
  CHECK(big_endian(16) == 1050);
  CHECK(big_endian(20) == 750);
  std::filesystem::remove_all(directory);
}

TEST_CASE("convergence plot defaults: catalogue labels, a short title, errors first",
          "[report][plots][convergence][plot]") {
  const Run run(R"toml([study]
name = "defaults"
metrics = ["fill_distance", "power_function_sup", "l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 14, 20, 28, 40]
[[kernel]]
name = "bspline"
degree = 1
[[target]]
name = "expression"
f = "sin(s) + 0.5 * cos(3 * s)"
)toml",
                [](const TrialSpec& trial, const std::string&) {
    return std::pow(static_cast<double>(trial.n), -1.5);
                });
  const auto plan = plot_scripts(run.record());
  std::vector<std::string> stems;
  for (const auto& [stem, script] : plan.scripts) stems.push_back(stem);
  CHECK(stems == std::vector<std::string>{"convergence_l2_error", "convergence_power_function_sup",
                                          "convergence_fill_distance"});
  const auto& script = plan.scripts.front().second;
  CHECK_THAT(script, Catch::Contains("set ylabel 'L^2 error' enhanced"));
  CHECK_THAT(script, Catch::Contains("set xlabel 'n' enhanced"));
  CHECK_THAT(plan.scripts.back().second,
             Catch::Contains("set ylabel 'fill distance h (m)' enhanced"));
  // The title names the plugins, not the target's formula nor the kernel's parameters.
  CHECK_THAT(script, Catch::Contains("set title 'defaults: kernel=bspline, target=expression"));
  CHECK_THAT(script, !Catch::Contains("cos(3"));
  CHECK_THAT(script, !Catch::Contains("degree=1"));
  // The key below the x axis' label; a 6-inch figure, the PNG at 150 dpi.
  CHECK_THAT(script, Catch::Contains("outside below center horizontal"));
  CHECK_THAT(script, Catch::Contains("set terminal pdfcairo size 6in,"));
  CHECK_THAT(script, Catch::Contains("set terminal pngcairo size 900,"));
  CHECK(convergence_plot_order({"fill_distance", "gram_condition_number", "sup_error",
                                "separation_distance", "l2_error"}) ==
        std::vector<std::string>{"sup_error", "l2_error", "gram_condition_number", "fill_distance",
                                 "separation_distance"});
}
