// What a study file can make the command do, and what a run leaves in its folder (issue 36):
// study text reaches gnuplot only as single-quoted strings (no backquote command runs), `run`
// removes only the plot files an earlier run listed, an output folder that cannot be written is
// exit 2 before any trial, messages show control bytes as escapes, a data path may not climb out
// of the data root, a CSV line too long fails after reading about the limit, and a folder whose
// outputs were rewritten part-way carries INCOMPLETE.
#include <sys/resource.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = rkhs::test::CommandOutcome;
using rkhs::test::read_text;

Outcome rkhs_study(const std::string& arguments) {
  return rkhs::test::rkhs_study(arguments, "env -u RKHS_STUDY_DATA");
}

bool have_gnuplot() {
  return std::system("command -v gnuplot > /dev/null 2>&1") == 0;
}

// `text` as a TOML basic string.
std::string toml_string(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned>(c));
      out += code;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

const std::string profile = "u,z\n0,0\n0.5,0.1\n1,-0.1\n1.5,0.05\n2,0.02\n";

// A study of the csv target over two B-spline degrees; `targets` are its [[target]] entries.
std::string road_study(const std::string& targets, const std::string& name = "safe_output") {
  return "[study]\nname = \"" + name +
         "\"\nevaluation_points = 256\nmetrics = [\"l2_error\", \"sup_error\"]\n"
         "[domain]\nlength = 2.0\n[grid]\nn = [8, 16]\n"
         "[[kernel]]\nname = \"bspline\"\ndegree = [1, 2]\nJ = 4\n" +
         targets;
}

std::string csv_target(const std::string& file, const std::string& extra = "") {
  return "[[target]]\nname = \"csv\"\nfile = " + toml_string(file) + "\ndetrend = \"linear\"\n" +
         extra;
}

std::vector<fs::path> files_named_like(const fs::path& root, const std::string& part) {
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.path().filename().string().find(part) != std::string::npos &&
        entry.path().filename().string().find(".csv") == std::string::npos)
      found.push_back(entry.path());
  return found;
}

// What in a gnuplot script gnuplot could take for a command rather than text: a backquote or
// an '@' (macro) outside single quotes, a double-quoted string other than the script's own
// fixed ones, a control character or a line break inside a single-quoted string. Scanned as
// gnuplot's lexer scans a line (a single-quoted string ends at the first lone quote; '' is a
// quote). "" when there is none.
std::string unsafe_part(const std::string& script) {
  const std::vector<std::string> fixed{"\\n", "svg png pdf", "svg", "png", "pdf"};
  std::size_t line = 1;
  for (std::size_t i = 0; i < script.size(); ++i) {
    const char c = script[i];
    const auto where = [&](const std::string& what) {
      return "line " + std::to_string(line) + ": " + what;
    };
    if (c == '\n') {
      ++line;
    } else if (c == '`' || c == '@') {
      return where(std::string("'") + c + "' outside a single-quoted string");
    } else if (c == '\'') {
      for (++i;; ++i) {
        if (i >= script.size()) return where("unterminated single-quoted string");
        const auto b = static_cast<unsigned char>(script[i]);
        if (b == '\'' && i + 1 < script.size() && script[i + 1] == '\'') {
          ++i;
          continue;
        }
        if (b == '\'') break;
        if (b < 0x20 || b == 0x7f) return where("a control character in a string");
      }
    } else if (c == '"') {
      const auto end = script.find('"', i + 1);
      if (end == std::string::npos) return where("unterminated double-quoted string");
      const auto text = script.substr(i + 1, end - i - 1);
      if (std::find(fixed.begin(), fixed.end(), text) == fixed.end())
        return where("a double-quoted string \"" + text + "\"");
      i = end;
    } else if (static_cast<unsigned char>(c) < 0x20 && c != '\t') {
      return where("a control character");
    }
  }
  return "";
}

}  // namespace

TEST_CASE("the scanner of gnuplot scripts finds what gnuplot would run", "[cli][plots][security]") {
  CHECK(unsafe_part("set title 'a`b`' noenhanced\nplot x title 'it''s'\n").empty());
  CHECK(unsafe_part("set title 'a'.\"\\n\".'b' noenhanced\n").empty());
  CHECK_FALSE(unsafe_part("set title \"a`touch x`\" noenhanced\n").empty());
  CHECK_FALSE(unsafe_part("set title 'a''`touch x`\n").empty());  // the string goes on
  CHECK_FALSE(unsafe_part("set title 'a'`touch x`'b'\n").empty());
  CHECK_FALSE(unsafe_part("set title 'a\x1b[2J'\n").empty());
}

