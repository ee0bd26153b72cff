// Study files: valid grids expand as documented; every kind of mistake is reported with
// file:line:column, the key, what was found and what is allowed.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "rkhs/study/study.hpp"
#include "rkhs/study/trial_grid.hpp"

using rkhs::parse_study;
using rkhs::StudyError;

namespace {

const char* const minimal = R"(
[study]
name = "t"
[domain]
radius = 4.0
[grid]
n = [10, 20]
[[kernel]]
name = "gaussian"
)";

std::string error_of(const std::string& text) {
  try {
    parse_study(text, "s.toml");
  } catch (const StudyError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("a minimal study has defaults for target, centres, metrics and solver", "[study]") {
  const auto study = parse_study(minimal, "s.toml");
  CHECK(study.name == "t");
  CHECK(study.domain.length == Approx(2 * 3.14159265358979323846 * 4).epsilon(1e-15));
  CHECK(study.domain.periodic);
  CHECK(study.n_values == std::vector<std::size_t>{10, 20});
  REQUIRE(study.kernels.size() == 1);
  CHECK(study.targets.at(0).name == "sine");
  CHECK(study.centres.at(0).name == "uniform");
  CHECK(study.evaluation_points == 4096);
  CHECK(study.trials().size() == 2);
}

TEST_CASE("list-valued parameters and n ranges expand to the Cartesian product", "[study]") {
  const auto study = parse_study(R"(
[study]
name = "grid"
[domain]
length = 10.0
periodic = false
[grid]
n = { from = 10, to = 40, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = [4, 5, 6]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1]
[[centres]]
name = "random"
seed = [1, 2]
)", "grid.toml");
  CHECK(study.n_values == std::vector<std::size_t>{10, 20, 30, 40});
  CHECK(study.kernels.size() == 8);
  CHECK(study.centres.size() == 2);
  const auto trials = study.trials();
  REQUIRE(trials.size() == 8 * 2 * 4);
  // n varies fastest; the first parameter of the first kernel slowest.
  CHECK(trials[0].n == 10);
  CHECK(trials[1].n == 20);
  CHECK(trials[0].kernel.parameters.integer("degree") == 1);
  CHECK(trials[0].kernel.parameters.integer("J") == 4);
  CHECK(trials[8].kernel.parameters.integer("J") == 5);
  CHECK(trials[0].group_key == trials[3].group_key);
  CHECK(trials[0].group_key != trials[4].group_key);
  // Keys and seeds are unique per trial.
  std::set<std::string> keys;
  std::set<std::uint64_t> seeds;
  for (const auto& t : trials) {
    keys.insert(t.key);
    seeds.insert(t.seed);
  }
  CHECK(keys.size() == trials.size());
  CHECK(seeds.size() == trials.size());
  // The B-spline's r defaults to its degree.
  CHECK(study.kernels[0].parameters.real("r") == 1.0);
  CHECK(study.kernels[3].parameters.real("r") == 2.0);

  const auto geometric = parse_study(R"(
[study]
name = "g"
[domain]
radius = 1
[grid]
n = { from = 8, to = 100, factor = 2 }
[[kernel]]
name = "matern"
)", "g.toml");
  CHECK(geometric.n_values == std::vector<std::size_t>{8, 16, 32, 64});
}

TEST_CASE("study file errors name file, line, column, key, what was found and what is allowed",
          "[study]") {
  SECTION("misspelt kernel name with suggestion") {
    std::string text = minimal;
    text.replace(text.find("\"gaussian\""), 10, "\"gausian\"");
    CHECK(error_of(text) ==
          "s.toml:9:8: kernel.name: unknown kernel 'gausian' (known: bspline, gaussian, matern, "
          "wendland; did you mean 'gaussian'?)");
  }
  SECTION("unknown parameter with suggestion") {
    const auto e = error_of(std::string(minimal) + "sigam = 2.0\n");
    CHECK(e.starts_with("s.toml:10:1: kernel.sigam: unknown parameter of kernel 'gaussian'"));
    CHECK_THAT(e, Catch::Contains("did you mean 'sigma'?"));
  }
  SECTION("out-of-range parameter") {
    CHECK(error_of(std::string(minimal) + "sigma = -1.0\n") ==
          "s.toml:10:9: kernel.sigma: parameter 'sigma' must be > 0, found -1");
  }
  SECTION("wrong type") {
    CHECK(error_of(std::string(minimal) + "sigma = \"wide\"\n") ==
          "s.toml:10:9: kernel.sigma: parameter 'sigma' must be a number, found a string");
  }
  SECTION("bad value inside an axis list points at the element") {
    CHECK(error_of(std::string(minimal) + "sigma = [1.0, 0.0]\n") ==
          "s.toml:10:15: kernel.sigma: parameter 'sigma' must be > 0, found 0");
  }
  SECTION("unknown top-level key") {
    const auto e = error_of(std::string(minimal) + "[kernels]\nx = 1\n");
    CHECK(e ==
          "s.toml:10:2: kernels: unknown key (known: study, domain, grid, kernel, target, "
          "centres, projection, solver, linear_algebra, limits, rates, adaptive, plant, "
          "law, integrator, plugins, expect, plot; did you mean 'kernel'?)");
  }
  SECTION("invalid TOML") {
    const auto e = error_of("[study\nname = 1\n");
    CHECK_THAT(e, Catch::StartsWith("s.toml:1:"));
    CHECK_THAT(e, Catch::Contains("invalid TOML"));
  }
  SECTION("n must be positive integers") {
    std::string text = minimal;
    text.replace(text.find("[10, 20]"), 8, "[10, 0]");
    CHECK(error_of(text) ==
          "s.toml:7:10: grid.n: must be between 1 and 1000000000 (centres), "
          "found 0");
    text = minimal;
    text.replace(text.find("[10, 20]"), 8, "[10, 2.5]");
    CHECK(error_of(text) == "s.toml:7:10: grid.n: expected integers, found a number (2.5)");
  }
  SECTION("domain needs exactly one of length and radius") {
    std::string text = minimal;
    text.replace(text.find("radius = 4.0"), 12, "radius = 4.0\nlength = 3.0");
    CHECK_THAT(error_of(text), Catch::Contains("domain: give exactly one of 'length'"));
  }
  SECTION("a radius whose track is longer than the largest number") {
    // 2 pi radius was an infinite domain length (found writing fuzz_study_file's checks of what a
    // parsed study holds); a finite one beyond 1e100 overflowed in the kernels (issue 36).
    std::string text = minimal;
    text.replace(text.find("radius = 4.0"), 12, "radius = 1e308");
    CHECK(error_of(text) ==
          "s.toml:5:10: domain.radius: must be between 1.5915494309189535e-101 and "
          "1.5915494309189535e+99 metres (the track's length, 2 pi radius, between 1e-100 and "
          "1e+100), found 1e+308 (beyond these the squared distances, volumes and spline knots "
          "computed on the domain leave the range of double)");
    text = minimal;
    text.replace(text.find("radius = 4.0"), 12, "radius = 1.5e99");
    CHECK(parse_study(text, "s.toml").domain.length == 2 * std::numbers::pi * 1.5e99);
  }
  SECTION("unknown metric") {
    std::string text = minimal;
    text.replace(text.find("name = \"t\""), 10, "name = \"t\"\nmetrics = [\"power_function_supp\"]");
    CHECK(error_of(text) ==
          "s.toml:4:12: study.metrics: unknown metric 'power_function_supp' (known: "
          "fill_distance, separation_distance, gram_condition_number, gram_min_eigenvalue, "
          "gram_max_eigenvalue, power_function_sup, power_function_floor, l2_error, sup_error, "
          "error_floor, interpolant_native_norm, projection_norm_H_to_C, projection_operator_norm, "
          "level_reduction_factor, level_condition_number, level_nonzeros; did you mean "
          "'power_function_sup'?)");
  }
  SECTION("a target that is not periodic on a closed track") {
    // The plugin's ParameterError names cycles: reported at its value, like the declaration's.
    const auto e = error_of(std::string(minimal) + "[[target]]\nname = \"sine\"\ncycles = 1.5\n");
    CHECK_THAT(e, Catch::StartsWith("s.toml:12:10: target.cycles: sine cycles=1.5: parameter "
                                    "'cycles' must be a whole number on a closed track"));
  }
  SECTION("missing kernel") {
    std::string text = minimal;
    text.erase(text.find("[[kernel]]"));
    CHECK_THAT(error_of(text), Catch::Contains("kernel: missing: add at least one [[kernel]]"));
  }
  SECTION("duplicate plugin entries") {
    CHECK_THAT(error_of(std::string(minimal) + "[[kernel]]\nname = \"gaussian\"\n"),
               Catch::Contains("is listed twice"));
  }
  SECTION("missing file") {
    CHECK_THROWS_WITH(rkhs::load_study("no/such/study.toml"),
                      "no/such/study.toml: cannot read the study file: No such file or directory");
  }
}

TEST_CASE("the grid's axes multiply to its trials, adaptive axes included", "[study]") {
  const auto approximation = parse_study(minimal, "s.toml");
  std::size_t product = 1;
  std::vector<std::string> names;
  for (const auto& axis : approximation.grid_axes()) {
    product *= axis.count;
    names.push_back(axis.plural);
  }
  CHECK(names == std::vector<std::string>{"kernels", "targets", "centre placements", "values of n"});
  CHECK(product == approximation.trials().size());

  const auto adaptive = parse_study(R"(
[study]
name = "a"
kind = "adaptive"
[domain]
radius = 4.0
[grid]
n = [6, 8]
[[kernel]]
name = "gaussian"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
[[law]]
name = "rkhs"
[[integrator]]
name = "rosenbrock4"
[[integrator]]
name = "rodas4"
[[integrator]]
name = "dopri5"
[adaptive]
speed = 0.1
laps = 1
)",
                                    "a.toml");
  product = 1;
  names.clear();
  for (const auto& axis : adaptive.grid_axes()) {
    product *= axis.count;
    names.push_back(axis.singular);
  }
  CHECK(names == std::vector<std::string>{"kernel", "target", "centre placement", "plant",
                                          "learning law", "integrator", "value of n"});
  CHECK(product == 2 * 3 * 2);
  CHECK(product == adaptive.trials().size());
}

TEST_CASE("an evaluation grid no finer than the centres is refused, a coarse one warned",
          "[study]") {
  const auto study_with = [](const std::string& points, const std::string& metrics) {
    return "[study]\nname = \"g\"\n" + points + metrics +
           "[domain]\nradius = 4.0\n[grid]\nn = [16, 32, 64]\n[[kernel]]\nname = \"bspline\"\n";
  };
  // 64 points for n = 64 uniform centres: every evaluation point is a centre, P_n = 0 there.
  CHECK(error_of(study_with("evaluation_points = 64\n", "")) ==
        "s.toml:3:21: study.evaluation_points: 64 evaluation points for up to n = 64 centres: the "
        "grid is no finer than the centres, so power_function_sup, power_function_floor, "
        "l2_error, sup_error, error_floor would be measured at or next to the centres, where they "
        "vanish (round-off), not over the domain; use evaluation_points >= 256 (4 per centre "
        "spacing) or leave these metrics out of study.metrics");
  CHECK_THAT(error_of(study_with("evaluation_points = 40\n", "")),
             Catch::Contains("40 evaluation points for up to n = 64 centres"));
  // Only the grid metrics need the grid: a study of condition numbers may use any.
  const auto conditioning = parse_study(
      study_with("evaluation_points = 16\n", "metrics = [\"gram_condition_number\"]\n"), "s.toml");
  CHECK(conditioning.warnings.empty());
  // Fewer than 4 points per centre spacing: valid, with a warning at the same place.
  const auto coarse = parse_study(study_with("evaluation_points = 200\n", ""), "s.toml");
  REQUIRE(coarse.warnings.size() == 1);
  CHECK_THAT(coarse.warnings[0],
             Catch::StartsWith("s.toml:3:21: study.evaluation_points: warning: 200 evaluation "
                               "points give fewer than 4 per centre spacing for n > 50"));
  CHECK(parse_study(study_with("evaluation_points = 256\n", ""), "s.toml").warnings.empty());
}

namespace {

// An adaptive study whose [adaptive] table ends with `adaptive` (laps, engine, ...) and which
// may add [[expect]] tables after it.
std::string adaptive_text(const std::string& adaptive, const std::string& after = "") {
  return R"([study]
name = "laps"
kind = "adaptive"
evaluation_points = 64
[domain]
radius = 1.0
[grid]
n = [4, 6]
[[kernel]]
name = "gaussian"
[[centres]]
name = "random"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
[adaptive]
speed = 0.5
)" + adaptive + after;
}

// The line of adaptive_text's first added line (the line after "speed = 0.5").
constexpr int adaptive_line = 21;

}  // namespace

