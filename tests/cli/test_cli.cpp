// The rkhs-study command as a user runs it: outputs, exit codes, error messages.
#include <sys/stat.h>
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../study_data_support.hpp"
#include "cli_support.hpp"
#include "rkhs/study/study.hpp"

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
  // The floors of the metrics that have one follow the status columns (docs/results.md);
  // fill_distance is exact and has none.
  CHECK_THAT(trials, Catch::Contains(",status,reason,solve,flags,gram_condition_number_floor,"));
  CHECK_THAT(trials, Catch::Contains(",projection_operator_norm_floor\n"));
  CHECK_THAT(trials, !Catch::Contains("fill_distance_floor"));
  CHECK(std::count(trials.begin(), trials.end(), '\n') == 7);
  {
    // Rows in grid order (degree, n) although trials start largest first (n = 32 first).
    const auto grid = rkhs::parse_study(small_study, "study.toml").trials();
    std::istringstream rows(trials);
    std::string line;
    std::getline(rows, line);  // header: kernel,degree,...,n,...
    std::vector<std::string> seen, expected;
    while (std::getline(rows, line)) {
      std::vector<std::string> fields;
      std::istringstream in(line);
      for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
      REQUIRE(fields.size() > 11);
      seen.push_back(fields[1] + " " + fields[11]);  // degree, n
    }
    for (const auto& trial : grid)
      expected.push_back(rkhs::format_real(trial.kernel.parameters.real("degree")) + " " +
                         std::to_string(trial.n));
    CHECK(seen == expected);
    CHECK(expected.front() == "1 8");
  }
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
  CHECK(read(dir / "out" / "rates.md").find(" power_function_sup | rate |") != std::string::npos);
  // `report DIR` gives the tables of the run again, from DIR/summary.json.
  const auto markdown = run("report " + (dir / "out").string() + " --format md");
  CHECK(markdown.exit_code == 0);
  CHECK(markdown.output == read(dir / "out" / "rates.md"));
  // --format text: the console's tables, every group's.
  const auto text = run("report " + (dir / "out").string() + " --format text");
  CHECK(text.exit_code == 0);
  CHECK(text.output.find("power_function_sup, fitted rate: ") != std::string::npos);
  CHECK(text.output.find("\nfit ") != std::string::npos);
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

