// Study files: valid grids expand as documented; every kind of mistake is reported with
// file:line:column, the key, what was found and what is allowed.
#include <catch2/catch.hpp>

#include <set>

#include "rkhs/study/study.hpp"

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
    CHECK(e == "s.toml:10:2: kernels: unknown key (known: study, domain, grid, kernel, target, "
               "centres, solver, limits, adaptive, plant, law, integrator, plugins, expect; did you mean "
               "'kernel'?)");
  }
  SECTION("invalid TOML") {
    const auto e = error_of("[study\nname = 1\n");
    CHECK_THAT(e, Catch::StartsWith("s.toml:1:"));
    CHECK_THAT(e, Catch::Contains("invalid TOML"));
  }
  SECTION("n must be positive integers") {
    std::string text = minimal;
    text.replace(text.find("[10, 20]"), 8, "[10, 0]");
    CHECK(error_of(text) == "s.toml:7:10: grid.n: must be >= 1, found 0");
    text = minimal;
    text.replace(text.find("[10, 20]"), 8, "[10, 2.5]");
    CHECK(error_of(text) == "s.toml:7:10: grid.n: expected integers, found a number (2.5)");
  }
  SECTION("domain needs exactly one of length and radius") {
    std::string text = minimal;
    text.replace(text.find("radius = 4.0"), 12, "radius = 4.0\nlength = 3.0");
    CHECK_THAT(error_of(text), Catch::Contains("domain: give exactly one of 'length'"));
  }
  SECTION("unknown metric") {
    std::string text = minimal;
    text.replace(text.find("name = \"t\""), 10, "name = \"t\"\nmetrics = [\"power_function_supp\"]");
    CHECK(error_of(text) ==
          "s.toml:4:12: study.metrics: unknown metric 'power_function_supp' (known: "
          "fill_distance, separation_distance, gram_condition_number, gram_min_eigenvalue, "
          "gram_max_eigenvalue, power_function_sup, power_function_floor, l2_error, sup_error, "
          "error_floor, interpolant_native_norm; did you mean 'power_function_sup'?)");
  }
  SECTION("a target that is not periodic on a closed track") {
    const auto e = error_of(std::string(minimal) + "[[target]]\nname = \"sine\"\ncycles = 1.5\n");
    CHECK_THAT(e, Catch::Contains("target: sine amplitude=2 cycles=1.5 phase=0: parameter "
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
                      "no/such/study.toml: cannot open the study file");
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