TEST_CASE("[adaptive] laps: one value is a setting, a list is an axis of the grid nested outside n",
          "[study][laps]") {
  SECTION("one number: no axis, keys as before") {
    const auto study = parse_study(adaptive_text("laps = 3\n"), "s.toml");
    CHECK(study.adaptive_axes().settings.laps == 3);
    CHECK(study.adaptive_axes().laps_values.empty());
    const auto trials = study.trials();
    REQUIRE(trials.size() == 2);
    for (const auto& trial : trials) {
      CHECK_FALSE(trial.adaptive_axes().laps.has_value());
      CHECK_THAT(trial.key, !Catch::Contains("laps"));
    }
    CHECK(trials[0].key == trials[0].group_key + " | n=4");
    CHECK(trials[0].group_key.ends_with(" | integrator=" +
                                        trials[0].adaptive_axes().integrator.label()));
    const auto columns = rkhs::axis_columns(trials);
    CHECK(std::find(columns.begin(), columns.end(), "laps") == columns.end());
    CHECK(rkhs::trial_adaptive_settings(study, trials[0]).laps == 3);
    std::vector<std::string> names;
    for (const auto& axis : study.grid_axes()) names.push_back(axis.singular);
    CHECK(std::find(names.begin(), names.end(), std::string("value of laps")) == names.end());
  }
  SECTION("\"limit\" alone: +infinity, still no axis") {
    const auto study = parse_study(adaptive_text("laps = \"limit\"\n"), "s.toml");
    CHECK(std::isinf(study.adaptive_axes().settings.laps));
    CHECK(study.adaptive_axes().settings.limit());
    CHECK(study.adaptive_axes().laps_values.empty());
    CHECK_THAT(study.trials().front().key, !Catch::Contains("laps"));
    CHECK(rkhs::trial_adaptive_settings(study, study.trials().front()).limit());
  }
  SECTION("a list: sorted, \"limit\" last, one group per lap count, n fastest") {
    const auto study =
        parse_study(adaptive_text("laps = [1000, 10, \"limit\", 1e4, 100, 2.5]\n"), "s.toml");
    const double inf = std::numeric_limits<double>::infinity();
    CHECK(study.adaptive_axes().laps_values == std::vector<double>{2.5, 10, 100, 1000, 10000, inf});
    CHECK(std::isnan(study.adaptive_axes().settings.laps));
    const auto trials = study.trials();
    REQUIRE(trials.size() == 6 * 2);
    const std::vector<std::string> laps_texts{"2.5", "10", "100", "1000", "10000", "limit"};
    for (std::size_t i = 0; i < trials.size(); ++i) {
      const auto& trial = trials[i];
      INFO(trial.key);
      CHECK(trial.index == i);
      CHECK(trial.n == (i % 2 == 0 ? 4u : 6u));  // n varies fastest
      REQUIRE(trial.adaptive_axes().laps.has_value());
      CHECK(*trial.adaptive_axes().laps == study.adaptive_axes().laps_values[i / 2]);
      CHECK(trial.group_key.ends_with(" | laps=" + laps_texts[i / 2]));
      CHECK(trial.key == trial.group_key + (i % 2 == 0 ? " | n=4" : " | n=6"));
      // The same random centres for every lap count of a series.
      CHECK(trial.seed == trials[i % 2].seed);
      // run_trial's settings: the trial's lap count.
      const auto settings = rkhs::trial_adaptive_settings(study, trial);
      CHECK(settings.laps == *trial.adaptive_axes().laps);
    }
    CHECK(trials[0].seed != trials[1].seed);
    CHECK(trials.back().key.ends_with("| laps=limit | n=6"));

    const auto columns = rkhs::axis_columns(trials);
    CHECK(columns.back() == "laps");
    CHECK(rkhs::axis_values({"laps"}, trials[10]) == std::vector<std::string>{"limit"});
    CHECK(rkhs::axis_values({"laps"}, trials[8]) == std::vector<std::string>{"10000"});
    CHECK(rkhs::axis_values({"laps"}, trials[0]) == std::vector<std::string>{"2.5"});

    std::size_t product = 1;
    std::vector<std::string> names;
    for (const auto& axis : study.grid_axes()) {
      product *= axis.count;
      names.push_back(axis.plural);
    }
    CHECK(names == std::vector<std::string>{"kernels", "targets", "centre placements", "plants",
                                            "learning laws", "integrators", "values of laps",
                                            "values of n"});
    CHECK(product == trials.size());
  }
  SECTION("lap counts print as whole numbers without an exponent") {
    CHECK(rkhs::laps_text(10) == "10");
    CHECK(rkhs::laps_text(1e6) == "1000000");
    CHECK(rkhs::laps_text(0.5) == "0.5");
    CHECK(rkhs::laps_text(std::numeric_limits<double>::infinity()) == "limit");
  }
  SECTION("a trial records the snapshot laps it reaches; \"limit\" records them all") {
    const auto study = parse_study(
        adaptive_text("laps = [2, 5, \"limit\"]\nsnapshot_laps = [1, 2, 5]\n"), "s.toml");
    const auto trials = study.trials();
    CHECK(rkhs::trial_adaptive_settings(study, trials[0]).snapshot_laps == std::vector<double>{1, 2});
    CHECK(rkhs::trial_adaptive_settings(study, trials[2]).snapshot_laps ==
          std::vector<double>{1, 2, 5});
    CHECK(rkhs::trial_adaptive_settings(study, trials[4]).snapshot_laps ==
          std::vector<double>{1, 2, 5});
  }
}

