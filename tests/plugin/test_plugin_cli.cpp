// Plugins from the command line and from study files: --plugin (repeatable) on run, validate and
// list, RKHS_STUDY_PLUGIN_PATH, `plugins = [...]` relative to the study file, verify-plugin.
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "plugin_test_support.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/study/study.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = rkhs::test::CommandOutcome;

Outcome run(const std::string& arguments, const std::string& environment = "") {
  return rkhs::test::rkhs_study(arguments, environment);
}

fs::path scratch(const std::string& name) {
  return rkhs::test::scratch_directory("plugin_cli_test_" + name);
}

const fs::path plugin_dir = RKHS_TEST_PLUGIN_DIR;
const fs::path imq = plugin_dir / "inverse_multiquadric.so";

std::string study_using(const std::string& plugins_line) {
  return plugins_line + R"(
[study]
name = "imq_small"
evaluation_points = 256
[domain]
radius = 4
[grid]
n = [8, 16]
[[kernel]]
name = "inverse_multiquadric"
beta = [1, 2]
)";
}

void write(const fs::path& file, const std::string& text) {
  std::ofstream(file) << text;
}

}  // namespace

TEST_CASE("a study file loads its plugins relative to its own directory", "[plugin][study]") {
  const auto dir = scratch("study");
  const auto relative = fs::relative(imq, dir).string();
  write(dir / "study.toml", study_using("plugins = [\"" + relative + "\"]"));
  const auto study = rkhs::load_study(dir / "study.toml");
  CHECK(study.kernels.size() == 2);
  CHECK(study.kernels[0].label() == "inverse_multiquadric beta=1 c=1");
  CHECK(rkhs::unload_plugin(imq));  // loaded by the study file

  const auto out = run("run " + (dir / "study.toml").string() + " --out " + (dir / "out").string() +
                       " --quiet --threads 2");
  INFO(out.output);
  CHECK(out.exit_code == 0);
  CHECK(fs::exists(dir / "out" / "trials.csv"));
}

TEST_CASE("a study file's plugin errors name file, line, column and the key", "[plugin][study]") {
  const auto dir = scratch("study_errors");
  write(dir / "missing.toml", study_using("plugins = [\"nowhere/missing.so\"]"));
  CHECK_THROWS_WITH(rkhs::load_study(dir / "missing.toml"),
                    (dir / "missing.toml").string() + ":1:12: plugins: " +
                        (dir / "nowhere" / "missing.so").string() + ": plugin file not found");
  write(dir / "scalar.toml", study_using("plugins = \"x.so\""));
  CHECK_THROWS_WITH(rkhs::load_study(dir / "scalar.toml"),
                    (dir / "scalar.toml").string() +
                        ":1:11: plugins: expected an array of plugin files, found a string");
  write(dir / "abi.toml",
        study_using("plugins = [\"" + (plugin_dir / "wrong_abi.so").string() + "\"]"));
  CHECK_THROWS_WITH(rkhs::load_study(dir / "abi.toml"),
                    Catch::StartsWith((dir / "abi.toml").string() +
                                      ":1:12: plugins: " + (plugin_dir / "wrong_abi.so").string() +
                                      ": built against plugin ABI 999"));
}

TEST_CASE("the --plugin option of run, validate and list is repeatable, and its errors exit 2",
          "[plugin][cli]") {
  const auto dir = scratch("flag");
  write(dir / "study.toml", study_using(""));

  // Without the plugin the kernel is unknown.
  const auto unknown = run("validate " + (dir / "study.toml").string());
  CHECK(unknown.exit_code == 2);
  CHECK_THAT(unknown.output, Catch::Contains("unknown kernel 'inverse_multiquadric'"));

  const auto valid = run("validate --plugin " + imq.string() + " " + (dir / "study.toml").string());
  INFO(valid.output);
  CHECK(valid.exit_code == 0);
  CHECK_THAT(valid.output, Catch::Contains("valid; 2 kernels"));

  const auto list = run("list --plugin " + imq.string() + " --plugin " + imq.string());
  CHECK(list.exit_code == 0);
  CHECK_THAT(list.output, Catch::Contains("inverse_multiquadric inverse multiquadric"));
  CHECK_THAT(list.output, Catch::Contains("plugin modules:\n  inverse_multiquadric " +
                                          fs::canonical(imq).string()));

  const auto ran = run("run " + (dir / "study.toml").string() + " --plugin " + imq.string() +
                       " --quiet --out " + (dir / "out").string());
  CHECK(ran.exit_code == 0);

  const auto missing = run("list --plugin " + (plugin_dir / "missing.so").string());
  CHECK(missing.exit_code == 2);
  CHECK(missing.output ==
        "rkhs-study: " + (plugin_dir / "missing.so").string() + ": plugin file not found\n");
  const auto duplicate = run("list --plugin " + (plugin_dir / "duplicate_kernel_name.so").string());
  CHECK(duplicate.exit_code == 2);
  CHECK_THAT(duplicate.output, Catch::Contains("kernel plugin 'gaussian': duplicate name"));
}

