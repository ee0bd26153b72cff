// Measured roads through the command: --data-dir and RKHS_STUDY_DATA, CSV errors reaching the
// user with both positions (study file and CSV file), the data's SHA-256 in summary.json.
#include <sys/stat.h>
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_support.hpp"
#include "rkhs/core/sha256.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = rkhs::test::CommandOutcome;

// `environment` is prefixed to the command (e.g. "RKHS_STUDY_DATA=/x"); the caller's own
// RKHS_STUDY_DATA is removed so that each test says where the data is.
Outcome rkhs_study(const std::string& arguments, const std::string& environment = "") {
  return rkhs::test::rkhs_study(arguments, "env -u RKHS_STUDY_DATA " + environment);
}

fs::path scratch(const std::string& name) {
  auto dir = rkhs::test::scratch_directory("roads_cli_" + name);
  fs::create_directories(dir / "data" / "roads");
  return dir;
}

std::string read(const fs::path& file) {
  return rkhs::test::read_text(file);
}

const char* const road_study = R"([study]
name = "road_cli"
evaluation_points = 256
[domain]
length = 2.0
[grid]
n = [8, 16]
[[kernel]]
name = "bspline"
degree = 1
J = 4
[[target]]
name = "csv"
file = "roads/profile.csv"
detrend = "linear"
)";

}  // namespace

TEST_CASE("a CSV error reaches the user with the study's and the file's positions",
          "[cli][csv_road]") {
  const auto dir = scratch("error");
  std::ofstream(dir / "study.toml") << road_study;
  std::ofstream(dir / "data" / "roads" / "profile.csv") << "u,z\n0,0\n0.5,0.1\n1.0,oops\n2.0,0\n";
  const auto outcome = rkhs_study("validate --data-dir " + (dir / "data").string() + " " +
                                  (dir / "study.toml").string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output,
             Catch::StartsWith((dir / "study.toml").string() + ":12:1: target: csv "));
  CHECK_THAT(outcome.output,
             Catch::Contains(": " + (dir / "data" / "roads" / "profile.csv").string() +
                             ":4:5: elevation: 'oops' is not a number\n"));
}

TEST_CASE(
    "data files are found through --data-dir or RKHS_STUDY_DATA, else the error says where it "
    "looked",
    "[cli][csv_road]") {
  const auto dir = scratch("root");
  std::ofstream(dir / "study.toml") << road_study;
  const std::string study = (dir / "study.toml").string();
  // Not found: the default root below the current directory.
  const auto missing = rkhs_study("validate " + study);
  INFO(missing.output);
  CHECK(missing.exit_code == 2);
  CHECK_THAT(
      missing.output,
      Catch::Contains("data file 'roads/profile.csv' not found (looked at " +
                      (fs::current_path() / "studies" / "data" / "roads" / "profile.csv").string() +
                      ", in the default data root studies/data/ below the current directory"));
  // Found through either setting once the file exists.
  std::ofstream(dir / "data" / "roads" / "profile.csv") << "u,z\n0,0\n1,0.1\n2,0\n";
  const auto by_option = rkhs_study("validate --data-dir " + (dir / "data").string() + " " + study);
  INFO(by_option.output);
  CHECK(by_option.exit_code == 0);
  const auto by_environment =
      rkhs_study("validate " + study, "RKHS_STUDY_DATA=" + (dir / "data").string());
  INFO(by_environment.output);
  CHECK(by_environment.exit_code == 0);
  // --data-dir wins over the environment.
  const auto both = rkhs_study("validate --data-dir " + (dir / "data").string() + " " + study,
                               "RKHS_STUDY_DATA=/nonexistent");
  CHECK(both.exit_code == 0);
  const auto bad_option =
      rkhs_study("validate --data-dir " + (dir / "absent").string() + " " + study);
  CHECK(bad_option.exit_code == 2);
  CHECK_THAT(bad_option.output, Catch::Contains("--data-dir"));
}

TEST_CASE("the data file's SHA-256 is recorded with every trial in summary.json",
          "[cli][csv_road]") {
  const auto dir = scratch("provenance");
  std::ofstream(dir / "study.toml") << road_study;
  const auto file = dir / "data" / "roads" / "profile.csv";
  std::ofstream(file) << "u,z\n0,0\n0.5,0.1\n1,-0.1\n1.5,0.05\n2,0.02\n";
  const auto outcome =
      rkhs_study("run --quiet --threads 1 --data-dir " + (dir / "data").string() + " --out " +
                 (dir / "out").string() + " " + (dir / "study.toml").string());
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  const auto summary = read(dir / "out" / "summary.json");
  const std::string data = "\"data\": \"sha256:" + rkhs::sha256_file(file) + "\"";
  std::size_t count = 0;
  for (auto at = summary.find(data); at != std::string::npos; at = summary.find(data, at + 1))
    ++count;
  CHECK(count == 2);
  // A closed-form road has no data to record.
  std::string sine(road_study);
  sine.replace(sine.find("name = \"csv\""), std::string::npos, "name = \"sine\"\n");
  std::ofstream(dir / "sine.toml") << sine;
  const auto closed_form = rkhs_study("run --quiet --threads 1 --out " + (dir / "sine").string() +
                                      " " + (dir / "sine.toml").string());
  INFO(closed_form.output);
  REQUIRE(closed_form.exit_code == 0);
  CHECK_THAT(read(dir / "sine" / "summary.json"), Catch::Contains("\"n\": 8, \"data\": null,"));
}