TEST_CASE("a study's kind is the alternative of its own part, which only its kind's code reads",
          "[study][kind]") {
  const auto approximation = parse_study(minimal, "s.toml");
  CHECK(approximation.kind() == rkhs::StudyKind::approximation);
  CHECK(approximation.adaptive_axes_if() == nullptr);
  CHECK_THROWS_WITH(approximation.adaptive_axes(),
                    "StudyDefinition::adaptive_axes: approximation studies have none");
  const auto trials = approximation.trials();
  REQUIRE(!trials.empty());
  CHECK(trials.front().kind() == rkhs::StudyKind::approximation);
  CHECK(trials.front().adaptive_axes_if() == nullptr);
  CHECK_THROWS_WITH(trials.front().adaptive_axes(),
                    "TrialSpec::adaptive_axes: approximation trials have none");
  std::vector<std::string> axes;
  for (const auto& entry : trials.front().plugin_choices()) axes.emplace_back(entry.first);
  CHECK(axes == std::vector<std::string>{"kernel", "target", "centres", "projection"});

  const auto adaptive = parse_study(adaptive_text("laps = [2, 3]\n"), "s.toml");
  CHECK(adaptive.kind() == rkhs::StudyKind::adaptive);
  REQUIRE(adaptive.adaptive_axes_if() == &adaptive.adaptive_axes());
  CHECK(adaptive.adaptive_axes().laps_values == std::vector<double>{2, 3});
  std::vector<std::string> study_axes;
  for (const auto& entry : adaptive.plugin_axes()) study_axes.emplace_back(entry.first);
  CHECK(study_axes == std::vector<std::string>{"kernel", "target", "centres", "projection", "plant",
                                               "law", "integrator"});
  for (const auto& trial : adaptive.trials()) {
    CHECK(trial.kind() == rkhs::StudyKind::adaptive);
    CHECK(trial.adaptive_axes().plant.name == "linear");
    CHECK(trial.adaptive_axes().laps.has_value());
  }
  // A kind's empty part: what a reader sets before filling it in.
  CHECK(rkhs::study_kind_axes(rkhs::StudyKind::adaptive).index() ==
        static_cast<std::size_t>(rkhs::StudyKind::adaptive));
  CHECK(std::holds_alternative<rkhs::ApproximationTrialAxes>(
      rkhs::trial_kind_axes(rkhs::StudyKind::approximation)));
}

