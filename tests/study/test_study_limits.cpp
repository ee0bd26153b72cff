// Bounded parsing: the size of a study's grid is counted from its lists before anything is
// built and refused above [limits] trials, naming the lists that multiply to it; n ranges are
// checked without overflow.
#include <catch2/catch.hpp>

#include <chrono>
#include <string>

#include "rkhs/study/study.hpp"

using rkhs::parse_study;
using rkhs::StudyError;

namespace {

std::string error_of(const std::string& text) {
  try {
    parse_study(text, "s.toml");
  } catch (const StudyError& e) {
    return e.what();
  }
  return "no error";
}

std::string values(int count, double first, double step) {
  std::string out = "[";
  for (int i = 0; i < count; ++i) out += (i ? ", " : "") + std::to_string(first + i * step);
  return out + "]";
}

// 200 kernels x 300 targets x 360 values of n: 21.6 million trials from about 8 kB of text.
std::string huge_grid(const std::string& limits = "") {
  return R"([study]
name = "huge"
evaluation_points = 2048
[domain]
radius = 4
[grid]
n = { from = 1, to = 360, step = 1 }
[[kernel]]
name = "gaussian"
sigma = )" + values(200, 0.1, 0.01) +
         R"(
[[target]]
name = "sine"
amplitude = )" + values(300, 1.0, 0.01) +
         "\n" + limits;
}

}  // namespace

TEST_CASE("a grid beyond [limits] trials is refused before it is built", "[study][limits]") {
  const auto start = std::chrono::steady_clock::now();
  const auto error = error_of(huge_grid());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(seconds < 1);
  // At the list that contributes most (n, 360 values), with the product and every list that
  // multiplies to it.
  CHECK(error ==
        "s.toml:7:5: grid.n: the grid has 21600000 trials, more than [limits] trials = 1000000: "
        "200 kernels ([[kernel]] 'gaussian' at line 8: sigma 200) x 300 targets ([[target]] "
        "'sine' at line 11: amplitude 300) x 1 centre placement (the default) x 360 values of "
        "n; shorten these lists, or raise [limits] trials");
}

TEST_CASE("[limits] trials sets the cap: the count includes every axis", "[study][limits]") {
  const std::string small = R"([study]
name = "small"
[domain]
radius = 4
[grid]
n = [8, 16, 32]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = [4, 5]
[[centres]]
name = "random"
seed = [1, 2]
)";
  // (2 + 4) kernels x 1 target x 2 placements x 3 values of n = 36 trials.
  CHECK(parse_study(small + "[limits]\ntrials = 36\n", "s.toml").trials().size() == 36);
  CHECK(error_of(small + "[limits]\ntrials = 35\n") ==
        "s.toml:10:1: kernel: the grid has 36 trials, more than [limits] trials = 35: 6 kernels "
        "([[kernel]] 'gaussian' at line 7: sigma 2; [[kernel]] 'bspline' at line 10: "
        "J 2 x degree 2) x 1 target (the default) x 2 centre placements ([[centres]] 'random' "
        "at line 14: seed 2) x 3 values of n; shorten these lists, or raise [limits] trials");
  CHECK(error_of(small + "[limits]\ntrials = 2.5\n") ==
        "s.toml:18:10: limits.trials: must be a whole number between 1 and 10000000 (every "
        "trial of the grid is held in memory, about 1.7 KB each), found 2.5");
  CHECK(error_of(small + "[limits]\ntrials = 0\n") ==
        "s.toml:18:10: limits.trials: must be a whole number between 1 and 10000000 (every "
        "trial of the grid is held in memory, about 1.7 KB each), found 0");
  // Raised to its largest, 10^7, the 21.6 million trials of the huge grid are still refused
  // by their count; a limit above that is refused itself (issue 50: under trials = 1e15 a grid
  // of 2^31 trials was valid, and run ended in std::bad_alloc at 6.6 GB).
  CHECK_THAT(error_of(huge_grid("[limits]\ntrials = 10000000\n")),
             Catch::StartsWith("s.toml:7:5: grid.n: the grid has 21600000 trials, more than "
                               "[limits] trials = 10000000: "));
  CHECK(error_of(huge_grid("[limits]\ntrials = 30000000\n")) ==
        "s.toml:15:10: limits.trials: must be a whole number between 1 and 10000000 (every "
        "trial of the grid is held in memory, about 1.7 KB each), found 30000000");
  CHECK_THAT(error_of(huge_grid("[limits]\ntrials = 1e15\n")),
             Catch::StartsWith("s.toml:15:10: limits.trials: must be a whole number between 1 "
                               "and 10000000"));
}

