#pragma once
// A finished run's output folder, written the one way `rkhs-study run`, `rkhs-study check --out`
// and the Python package (Study.run, python/src/module.cpp) write it.

#include <filesystem>
#include <functional>

#include "rkhs/report/output.hpp"

namespace rkhs {

/// Writes `record` into `directory`: the INCOMPLETE marker first (mark_outputs_incomplete,
/// listing plots/ when `with_plots`), then write_outputs, then `after_outputs` (what the caller
/// does in between: `run` removes its journal; the commands render the plots into
/// <directory>/plots), then report.html (html_report with record.verdicts, embedding
/// <directory>/plots when `with_plots`), and last removes the marker. A marker that cannot be
/// written throws as mark_outputs_incomplete does (nothing written over); a failure after it
/// throws std::runtime_error "<what>; the outputs in <directory> may now be partly this run's
/// and partly an earlier run's: <directory>/INCOMPLETE says so and lists them".
void write_run_folder(const RunRecord& record, const std::filesystem::path& directory,
                      bool with_plots, const std::function<void()>& after_outputs = {});

}  // namespace rkhs
