#pragma once
// The commands of rkhs-study, one file each (commands/<name>.cpp). Each file declares its own
// subcommand and options (add_<name>_command, CLI11's subcommands in files) and acts on them
// (command_<name>); main.cpp only assembles the commands, parses, and runs the one named. Each
// command returns the process exit code.

#include <functional>
#include <string>
#include <vector>

#include "commands/session.hpp"
#include "rkhs/pipeline/executor.hpp"
#include "rkhs/pipeline/study_pipeline.hpp"

namespace CLI {
class App;
}

namespace rkhs::cli {

constexpr int exit_ok = 0, exit_failed_trials = 1, exit_bad_input = 2, exit_interrupted = 130;
// `check` adds the verdicts' codes: check_failed (1), check_inconclusive (3) and
// check_none_selected (5) of rkhs/verify/verification.hpp.

/// Options of the commands that run trials.
struct RunArguments {
  int threads = 0;     ///< 0: the executor's default (all cores)
  bool quiet = false;  ///< no progress line, no per-run messages
  pipeline::StoreOptions store;
  bool plots = true;  ///< render plots into <out>/plots (--no-plots: not)
};

struct RunCommand : RunArguments {
  std::string study_file;
  std::string out_dir;  ///< "" : results/<study name>
  std::string shard;    ///< "K/N" or ""
  /// --tables: print each group's convergence table (console_tables) before the answer; they
  /// are in rates.md, rates.tex and report.html either way.
  bool tables = false;
};
int command_run(const RunCommand& arguments, pipeline::Executor& executor);

/// `check`: the studies run and judged in turn with the same options, one report, one exit
/// code (docs/verification.md).
struct CheckCommand : RunArguments {
  std::vector<std::string> study_files;
  std::string tier, junit_file;
  std::string out_dir;             ///< "": none; with several studies, DIR/<study name> each
  std::string keyword_expression;  ///< -k: the test cases to judge ("": all)
  std::vector<std::string> allow;  ///< --allow: verdicts that do not fail ("inconclusive")
  bool strict = false;
};
int command_check(const CheckCommand& arguments, pipeline::Executor& executor);

/// `report DIR`: DIR's tables (text, md, tex on stdout; html into DIR/report.html) from
/// DIR/summary.json alone: runs nothing, loads no plugin, opens no store.
int command_report(const std::string& directory, const std::string& format);
int command_validate(const std::string& study_file);
/// `kind`: a plugin kind (singular or plural), "metric(s)", or "" for everything.
int command_list(const std::string& kind);
int command_merge(const std::string& into, const std::vector<std::string>& from,
                  const std::string& prefer);
int command_verify_plugin(const std::string& file);

/// `store check|vacuum|export`: the records of a result store verified (exit 1 when some do
/// not), the ones that do not verify removed, or every record written as CSV or JSON.
struct StoreCommand {
  std::string action;  ///< "check", "vacuum" or "export"
  std::string store_file = "results/rkhs-study.sqlite";
  std::string format = "csv";  ///< export: "csv" or "json"
  std::string out_file;        ///< export: "" or "-" for stdout
};
int command_store(const StoreCommand& arguments);

/// A command as main() assembles it: its subcommand of the application, with every option it
/// owns bound to arguments that `prepare` and `action` keep alive.
struct Command {
  CLI::App* subcommand = nullptr;
  /// After parsing, before the session starts: what the session must know of this command
  /// (SessionOptions: runs trials, loads plugins, a shard), and options read off flags.
  std::function<void(SessionOptions&)> prepare;
  /// The command's work, with the executor the session set up; returns the exit code.
  std::function<int(pipeline::Executor&)> action;
};

/// Each declares its subcommand on `app` (in the order main.cpp calls them, the order of
/// `rkhs-study --help`); options shared with other commands come from commands/options.hpp and
/// bind into `session`.
Command add_run_command(CLI::App& app, SessionOptions& session);
Command add_merge_command(CLI::App& app);
Command add_store_command(CLI::App& app);
Command add_list_command(CLI::App& app, SessionOptions& session);
Command add_report_command(CLI::App& app);
Command add_validate_command(CLI::App& app, SessionOptions& session);
Command add_check_command(CLI::App& app, SessionOptions& session);
Command add_verify_plugin_command(CLI::App& app);

}  // namespace rkhs::cli