// Issue 50: a dotted key of 100,000 parts ("[a.a.a...]", "a.a.a... = 1") was a SIGSEGV
// (toml++ builds and destroys its tables by recursion); toml++ bounds arrays and inline
// tables itself.
TEST_CASE("TOML nesting is bounded before toml++ parses it", "[study][limits][hostile]") {
  const auto dotted = [](std::size_t parts) {
    std::string key = "a";
    for (std::size_t i = 1; i < parts; ++i) key += ".a";
    return key;
  };
  const std::string deep = "invalid TOML: keys, arrays and inline tables nested more than 256 deep";
  CHECK(error_of("[" + dotted(100000) + "]\n") == "s.toml:1:515: " + deep);
  CHECK(error_of("[[" + dotted(100000) + "]]\n") == "s.toml:1:516: " + deep);
  CHECK(error_of("x = 1\n" + dotted(100000) + " = 1\n") == "s.toml:2:514: " + deep);
  // Dotted keys inside nested inline tables add up.
  CHECK_THAT(error_of("x = { " + dotted(200) + " = { " + dotted(200) + " = 1 } }\n"),
             Catch::StartsWith("s.toml:1:") && Catch::EndsWith(deep));
  CHECK(error_of("x = " + std::string(100000, '[') + std::string(100000, ']') + "\n") ==
        "s.toml:1:261: " + deep);
  // Within the bound: toml++ parses, and the study parser names the unknown key.
  CHECK_THAT(error_of("[" + dotted(250) + "]\n"), Catch::StartsWith("s.toml:1:2: a: unknown key"));
  // Dots in strings, comments and values are no keys.
  const std::string dots(100000, '.');
  CHECK_THAT(error_of("[study] # " + dots + "\nname = \"x\"\ndescription = \"" + dots +
                      "\"\nother = '''" + dots + "'''\n"),
             Catch::StartsWith("s.toml:4:1: study.other: unknown key"));
  CHECK_THAT(error_of(huge_grid()), Catch::Contains("the grid has 21600000 trials"));
}

TEST_CASE("n ranges with huge bounds are errors, not overflows", "[study][limits]") {
  auto with_n = [](const std::string& n) {
    return error_of("[study]\nname = \"n\"\n[domain]\nradius = 4\n[grid]\nn = " + n +
                    "\n[[kernel]]\nname = \"gaussian\"\n");
  };
  CHECK(with_n("{ from = 1, to = 9223372036854775807, factor = 2 }") ==
        "s.toml:6:22: grid.n.to: must be between 1 and 1000000000 (centres), found "
        "9223372036854775807");
  CHECK(with_n("{ from = -9223372036854775808, to = 10, step = 1 }") ==
        "s.toml:6:14: grid.n.from: must be between 1 and 1000000000 (centres), found "
        "-9223372036854775808");
  CHECK(with_n("{ from = 1, to = 1000000000, step = 1 }") ==
        "s.toml:6:5: grid.n: 1000000000 values of n (from 1 to 1000000000 in steps of 1), more "
        "than 100000");
  CHECK(with_n("[8, 9223372036854775807]") ==
        "s.toml:6:9: grid.n: must be between 1 and 1000000000 (centres), found "
        "9223372036854775807");
  // A step or factor beyond the bounds gives the first value alone (v + step, v * factor
  // would overflow).
  const auto step = parse_study(
      "[study]\nname = \"n\"\nevaluation_points = 64\n[domain]\nradius = 4\n[grid]\n"
      "n = { from = 8, to = 1000000000, step = 9223372036854775807 }\n[[kernel]]\nname = "
      "\"gaussian\"\n",
      "s.toml");
  CHECK(step.n_values == std::vector<std::size_t>{8});
  const auto factor = parse_study(
      "[study]\nname = \"n\"\nevaluation_points = 64\n[domain]\nradius = 4\n[grid]\n"
      "n = { from = 3, to = 1000000000, factor = 4611686018427387904 }\n[[kernel]]\nname = "
      "\"gaussian\"\n",
      "s.toml");
  CHECK(factor.n_values == std::vector<std::size_t>{3});
  const auto doubling = parse_study(
      "[study]\nname = \"n\"\nevaluation_points = 4096\n[domain]\nradius = 4\n[grid]\n"
      "n = { from = 8, to = 1000, factor = 2 }\n[[kernel]]\nname = \"gaussian\"\n",
      "s.toml");
  CHECK(doubling.n_values == std::vector<std::size_t>{8, 16, 32, 64, 128, 256, 512});
}