TEST_CASE("[adaptive] engine and the lap map's tolerances", "[study][laps]") {
  const auto defaults = parse_study(adaptive_text("laps = 2\n"), "s.toml");
  CHECK(defaults.adaptive_axes().settings.engine == rkhs::AdaptiveEngine::automatic);
  CHECK(defaults.adaptive_axes().settings.lap_map_rtol == 1e-10);
  CHECK(defaults.adaptive_axes().settings.lap_map_atol == 1e-10);
  const auto chosen = parse_study(
      adaptive_text("laps = 2\nengine = \"lap_map\"\nlap_map_rtol = 1e-8\nlap_map_atol = 1e-9\n"),
      "s.toml");
  CHECK(chosen.adaptive_axes().settings.engine == rkhs::AdaptiveEngine::lap_map);
  CHECK(chosen.adaptive_axes().settings.lap_map_rtol == 1e-8);
  CHECK(chosen.adaptive_axes().settings.lap_map_atol == 1e-9);
  const auto stepping =
      parse_study(adaptive_text("laps = 2.5\nengine = \"time_stepping\"\n"), "s.toml");
  CHECK(stepping.adaptive_axes().settings.engine == rkhs::AdaptiveEngine::time_stepping);
  CHECK(stepping.adaptive_axes().settings.laps == 2.5);
  for (const auto engine : {rkhs::AdaptiveEngine::automatic, rkhs::AdaptiveEngine::lap_map,
                            rkhs::AdaptiveEngine::time_stepping})
    CHECK(rkhs::adaptive_engine_from_name(rkhs::adaptive_engine_name(engine)) == engine);
  CHECK_FALSE(rkhs::adaptive_engine_from_name("lapmap"));
}

