#pragma once
// A finished run written out: trials.csv (tidy, one row per trial), rates.csv (one row per
// group, metric and rate: the fit and every pairwise rate), summary.json (the study, its
// provenance, trials and rates), and the console tables. Files are written to a temporary name
// unique to the write, synced and renamed, so a reader never sees a half-written file, a crash
// leaves the old file or the new one, and a failed write leaves no temporary behind.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/trial_grid.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

struct RunRecord {
  const StudyDefinition& study;
  const std::vector<TrialSpec>& trials;
  const std::vector<TrialResult>& results;
  const std::vector<MetricSeries>& rates;
  int threads = 1;
  double wall_seconds = 0;
  std::string started;                 ///< ISO 8601 UTC time the run started
  std::vector<RankRecord> ranks = {};  ///< MPI ranks of a distributed run (empty: one process)
  std::string tier = {};  ///< the tier the run was restricted to (`check --tier`; "": none)
  /// The expectations' outcomes on this run (verify_expectations, the cases `check -k`
  /// selected), written to summary.json as "expectations"; null: not judged, no such key.
  const std::vector<ExpectationOutcome>* verdicts = nullptr;
  std::size_t deselected = 0;  ///< cases `check -k` left out
};

std::string trials_csv(const RunRecord& run);
std::string rates_csv(const RunRecord& run);
/// The study, its provenance, trials and rates as JSON; with RunRecord::verdicts also
/// "expectations": the counts and, per test case, its name, metric, group, verdict, outcome
/// (with xfail), rate, CI, accepted interval, window and reason (docs/results.md).
std::string summary_json(const RunRecord& run);
/// Adaptive studies: fhat and f on the snapshot grid at the chosen laps (one row per trial, lap
/// and point: the data of the paper's "road surface estimates" figures).
std::string estimates_csv(const RunRecord& run);
/// Adaptive studies: |x - xhat| and V at the output samples of every trial.
std::string timeseries_csv(const RunRecord& run);
/// The rate tables as Markdown and LaTeX, written as rates.md and rates.tex: first the fitted
/// rates (a row per group, a column per metric, each rate with its confidence interval), then a
/// convergence table per group in deal.II's ConvergenceTable layout (n, h when the study fits
/// against it, a value and a pairwise-rate column per metric, the fitted rates at the foot),
/// followed by each metric's fit, window and notes. Flagged values carry a '*'. The LaTeX
/// tables use booktabs and siunitx (S columns aligned on the decimal point, real minus signs);
/// wide groups stack tabulars of three metrics. Both render rate_tables(run) and group_tables
/// (rkhs/report/rate_table.hpp), as console_tables and html_report do.
std::string markdown_tables(const RunRecord& run);
std::string latex_tables(const RunRecord& run);
/// The console's view: the fitted rates of every group (format_fitted_rates) when there is more
/// than one group, then each group's table (format_group_table), up to `group_tables_shown` groups
/// (`run` prints them for 12 at most, `report --format text` for all); beyond, a line that
/// points to rates.md, rates.tex and report.html.
std::string console_tables(const RunRecord& run, std::size_t group_tables_shown = 12);
/// The answer `run` ends with: unless `verdicts_only` (-q), the fitted rates, a row per group and
/// metric (format_rate_summary), and the convergence in time of an adaptive study's groups
/// (format_time_convergence); then, last, where a terminal leaves them in view, a line per
/// expectation and the counts (format_verdict_lines, "no expectations" when there is no outcome).
std::string console_answer(const RunRecord& run, const std::vector<ExpectationOutcome>& verdicts,
                           bool verdicts_only);

/// Writes trials.csv, rates.csv and summary.json (and, for adaptive studies, estimates.csv and
/// timeseries.csv) into `directory` (created if needed).
void write_outputs(const RunRecord& run, const std::filesystem::path& directory);

/// Makes sure, before the first trial runs, that `directory` can take a run's outputs: creates
/// it (and its parents) when needed, and creates, writes and removes a probe file in it. Throws
/// std::runtime_error "cannot write the output folder <dir>: <why> (choose another with --out
/// DIR)" otherwise.
void prepare_output_directory(const std::filesystem::path& directory);

/// The marker of a folder whose outputs may be of two runs: <directory>/INCOMPLETE.
inline constexpr const char* incomplete_marker = "INCOMPLETE";

/// The files a run writes into its folder, in the order it writes them ("plots/" for the plots
/// folder, report.html last), for the INCOMPLETE marker.
std::vector<std::string> output_file_names(const RunRecord& run, bool with_report, bool with_plots);

/// Writes <directory>/INCOMPLETE (atomically) before a run's first output file: it says that
/// the folder's outputs may be of two runs, which run wrote it, and lists `files`. Each file is
/// replaced atomically, but a write that fails part-way (a full disk) leaves the folder with
/// some new and some old files: the marker stays and says so. mark_outputs_complete removes it
/// after the last file is written. Throws (std::runtime_error) when it cannot be written: then
/// nothing has been written over.
void mark_outputs_incomplete(const RunRecord& run, const std::filesystem::path& directory,
                             const std::vector<std::string>& files);
void mark_outputs_complete(const std::filesystem::path& directory);

/// Writes `content` to `file` atomically: to `<file>.tmp.<pid>.<counter>` in the same
/// directory (created exclusively), fsync, rename over `file`, fsync of the directory. On any
/// failure the temporary is removed and std::runtime_error names `file`, the step and the
/// system's reason ("cannot write out/trials.csv (write): File too large").
void write_file_atomically(const std::filesystem::path& file, const std::string& content);

/// A CSV field, quoted when it contains a comma, quote or line break (RFC 4180); control bytes
/// other than line breaks and tabs, and bytes that are not UTF-8, written as \xNN (printable).
std::string csv_field(const std::string& value);
/// A real for CSV: shortest round-trip representation, "inf"/"-inf", "" for NaN.
std::string csv_number(double value);

/// A JSON string literal (quotes, backslashes and control characters escaped).
std::string json_string(std::string_view text);
/// A real for JSON: shortest round-trip representation, "inf"/"-inf" as strings, null for NaN.
std::string json_number(double value);

/// The members of a JSON object for `work`'s counters, in work_count_fields order
/// (`"kernel_evaluations": 12, ..., "peak_bytes": null`; the allocation counters null when
/// not tracked): what summary.json and `rkhs-study store export` write.
std::string work_counts_json(const WorkCounts& work);

}  // namespace rkhs