TEST_CASE("report reads a results folder and runs, loads and stores nothing it names",
          "[cli][report]") {
  const auto dir = scratch("report_reads_only");
  {
    std::ofstream(dir / "study.toml") << small_study;
  }
  REQUIRE(run("run " + (dir / "study.toml").string() + " --out " + (dir / "out").string() +
              " --no-store --no-plots --quiet")
              .exit_code == 0);
  const auto markdown_of_run = read(dir / "out" / "rates.md");
  // The folder now names a study that loads a plugin, a library whose loading creates a marker
  // file (tests/plugin/modules/writes_marker.cpp), and the plugin path holds it too.
  const auto library = fs::path(RKHS_TEST_PLUGIN_DIR) / "writes_marker.so";
  REQUIRE(fs::exists(library));
  fs::create_directories(dir / "plugins");
  fs::copy_file(library, dir / "plugins" / "writes_marker.so");
  {
    std::ofstream(dir / "hostile.toml") << "plugins = [\"" << library.string() << "\"]\n"
                                        << small_study;
  }
  auto summary = read(dir / "out" / "summary.json");
  const auto source = "\"source\": \"" + (dir / "study.toml").string() + "\"";
  REQUIRE(summary.find(source) != std::string::npos);
  summary.replace(summary.find(source), source.size(),
                  "\"source\": \"" + (dir / "hostile.toml").string() + "\"");
  {
    std::ofstream(dir / "out" / "summary.json", std::ios::trunc) << summary;
  }
  const auto marker = dir / "loaded";
  const auto environment = "cd " + dir.string() + " && RKHS_TEST_LOAD_MARKER=" + marker.string() +
                           " RKHS_STUDY_PLUGIN_PATH=" + (dir / "plugins").string();
  // The marker works: loading the library (verify-plugin, then refused) creates it.
  CHECK(rkhs::test::rkhs_study("verify-plugin " + library.string(), environment).exit_code == 2);
  CHECK(fs::exists(marker));
  fs::remove(marker);
  for (const char* format : {"md", "tex", "text", "html"}) {
    const auto report = rkhs::test::rkhs_study(
        "report " + (dir / "out").string() + " --format " + format, environment);
    INFO(format << ": " << report.output);
    CHECK(report.exit_code == 0);
    CHECK_FALSE(fs::exists(marker));
    if (std::string(format) == "md") CHECK(report.output == markdown_of_run);
  }
  // No result store in the current directory, nor anywhere in the folder.
  CHECK_FALSE(fs::exists(dir / "results"));
  // Plots that are links to other files of this machine, or FIFOs, are not embedded in
  // report.html (nor waited on): only the folder's own regular files are.
  {
    std::ofstream(dir / "secret.txt") << "SECRET-NOT-FOR-THE-PAGE\n";
  }
  fs::create_directories(dir / "out" / "plots");
  fs::create_symlink(dir / "secret.txt", dir / "out" / "plots" / "convergence_power_function_sup.svg");
  fs::create_symlink(dir / "secret.txt", dir / "out" / "plots" / "estimates_link.svg");
  REQUIRE(mkfifo((dir / "out" / "plots" / "estimates_fifo.svg").c_str(), 0600) == 0);
  const auto page = rkhs::test::run_command("timeout 60 " + std::string(RKHS_STUDY_EXECUTABLE) +
                                            " report " + (dir / "out").string());
  INFO(page.output);
  CHECK(page.exit_code == 0);
  CHECK(read(dir / "out" / "report.html").find("<img") == std::string::npos);
  fs::remove_all(dir / "out" / "plots");
  // A study file that cannot be parsed is not read either.
  {
    std::ofstream(dir / "hostile.toml", std::ios::trunc) << "[[[ not toml\n";
  }
  CHECK(rkhs::test::rkhs_study("report " + (dir / "out").string() + " --format md", environment)
            .output == markdown_of_run);
  // --store and --fresh are gone: there is no store to name.
  CHECK(run("report " + (dir / "out").string() + " --store x.sqlite").exit_code == 2);

  // A summary.json that is not what a run writes is refused, naming where.
  // `content` "": the file as it is.
  const auto refused = [&](const std::string& content, const std::string& message) {
    if (!content.empty()) std::ofstream(dir / "out" / "summary.json", std::ios::trunc) << content;
    const auto report = run("report " + (dir / "out").string() + " --format md");
    INFO(report.output);
    CHECK(report.exit_code == 2);
    CHECK_THAT(report.output, Catch::Contains(message));
  };
  auto wrong_type = summary;
  const auto metric = wrong_type.find("\"power_function_sup\": ");
  REQUIRE(metric != std::string::npos);
  wrong_type.insert(metric + std::string("\"power_function_sup\": ").size(), "\"fast\", \"x\": ");
  refused(wrong_type, "summary.json: trials[0].metrics.power_function_sup: expected a number, "
                      "\"inf\", \"-inf\" or null; found a string");
  refused("{\n  \"study\": \"x\",\n  oops\n}\n", "summary.json:3:3: not JSON");
  refused("[]", "summary.json: (top level): expected an object; found an array");
  refused("{\"study\": \"x\"}", "summary.json: kind: missing");
  // Larger than read_results_folder reads: refused by its size, unread (a sparse file).
  fs::resize_file(dir / "out" / "summary.json", std::uintmax_t{300} << 20);
  refused("", "summary.json: 314572800 bytes; at most 268435456 bytes are read");
  fs::remove(dir / "out" / "summary.json");
  fs::create_directory(dir / "out" / "summary.json");
  const auto directory = run("report " + (dir / "out").string() + " --format md");
  CHECK(directory.exit_code == 2);
  CHECK_THAT(directory.output, Catch::Contains("summary.json: not a regular file (a directory)"));
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

TEST_CASE("list shows plugins with parameters and docs: --help works", "[cli]") {
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

TEST_CASE("validate names every axis of the grid, in words that agree in number", "[cli]") {
  const auto manufactured = run("validate " + std::string(RKHS_STUDY_SOURCE_DIR) +
                                "/studies/manufactured.toml");
  INFO(manufactured.output);
  CHECK(manufactured.exit_code == 0);
  CHECK_THAT(manufactured.output,
             Catch::Contains("valid; 1 kernel x 1 target x 1 centre placement x 1 plant x 2 "
                             "learning laws x 1 integrator x 4 values of n = 8 trials"));
  const auto dir = scratch("validate_axes");
  std::ofstream(dir / "study.toml") << small_study;
  const auto small = run("validate " + (dir / "study.toml").string());
  CHECK_THAT(small.output,
             Catch::Contains("valid; 2 kernels x 1 target x 1 centre placement x 3 values of n = "
                             "6 trials"));
  const auto one_thread = run("run " + (dir / "study.toml").string() + " --threads 1 --no-store " +
                              "--no-plots --out " + (dir / "out").string());
  CHECK_THAT(one_thread.output, Catch::Contains("cli_small (6 trials, 1 thread) -> "));
}

TEST_CASE(
    "validate names the trials above limits.matrix_megabytes from the counts, and run fails "
    "them before building anything",
    "[cli][limits]") {
  // n = 20000 with 80000 points: 8 (3 n^2 + 2 n E) bytes = 33569 MB, above a limit of 100 MB;
  // n = 10 is within it. validate answers from the counts alone (exit 1, the exit of the run),
  // and the run fails that one trial up front and runs the other.
  const auto dir = scratch("validate_matrix_limit");
  std::ofstream(dir / "study.toml") << R"([study]
name = "matrix_limit"
evaluation_points = 80000
metrics = ["l2_error"]
[domain]
radius = 4
[grid]
n = [10, 20000]
[[kernel]]
name = "gaussian"
sigma = 0.5
[[target]]
name = "sine"
[limits]
matrix_megabytes = 100
)";
  const auto validated = run("validate " + (dir / "study.toml").string());
  INFO(validated.output);
  CHECK(validated.exit_code == 1);
  CHECK_THAT(validated.output,
             Catch::Contains("limits: 1 trial of n = 20000 needs more than "
                             "limits.matrix_megabytes = 100 MB of matrices (the largest, n = "
                             "20000 with 80000 evaluation points, dense: the n x n Gram matrix "
                             "three times and two n x E matrices: 33569 MB)"));
  const auto ran = run("run " + (dir / "study.toml").string() + " --no-store --no-plots --out " +
                       (dir / "out").string());
  INFO(ran.output);
  CHECK(ran.exit_code == 1);
  CHECK_THAT(read_text(dir / "out" / "trials.csv"),
             Catch::Contains("needs 33569 MB of matrices (dense: the n x n Gram matrix three "
                             "times and two n x E matrices), above "
                             "limits.matrix_megabytes = 100"));
}

TEST_CASE(
    "validate predicts a sparse trial's footprint from its nonzeros: a 3-D study at n = 10^6 is "
    "refused with its estimate, n = 4096 is not",
    "[cli][limits][sparse]") {
  // Wendland phi_{3,1} of support radius 0.05 on the unit cube, solver "sparse": at n = 10^6
  // (spacing 0.01) about 520 neighbours a centre, 5.2e8 nonzeros in G; the dense estimate of
  // the same trial would be 2.3e7 MB. Nothing is built: validate answers at once.
  const auto dir = scratch("validate_sparse_limit");
  std::ofstream(dir / "study.toml") << R"([study]
name = "sparse_limit"
evaluation_points = 1030301
metrics = ["power_function_sup", "l2_error"]
[domain]
lengths = [1.0, 1.0, 1.0]
periodic = false
[grid]
n = [4096, 1000000]
[linear_algebra]
solver = "sparse"
[[kernel]]
name = "wendland"
k = 1
radius = 0.05
[[target]]
name = "expression"
f = "x1 * x2 * x3"
[limits]
matrix_megabytes = 8192
)";
  const auto validated = run("validate " + (dir / "study.toml").string());
  INFO(validated.output);
  CHECK(validated.exit_code == 1);
  CHECK_THAT(validated.output,
             Catch::Contains("limits: 1 trial of n = 1000000 needs more than "
                             "limits.matrix_megabytes = 8192 MB of matrices (the largest, n = "
                             "1000000 with 1030301 evaluation points, sparse: 5.2e+08 nonzeros "
                             "in G, "));
  CHECK_THAT(validated.output, Catch::Contains("in its Cholesky factor (predicted): "));
}

