#pragma once
// report.html: one self-contained page per run (no external resources; plots embedded as
// data URIs), with the study, provenance, the rate tables with fits, windows and notes, the
// expectation verdicts, the plots, and the failed trials with their reasons.

#include <filesystem>
#include <string>
#include <vector>

#include "rkhs/report/output.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

/// The page. `plots` is the folder write_plots rendered into (its SVGs are embedded; an empty
/// path or a missing folder gives a page without plots). The rate tables render
/// rate_tables(run) (rkhs/report/rate_table.hpp): the axis is n or h as the study fits, the
/// confidence level is each fit's own.
///
/// `verdicts` are the study's expectation outcomes as the caller computed them
/// (verify_expectations on this run's trials, results and rates); the page shows them and
/// judges nothing itself. When the study has expectations and `verdicts` is null, the page
/// says they were not judged. Not retained after the call.
std::string html_report(const RunRecord& run, const std::filesystem::path& plots,
                        const std::vector<ExpectationOutcome>* verdicts = nullptr);

}  // namespace rkhs