TEST_CASE(
    "study text with backquotes, $(), quotes, backslashes and line breaks runs nothing in "
    "gnuplot",
    "[cli][plots][security]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_injection");
  fs::create_directories(dir / "data");
  // The reproducer of issue 36, and every character gnuplot or a shell interprets, in the data
  // file names (the legends and titles name them) and a column name.
  const std::string reproducer = "r`touch PWNED`.csv";
  const std::string names = "s`touch PWNED1`$(touch PWNED2)'q\"b\\@x.csv";
  const std::string broken = "t`touch PWNED3`\nline\t2.csv";
  const std::string column = "u`touch PWNED4`'\"\\$(touch PWNED5)";
  // Profiles that differ, so that each file is a curve of its own (and names it in the legend).
  std::ofstream(dir / "data" / reproducer) << profile;
  std::ofstream(dir / "data" / names) << "u,z\n0,0\n0.5,0.3\n1,-0.2\n1.5,0.1\n2,0.02\n";
  std::ofstream(dir / "data" / broken) << column << ",z\n0,0\n0.5,-0.1\n1,0.4\n1.5,0.05\n2,0\n";
  std::ofstream(dir / "study.toml")
      << road_study(csv_target(reproducer) + csv_target(names) +
                    csv_target(broken, "arc_length_column = " + toml_string(column) +
                                           "\nelevation_column = \"z\"\n"));
  const auto outcome =
      rkhs_study("run --quiet --threads 1 --data-dir " + (dir / "data").string() + " --out " +
                 (dir / "out").string() + " " + (dir / "study.toml").string());
  INFO(outcome.output);
  REQUIRE(outcome.exit_code == 0);
  if (!have_gnuplot()) {
    WARN("gnuplot is not installed: the plot scripts were not written");
    return;
  }
  const auto plots = dir / "out" / "plots";
  REQUIRE(fs::exists(plots / "convergence_l2_error.svg"));
  CHECK(files_named_like(dir, "PWNED").empty());
  CHECK(files_named_like(fs::current_path(), "PWNED").empty());
  bool quoted = false;  // the hostile text reached a script, as text
  for (const auto& entry : fs::directory_iterator(plots)) {
    if (entry.path().extension() != ".gp") continue;
    const auto script = read_text(entry.path());
    INFO(entry.path().string());
    CHECK(unsafe_part(script) == "");
    quoted = quoted || script.find("touch PWNED4") != std::string::npos;
  }
  CHECK(quoted);
  // Shown as written: the legend of the SVG has the quotes and the file name's parts.
  const auto svg = read_text(plots / "convergence_l2_error.svg");
  CHECK_THAT(svg, Catch::Contains("r`touch PWNED`.csv"));
  // The script rendered again by hand, as its first line says, creates nothing either.
  REQUIRE(std::system(("cd '" + plots.string() + "' && gnuplot convergence_l2_error.gp").c_str()) ==
          0);
  CHECK(files_named_like(dir, "PWNED").empty());
}

TEST_CASE("run removes only the plot files an earlier run listed in plots/", "[cli][plots]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_manifest");
  fs::create_directories(dir / "data");
  std::ofstream(dir / "data" / "profile.csv") << profile;
  std::ofstream(dir / "study.toml") << road_study(csv_target("profile.csv"));
  const std::string command = "run --quiet --threads 1 --data-dir " + (dir / "data").string() +
                              " --out " + (dir / "out").string() + " " +
                              (dir / "study.toml").string();
  const auto plots = dir / "out" / "plots";
  // The user's own files in plots/, before and after the first run.
  fs::create_directories(plots);
  std::ofstream(plots / "mine.png") << "my figure";
  std::ofstream(plots / "notes.log") << "my notes";
  const auto first = rkhs_study(command);
  INFO(first.output);
  REQUIRE(first.exit_code == 0);
  std::ofstream(plots / "sketch.gp") << "plot x";
  std::ofstream(plots / "draft.pdf") << "my draft";
  const auto manifest = read_text(plots / ".rkhs-study-manifest");
  CHECK_THAT(manifest, Catch::Contains("\nconvergence_l2_error.svg\n"));
  CHECK_THAT(manifest, !Catch::Contains("mine.png"));
  // A plot of an earlier run that this run no longer writes is listed, so it goes.
  std::ofstream(plots / "convergence_gone.svg") << "stale";
  std::ofstream(plots / ".rkhs-study-manifest", std::ios::app)
      << "convergence_gone.svg\n../../study.toml\n/etc/hostname\n";
  const auto second = rkhs_study(command);
  INFO(second.output);
  REQUIRE(second.exit_code == 0);
  for (const char* mine : {"mine.png", "notes.log", "sketch.gp", "draft.pdf"}) {
    INFO(mine);
    CHECK(fs::exists(plots / mine));
  }
  CHECK(read_text(plots / "mine.png") == "my figure");
  CHECK_FALSE(fs::exists(plots / "convergence_gone.svg"));
  CHECK(fs::exists(dir / "study.toml"));  // a manifest entry with a path is ignored
  CHECK(fs::exists("/etc/hostname"));
  if (have_gnuplot()) CHECK(fs::exists(plots / "convergence_l2_error.svg"));
}

