#pragma once
// summary.json of an earlier run read back: the fields a later command needs, parsed as JSON
// (nlohmann::json), not searched for as text; and a whole results folder read back for
// `rkhs-study report`, which renders its tables again from the folder alone.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "rkhs/report/output.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/verify/study_rates.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

struct RunSummary {
  std::string study;   ///< the study's name
  std::string source;  ///< the study file the run read, as it was given
  std::string tier;    ///< the tier the run was restricted to (`check --tier`), "" for none
};

/// Reads `file` (summary.json, as summary_json() writes it; "tier" may be absent or null, as
/// in files written before it was recorded). Throws std::runtime_error naming
/// the file when it cannot be opened, is not JSON (with the byte offset), or has no "source".
RunSummary read_run_summary(const std::filesystem::path& file);

/// The largest summary.json read_results_folder reads (bytes; 256 MiB, about 150,000 trials):
/// a larger file is refused by its size before it is read. Reading takes about 5.5 times the
/// file's size in memory.
inline constexpr std::uintmax_t max_summary_bytes = std::uintmax_t{256} << 20;

/// A finished run as its folder records it: the study's description (name, kind, metrics,
/// abscissa, n; no plugins, no expectations' definitions), its trials with their results, its
/// rates and the verdicts of its expectations, rebuilt from summary.json alone. The study file
/// the folder names (`source`) is never read and no plugin is loaded: what the folder says is
/// taken as data, validated, and rendered. Not copyable: `verdicts` point into
/// `study.expectations` (moving keeps them valid).
struct ResultsFolder {
  StudyDefinition study;
  std::vector<TrialSpec> trials;
  std::vector<TrialResult> results;
  std::vector<MetricSeries> rates;
  /// The verdicts recorded in "expectations" (`judged` false: the run judged none); each
  /// points to an Expectation of `study.expectations` holding its number, location, name,
  /// metric, kind and xfail marker (the rest of the expectation is not recorded).
  std::vector<ExpectationOutcome> verdicts;
  bool judged = false;
  std::size_t deselected = 0;
  std::string tier;     ///< the tier of the run ("" none)
  std::string started;  ///< provenance.started
  int threads = 1;      ///< provenance.threads
  double wall_seconds = 0;

  ResultsFolder() = default;
  ResultsFolder(ResultsFolder&&) = default;
  ResultsFolder& operator=(ResultsFolder&&) = default;
  ResultsFolder(const ResultsFolder&) = delete;
  ResultsFolder& operator=(const ResultsFolder&) = delete;

  /// The record the report writers take (markdown_tables, latex_tables, console_tables,
  /// html_report); it refers to this folder's members.
  RunRecord record() const;
};

/// Reads <directory>/summary.json as summary_json() writes it. Refused with
/// std::runtime_error naming the file and what is wrong: a path that is not a regular file
/// (checked by type before it is opened), a file above max_summary_bytes, text that is not
/// JSON (with its line and column), or a key missing or of the wrong type or value (named by
/// its JSON path, e.g. `trials[3].metrics.l2_error: expected a number, "inf", "-inf" or null;
/// found a string`). Reads nothing else, runs nothing, loads nothing, writes nothing.
ResultsFolder read_results_folder(const std::filesystem::path& directory);

}  // namespace rkhs
