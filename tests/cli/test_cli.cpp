// The rkhs-study command as a user runs it: outputs, exit codes, error messages.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../study_data_support.hpp"
#include "cli_support.hpp"

namespace fs = std::filesystem;

namespace {

using rkhs::test::read_text;

rkhs::test::CommandOutcome run(const std::string& arguments) {
  return rkhs::test::rkhs_study(arguments);
}

std::string read(const fs::path& file) {
  return read_text(file);
}

fs::path scratch(const std::string& name) {
  return rkhs::test::scratch_directory("cli_test_" + name);
}

const char* const small_study = R"([study]
name = "cli_small"
evaluation_points = 256
[domain]
radius = 4
[grid]
n = [8, 16, 32]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 5
)";

}  // namespace

TEST_CASE("run writes trials.csv, rates.csv and a valid summary.json", "[cli]") {
  const auto dir = scratch("run");
  std::ofstream(dir / "study.toml") << small_study;
  const auto outcome = run("run " + (dir / "study.toml").string() + " --out " +
                           (dir / "out").string() + " --threads 2");
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("power_function_sup"));
  CHECK_THAT(outcome.output, Catch::Contains("fitted rate"));
  CHECK_THAT(outcome.output, Catch::Contains("cli_small: 6 trials, 6 ok, 0 failed"));

  const auto trials = read(dir / "out" / "trials.csv");
  CHECK_THAT(trials, Catch::StartsWith("kernel,degree,r,n0,J,target,target_amplitude,target_cycles,"
                                       "target_phase,centres,centres_offset,n,fill_distance,"));
  CHECK_THAT(trials, Catch::Contains(",status,reason,solve,flags\n"));
  CHECK(std::count(trials.begin(), trials.end(), '\n') == 7);
  const auto rates = read(dir / "out" / "rates.csv");
  CHECK_THAT(rates, Catch::Contains("metric,abscissa,kind,model,n_from,n_to,points,rate,std_error,"
                                    "ci_low,ci_high,r_squared,delta_aic,note"));
  CHECK_THAT(rates, Catch::Contains("power_function_sup,n,fit,power_law,8,32,3,"));
  CHECK_THAT(rates, Catch::Contains("power_function_sup,n,alternative_fit,exponential,8,32,3,"));
  CHECK_FALSE(fs::exists(dir / "out" / "journal.csv"));
  // Plots: one convergence plot per metric, as SVG (well-formed XML) and PNG.
  for (const char* metric : {"power_function_sup", "gram_condition_number"}) {
    const auto stem = dir / "out" / "plots" / (std::string("convergence_") + metric);
    INFO(stem.string());
    CHECK(fs::exists(stem.string() + ".gp"));
    CHECK(read(stem.string() + ".png").substr(0, 4) == "\x89PNG");
    CHECK(std::system(("python3 -c 'import sys, xml.etree.ElementTree as e; "
                       "assert e.parse(sys.argv[1]).getroot().tag.endswith(\"svg\")' " +
                       stem.string() + ".svg").c_str()) == 0);
  }
  CHECK(read(dir / "out" / "rates.md").find("## power_function_sup") != std::string::npos);
  // `report DIR` gives the tables of the run again, from the store.
  const auto markdown = run("report " + (dir / "out").string() + " --format md");
  CHECK(markdown.exit_code == 0);
  CHECK(markdown.output == read(dir / "out" / "rates.md"));
  CHECK(read(dir / "out" / "report.html").find("<h2>Rates</h2>") != std::string::npos);
  CHECK(run("report " + (dir / "missing").string()).exit_code == 2);
  const int json_ok = std::system(("python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); "
                                   "assert d[\"counts\"][\"trials\"]==6 and len(d[\"rates\"])>0' " +
                                   (dir / "out" / "summary.json").string())
                                      .c_str());
  CHECK(json_ok == 0);

  // The same study with one thread writes the same trials.csv, byte for byte.
  REQUIRE(run("run " + (dir / "study.toml").string() + " --quiet --out " + (dir / "one").string() +
              " --threads 1 --fresh")
              .exit_code == 0);
  CHECK(read(dir / "one" / "trials.csv") == trials);
  CHECK(read(dir / "one" / "rates.csv") == rates);
}

TEST_CASE("bad input exits with code 2 and says where", "[cli]") {
  const auto dir = scratch("bad");
  std::string text = small_study;
  text.replace(text.find("\"bspline\""), 9, "\"bsplin\"");
  std::ofstream(dir / "bad.toml") << text;
  auto outcome = run("run " + (dir / "bad.toml").string());
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("bad.toml:9:8: kernel.name: unknown kernel 'bsplin'"));
  CHECK_THAT(outcome.output, Catch::Contains("did you mean 'bspline'?"));

  CHECK(run("run " + (dir / "missing.toml").string()).exit_code == 2);
  CHECK(run("run").exit_code == 2);
  CHECK(run("frobnicate").exit_code == 2);
  CHECK(run("run " + (dir / "bad.toml").string() + " --threads 0").exit_code == 2);
  CHECK(run("list nonsense").exit_code == 2);
}

TEST_CASE("list shows plugins with parameters and docs; --help works", "[cli]") {
  auto outcome = run("list kernel");
  CHECK(outcome.exit_code == 0);
  for (const char* expected : {"bspline", "gaussian", "matern", "wendland", "sigma", "degree"})
    CHECK_THAT(outcome.output, Catch::Contains(expected));
  // Defaults and ranges, worded as in error messages.
  CHECK_THAT(outcome.output, Catch::Contains("(default 1; in [0, 3])"));
  CHECK_THAT(outcome.output, Catch::Contains("(default 1; > 0)"));
  CHECK_THAT(outcome.output, Catch::Contains("(default 1.5; one of 0.5, 1.5, 2.5)"));
  CHECK_THAT(outcome.output, Catch::Contains("(default 2sigma2; one of 2sigma2, sigma2)"));
  outcome = run("list integrator");
  CHECK(outcome.exit_code == 0);
  for (const char* expected : {"rosenbrock4", "rodas4", "dopri5", "rk_fehlberg78", "rk4", "rtol"})
    CHECK_THAT(outcome.output, Catch::Contains(expected));
  outcome = run("list");
  for (const char* expected : {"quarter_car", "linear", "gradient", "rkhs", "lyapunov_max_increase"})
    CHECK_THAT(outcome.output, Catch::Contains(expected));
  CHECK_THAT(outcome.output, Catch::Contains("uniform"));
  CHECK_THAT(outcome.output, Catch::Contains("power_function_sup"));
  for (const char* help : {"--help", "run --help", "list --help", "validate --help"}) {
    outcome = run(help);
    CHECK(outcome.exit_code == 0);
    CHECK_THAT(outcome.output, Catch::Contains("Usage"));
  }
}

TEST_CASE("the project's studies are valid", "[cli]") {
  // As a user runs them: from the repository's root, with the data root's default (the measured
  // roads of studies/belgian_block*.toml are in studies/data/) and no RKHS_STUDY_DATA.
  rkhs::testing::require_study_data();
  for (const auto& entry : fs::directory_iterator(fs::path(RKHS_STUDY_SOURCE_DIR) / "studies")) {
    if (entry.path().extension() != ".toml") continue;
    const auto outcome =
        rkhs::test::run_command("cd " + std::string(RKHS_STUDY_SOURCE_DIR) +
                                " && env -u RKHS_STUDY_DATA " RKHS_STUDY_EXECUTABLE " validate " +
                                "studies/" + entry.path().filename().string());
    INFO(outcome.output);
    CHECK(outcome.exit_code == 0);
  }
}
