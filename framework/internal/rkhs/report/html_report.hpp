#pragma once
// report.html: one self-contained page per run (no external resources; plots embedded as
// data URIs): the study and its provenance, the failed trials with their reasons, the
// expectation verdicts as a table coloured by outcome (fitted rate, CI, accepted interval,
// window, reason, and what was expected and found), the fitted rates of every group and metric
// in one table, the convergence plots of each metric (all parts of a plot split into several
// files), and a convergence table per group (every metric's value and rate side by side).

#include <filesystem>
#include <string>
#include <vector>

#include "rkhs/report/output.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

/// The page. `plots` is the folder write_plots rendered into (its SVGs are embedded; an empty
/// path or a missing folder gives a page without plots; only regular files, not links, of at
/// most 64 MiB are embedded, so that a results folder from elsewhere can neither put another
/// file of this machine into the page nor make it wait on a FIFO). The rate tables render
/// rate_tables(run) and group_tables (rkhs/report/rate_table.hpp): the axis is n or h as the
/// study fits, the confidence level is each fit's own.
///
/// `verdicts` are the study's expectation outcomes as the caller computed them
/// (verify_expectations on this run's trials, results and rates); the page shows them and
/// judges nothing itself. When the study has expectations and `verdicts` is null, the page
/// says they were not judged. Not retained after the call.
std::string html_report(const RunRecord& run, const std::filesystem::path& plots,
                        const std::vector<ExpectationOutcome>* verdicts = nullptr);

}  // namespace rkhs