TEST_CASE("RKHS_STUDY_PLUGIN_PATH loads plugins at start-up", "[plugin][cli]") {
  const auto dir = scratch("env");
  write(dir / "study.toml", study_using(""));
  fs::create_directories(dir / "plugins");
  fs::copy_file(imq, dir / "plugins" / "inverse_multiquadric.so");
  const auto valid = run("validate " + (dir / "study.toml").string(),
                         "RKHS_STUDY_PLUGIN_PATH=" + (dir / "plugins").string());
  INFO(valid.output);
  CHECK(valid.exit_code == 0);
  const auto bad = run("list", "RKHS_STUDY_PLUGIN_PATH=" + (dir / "nothing").string());
  CHECK(bad.exit_code == 2);
  CHECK(bad.output == "rkhs-study: RKHS_STUDY_PLUGIN_PATH: " + (dir / "nothing").string() +
                          ": no such plugin file or directory\n");
}

TEST_CASE("verify-plugin prints the report, exits 0 when it passes and 2 when it cannot load",
          "[plugin][cli]") {
  const auto ok = run("verify-plugin " + imq.string());
  INFO(ok.output);
  CHECK(ok.exit_code == 0);
  CHECK_THAT(ok.output, Catch::Contains("pass  power-function rate: analytic"));
  CHECK_THAT(ok.output,
             Catch::EndsWith("verify-plugin: PASS (36 checks: 31 passed, 5 skipped, 0 failed)\n"));

  const auto wrong = run("verify-plugin " + (plugin_dir / "wrong_abi.so").string());
  CHECK(wrong.exit_code == 2);
  CHECK_THAT(wrong.output,
             Catch::StartsWith("rkhs-study: " + (plugin_dir / "wrong_abi.so").string() +
                               ": built against plugin ABI 999"));
}

// Issue 36: a truncated library was a SIGBUS inside dlopen, and a FIFO named x.so blocked
// forever, on every way a plugin is named. Each command runs under `timeout`: a hang fails.
TEST_CASE("a truncated plugin and a FIFO named .so are refused on every way a plugin is named",
          "[plugin][cli][hostile]") {
  const auto dir = scratch("hostile");
  fs::create_directories(dir / "truncated" / "plugins");
  fs::create_directories(dir / "fifo");
  const auto truncated = dir / "truncated" / "plugins" / "bad.so";
  {
    std::ifstream in(imq, std::ios::binary);
    std::string head(3000, '\0');
    in.read(head.data(), 3000);
    std::ofstream(truncated, std::ios::binary) << head;
  }
  const auto fifo = dir / "fifo" / "x.so";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);

  const auto refused = [](const Outcome& out, const std::string& why) {
    INFO(out.output);
    CHECK(out.exit_code == 2);
    CHECK_THAT(out.output, Catch::Contains(why));
  };
  const std::string incomplete = truncated.string() +
                                 ": not an rkhs-study plugin (not a complete shared library: "
                                 "3000 bytes, its ";
  const std::string special = fifo.string() + ": is a FIFO, not a plugin file (a shared library)";
  const std::string limit = "timeout 20";
  for (const auto& [file, why] : {std::pair{truncated, incomplete}, std::pair{fifo, special}}) {
    refused(run("verify-plugin " + file.string(), limit), why);
    refused(run("list --plugin " + file.string(), limit), why);
    write(dir / "study.toml", study_using("plugins = [\"" + file.string() + "\"]"));
    refused(run("validate " + (dir / "study.toml").string(), limit),
            (dir / "study.toml").string() + ":1:12: plugins: " + why);
    refused(run("list", "RKHS_STUDY_PLUGIN_PATH=" + file.string() + " " + limit),
            "RKHS_STUDY_PLUGIN_PATH: " + why);
    refused(run("list", "RKHS_STUDY_PLUGIN_PATH=" + file.parent_path().string() + " " + limit),
            "RKHS_STUDY_PLUGIN_PATH: " + why);
  }
  // The whole library, copied, still loads: the check reads headers, it does not refuse ELF.
  fs::copy_file(imq, dir / "whole.so");
  const auto whole = run("list --plugin " + (dir / "whole.so").string(), limit);
  INFO(whole.output);
  CHECK(whole.exit_code == 0);
}

