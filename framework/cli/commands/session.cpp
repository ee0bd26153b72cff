#include "commands/session.hpp"

#include <fmt/format.h>

#include <iostream>
#include <optional>

#include "commands/commands.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/mpi/distributed.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/run/result_store.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::cli {

namespace {

// A message that ends the command quotes at most this much (shortened): an error that echoes
// a huge input (a 10 MB expression) stays readable.
constexpr std::size_t max_message_bytes = 4000;

// Registration errors of the built-ins and built-in plugins a linker dropped: the build is
// broken, nothing can be trusted.
bool registries_sound() {
  if (const auto errors = registration_errors(); !errors.empty()) {
    for (const auto& e : errors)
      std::cerr << "rkhs-study: plugin registration error: " << e << "\n";
    return false;
  }
  if (const auto missing = missing_builtin_plugins(); !missing.empty()) {
    for (const auto& m : missing) std::cerr << "rkhs-study: built-in plugin missing: " << m << "\n";
    return false;
  }
  return true;
}

}  // namespace

int run_command(const SessionOptions& options, int& argc, char**& argv,
                const std::function<int(pipeline::Executor&)>& command) {
  if (!registries_sound()) return exit_bad_input;
  // A command started as several MPI processes without --mpi would run the whole study once
  // per process.
  if (options.runs_trials && !options.use_mpi && distributed::launched_process_count() > 1) {
    if (distributed::launched_first())
      std::cerr << fmt::format(
          "rkhs-study: started as {} MPI processes without --mpi: each would run "
          "the whole study and write the same files; add --mpi\n",
          distributed::launched_process_count());
    return exit_bad_input;
  }
  std::optional<distributed::Session> session;
  std::optional<distributed::MpiExecutor> mpi;
  pipeline::LocalExecutor local;
  if (options.use_mpi) {
    if (options.shard) {
      std::cerr << "rkhs-study: --mpi and --shard exclude each other (--shard is for schedulers "
                   "without MPI)\n";
      return exit_bad_input;
    }
    try {
      session.emplace(argc, argv);
    } catch (const std::exception& e) {
      std::cerr << "rkhs-study: " << e.what() << "\n";
      return exit_bad_input;
    }
    mpi.emplace(*session, options.rank_timeout_seconds);
  }
  pipeline::Executor& executor = mpi ? static_cast<pipeline::Executor&>(*mpi) : local;
  try {
    executor.on_every_process([&] {
      if (options.loads_plugins) {
        load_plugins_from_environment();
        for (const auto& file : options.plugin_files) load_plugin(file);
      }
      if (!options.data_dir.empty()) set_data_root(options.data_dir);
    });
    return command(executor);
  } catch (const distributed::QuietExit& e) {
    return e.code;
  } catch (const DamagedStore& e) {
    // Damaged, not bad input: the file was a store (`store check` says the same with exit 1).
    std::cerr << "rkhs-study: " << printable(e.what(), true) << "\n";
    return exit_failed_trials;
  } catch (const StudyError& e) {
    std::cerr << printable(shortened(e.what(), max_message_bytes), true) << "\n";
    return exit_bad_input;
  } catch (const std::exception& e) {
    std::cerr << "rkhs-study: " << printable(shortened(e.what(), max_message_bytes), true) << "\n";
    return exit_bad_input;
  }
}

}  // namespace rkhs::cli