TEST_CASE("validate and run say which metrics a trial will compute", "[cli][work]") {
  const auto iso = run("validate " + std::string(RKHS_STUDY_SOURCE_DIR) + "/studies/iso8608.toml");
  CHECK(iso.exit_code == 0);
  CHECK_THAT(iso.output, Catch::Contains("metrics computed: gram_condition_number, "
                                         "power_function_sup, l2_error, sup_error (4 of 13)"));
  // Rates against h need the fill distance, theory expectations the centres' quasi-uniformity.
  const auto scattered =
      run("validate " + std::string(RKHS_STUDY_SOURCE_DIR) + "/studies/scattered_centres.toml");
  CHECK_THAT(scattered.output, Catch::Contains("metrics computed: fill_distance, "
                                               "separation_distance, gram_condition_number"));
  const auto all = run("validate " + std::string(RKHS_STUDY_SOURCE_DIR) +
                       "/studies/gram_and_power.toml");
  CHECK_THAT(all.output, Catch::Contains("metrics computed: all 13 of an approximation trial"));
}

TEST_CASE("an evaluation grid that cannot measure the metrics is refused or warned", "[cli]") {
  const auto dir = scratch("evaluation_grid");
  std::string coarse = small_study;
  coarse.replace(coarse.find("evaluation_points = 256"), 23, "evaluation_points = 100");
  std::ofstream(dir / "coarse.toml") << coarse;
  const auto warned = run("validate " + (dir / "coarse.toml").string());
  CHECK(warned.exit_code == 0);
  CHECK_THAT(warned.output,
             Catch::Contains("coarse.toml:3:21: study.evaluation_points: warning: 100 evaluation "
                             "points give fewer than 4 per centre spacing for n > 25"));
  std::string aliased = small_study;
  aliased.replace(aliased.find("evaluation_points = 256"), 23, "evaluation_points = 32");
  std::ofstream(dir / "aliased.toml") << aliased;
  for (const std::string command : {"validate ", "run --no-store "}) {
    const auto refused = run(command + (dir / "aliased.toml").string());
    INFO(refused.output);
    CHECK(refused.exit_code == 2);
    CHECK_THAT(refused.output,
               Catch::Contains("aliased.toml:3:21: study.evaluation_points: 32 evaluation points "
                               "for up to n = 32 centres: the grid is no finer than the centres"));
  }
}

