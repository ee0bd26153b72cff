// The rkhs-study command: the commands assembled (each declares its own options,
// commands/<command>.cpp), the command line parsed with CLI11, and one call into the command it
// names (commands/session.cpp sets up what every command shares).
#include <fmt/format.h>
#include <malloc.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <streambuf>
#include <vector>

#include "commands/commands.hpp"
#include "commands/session.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/mpi/distributed.hpp"
#include "rkhs/run/run.hpp"              // trials_abandoned
#include "rkhs/verify/verification.hpp"  // check_none_selected

namespace {

int rkhs_study_main(int argc, char** argv) {
  using namespace rkhs::cli;
  CLI::App app{
      "rkhs-study: convergence studies of kernel approximation and adaptive estimation "
      "in reproducing kernel Hilbert spaces"};
  app.require_subcommand(1);
  app.set_version_flag(
      "--version",
      fmt::format("rkhs-study {} (commit {}; {}; MPI runner: {})", rkhs::build_info().version,
                  rkhs::build_info().git_commit, rkhs::build_info().build_type,
                  rkhs::distributed::available() ? "yes" : "no, see docs/cluster.md"));

  // The commands, each declaring its own options (commands/<name>.cpp), in the order of
  // `rkhs-study --help`.
  SessionOptions session;
  const std::vector<Command> commands = {
      add_run_command(app, session),   add_merge_command(app),
      add_store_command(app),          add_list_command(app, session),
      add_report_command(app),         add_validate_command(app, session),
      add_check_command(app, session), add_verify_plugin_command(app)};

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? exit_ok : exit_bad_input;
  }

  // require_subcommand(1): exactly one of them was named.
  const auto named = std::find_if(commands.begin(), commands.end(),
                                  [](const Command& command) { return bool(*command.subcommand); });
  if (named == commands.end()) return exit_bad_input;
  if (named->prepare) named->prepare(session);
  return run_command(session, argc, argv, named->action);
}

// Standard output for std::cout: buffered, written with write(2), and the first failure kept
// with its errno (stdio forgets the reason of a failed write once its buffer moved on).
class StandardOutput : public std::streambuf {
 public:
  StandardOutput() { setp(buffer_, buffer_ + sizeof buffer_); }
  /// The errno of the first write that failed; 0 while every write succeeded.
  int error() const noexcept { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  // Writes what is buffered; false once a write failed (what follows is dropped).
  bool drain() {
    const char* next = pbase();
    while (error_ == 0 && next < pptr()) {
      const auto written = ::write(STDOUT_FILENO, next, static_cast<std::size_t>(pptr() - next));
      if (written < 0 && errno == EINTR) continue;
      if (written < 0)
        error_ = errno;
      else
        next += written;
    }
    setp(buffer_, buffer_ + sizeof buffer_);
    return error_ == 0;
  }
  char buffer_[1 << 16];
  int error_ = 0;
};

// Standard output flushed and checked once, for every command: a write that failed (a full disk,
// `> /dev/full`, a closed descriptor) turns a success into exit 1 with the reason, and so `check`'s
// 5 (nothing verified: what it printed was all it had to say); an exit code that already says
// failure is kept.
int checked_standard_output(int code, const StandardOutput& output) {
  std::cout.flush();
  if (output.error() == 0 && std::cout.good()) return code;
  std::cerr << "rkhs-study: cannot write to standard output"
            << (output.error() ? std::string(": ") + std::strerror(output.error()) : std::string())
            << "\n";
  return code == 0 || code == rkhs::check_none_selected ? 1 : code;
}

}  // namespace

int main(int argc, char** argv) {
  // A trial allocates and frees matrices of several MB per block of evaluation points (and
  // Eigen its packing buffers per triangular solve): keep freed memory in the heap for the next
  // block instead of glibc's default of mapping blocks above 128 KiB (its threshold grows only
  // to the largest freed block) and trimming the heap top, both of which make every new block
  // fault its pages in again (13 % of a 2-D trial at n = 4096, most of iso8608 before).
  // 32 MiB is the largest mmap threshold glibc accepts.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  static StandardOutput output;  // static: an abandoned trial's thread may outlive main's frame
  std::streambuf* const standard = std::cout.rdbuf(&output);
  if (::isatty(STDOUT_FILENO)) std::cout << std::unitbuf;  // a terminal sees each line at once
  const int code = checked_standard_output(rkhs_study_main(argc, argv), output);
  std::cout.rdbuf(standard);  // before `output` is destroyed at exit
  if (rkhs::trials_abandoned()) {
    // Abandoned trials still compute on their threads: end now, without static destructors.
    std::cerr.flush();
    std::fflush(nullptr);
    std::_Exit(code);
  }
  return code;
}
