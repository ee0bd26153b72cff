// The [domain] table in R^d: lengths = [...] gives a box or a torus, and what cannot run on it
// (one-dimensional plugins, adaptive studies, a grid of n that is no m^d, a coarse evaluation
// grid) is refused at the line and column that say it.
#include <catch2/catch.hpp>
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

std::string planar(const std::string& domain, const std::string& rest = "") {
  return R"([study]
name = "planar"
evaluation_points = 4096
[domain]
)" + domain +
         R"(
[grid]
n = [16, 64]
[[kernel]]
name = "wendland"
[[target]]
name = "expression"
f = "x1 * x2"
)" + rest;
}

}  // namespace

TEST_CASE("lengths = [...] makes a box or a torus of that many dimensions", "[study][rd]") {
  const auto study = parse_study(planar("lengths = [2.0, 3]\nperiodic = false"), "s.toml");
  CHECK(study.domain.dimension == 2);
  CHECK(study.domain.length == 2.0);
  CHECK(study.domain.width == 3.0);
  CHECK_FALSE(study.domain.periodic);
  auto text = planar("lengths = [1, 1, 1]", "[[centres]]\nname = \"halton\"\n");
  text.replace(text.find("x1 * x2"), 7, "x1 * x3");
  const auto space = parse_study(text, "s.toml");
  CHECK(space.domain.dimension == 3);
  CHECK(space.domain.periodic);
}

TEST_CASE("a domain in R^d that is malformed or cannot run is refused where it is written",
          "[study][rd]") {
  CHECK(error_of(planar("lengths = []")) ==
        "s.toml:5:11: domain.lengths: expected a list of 1 to 3 extents in metres (one per axis), "
        "found []");
  CHECK(error_of(planar("lengths = [1, 1, 1, 1]"))
            .starts_with("s.toml:5:11: domain.lengths: expected a list of 1 to 3 extents"));
  CHECK_THAT(error_of(planar("lengths = [1, -2]")),
             Catch::StartsWith("s.toml:5:15: domain.lengths: axis 2: must be between 1e-100 and "));
  CHECK_THAT(error_of(planar("lengths = [1, \"wide\"]")),
             Catch::StartsWith("s.toml:5:15: domain.lengths: axis 2: expected an extent in metres "
                               "(a number between 1e-100 and "));
  CHECK(error_of(planar("lengths = [1, 1]\nlength = 1"))
            .starts_with("s.toml:4:1: domain: give exactly one of 'length' (metres), 'radius'"));
  // One-dimensional plugins.
  const auto sine = planar("lengths = [1, 1]");
  CHECK_THAT(
      error_of(std::string(sine).replace(sine.find("expression\"\nf = \"x1 * x2\""), 26, "sine\"")),
      Catch::Contains("s.toml:10:1: target: sine: target 'sine' is a "
                      "function of the arc length s (d = 1); this domain has d = 2"));
  // s, the arc length of a track, names the point's coordinates of this domain instead.
  CHECK_THAT(error_of(std::string(sine).replace(sine.find("x1 * x2"), 7, "sin(s)")),
             Catch::EndsWith("found the unknown name \"s\", expected a variable or constant (x1, "
                             "x2, L1, L2, pi) or a function (s is not a variable on this domain "
                             "(d = 2): f reads its point as x1, x2)"));
  // A grid of n that is no square.
  const auto grid = planar("lengths = [1, 1]");
  CHECK_THAT(error_of(std::string(grid).replace(grid.find("[16, 64]"), 8, "[16, 20]")),
             Catch::Contains(
                 "s.toml:7:5: grid.n: centres uniform: centres 'uniform' in d = 2 place a grid "
                 "of m^2 centres; n = 20 is not such a number (nearest: 16, 25)"));
  // Every n that is no square, located once.
  const auto message =
      error_of(std::string(grid).replace(grid.find("[16, 64]"), 8, "[10, 16, 20]"));
  CHECK_THAT(message, Catch::StartsWith("s.toml:7:5: grid.n: centres uniform: 2 values of n "
                                        "cannot be placed: centres 'uniform' in d = 2"));
  CHECK_THAT(message, Catch::Contains("n = 10 is not such a number (nearest: 9, 16); ") &&
                          Catch::EndsWith("n = 20 is not such a number (nearest: 16, 25)"));
  CHECK(message.find("s.toml", 1) == std::string::npos);
  // An adaptive study in d = 2 needs a plant whose f reads out 2 coordinates: a road plant
  // (quarter_car, the default) runs along a track.
  CHECK_THAT(error_of("[study]\nname = \"a\"\nkind = \"adaptive\"\n[domain]\nlengths = [1, 1]\n"
                      "[grid]\nn = [16]\n[[kernel]]\nname = \"wendland\"\n[[target]]\n"
                      "name = \"expression\"\nf = \"x1 * x2\"\n[adaptive]\nlaps = 1\n"),
             Catch::Contains("s.toml:") && Catch::Contains("quarter_car") &&
                 Catch::Contains("along a track (d = 1), and the domain has d = 2"));
  // An evaluation grid no finer than the centres: 64 points (8 per axis) for 64 centres.
  auto coarse = planar("lengths = [1, 1]");
  coarse.replace(coarse.find("4096"), 4, "64");
  CHECK_THAT(error_of(coarse),
             Catch::Contains("study.evaluation_points: 64 evaluation points (8 per axis of d = 2) "
                             "for up to n = 64 centres (8 per axis)"));
}
