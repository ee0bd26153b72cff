#pragma once
// report.html: one self-contained page per run (no external resources; plots embedded as
// data URIs), with the study, provenance, the rate tables with fits, windows and notes, the
// expectation verdicts, the plots, and the failed trials with their reasons.

#include <filesystem>
#include <string>

#include "rkhs/report/output.hpp"

namespace rkhs {

/// The page. `plots` is the folder write_plots rendered into (its SVGs are embedded; an empty
/// path or a missing folder gives a page without plots).
std::string html_report(const RunRecord& run, const std::filesystem::path& plots);

}  // namespace rkhs
