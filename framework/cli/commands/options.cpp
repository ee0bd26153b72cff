// Options several commands share (commands/options.hpp).
#include "commands/options.hpp"

namespace rkhs::cli {

void add_store_options(CLI::App& command, pipeline::StoreOptions& store) {
  command.add_option(
      "--store", store.file,
      "result store (SQLite) shared by studies (default: results/rkhs-study.sqlite)");
  command.add_flag("--fresh", store.fresh, "run every trial again, ignoring stored results");
  command.add_flag("--no-store", store.disabled, "neither read nor write a result store");
}

void add_mpi_options(CLI::App& command, SessionOptions& session) {
  command.add_flag("--mpi", session.use_mpi,
                   "spread the trials over MPI ranks (under mpirun or srun; rank 0 writes)");
  command
      .add_option("--rank-timeout", session.rank_timeout_seconds,
                  "with --mpi: seconds of silence after which a rank is taken as lost and its "
                  "trials run elsewhere (0: never; default 60)")
      ->check(CLI::Range(0.0, 1e9));
}

void add_plugin_option(CLI::App& command, SessionOptions& session) {
  command.add_option("--plugin", session.plugin_files, "load a plugin module (.so); repeatable")
      ->allow_extra_args(false);
}

void add_data_dir_option(CLI::App& command, SessionOptions& session) {
  command
      .add_option("--data-dir", session.data_dir,
                  "data files named in the study are relative to DIR (default: RKHS_STUDY_DATA, "
                  "else studies/data/)")
      ->check(CLI::ExistingDirectory);
}

}  // namespace rkhs::cli