TEST_CASE("a CSV line with more fields than its header is refused by validate", "[cli]") {
  const auto dir = scratch("csv_fields");
  fs::create_directories(dir / "data");
  std::ofstream(dir / "data" / "road.csv") << "u_m,z_m\n0.0000,2.131593\n0.0900,0,243774178082\n"
                                              "10.0,2.14\n";
  std::ofstream(dir / "road.toml") << R"([study]
name = "csv_fields"
evaluation_points = 512
[domain]
length = 10.0
periodic = false
[grid]
n = [8, 16]
[[kernel]]
name = "bspline"
degree = 1
[[target]]
name = "csv"
file = "road.csv"
)";
  const auto outcome = run("validate --data-dir " + (dir / "data").string() + " " +
                           (dir / "road.toml").string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("road.csv:3:10: 3 fields where line 1 has 2 (u_m, "
                                             "z_m): a decimal comma (0,5 for 0.5)"));
}

namespace {

// A small adaptive study whose road is f itself (not in H_n): coefficient_error has no value.
const char* const target_road_study = R"([study]
name = "cli_target_road"
kind = "adaptive"
evaluation_points = 256
metrics = ["coefficient_error", "l2_error", "final_state_error"]
[domain]
radius = 4.0
[grid]
n = [6, 8, 10]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
gamma = 0.1
[adaptive]
speed = 0.1
laps = 1
road = "target"
samples_per_lap = 20
snapshot_laps = [1]
snapshot_points = 64
)";

}  // namespace