TEST_CASE("[adaptive] laps and engine errors name file, line, column, key, found and allowed",
          "[study][laps]") {
  const auto at = [](int line, int column) {
    return "s.toml:" + std::to_string(adaptive_line + line) + ":" + std::to_string(column) + ": ";
  };
  CHECK(error_of(adaptive_text("engine = \"lapmap\"\n")) ==
        at(0, 10) + "adaptive.engine: unknown engine \"lapmap\" (known: automatic, lap_map, "
                    "time_stepping; did you mean 'lap_map'?)");
  CHECK(error_of(adaptive_text("engine = 2\n")) ==
        at(0, 10) + "adaptive.engine: expected a string, found an integer (2)");
  CHECK(error_of(adaptive_text("lap_map_rtol = 0\n")) ==
        at(0, 16) + "adaptive.lap_map_rtol: must be a finite number > 0, found 0");
  CHECK(error_of(adaptive_text("lap_map_atol = -1.5\n")) ==
        at(0, 16) + "adaptive.lap_map_atol: must be a finite number > 0, found -1.5");
  CHECK(error_of(adaptive_text("laps = \"forever\"\n")) ==
        at(0, 8) + "adaptive.laps: found \"forever\", expected a lap count > 0, \"limit\" (the "
                   "periodic steady state) or an array of them");
  CHECK(error_of(adaptive_text("laps = 0\n")) ==
        at(0, 8) + "adaptive.laps: must be a finite number > 0 or \"limit\", found 0");
  // final_time = 0 ran the default 10 laps while laps = 0 was refused: both are refused.
  CHECK(error_of(adaptive_text("final_time = 0\n")) ==
        at(0, 14) + "adaptive.final_time: must be a finite number > 0, found 0");
  CHECK(error_of(adaptive_text("laps = true\n")) ==
        at(0, 8) + "adaptive.laps: found a boolean (true), expected a lap count > 0, \"limit\" "
                   "(the periodic steady state) or an array of them");
  CHECK(error_of(adaptive_text("laps = [10, -1]\n")) ==
        at(0, 13) + "adaptive.laps: must be a finite number > 0 or \"limit\", found -1");
  CHECK(error_of(adaptive_text("laps = [10, \"lim\"]\n")) ==
        at(0, 13) + "adaptive.laps: found \"lim\", expected a lap count > 0 or \"limit\" (the "
                    "periodic steady state)");
  CHECK(error_of(adaptive_text("laps = []\n")) == at(0, 8) + "adaptive.laps: empty list of lap counts");
  CHECK(error_of(adaptive_text("laps = [10, 100, 10.0]\n")) ==
        at(0, 18) + "adaptive.laps: 10 is listed twice; lap counts must be distinct");
  CHECK(error_of(adaptive_text("laps = [10, \"limit\"]\nfinal_time = 5.0\n")) ==
        at(0, 13) + "adaptive.laps: found \"limit\" together with final_time = 5.0: the periodic "
                    "limit has no final time; give laps = \"limit\" without final_time, or a "
                    "final time without laps");
  CHECK_THAT(error_of(adaptive_text("laps = 10\nfinal_time = 5.0\n")),
             Catch::Contains("adaptive: give 'laps' or 'final_time', not both"));
  CHECK(error_of(adaptive_text("engine = \"time_stepping\"\nlaps = [10, \"limit\"]\n")) ==
        at(1, 13) + "adaptive.laps: found \"limit\" with engine = \"time_stepping\", which cannot "
                    "step through infinitely many laps; \"limit\" needs engine = \"automatic\" or "
                    "\"lap_map\"");
  CHECK(error_of(adaptive_text("engine = \"time_stepping\"\nlaps = \"limit\"\n")) ==
        at(1, 8) + "adaptive.laps: found \"limit\" with engine = \"time_stepping\", which cannot "
                   "step through infinitely many laps; \"limit\" needs engine = \"automatic\" or "
                   "\"lap_map\"");
  CHECK(error_of(adaptive_text("engine = \"lap_map\"\nlaps = [10, 2.5]\n")) ==
        at(1, 13) + "adaptive.laps: found 2.5 with engine = \"lap_map\", which advances whole "
                    "laps; give a whole number of laps, or engine = \"automatic\" or "
                    "\"time_stepping\"");
  CHECK(error_of(adaptive_text("laps = 10\nsnapshot_laps = [1, 20]\n")) ==
        at(1, 21) + "adaptive.snapshot_laps: found 20, after the end of the run (laps = 10); "
                    "snapshot laps must be <= 10");
  CHECK(error_of(adaptive_text("laps = [10, 100, \"limit\"]\nsnapshot_laps = [1, 200]\n")) ==
        at(1, 21) + "adaptive.snapshot_laps: found 200, after the end of the run (laps = 100, "
                    "the largest finite lap count); snapshot laps must be <= 100");
  // Speed 0.5 m/s on a track of 2 pi m: final_time = 4 pi s is one lap.
  CHECK_THAT(error_of(adaptive_text("final_time = 12.566370614359172\nsnapshot_laps = [1, 2]\n")),
             Catch::StartsWith(at(1, 21) + "adaptive.snapshot_laps: found 2, after the end of the "
                                           "run (final_time = 12.566370614359172 s, "));
  // Without a finite lap count every snapshot lap is reachable.
  CHECK_NOTHROW(parse_study(adaptive_text("laps = \"limit\"\nsnapshot_laps = [1, 1000]\n"), "s.toml"));
  CHECK_NOTHROW(parse_study(adaptive_text("laps = 10\nsnapshot_laps = [1, 10]\n"), "s.toml"));
}

TEST_CASE("[[expect]] selects groups of a laps axis by laps, as any axis column",
          "[study][laps][expect]") {
  const std::string laps = "laps = [10, 10000, \"limit\"]\n";
  const auto selected = [&](const std::string& selector) {
    const auto study = parse_study(
        adaptive_text(laps, "[[expect]]\nmetric = \"l2_error\"\nrate = { max = 0 }\n" + selector),
        "s.toml");
    REQUIRE(study.expectations.size() == 1);
    std::vector<std::string> groups;
    for (const auto& trial : study.trials())
      if (trial.n == 4 && study.expectations[0].selects(trial))
        groups.push_back(rkhs::axis_values({"laps"}, trial).front());
    return groups;
  };
  CHECK(selected("") == std::vector<std::string>{"10", "10000", "limit"});
  CHECK(selected("laps = \"limit\"\n") == std::vector<std::string>{"limit"});
  CHECK(selected("laps = 10000\n") == std::vector<std::string>{"10000"});
  CHECK(selected("laps = 1e4\n") == std::vector<std::string>{"10000"});
  CHECK(selected("laps = [10, \"limit\"]\n") == std::vector<std::string>{"10", "limit"});
  // A lap count the study does not have is a typo: refused with the values there are.
  CHECK_THAT(error_of(adaptive_text(laps, "[[expect]]\nmetric = \"l2_error\"\nrate = { max = 0 }\n"
                                          "laps = 100\n")),
             Catch::Contains("expect: laps=100 selects no group of this study (values in the "
                             "study: laps: 10, 10000, limit)"));
  // Without the axis there is no laps column to select by.
  CHECK_THAT(error_of(adaptive_text("laps = 10\n", "[[expect]]\nmetric = \"l2_error\"\n"
                                                   "rate = { max = 0 }\nlaps = 10\n")),
             Catch::Contains("expect.laps: unknown key"));
}

