// The rkhs-study command: the command line parsed with CLI11, and one call into the command it
// names (commands/<command>.cpp; commands/session.cpp sets up what every command shares).
#include <fmt/format.h>
#include <malloc.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <streambuf>

#include "commands/commands.hpp"
#include "commands/session.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/distributed.hpp"
#include "rkhs/plugin/builtins.hpp"  // plugin_kind_names(), for `list`
#include "rkhs/run/run.hpp"
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

  RunCommand run_arguments;
  CheckCommand check_arguments;
  SessionOptions session;
  std::string study_file, kind;
  auto* run =
      app.add_subcommand("run", "run a study: trials, rates, trials.csv, rates.csv, summary.json");
  run->add_option("study", run_arguments.study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  run->add_option("--out", run_arguments.out_dir,
                  "output directory (default: results/<study name>)");
  run->add_option("--threads", run_arguments.threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  run->add_flag("--quiet,-q", run_arguments.quiet,
                "print only the summary line and the verdict lines");
  auto add_store_options = [&](CLI::App* command, rkhs::pipeline::StoreOptions& store_options) {
    command->add_option(
        "--store", store_options.file,
        "result store (SQLite) shared by studies (default: results/rkhs-study.sqlite)");
    command->add_flag("--fresh", store_options.fresh,
                      "run every trial again, ignoring stored results");
    command->add_flag("--no-store", store_options.disabled,
                      "neither read nor write a result store");
  };
  add_store_options(run, run_arguments.store);
  run->add_option(
      "--shard", run_arguments.shard,
      "K/N (digits only, 1 <= K <= N): run only the K-th of N deterministic subsets into "
      "the store (job arrays)");
  std::string merge_into;
  std::vector<std::string> merge_from;
  auto* merge = app.add_subcommand(
      "merge",
      "combine result stores (e.g. of shards) into one, all or nothing: every source record "
      "verified, a trial stored with two different results refused unless --prefer says which "
      "record wins");
  merge->add_option("into", merge_into, "the store to merge into (created if needed)")->required();
  merge->add_option("from", merge_from, "stores to copy from")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  std::string merge_prefer;
  merge
      ->add_option("--prefer", merge_prefer,
                   "when a trial is stored with two different results: destination keeps the "
                   "record already there, source takes the one merged later (default: refuse "
                   "the merge)")
      ->check(CLI::IsMember({"source", "destination"}));
  StoreCommand store_arguments;
  auto* store = app.add_subcommand(
      "store",
      "the result store: check (verify every record), vacuum (remove the records that "
      "do not verify), export (records as CSV or JSON)");
  store->add_option("action", store_arguments.action, "check, vacuum or export")
      ->required()
      ->check(CLI::IsMember({"check", "vacuum", "export"}));
  store->add_option("--store", store_arguments.store_file,
                    "result store (default: results/rkhs-study.sqlite)");
  store->add_option("--format", store_arguments.format, "export: csv (default) or json")
      ->check(CLI::IsMember({"csv", "json"}));
  store->add_option("--out", store_arguments.out_file, "export: write to FILE (default: stdout)");
  run->add_flag("--mpi", session.use_mpi,
                "spread the trials over MPI ranks (under mpirun or srun; rank 0 writes)");
  const auto add_rank_timeout = [&](CLI::App* command) {
    command
        ->add_option("--rank-timeout", session.rank_timeout_seconds,
                     "with --mpi: seconds of silence after which a rank is taken as lost and its "
                     "trials run elsewhere (0: never; default 60)")
        ->check(CLI::Range(0.0, 1e9));
  };
  add_rank_timeout(run);
  bool no_plots = false, no_check_plots = false;
  run->add_flag("--no-plots", no_plots, "do not render plots (gnuplot) into <out>/plots");
  run->add_flag("--tables", run_arguments.tables,
                "also print each group's convergence table (they are in rates.md, rates.tex and "
                "report.html either way)");

  // The kinds `list` accepts come from the table of plugin kinds (plugin_kinds.hpp).
  std::string list_kinds;
  std::vector<std::string> list_accepts;
  for (const auto& name : rkhs::plugin_kind_names()) {
    list_kinds += (list_kinds.empty() ? "" : ", ") + name.singular;
    list_accepts.push_back(name.singular);
    if (name.plural != name.singular) list_accepts.push_back(name.plural);
  }
  list_accepts.insert(list_accepts.end(), {"metric", "metrics"});
  auto* list = app.add_subcommand("list", "list plugins (" + list_kinds + ") or metrics");
  list->add_option("kind", kind, list_kinds + " or metrics (default: all)")
      ->check(CLI::IsMember(list_accepts));

  std::string report_dir, report_format = "html";
  auto* report = app.add_subcommand(
      "report",
      "the rate tables of a run again, from the folder's summary.json alone (runs nothing, "
      "loads no plugin, opens no store): text, Markdown, LaTeX or report.html");
  report->add_option("directory", report_dir, "a results directory (with summary.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  report
      ->add_option("--format", report_format,
                   "text (the console's tables, every group's), md, tex or html (default html: "
                   "writes DIR/report.html)")
      ->check(CLI::IsMember({"text", "md", "tex", "html"}));

  auto* validate = app.add_subcommand("validate", "check a study file and count its trials");
  validate->add_option("study", study_file, "study definition (TOML)")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type

  auto* check = app.add_subcommand(
      "check",
      "run studies and judge their [[expect]] tables: exit 0 all pass, 1 a failure, 2 bad "
      "input, 3 inconclusive, 5 -k selected nothing");
  check
      ->add_option("studies", check_arguments.study_files,
                   "study definitions (TOML), run and judged in turn")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  check->add_option("--tier", check_arguments.tier,
                    "run only the entries and expectations of this tier (e.g. quick)");
  check
      ->add_option("-k", check_arguments.keyword_expression,
                   "judge only the test cases whose names match EXPR: case-insensitive "
                   "substrings with and, or, not and parentheses, as pytest's -k (e.g. \"power "
                   "and not gaussian\"); a study with none selected is not run")
      ->type_name("EXPR");
  auto* strict = check->add_flag("--strict", check_arguments.strict,
                                 "count inconclusive verdicts and XPASS as failures");
  check
      ->add_option("--allow", check_arguments.allow,
                   "verdicts that do not fail the check: inconclusive (exit 0, not 3)")
      ->check(CLI::IsMember({"inconclusive"}))
      ->delimiter(',')
      ->allow_extra_args(false)
      ->excludes(strict);
  check->add_option("--junit", check_arguments.junit_file,
                    "write JUnit XML: one suite per study, one test case per expectation and "
                    "group");
  check->add_option("--out", check_arguments.out_dir,
                    "also write what `run` writes (trials.csv, rates.csv, summary.json with the "
                    "verdicts, report.html, plots) here; DIR/<study name> for several studies");
  check->add_flag("--no-plots", no_check_plots, "with --out: do not render plots");
  check->add_option("--threads", check_arguments.threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  check->add_flag("--quiet,-q", check_arguments.quiet, "no progress line");
  add_store_options(check, check_arguments.store);
  check->add_flag("--mpi", session.use_mpi,
                  "spread the trials over MPI ranks (under mpirun or srun; rank 0 writes)");
  add_rank_timeout(check);

  // Plugin modules: --plugin (repeatable) here, RKHS_STUDY_PLUGIN_PATH, `plugins = [...]`.
  std::string plugin_to_verify;
  for (auto* command : {run, list, validate, check})
    command->add_option("--plugin", session.plugin_files, "load a plugin module (.so); repeatable")
        ->allow_extra_args(false);
  // The data root that data files in study files are relative to (rkhs/core/data_root.hpp).
  for (auto* command : {run, validate, check})
    command
        ->add_option("--data-dir", session.data_dir,
                     "data files named in the study are relative to DIR (default: "
                     "RKHS_STUDY_DATA, else studies/data/)")
        ->check(CLI::ExistingDirectory);
  auto* verify =
      app.add_subcommand("verify-plugin",
                         "load a plugin module and check its kernels: the kernel contract, and the "
                         "declared smoothness against the measured power-function rate");
  verify->add_option("plugin", plugin_to_verify, "plugin module (.so)")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? exit_ok : exit_bad_input;
  }

  session.runs_trials = *run || *check;
  session.loads_plugins = !*report;
  session.shard = !run_arguments.shard.empty();
  run_arguments.plots = !no_plots;
  check_arguments.plots = !no_check_plots;
  return run_command(session, argc, argv, [&](rkhs::pipeline::Executor& executor) {
    if (*run) return command_run(run_arguments, executor);
    if (*check) return command_check(check_arguments, executor);
    if (*verify) return command_verify_plugin(plugin_to_verify);
    if (*merge) return command_merge(merge_into, merge_from, merge_prefer);
    if (*store) return command_store(store_arguments);
    if (*list) return command_list(kind);
    if (*report) return command_report(report_dir, report_format);
    if (*validate) return command_validate(study_file);
    return exit_ok;
  });
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
