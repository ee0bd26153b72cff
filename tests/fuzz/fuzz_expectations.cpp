// libFuzzer harness: [[expect]] tables (framework/src/study/expectation_parser.cpp) read from
// arbitrary bytes. The input follows a fixed, valid study header (an approximation study, or an
// adaptive one when the input starts with the line "#adaptive") whose grid has several values on
// every axis, so that selectors, metrics, tiers and every kind of expectation can select
// something; the whole is parsed by rkhs::parse_study, and a study that parses is restricted to
// each tier it names (rkhs::restrict_to_tier, what `check --tier` does) when its grid is small.
// Refusals are StudyError, the one exception both document; anything else is a bug. What parses
// must hold what the parser promises: known metrics, positive finite tolerances and constants,
// an interval whose minimum is not above its maximum, an xfail reason that is not blank; and
// its test cases must have names unique within the study.
//
// Inputs that name `plugins` are skipped, as in fuzz_study_file.cpp (no dlopen of what a
// mutation names).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <set>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/tiers.hpp"
#include "rkhs/verify/expectation_cases.hpp"

namespace {

constexpr std::string_view approximation_study = R"([study]
name = "fuzz_expectations"
kind = "approximation"
evaluation_points = 64
[domain]
radius = 4.0
[grid]
n = [8, 16]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
tier = "quick"
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 4
[[target]]
name = "sine"
amplitude = [1.0, 2.0]
[[centres]]
name = "uniform"
[[centres]]
name = "random"
seed = [1, 2]
tier = ["quick", "full"]
)";

constexpr std::string_view adaptive_study = R"([study]
name = "fuzz_expectations"
kind = "adaptive"
evaluation_points = 64
[domain]
radius = 4.0
[grid]
n = [8, 16]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 4
tier = "quick"
[[target]]
name = "sine"
[[plant]]
name = "quarter_car"
[[law]]
name = "gradient"
gamma = [1e-3, 1.0]
[[law]]
name = "rkhs"
gamma = 1.0
[[integrator]]
name = "rk4"
[adaptive]
laps = [1, "limit"]
)";

constexpr std::string_view adaptive_marker = "#adaptive\n";

bool listed(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// What read_expectations promises of every expectation of a study that parses.
void check(const rkhs::StudyDefinition& study) {
  for (const auto& e : study.expectations) {
    if (!listed(study.metrics, e.metric)) std::abort();
    if (!(e.tolerance > 0) || !std::isfinite(e.tolerance)) std::abort();
    if (e.kind == rkhs::ExpectationKind::rate && e.interval.low > e.interval.high) std::abort();
    if (e.kind == rkhs::ExpectationKind::bound) {
      if (!(e.bound.constant > 0) || !std::isfinite(e.bound.constant)) std::abort();
      if (!e.bound.by.empty() && !listed(study.metrics, e.bound.by)) std::abort();
      if (!e.bound.times.empty() && (e.bound.by.empty() || !listed(study.metrics, e.bound.times)))
        std::abort();
    }
    if (!e.xfail.empty() && e.xfail.find_first_not_of(" \t") == std::string::npos) std::abort();
    (void)e.selector_text();
  }
}

// The test cases of `check` have names unique within the study (expectation_cases.hpp).
void check_case_names(const rkhs::StudyDefinition& study) {
  std::set<std::string> names;
  for (const auto& c : rkhs::expectation_cases(study, study.trials()))
    if (!names.insert(c.name).second) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  if (input.find("plugins") != std::string_view::npos) return 0;
  const bool adaptive = input.starts_with(adaptive_marker);
  std::string text(adaptive ? adaptive_study : approximation_study);
  text += input.substr(adaptive ? adaptive_marker.size() : 0);
  try {
    const auto study = rkhs::parse_study(text, "fuzz.toml");
    check(study);
    std::size_t trials = 1;
    for (const auto& axis : study.grid_axes()) trials *= axis.count;
    if (trials > 2000) return 0;  // restrict_to_tier builds the grid
    check_case_names(study);
    for (const auto& tier : rkhs::study_tiers(study)) {
      try {
        check(rkhs::restrict_to_tier(study, tier));
      } catch (const rkhs::StudyError&) {
        // A tier in which an expectation selects nothing.
      }
    }
  } catch (const rkhs::StudyError&) {
    // A refusal is a correct answer to a malformed table.
  } catch (const std::exception& e) {
    rkhs::fuzz::unexpected_exception(e);
  }
  return 0;
}
