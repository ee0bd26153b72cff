#pragma once
// What every command does before its own work: the start-up checks of the registries, MPI when
// --mpi is given, plugin modules and the data root loaded on every process; and the one place
// that turns an exception into a message and an exit code.

#include <functional>
#include <string>
#include <vector>

#include "rkhs/pipeline/executor.hpp"

namespace rkhs::cli {

struct SessionOptions {
  bool runs_trials = false;  ///< run or check: refused when started as several processes
  bool use_mpi = false;      ///< --mpi
  bool shard = false;        ///< --shard given (excludes --mpi)
  /// Load plugin modules (RKHS_STUDY_PLUGIN_PATH, --plugin) before the command; false for
  /// commands that only read data (`report`), which must never run code a file names.
  bool loads_plugins = true;
  double rank_timeout_seconds = 60;       ///< --rank-timeout
  std::vector<std::string> plugin_files;  ///< --plugin
  std::string data_dir;                   ///< --data-dir ("" : the default data root)
};

/// Runs `command` with the executor the options ask for and returns its exit code: 2 (bad
/// input) with a message when the registries hold errors, MPI cannot start, a plugin cannot be
/// loaded, or the command throws (a StudyError as it is, anything else after "rkhs-study: ").
int run_command(const SessionOptions& options, int& argc, char**& argv,
                const std::function<int(pipeline::Executor&)>& command);

}  // namespace rkhs::cli