// Issue 36: values that validate accepted and run crashed on, or that ended in an exception
// without a position.
TEST_CASE("hostile values are refused at their key with the allowed range, or read as documented",
          "[study][hostile]") {
  const auto with = [](std::string_view from, const std::string& to) {
    std::string text = minimal;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  SECTION("a domain length beyond 1e100 (a periodic B-spline died with SIGSEGV at 3e307)") {
    const auto text = with("radius = 4.0", "length = 1e308") + "[[kernel]]\nname = \"bspline\"\n";
    CHECK(error_of(text) ==
          "s.toml:5:10: domain.length: must be between 1e-100 and 1e+100 metres, found 1e+308 "
          "(beyond these the squared distances, volumes and spline knots computed on the domain "
          "leave the range of double)");
    CHECK_THAT(error_of(with("radius = 4.0", "length = 3e307")),
               Catch::StartsWith("s.toml:5:10: domain.length: must be between"));
    CHECK_THAT(error_of(with("radius = 4.0", "length = 1e-101")),
               Catch::StartsWith("s.toml:5:10: domain.length: must be between"));
    CHECK(parse_study(with("radius = 4.0", "length = 1e100"), "s.toml").domain.length == 1e100);
    CHECK(error_of(with("radius = 4.0", "lengths = [1.0, 2e100]")) ==
          "s.toml:5:17: domain.lengths: axis 2: must be between 1e-100 and 1e+100 metres, found "
          "2e+100 (beyond these the squared distances, volumes and spline knots computed on the "
          "domain leave the range of double)");
  }
  SECTION("a periodic Wendland radius of 2^31 periods (undefined behaviour casting the images)") {
    const auto text =
        with("radius = 4.0", "length = 1.0") + "[[kernel]]\nname = \"wendland\"\nradius = 3e9\n";
    CHECK_THAT(
        error_of(text),
        Catch::StartsWith("s.toml:12:10: kernel.radius: ") &&
            Catch::Contains("parameter 'radius' must be at most 1048575 times the length "
                            "of a periodic track (a kernel value sums 2 ceil(radius / L + "
                            "1/2) + 1 images), found radius = 3e+09 on a track of length 1"));
    // On an interval there are no images: any radius is a kernel.
    CHECK_NOTHROW(parse_study(with("radius = 4.0", "length = 1.0\nperiodic = false") +
                                  "[[kernel]]\nname = \"wendland\"\nradius = 3e9\n",
                              "s.toml"));
    CHECK_NOTHROW(parse_study(with("radius = 4.0", "length = 1.0") +
                                  "[[kernel]]\nname = \"wendland\"\nradius = 1048575\n",
                              "s.toml"));
    // On a torus the lattice sum is bounded by the number of images per kernel value.
    CHECK_THAT(error_of(with("radius = 4.0", "lengths = [1.0, 1.0]") +
                        "[[kernel]]\nname = \"wendland\"\nradius = 2000\n"),
               Catch::StartsWith("s.toml:12:10: kernel.radius: ") &&
                   Catch::Contains("would sum 1.602e+07 images per kernel value on this torus"));
  }
  SECTION("a periodic Gaussian sigma above 1e5 periods (2 million images per kernel value)") {
    // The property fuzzer's hang-2-642: a track of 1e-12 m, sigma = 1: image_count reached its
    // cap of 2^20 images each side and a trial of n = 16 ran 39 s past trial_seconds = 2.
    const auto gaussian = [](const std::string& domain) {
      return "[study]\nname = \"t\"\n[domain]\n" + domain +
             "\n[grid]\nn = [4, 8, 16]\n[[kernel]]\nname = \"gaussian\"\nsigma = 1.0\n"
             "convention = \"sigma2\"\n";
    };
    CHECK_THAT(error_of(gaussian("length = 1e-12\nperiodic = true")),
               Catch::StartsWith("s.toml:10:9: kernel.sigma: ") &&
                   Catch::Contains("parameter 'sigma' must be at most 100000 times the period of "
                                   "a periodic domain") &&
                   Catch::Contains("found sigma = 1 on a period of 1e-12"));
    // At the bound it is a kernel; on an interval any sigma is; on a torus each axis counts.
    CHECK_NOTHROW(parse_study(gaussian("length = 1e-5"), "s.toml"));
    CHECK_NOTHROW(parse_study(gaussian("length = 1e-12\nperiodic = false"), "s.toml"));
    CHECK_THAT(error_of(gaussian("lengths = [1.0, 1e-6]")),
               Catch::Contains("found sigma = 1 on a period of 1e-06"));
  }
  SECTION("integers above 2^53 in real-valued keys are read as the nearest double") {
    // 9007199254740993 = 2^53 + 1 is no double: toml++ gives no value<double>() for it, and the
    // parser ended in "bad optional access" without a position.
    const std::string big = "9007199254740993";
    const double nearest = 9007199254740992.0;
    CHECK(parse_study(with("radius = 4.0", "length = " + big), "s.toml").domain.length == nearest);
    CHECK(parse_study(with("radius = 4.0", "radius = " + big), "s.toml").domain.length ==
          2 * std::numbers::pi * nearest);
    CHECK(parse_study(with("radius = 4.0", "lengths = [" + big + "]"), "s.toml").domain.length ==
          nearest);
    const auto limits = parse_study(std::string(minimal) + "[limits]\ntrial_seconds = " + big +
                                        "\nmatrix_megabytes = " + big +
                                        "\n[solver]\nregularisation = " + big + "\n",
                                    "s.toml");
    CHECK(limits.limits.trial_seconds == nearest);
    CHECK(limits.limits.matrix_megabytes == nearest);
    CHECK(limits.solver.regularisation == nearest);
    const auto expect =
        parse_study(std::string(minimal) + "[[expect]]\nmetric = \"fill_distance\"\nrate = " + big +
                        "\ntolerance = " + big + "\n",
                    "s.toml");
    REQUIRE(expect.expectations.size() == 1);
    CHECK(expect.expectations[0].expected == nearest);
    CHECK(expect.expectations[0].tolerance == nearest);
    // A real-valued kernel parameter (ParameterSet reads integers itself).
    CHECK(parse_study(with("radius = 4.0", "length = 1.0\nperiodic = false") +
                          "[[kernel]]\nname = \"wendland\"\nradius = " + big + "\n",
                      "s.toml")
              .kernels.size() == 2);
  }
  SECTION("whole-number keys name their range") {
    CHECK(error_of(with("name = \"t\"", "name = \"t\"\nevaluation_points = 9007199254740993")) ==
          "s.toml:4:21: study.evaluation_points: must be a whole number between 2 and "
          "100000000, found 9007199254740993");
    CHECK(error_of(std::string(minimal) + "[limits]\ntrials = 9007199254740993\n") ==
          "s.toml:11:10: limits.trials: must be a whole number between 1 and 10000000 (every "
          "trial of the grid is held in memory, about 1.7 KB each), found 9007199254740993");
    // Below the range, not whole, or not a number: the same message, naming both bounds (issue
    // 50: evaluation_points = 1 was "must be a finite number > 1", 1e8 + 1 named only 2).
    for (const auto& [value, shown] :
         std::vector<std::pair<std::string, std::string>>{{"1", "1"},
                                                          {"0", "0"},
                                                          {"-3", "-3"},
                                                          {"2.5", "2.5"},
                                                          {"1.5e8", "150000000.0"},
                                                          {"100000001", "100000001"},
                                                          {"inf", "inf"},
                                                          {"nan", "nan"},
                                                          {"\"many\"", "a string ('many')"}})
      CHECK(error_of(with("name = \"t\"", "name = \"t\"\nevaluation_points = " + value)) ==
            "s.toml:4:21: study.evaluation_points: must be a whole number between 2 and "
            "100000000, found " +
                shown);
    CHECK(error_of(std::string(minimal) + "[limits]\ntrials = 0\n") ==
          "s.toml:11:10: limits.trials: must be a whole number between 1 and 10000000 (every "
          "trial of the grid is held in memory, about 1.7 KB each), found 0");
  }
  SECTION("adaptive speed and laps above 2^53") {
    const std::string adaptive = R"(
[study]
name = "a"
kind = "adaptive"
evaluation_points = 64
[domain]
radius = 4.0
[grid]
n = [8]
[[kernel]]
name = "gaussian"
[adaptive]
)";
    // Read, then judged by the adaptive checks: a refusal with a position, never an exception
    // without one.
    for (const auto* key :
         {"speed = 9007199254740993", "laps = 9007199254740993", "laps = [1, 9007199254740993]"}) {
      const auto e = error_of(adaptive + key + "\n");
      INFO(key << ": " << e);
      CHECK((e == "no error" || e.rfind("s.toml:", 0) == 0));
    }
  }
  SECTION("a study name longer than 100 characters (run failed: File name too long)") {
    CHECK(error_of(with("name = \"t\"", "name = \"" + std::string(300, 'a') + "\"")) ==
          "s.toml:3:8: study.name: is 300 characters long, at most 100 are allowed (it names "
          "the output folder results/<name>/ and the files in it)");
    CHECK(parse_study(with("name = \"t\"", "name = \"" + std::string(100, 'a') + "\""), "s.toml")
              .name.size() == 100);
  }
}