// Issue 50: a newline in a CSV road's file name broke the rows of rates.md and ended the "% group"
// comment of rates.tex, putting the rest of the name ("\end{document}") into the LaTeX; an ESC
// byte reached every output raw.
TEST_CASE("control bytes in a CSV road's file name stay inside their row of every output",
          "[cli][csv_road]") {
  const auto dir = scratch("control_name");
  const std::string name = "pro\nfile |x| \x1b[31m\\end{document}.csv";
  std::ofstream(dir / "data" / "roads" / name) << "u,z\n0,0\n0.5,0.1\n1,-0.1\n1.5,0.05\n2,0.02\n";
  std::string study(road_study);
  study.replace(study.find("roads/profile.csv"), 17,
                "roads/pro\\nfile |x| \\u001b[31m\\\\end{document}.csv");
  std::ofstream(dir / "study.toml") << study;
  const auto outcome =
      rkhs_study("run --quiet --no-plots --threads 1 --data-dir " + (dir / "data").string() +
                 " --out " + (dir / "out").string() + " " + (dir / "study.toml").string());
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  for (const char* file : {"rates.md", "rates.tex", "trials.csv", "rates.csv"}) {
    const auto text = read(dir / "out" / file);
    INFO(file);
    CHECK(text.find('\x1b') == std::string::npos);
    CHECK_THAT(text, Catch::Contains("pro\\x0afile") || Catch::Contains("pro\nfile"));
  }
  // Markdown and LaTeX: the name is on one line, its escapes visible.
  const auto md = read(dir / "out" / "rates.md");
  CHECK_THAT(md, Catch::Contains("target=csv file=roads/pro\\x0afile |x| \\x1b[31m"));
  CHECK(md.find("\nfile |x|") == std::string::npos);
  const auto tex = read(dir / "out" / "rates.tex");
  CHECK(tex.find("\nfile |x|") == std::string::npos);
  CHECK(tex.find("\n\\end{document}.csv") == std::string::npos);
  CHECK_THAT(tex, Catch::Contains("% group kernel=bspline"));
}

// Issue 50: /dev/zero, /dev/stdin or a FIFO as a CSV road was "not found" (and a FIFO below
// the data root would have blocked the reader); a CSV file above its limit was read whole.
// Each command runs under `timeout`: a hang fails.
TEST_CASE("a data file that is not a regular file is named as what it is, a huge one refused",
          "[cli][csv_road][hostile]") {
  const auto dir = scratch("special");
  REQUIRE(mkfifo((dir / "data" / "roads" / "profile.csv").c_str(), 0600) == 0);
  fs::create_directories(dir / "data" / "folder.csv");
  const std::string data = " --data-dir " + (dir / "data").string() + " ";
  const auto refused = [&](const std::string& file, const std::string& why) {
    std::string study = road_study;
    study.replace(study.find("roads/profile.csv"), 17, file);
    std::ofstream(dir / "study.toml") << study;
    const auto out = rkhs_study("validate" + data + (dir / "study.toml").string(), "timeout 20");
    INFO(out.output);
    CHECK(out.exit_code == 2);
    CHECK_THAT(out.output, Catch::Contains(why));
  };
  refused("/dev/zero",
          "data file '/dev/zero' is a character device, not a data file (a regular file; looked "
          "at /dev/zero)");
  refused("/dev/stdin", "data file '/dev/stdin' is a ");
  refused("roads/profile.csv", "data file 'roads/profile.csv' is a FIFO, not a data file");
  refused("folder.csv", "data file 'folder.csv' is a directory, not a data file");
  // 300 MiB, sparse: refused by its size before a byte of it is read.
  const auto huge = dir / "data" / "huge.csv";
  std::ofstream(huge) << "u,z\n";
  fs::resize_file(huge, std::uintmax_t{300} << 20);
  refused("huge.csv", huge.string() +
                          ": is 314572800 bytes, more than the 268435456 bytes (256 MiB) a CSV "
                          "data file may have");
}
