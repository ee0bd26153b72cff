// Crash-safe outputs: a write goes to a unique temporary in the same directory, is synced and
// renamed; a write that fails (a full disk, a rename that is refused) removes its temporary and
// names the file.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "rkhs/report/output.hpp"

namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("rkhs_atomic_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(dir)) out.push_back(entry.path().filename());
  std::sort(out.begin(), out.end());
  return out;
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("write_file_atomically replaces a file and leaves nothing else", "[output][atomic]") {
  const auto dir = scratch("replace");
  rkhs::write_file_atomically(dir / "a.csv", "first\n");
  rkhs::write_file_atomically(dir / "a.csv", "second\n");
  CHECK(text_of(dir / "a.csv") == "second\n");
  CHECK(names_in(dir) == std::vector<std::string>{"a.csv"});
}

TEST_CASE("a refused rename removes the temporary and names the file", "[output][atomic]") {
  const auto dir = scratch("rename");
  fs::create_directories(dir / "trials.csv" / "inside");  // a directory where the file goes
  CHECK_THROWS_WITH(
      rkhs::write_file_atomically(dir / "trials.csv", "x\n"),
      Catch::StartsWith("cannot write " + (dir / "trials.csv").string() + " (rename): "));
  CHECK(names_in(dir) == std::vector<std::string>{"trials.csv"});
  CHECK_THROWS_WITH(
      rkhs::write_file_atomically(dir / "missing" / "a.csv", "x\n"),
      "cannot write " + (dir / "missing" / "a.csv").string() + ": No such file or directory");
}

TEST_CASE("a write that runs out of space removes the temporary", "[output][atomic]") {
  // A full disk, as the file size limit makes it: writes past 4 kB fail (EFBIG).
  const auto dir = scratch("full");
  rkhs::write_file_atomically(dir / "summary.json", "old\n");
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    setrlimit(RLIMIT_FSIZE, &limit);
    try {
      rkhs::write_file_atomically(dir / "summary.json", std::string(1 << 20, 'x'));
    } catch (const std::runtime_error& e) {
      const std::string why = e.what();
      _exit(why.find("cannot write " + (dir / "summary.json").string() + " (write): ") == 0 ? 0
                                                                                            : 3);
    }
    _exit(4);  // no error at all
  }
  int status = 0;
  waitpid(child, &status, 0);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(names_in(dir) == std::vector<std::string>{"summary.json"});
  CHECK(text_of(dir / "summary.json") == "old\n");  // the old file, whole
}