TEST_CASE("[plot] sets the figures' metrics, labels, title, size, font, legend and resolution",
          "[study][plot]") {
  const auto plain = parse_study(minimal, "s.toml");
  CHECK(plain.plot.metrics.empty());
  CHECK(plain.plot.labels.empty());
  CHECK(!plain.plot.title);
  CHECK(plain.plot.width_inches == 0);
  CHECK(plain.plot.legend == "below");
  CHECK(plain.plot.png_dpi == 150);

  const auto study = parse_study(std::string(minimal) + R"([plot]
metrics = ["sup_error", "l2_error"]
labels = { l2_error = "L^2 error ||f - {/Symbol P}_n f||", sup_error = "$\\|f\\|_\\infty$" }
title = false
size = [3.5, 2.5]
font_size = 8
legend = "top right"
png_dpi = 300
)",
                                 "s.toml");
  CHECK(study.plot.metrics == std::vector<std::string>{"sup_error", "l2_error"});
  CHECK(study.plot.labels.at("l2_error") == "L^2 error ||f - {/Symbol P}_n f||");
  CHECK(study.plot.labels.at("sup_error") == "$\\|f\\|_\\infty$");
  REQUIRE(study.plot.title);
  CHECK(study.plot.title->empty());
  CHECK(study.plot.width_inches == 3.5);
  CHECK(study.plot.height_inches == 2.5);
  CHECK(study.plot.font_points == 8);
  CHECK(study.plot.legend == "top right");
  CHECK(study.plot.png_dpi == 300);
  // The trials are the same: [plot] changes the figures only.
  CHECK(study.trials().size() == plain.trials().size());
  CHECK(study.trials().front().key == plain.trials().front().key);

  const auto titled =
      parse_study(std::string(minimal) + "[plot]\ntitle = \"Gaussian kernel\"\n", "s.toml");
  CHECK(titled.plot.title == std::optional<std::string>("Gaussian kernel"));
}

