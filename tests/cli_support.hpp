#pragma once
// Running the rkhs-study command from tests, as a user would.

#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#ifndef RKHS_TEST_SLOWDOWN
#error "RKHS_TEST_SLOWDOWN is defined by tests/CMakeLists.txt for every target that runs commands"
#endif

namespace rkhs::test {

/// How many times longer than in a release build a test waits for a command to reach a point (a
/// trial stored, a rank started): RKHS_TEST_SLOWDOWN, set in tests/CMakeLists.txt (1 there, more
/// in a sanitizer build, which runs every program several times slower, docs/sanitizers.md). The
/// same factor scales the tests' ctest limits.
inline constexpr int patience = RKHS_TEST_SLOWDOWN;

/// Polls `reached` every 50 ms for up to `seconds` x `patience`; true once it held.
template <class Predicate>
bool wait_until(Predicate reached, int seconds) {
  for (int i = 0; i < 20 * seconds * patience; ++i) {
    if (reached()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return reached();
}

struct CommandOutcome {
  int exit_code;       ///< -1 when the command did not exit normally
  std::string output;  ///< stdout and stderr, interleaved
};

/// Runs a whole command line in the shell; stdout and stderr are captured together.
inline CommandOutcome run_command(const std::string& command_line) {
  FILE* pipe = popen((command_line + " 2>&1").c_str(), "r");
  REQUIRE(pipe);
  std::string output;
  char buffer[4096];
  while (std::size_t got = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, got);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

/// Runs the rkhs-study executable of this build with `arguments`. `environment` is put before
/// the command (e.g. "RKHS_STUDY_DATA=/x" or "env -u RKHS_STUDY_DATA").
inline CommandOutcome rkhs_study(const std::string& arguments,
                                 const std::string& environment = "") {
  return run_command(environment + " " + std::string(RKHS_STUDY_EXECUTABLE) + " " + arguments);
}

/// A study named `name` of ten trials of about 0.1-1 s each (Gaussian kernels of widths
/// `sigmas`, a TOML array of two, n = 300..900), so that a run can be caught midway.
inline std::string slow_study(const std::string& name, const std::string& sigmas = "[0.5, 0.7]") {
  return R"([study]
name = ")" +
         name + R"("
evaluation_points = 4096
metrics = ["gram_condition_number", "power_function_sup", "l2_error"]
[domain]
radius = 4
[grid]
n = { from = 300, to = 900, step = 150 }
[[kernel]]
name = "gaussian"
sigma = )" +
         sigmas + "\n";
}

/// "1 trial", "3 trials": as the command counts trials in its messages.
inline std::string trials_text(std::size_t count) {
  return std::to_string(count) + (count == 1 ? " trial" : " trials");
}

/// The whole content of a text file ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A fresh, empty directory rkhs_<name> under the system's temporary directory.
inline std::filesystem::path scratch_directory(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("rkhs_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace rkhs::test
