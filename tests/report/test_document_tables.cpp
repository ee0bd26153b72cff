// Golden-file tests of the Markdown and LaTeX rate tables (rates.md, rates.tex). The study's
// metrics are exact functions of n (fill and separation distances of uniform centres), so the
// files are the same on every platform. To update after a deliberate format change, run this
// test with RKHS_UPDATE_GOLDEN=1 and review the diff.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>
#include <fstream>

#include "cli_support.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/verify/study_rates.hpp"

using namespace rkhs;

TEST_CASE("Markdown and LaTeX rate tables match their golden files", "[output]") {
  const auto study = parse_study(R"([study]
name = "golden"
evaluation_points = 64
metrics = ["fill_distance", "separation_distance"]
[domain]
length = 10.0
[grid]
n = [4, 8, 16, 32]
[[kernel]]
name = "bspline"
degree = 1
J = 2
)", "golden.toml");
  const auto trials = study.trials();
  const auto results = run_trials(study, trials, {1});
  const auto rates = compute_rates(study, trials, results);
  const RunRecord record{study, trials, results, rates, 1, 0.0, "2026-01-01T00:00:00Z"};
  const std::string golden_dir = std::string(RKHS_STUDY_SOURCE_DIR) + "/tests/golden/";
  for (const auto& [file, text] : {std::pair{std::string("rates.md"), markdown_tables(record)},
                                   std::pair{std::string("rates.tex"), latex_tables(record)}}) {
    INFO(file);
    if (std::getenv("RKHS_UPDATE_GOLDEN")) std::ofstream(golden_dir + file) << text;
    CHECK(text == rkhs::test::read_text(golden_dir + file));
  }
}
