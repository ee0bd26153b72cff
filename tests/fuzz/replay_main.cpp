// Replays inputs through a libFuzzer harness without libFuzzer, so that any compiler builds it:
// every file named, and every regular file of every directory named (sorted by name), goes once
// through the harness's LLVMFuzzerTestOneInput. The fuzz_regression.* tests run the regression
// inputs (tests/fuzz/regression/<harness>/) and the seed corpus this way in every build.
//
//   fuzz_replay_<harness> [--budget SECONDS] PATH...
//
// Each input has a time budget (default 1 s, the -timeout of the libFuzzer runs): one that takes
// longer is named and fails the run (exit 1). A crash, a sanitizer report or an exception the
// harness does not accept aborts, naming the input. No input at all is an error (exit 2): a
// misspelt directory must not pass.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

// The input being replayed, for the crash handler (a fixed buffer: written before each input,
// read in a signal handler).
char current_input[4096] = "";

extern "C" void report_crash(int signal_number) {
  const char prefix[] = "fuzz replay: crashed on input ";
  const auto ignore = [](ssize_t) {};
  ignore(write(STDERR_FILENO, prefix, sizeof prefix - 1));
  ignore(write(STDERR_FILENO, current_input, std::strlen(current_input)));
  ignore(write(STDERR_FILENO, "\n", 1));
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

std::vector<fs::path> inputs_of(const fs::path& path) {
  if (!fs::is_directory(path)) return {path};
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(path))
    if (entry.is_regular_file() && entry.path().filename().string().front() != '.')
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  double budget = 1.0;
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--budget" && i + 1 < argc) {
      budget = std::stod(argv[++i]);
      continue;
    }
    if (!fs::exists(argument)) {
      std::fprintf(stderr, "fuzz replay: %s: no such file or directory\n", argument.c_str());
      return 2;
    }
    const auto found = inputs_of(argument);
    inputs.insert(inputs.end(), found.begin(), found.end());
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "usage: %s [--budget SECONDS] PATH... (no input found)\n", argv[0]);
    return 2;
  }
  for (int signal_number : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL})
    std::signal(signal_number, report_crash);

  std::size_t over_budget = 0;
  double slowest = 0;
  std::string slowest_input;
  for (const auto& input : inputs) {
    const std::string name = input.string();
    std::snprintf(current_input, sizeof current_input, "%s", name.c_str());
    std::ifstream in(input, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (!in && !in.eof()) {
      std::fprintf(stderr, "fuzz replay: %s: cannot read\n", name.c_str());
      return 2;
    }
    const auto start = std::chrono::steady_clock::now();
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (seconds > slowest) {
      slowest = seconds;
      slowest_input = name;
    }
    if (seconds > budget) {
      ++over_budget;
      std::fprintf(stderr, "fuzz replay: %s: %.3f s, over the budget of %g s\n", name.c_str(),
                   seconds, budget);
    }
  }
  std::printf("fuzz replay: %zu input%s, %zu over the budget of %g s; slowest %.3f s (%s)\n",
              inputs.size(), inputs.size() == 1 ? "" : "s", over_budget, budget, slowest,
              slowest_input.c_str());
  return over_budget ? 1 : 0;
}