TEST_CASE("plots: an empty series gets a note, and one failed plot does not stop the others",
          "[cli]") {
  const auto dir = scratch("plots_empty");
  std::ofstream(dir / "study.toml") << target_road_study;
  const auto outcome = run("run " + (dir / "study.toml").string() + " --no-store --out " +
                           (dir / "out").string());
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  CHECK_THAT(outcome.output, Catch::Contains("note: convergence_coefficient_error: not plotted: no "
                                             "trial has a finite positive coefficient_error"));
  CHECK_THAT(outcome.output, !Catch::Contains("warning"));
  const auto plots = dir / "out" / "plots";
  CHECK_FALSE(fs::exists(plots / "convergence_coefficient_error.gp"));
  for (const char* stem : {"convergence_l2_error", "convergence_final_state_error",
                           "estimates_group1", "state_error_group1", "lyapunov_group1"})
    CHECK(fs::exists(plots / (std::string(stem) + ".svg")));

  // A gnuplot that fails on one script, as the real one does, and renders the rest.
  const auto bin = dir / "bin";
  fs::create_directories(bin);
  const auto real = rkhs::test::run_command("command -v gnuplot").output;
  std::ofstream(bin / "gnuplot")
      << "#!/bin/sh\ncase \"$1\" in\n  *convergence_l2_error.gp)\n"
         "    echo '\"'\"$1\"'\", line 12: x range is invalid' >&2; exit 1;;\nesac\nexec "
      << real.substr(0, real.find('\n')) << " \"$@\"\n";
  fs::permissions(bin / "gnuplot", fs::perms::owner_all);
  // Into the same folder: what the first run rendered must not pass for this run's plots.
  const auto failing = rkhs::test::rkhs_study(
      "run " + (dir / "study.toml").string() + " --no-store --out " + (dir / "out").string(),
      "PATH=" + bin.string() + ":$PATH");
  INFO(failing.output);
  REQUIRE(failing.exit_code == 0);
  // gnuplot runs in plots/ and names the script as it was given, without its folder.
  CHECK_THAT(failing.output, Catch::Contains("warning: plot not rendered: " +
                                             (dir / "out" / "plots").string() +
                                             "/convergence_l2_error.gp: "
                                             "\"convergence_l2_error.gp\", line 12: x range is "
                                             "invalid"));
  CHECK_THAT(failing.output, !Catch::Contains("is gnuplot installed"));
  CHECK_FALSE(fs::exists(dir / "out" / "plots" / "convergence_l2_error.svg"));
  for (const char* stem : {"convergence_final_state_error", "estimates_group1", "lyapunov_group1"})
    CHECK(fs::exists(dir / "out" / "plots" / (std::string(stem) + ".svg")));
  const auto report = read(dir / "out" / "report.html");
  CHECK(report.find("alt=\"convergence of l2_error\"") == std::string::npos);  // it failed
  CHECK(report.find("alt=\"convergence of final_state_error\"") != std::string::npos);
  // --no-plots: the page embeds no plot, not even those left in plots/.
  REQUIRE(run("run " + (dir / "study.toml").string() + " --no-store --no-plots --out " +
              (dir / "out").string())
              .exit_code == 0);
  CHECK(read(dir / "out" / "report.html").find("<img") == std::string::npos);
}