TEST_CASE("an output folder that cannot be written is exit 2, naming it, before any trial",
          "[cli][output]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_folder");
  fs::create_directories(dir / "data");
  std::ofstream(dir / "data" / "profile.csv") << profile;
  std::ofstream(dir / "study.toml") << road_study(csv_target("profile.csv"));
  std::ofstream(dir / "a_file") << "not a folder";
  const auto run = [&](const std::string& out) {
    return rkhs_study("run --threads 1 --data-dir " + (dir / "data").string() + " --out " + out +
                      " " + (dir / "study.toml").string());
  };
  // Tests run as root: a path below a regular file is one no one can create.
  for (const std::string out : {std::string("/etc/hostname/x"), (dir / "a_file").string(),
                                (dir / "a_file" / "x").string()}) {
    const auto outcome = run(out);
    INFO(outcome.output);
    CHECK(outcome.exit_code == 2);
    CHECK_THAT(outcome.output, Catch::Contains("cannot write the output folder " + out + ": "));
    CHECK_THAT(outcome.output, !Catch::Contains("ok, 0 failed"));
    CHECK_THAT(outcome.output, !Catch::Contains("[1/"));
  }
  // plots/ that is a file: refused before the trials too.
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "plots") << "a file";
  const auto plots = run((dir / "out").string());
  INFO(plots.output);
  CHECK(plots.exit_code == 2);
  CHECK_THAT(plots.output,
             Catch::Contains("cannot write the output folder " + (dir / "out" / "plots").string()));
  CHECK_FALSE(fs::exists(dir / "out" / "trials.csv"));
}

TEST_CASE("messages show control bytes and bytes that are not UTF-8 as escapes",
          "[cli][messages][security]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_messages");
  fs::create_directories(dir / "data");
  // The study file: a name with an escape sequence (it is not a valid name).
  std::ofstream(dir / "name.toml") << road_study(csv_target("profile.csv"), "a\\u001b[31mb\\nc");
  const auto name = rkhs_study("validate " + (dir / "name.toml").string());
  INFO(name.output);
  CHECK(name.exit_code == 2);
  CHECK_THAT(name.output, Catch::Contains("'a\\x1b[31mb\\x0ac' is not a valid name"));
  CHECK(name.output.find('\x1b') == std::string::npos);
  // An unknown key with an escape in it.
  std::ofstream(dir / "key.toml") << road_study(csv_target("profile.csv")) +
                                         "[\"k\\u001b]0;title\\u0007\"]\nx = 1\n";
  const auto key = rkhs_study("validate " + (dir / "key.toml").string());
  INFO(key.output);
  CHECK(key.exit_code == 2);
  CHECK(key.output.find('\x1b') == std::string::npos);
  CHECK(key.output.find('\x07') == std::string::npos);
  // The CSV reader: a field with an escape sequence, a field that is not UTF-8.
  std::ofstream(dir / "data" / "profile.csv") << "u,z\n0,0\n0.5,\x1b[2Jwiped\n1,0\n2,0\n";
  std::ofstream(dir / "data" / "latin1.csv") << "u,z\n0,0\n0.5,caf\xe9\n1,0\n2,0\n";
  std::ofstream(dir / "csv.toml") << road_study(csv_target("profile.csv"));
  std::ofstream(dir / "latin1.toml") << road_study(csv_target("latin1.csv"));
  const auto csv = rkhs_study("validate --data-dir " + (dir / "data").string() + " " +
                              (dir / "csv.toml").string());
  INFO(csv.output);
  CHECK(csv.exit_code == 2);
  CHECK_THAT(csv.output, Catch::Contains("elevation: '\\x1b[2Jwiped' is not a number"));
  CHECK(csv.output.find('\x1b') == std::string::npos);
  const auto latin1 = rkhs_study("validate --data-dir " + (dir / "data").string() + " " +
                                 (dir / "latin1.toml").string());
  INFO(latin1.output);
  CHECK(latin1.exit_code == 2);
  CHECK_THAT(latin1.output, Catch::Contains("elevation: 'caf\\xe9' is not a number"));
}