TEST_CASE("a mistake beside a large grid is found before the grid is built", "[study][limits]") {
  // 100 x 100 x 100 = 1e6 targets, within the cap; expanding them takes seconds and a gigabyte.
  const std::string large = R"([study]
name = "large"
evaluation_points = 2048
[domain]
radius = 4
[grid]
n = [10]
[[kernel]]
name = "gaussian"
[[target]]
name = "sine"
amplitude = )" + values(100, 1.0, 0.01) +
                            "\nphase = " + values(100, 0.0, 0.01) +
                            "\ncycles = " + values(100, 1.0, 1.0) + "\n";
  auto timed_error = [](const std::string& text) {
    const auto start = std::chrono::steady_clock::now();
    auto error = error_of(text);
    CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 1);
    return error;
  };
  CHECK(timed_error(large + "[[centres]]\nname = \"nosuch\"\n") ==
        "s.toml:16:8: centres.name: unknown centres 'nosuch' (known: halton, passes, random, uniform)");
  CHECK(timed_error(large + "[solver]\nsingular = \"never\"\n") ==
        "s.toml:16:12: solver.singular: found \"never\", expected \"pseudo_inverse\", "
        "\"regularised\" or \"fail\"");
  CHECK(timed_error(large + "[[expect]]\nmetric = \"power_function_sup\"\namplitud = 1.0\n"
                            "rate = -1.0\ntolerance = 0.1\n") ==
        "s.toml:17:1: expect.amplitud: unknown key (an expectation takes metric, name, tier, "
        "xfail, theory, rate, tolerance, model, bound, constant, reference, n_from, n_to, h_from, "
        "h_to, "
        "last, and "
        "this study's axis columns as group "
        "selectors: kernel, sigma, convention, target, target_amplitude, target_cycles, "
        "target_phase, centres, centres_offset)");
  // A value out of range, or listed twice, in the large entry itself.
  std::string negative = large;
  negative.replace(negative.find("100.000000"), 10, "-1.000000");
  CHECK_THAT(timed_error(negative), Catch::StartsWith("s.toml:14:"));
  CHECK_THAT(timed_error(negative), Catch::Contains(": target.cycles: "));
  std::string twice = large;
  twice.replace(twice.find("1.010000"), 8, "1.000000");
  CHECK_THAT(timed_error(twice), Catch::StartsWith("s.toml:12:24: target.amplitude: 'sine amplitude=1 cycles=1 phase=0'"));
  CHECK_THAT(timed_error(twice), Catch::EndsWith("' is listed twice"));
}

TEST_CASE("a road that would need too many harmonics is refused before it is built",
          "[study][limits]") {
  const auto start = std::chrono::steady_clock::now();
  CHECK(error_of("[study]\nname = \"road\"\n[domain]\nradius = 4\n[grid]\nn = [8]\n[[kernel]]\n"
                 "name = \"gaussian\"\n[[target]]\nname = \"iso8608\"\nn_max = 1e12\n") ==
        "s.toml:11:9: target.n_max: iso8608 n_max=1e+12: 25132741228718 harmonics (n_max L) is "
        "more than 100000");
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 1);
}