TEST_CASE("the expression target: listed with its parameters, refused or noted by validate",
          "[cli][expression]") {
  const auto listed = run("list target");
  CHECK(listed.exit_code == 0);
  CHECK_THAT(listed.output, Catch::Contains("  expression f(s) written in the study file as an "
                                            "expression of the arc length s\n"));
  CHECK_THAT(listed.output, Catch::Contains("    f              f(s), an expression of the arc "
                                            "length s"));
  CHECK_THAT(listed.output, Catch::Contains("(default none: required)\n    <name>         any "
                                            "other key: a constant f reads by that name, e.g. a "
                                            "= 2 (a list is an axis) (a number)\n"));
  const auto dir = scratch("expression_target");
  const std::string header = R"([study]
name = "cli_expression"
evaluation_points = 256
[domain]
radius = 4.0
[grid]
n = [8, 16]
[[kernel]]
name = "gaussian"
[[target]]
name = "expression"
)";
  std::ofstream(dir / "typo.toml") << header << "f = \"2 * sin(2 * pi * s / L\"\n";
  const auto refused = run("validate " + (dir / "typo.toml").string());
  INFO(refused.output);
  CHECK(refused.exit_code == 2);
  CHECK_THAT(refused.output,
             Catch::Contains("typo.toml:12:5: target.f: expression f=2 * sin(2 * pi * s / L: at "
                             "the end of f = \"2 * sin(2 * pi * s / L\": found the end of the "
                             "expression, expected \")\""));
  std::ofstream(dir / "ramp.toml") << header << "f = \"a * s\"\na = [1, 2]\n";
  const auto noted = run("validate " + (dir / "ramp.toml").string());
  INFO(noted.output);
  CHECK(noted.exit_code == 0);
  CHECK_THAT(noted.output, Catch::Contains("ramp.toml:10:1: target: note: f = \"a * s\" is not "
                                           "periodic on the closed track"));
  CHECK_THAT(noted.output, Catch::Contains("valid; 1 kernel x 2 targets x 1 centre placement x 2 "
                                           "values of n = 4 trials"));
}

TEST_CASE("a constant series is reported as its value and band, by run and by report alike",
          "[cli][constant]") {
  const auto dir = scratch("constant");
  std::ofstream(dir / "study.toml") << R"([study]
name = "cli_constant"
metrics = ["power_function_sup", "projection_operator_norm"]
evaluation_points = 256
[domain]
radius = 4
[grid]
n = [8, 16, 32, 64]
[[kernel]]
name = "bspline"
degree = 1
J = 6
)";
  const auto outcome = run("run " + (dir / "study.toml").string() + " --out " +
                           (dir / "out").string() + " --no-store --tables");
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  // An interpolation's operator norm is 1 within its floors: constant, not a rate.
  CHECK_THAT(outcome.output,
             Catch::Contains("projection_operator_norm, constant 1.") &&
                 Catch::Contains("(within the values' floors) on n = 8..64, not a rate"));
  const auto rates = read(dir / "out" / "rates.csv");
  CHECK_THAT(rates, Catch::Contains(",value,band,value_floor\n"));
  CHECK_THAT(rates, Catch::Contains("projection_operator_norm,n,fit,constant,8,64,4,"));
  CHECK_THAT(read(dir / "out" / "summary.json"), Catch::Contains("\"constant\": {\"value\": 1"));
  // report DIR rebuilds the same tables from summary.json, constants included.
  const auto markdown = run("report " + (dir / "out").string() + " --format md");
  CHECK(markdown.exit_code == 0);
  CHECK_THAT(markdown.output, Catch::Contains("projection_operator_norm: constant 1."));
  CHECK(markdown.output == read(dir / "out" / "rates.md"));
}