TEST_CASE("a relative data path that leaves the data root through .. is refused at its key",
          "[cli][data_root][security]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_data_root");
  fs::create_directories(dir / "data" / "roads");
  std::ofstream(dir / "secret.csv") << profile;
  std::ofstream(dir / "data" / "roads" / "profile.csv") << profile;
  const std::string data = " --data-dir " + (dir / "data").string() + " ";
  for (const std::string path :
       {"../secret.csv", "roads/../../secret.csv", "../../../proc/self/environ"}) {
    std::ofstream(dir / "study.toml") << road_study(csv_target(path));
    const auto outcome = rkhs_study("validate" + data + (dir / "study.toml").string());
    INFO(outcome.output);
    CHECK(outcome.exit_code == 2);
    // [[target]] is on line 13, its file on line 15 (after `file = `, column 8).
    CHECK_THAT(outcome.output,
               Catch::StartsWith((dir / "study.toml").string() + ":15:8: target.file: data file '" +
                                 path + "' leaves the data root through '..'"));
    CHECK_THAT(outcome.output, !Catch::Contains("is not a number"));
  }
  // Below the root, ".." that stays inside it, and an absolute path: taken.
  for (const std::string path :
       {std::string("roads/profile.csv"), std::string("roads/../roads/profile.csv"),
        (dir / "secret.csv").string()}) {
    std::ofstream(dir / "study.toml") << road_study(csv_target(path));
    const auto outcome = rkhs_study("validate" + data + (dir / "study.toml").string());
    INFO(outcome.output);
    CHECK(outcome.exit_code == 0);
  }
}

TEST_CASE("a CSV file of 200 MiB without a line break fails after reading about the limit",
          "[cli][csv_road][limits]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_huge_line");
  fs::create_directories(dir / "data");
  const auto huge = dir / "data" / "huge.csv";
  std::ofstream(huge) << "u,z\n0,";
  // Sparse: 200 MiB of NUL bytes, no '\n' (a file above 256 MiB is refused by its size before
  // it is read, tests/cli/test_roads_cli.cpp).
  fs::resize_file(huge, std::uintmax_t{200} << 20);
  std::ofstream(dir / "study.toml") << road_study(csv_target("huge.csv"));
  const auto outcome = rkhs_study("validate --data-dir " + (dir / "data").string() + " " +
                                  (dir / "study.toml").string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output,
             Catch::Contains("huge.csv:2:1: the line is longer than 16777215 bytes"));
  // The command (a child of the shell, a child of this process) never held the file: its peak
  // resident set stays far below the file's 200 MiB (reading it whole took that much).
  rusage usage{};
  REQUIRE(getrusage(RUSAGE_CHILDREN, &usage) == 0);
  CHECK(usage.ru_maxrss < 100 * 1024);  // kilobytes
  fs::remove(huge);
}

TEST_CASE("a run whose writing of outputs fails part-way leaves INCOMPLETE, the next removes it",
          "[cli][output]") {
  const auto dir = rkhs::test::scratch_directory("safe_output_incomplete");
  fs::create_directories(dir / "data");
  std::ofstream(dir / "data" / "profile.csv") << profile;
  std::ofstream(dir / "study.toml") << road_study(csv_target("profile.csv"));
  const auto out = dir / "out";
  const std::string command = "run --quiet --no-plots --threads 1 --data-dir " +
                              (dir / "data").string() + " --out " + out.string() + " " +
                              (dir / "study.toml").string();
  const auto first = rkhs_study(command);
  INFO(first.output);
  REQUIRE(first.exit_code == 0);
  CHECK_FALSE(fs::exists(out / "INCOMPLETE"));
  const auto old_rates = read_text(out / "rates.csv");
  // rates.csv cannot be replaced (a folder in its place): trials.csv is written anew, the rest
  // stays the first run's, as after a disk that filled up after trials.csv.
  fs::remove(out / "rates.csv");
  fs::create_directories(out / "rates.csv" / "in_the_way");
  fs::remove(out / "trials.csv");
  const auto failed = rkhs_study(command);
  INFO(failed.output);
  CHECK(failed.exit_code != 0);
  CHECK_THAT(failed.output, Catch::Contains("rates.csv"));
  CHECK_THAT(failed.output, Catch::Contains((out / "INCOMPLETE").string()));
  CHECK(fs::exists(out / "trials.csv"));
  REQUIRE(fs::exists(out / "INCOMPLETE"));
  const auto marker = read_text(out / "INCOMPLETE");
  CHECK_THAT(marker, Catch::StartsWith("INCOMPLETE: the outputs in this folder are not those of "
                                       "one run."));
  CHECK_THAT(marker, Catch::Contains("study 'safe_output'"));
  for (const char* file : {"trials.csv", "rates.csv", "summary.json", "report.html"}) {
    INFO(file);
    CHECK_THAT(marker, Catch::Contains(std::string("  ") + file + "\n"));
  }
  // The marker is there while the run writes: a run that completes removes it.
  fs::remove_all(out / "rates.csv");
  const auto again = rkhs_study(command);
  INFO(again.output);
  CHECK(again.exit_code == 0);
  CHECK_FALSE(fs::exists(out / "INCOMPLETE"));
  CHECK(read_text(out / "rates.csv") == old_rates);
}
