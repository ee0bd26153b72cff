#pragma once
// Options several commands share, declared the same way on each (CLI11): the result store's,
// MPI's, plugin modules' and the data root's.

#include <CLI/CLI.hpp>

#include "commands/session.hpp"
#include "rkhs/pipeline/study_pipeline.hpp"

namespace rkhs::cli {

/// --store FILE, --fresh, --no-store.
void add_store_options(CLI::App& command, pipeline::StoreOptions& store);

/// --mpi and --rank-timeout SECONDS (the session's: one MPI session per process).
void add_mpi_options(CLI::App& command, SessionOptions& session);

/// --plugin FILE, repeatable: a plugin module loaded before the command (session.hpp).
void add_plugin_option(CLI::App& command, SessionOptions& session);

/// --data-dir DIR: the data root that data files named in a study are relative to
/// (rkhs/core/data_root.hpp).
void add_data_dir_option(CLI::App& command, SessionOptions& session);

}  // namespace rkhs::cli