namespace {

// The values of `column` in a trials.csv, in its row order.
std::vector<std::string> csv_column(const fs::path& file, const std::string& column) {
  std::istringstream in(rkhs::test::read_text(file));
  std::string line;
  std::getline(in, line);
  auto split = [](const std::string& row) {
    std::vector<std::string> cells;
    std::stringstream cells_in(row);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const auto header = split(line);
  const auto at = std::find(header.begin(), header.end(), column) - header.begin();
  REQUIRE(static_cast<std::size_t>(at) < header.size());
  std::vector<std::string> values;
  while (std::getline(in, line)) values.push_back(split(line).at(at));
  return values;
}

}  // namespace

TEST_CASE("a rebuilt plugin module re-runs its trials without --fresh", "[cli][store][plugin]") {
  const auto dir = rkhs::test::scratch_directory("store_rebuilt_plugin");
  const auto store = dir / "store.sqlite";
  // The study names the module by one path; "rebuilding" it replaces the file there.
  fs::copy_file(plugin_dir / "scaled_kernel_1.so", dir / "scaled.so",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "study.toml") << R"(plugins = ["scaled.so"]
[study]
name = "rebuilt_plugin"
metrics = ["power_function_sup", "l2_error"]
[domain]
radius = 4
[grid]
n = [8, 16, 32]
[[kernel]]
name = "scaled_gaussian"
)";
  const std::string run = "run " + (dir / "study.toml").string() + " --no-plots --store " +
                          store.string() + " --out " + (dir / "out").string();
  auto first = rkhs::test::rkhs_study(run);
  INFO(first.output);
  REQUIRE(first.exit_code == 0);
  CHECK_THAT(first.output,
             Catch::Contains("0 trials reused from " + store.string() + ", 3 run now"));
  const auto before = csv_column(dir / "out" / "trials.csv", "power_function_sup");

  // The same module again: every trial reused.
  auto again = rkhs::test::rkhs_study(run);
  INFO(again.output);
  REQUIRE(again.exit_code == 0);
  CHECK_THAT(again.output,
             Catch::Contains("3 trials reused from " + store.string() + ", 0 run now"));
  CHECK(csv_column(dir / "out" / "trials.csv", "power_function_sup") == before);

  // Rebuilt with another width: its trials run again, and say why; the new values.
  fs::copy_file(plugin_dir / "scaled_kernel_2.so", dir / "scaled.so",
                fs::copy_options::overwrite_existing);
  auto rebuilt = rkhs::test::rkhs_study(run);
  INFO(rebuilt.output);
  REQUIRE(rebuilt.exit_code == 0);
  CHECK_THAT(rebuilt.output,
             Catch::Contains("0 trials reused from " + store.string() +
                             ", 3 run now (all stored before under another identity: a plugin "
                             "module rebuilt"));
  const auto after = csv_column(dir / "out" / "trials.csv", "power_function_sup");
  REQUIRE(after.size() == before.size());
  for (std::size_t i = 0; i < after.size(); ++i) CHECK(after[i] != before[i]);

  // Back to the first build: its stored trials are reused again.
  fs::copy_file(plugin_dir / "scaled_kernel_1.so", dir / "scaled.so",
                fs::copy_options::overwrite_existing);
  auto restored = rkhs::test::rkhs_study(run);
  INFO(restored.output);
  REQUIRE(restored.exit_code == 0);
  CHECK_THAT(restored.output,
             Catch::Contains("3 trials reused from " + store.string() + ", 0 run now"));
  CHECK(csv_column(dir / "out" / "trials.csv", "power_function_sup") == before);
}