TEST_CASE("[plot] errors name file, line, column, key, what was found and what is allowed",
          "[study][plot]") {
  // minimal ends on line 9: [plot] is line 10, its first key line 11.
  auto error = [](const std::string& lines) {
    return error_of(std::string(minimal) + "[plot]\n" + lines);
  };
  CHECK_THAT(error("legnd = \"below\"\n"),
             Catch::StartsWith("s.toml:11:1: plot.legnd: unknown key") &&
                 Catch::Contains("did you mean 'legend'"));
  CHECK_THAT(error("metrics = [\"l2_eror\"]\n"),
             Catch::StartsWith("s.toml:11:12: plot.metrics: unknown metric 'l2_eror'") &&
                 Catch::Contains("did you mean 'l2_error'"));
  CHECK_THAT(error("metrics = []\n"),
             Catch::StartsWith("s.toml:11:11: plot.metrics: expected a non-empty array"));
  CHECK_THAT(error("metrics = [\"l2_error\", \"l2_error\"]\n"),
             Catch::StartsWith("s.toml:11:24: plot.metrics: 'l2_error' is listed twice"));
  CHECK_THAT(error_of(R"(
[study]
name = "t"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [10, 20]
[[kernel]]
name = "gaussian"
[plot]
metrics = ["sup_error"]
)"),
             Catch::StartsWith("s.toml:12:12: plot.metrics: 'sup_error' is not among "
                               "study.metrics") &&
                 Catch::Contains("study.metrics: l2_error"));
  CHECK_THAT(error("labels = \"L2\"\n"),
             Catch::StartsWith("s.toml:11:10: plot.labels: expected an inline table"));
  CHECK_THAT(error("labels = { l2_err = \"L2\" }\n"),
             Catch::StartsWith("s.toml:11:21: plot.labels.l2_err: unknown metric 'l2_err'") &&
                 Catch::Contains("did you mean 'l2_error'"));
  CHECK_THAT(error("labels = { l2_error = 2 }\n"),
             Catch::StartsWith("s.toml:11:23: plot.labels.l2_error: expected a string"));
  CHECK_THAT(error("labels = { l2_error = \"a\\nb\" }\n"),
             Catch::StartsWith("s.toml:11:23: plot.labels.l2_error: must be one line"));
  CHECK_THAT(error("title = true\n"),
             Catch::StartsWith("s.toml:11:9: plot.title: expected a string, or false"));
  CHECK_THAT(error("title = 3\n"), Catch::StartsWith("s.toml:11:9: plot.title: expected a string"));
  CHECK_THAT(error("title = \"" + std::string(301, 'x') + "\"\n"),
             Catch::StartsWith("s.toml:11:9: plot.title: is 301 bytes long, at most 300"));
  CHECK_THAT(error("size = [6]\n"),
             Catch::StartsWith("s.toml:11:8: plot.size: expected [width, height] in inches"));
  CHECK_THAT(error("size = [0, 4]\n"),
             Catch::StartsWith("s.toml:11:9: plot.size: width: expected inches, a number above 0 "
                               "and at most 40, found 0"));
  CHECK_THAT(error("size = [6, 41]\n"),
             Catch::StartsWith("s.toml:11:12: plot.size: height: expected inches") &&
                 Catch::Contains("found 41"));
  CHECK_THAT(error("size = [6, \"4\"]\n"),
             Catch::StartsWith("s.toml:11:12: plot.size: height: expected inches"));
  CHECK_THAT(error("font_size = 3\n"),
             Catch::StartsWith("s.toml:11:13: plot.font_size: expected a number between 4 and "
                               "72 points, found 3"));
  CHECK_THAT(error("font_size = 73\n"), Catch::StartsWith("s.toml:11:13: plot.font_size:"));
  CHECK_THAT(error("legend = \"top rigth\"\n"),
             Catch::StartsWith("s.toml:11:10: plot.legend: unknown position 'top rigth'") &&
                 Catch::Contains("did you mean 'top right'"));
  CHECK_THAT(error("legend = 1\n"),
             Catch::StartsWith("s.toml:11:10: plot.legend: expected a string"));
  CHECK_THAT(error("png_dpi = 49\n"),
             Catch::StartsWith("s.toml:11:11: plot.png_dpi: must be a whole number between 50 "
                               "and 1200"));
  CHECK_THAT(error("png_dpi = 1201\n"), Catch::StartsWith("s.toml:11:11: plot.png_dpi:"));
  CHECK_THAT(error("png_dpi = 150.5\n"), Catch::StartsWith("s.toml:11:11: plot.png_dpi:"));
  CHECK_THAT(error("size = [30, 20]\npng_dpi = 1200\n"),
             Catch::StartsWith("s.toml:12:11: plot.png_dpi: 1200 dpi at 30 inches makes a PNG "
                               "of 36000 pixels a side, at most 20000"));
  CHECK_THAT(error_of("plot = 3\n" + std::string(minimal)),
             Catch::StartsWith("s.toml:1:8: plot: expected a table"));
}

TEST_CASE("[linear_algebra] solver is dense by default, sparse or auto, and nothing else",
          "[study]") {
  CHECK(parse_study(minimal, "s.toml").solver.algebra == rkhs::GramAlgebra::dense);
  CHECK(parse_study(std::string(minimal) + "[linear_algebra]\nsolver = \"sparse\"\n", "s.toml")
            .solver.algebra == rkhs::GramAlgebra::sparse);
  CHECK(parse_study(std::string(minimal) + "[linear_algebra]\nsolver = \"auto\"\n", "s.toml")
            .solver.algebra == rkhs::GramAlgebra::automatic);
  CHECK(error_of(std::string(minimal) + "[linear_algebra]\nsolver = \"cholmod\"\n") ==
        "s.toml:11:10: linear_algebra.solver: found \"cholmod\", expected \"dense\", "
        "\"sparse\" or \"auto\"");
  CHECK_THAT(error_of(std::string(minimal) + "[linear_algebra]\nsolve = \"dense\"\n"),
             Catch::StartsWith("s.toml:11:1: linear_algebra.solve: unknown key"));
}
