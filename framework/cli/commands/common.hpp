#pragma once
// What the commands print alike: counts with their noun, a study's warnings, how an interrupted
// run ended; and the SIGINT / SIGTERM handling every command that runs trials installs.

#include <cstddef>
#include <string>

#include "rkhs/pipeline/study_pipeline.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::cli {

/// Refuses (std::invalid_argument) an output file that is `input` by any path or link
/// (std::filesystem::equivalent; nothing is refused when either does not exist): "<option>
/// <output> is <what> <input>: writing it would replace what this command reads; write to
/// another file".
void refuse_output_onto_input(const std::string& option, const std::string& output,
                              const std::string& what, const std::string& input);

/// Removes the store `file` and its -wal, -shm and -journal files: a store this command
/// created and must not leave behind (a failed merge into a new file, a run refused after it
/// opened a new store).
void remove_store_files(const std::string& file);

/// "1 trial", "3 trials".
std::string counted(std::size_t count, const char* singular, const char* plural);

/// A study file's warnings (valid but doubtful settings), one line each, on stderr.
void print_warnings(const StudyDefinition& study);

/// "metrics computed: l2_error, sup_error (2 of 13)", with the metrics computed beyond
/// study.metrics and why ("fill_distance for abscissa = h"): what `validate` and the start line
/// of `run` and `check` say a trial will compute (StudyDefinition::computed_metrics()).
std::string computed_metrics_text(const StudyDefinition& study);

/// Installs the SIGINT / SIGTERM handlers (also where the shell started the command with them
/// ignored, as it does a background job's SIGINT): stop_was_requested() then tells whether one
/// arrived.
void stop_at_signals();

/// Installs the SIGINT / SIGTERM handlers and makes `options` stop at them: no new trial
/// starts, trials in flight stop at their next cancellation point (rkhs/core/cancellation.hpp)
/// or are abandoned 2 s later (in this process; main() then ends at once). Neither kind is
/// stored.
void stop_on_signals(RunOptions& options);

/// True once SIGINT or SIGTERM arrived.
bool stop_was_requested() noexcept;

/// What an interrupted run did and kept, in words that are true with and without a store;
/// returns exit_interrupted. `journal`: where `run` kept the finished trials' metrics (empty
/// for other commands).
int report_interruption(const StoredRun& run, const pipeline::StoreOptions& store,
                        const std::string& journal = {});

/// "  N trials reused from FILE, M run now" and, in an MPI job, the trials of each rank
/// (stderr), after a run whose every trial has a result.
void print_run_sources(const pipeline::PipelineOutcome& outcome,
                       const pipeline::Executor& executor);

/// Plots of `record` into <out_dir>/plots (rkhs/report/plots.hpp); the number rendered. What
/// could not be rendered is a warning on stderr, never an error.
std::size_t render_plots(const RunRecord& record, const std::string& out_dir, bool quiet);

/// "rkhs-study: warning: STORE: trial KEY: what is wrong; run again" for every stored record a
/// run did not trust (StoredRun::store_problems), on stderr, also with --quiet.
void print_store_problems(const pipeline::PipelineOutcome& outcome);

}  // namespace rkhs::cli
