#pragma once
// A console convergence table for one metric of one group of trials, in the shape of deal.II's
// ConvergenceTable: the refinement axis, the metric, the pairwise (local) rate, and a footer
// with the fitted rate and its confidence interval (docs/style.md practice 15).
//
//   l2_error, group gaussian/eps=2
//    n   l2_error    rate
//   10  3.162e-02       -
//   20  1.118e-02   -1.50
//   40  3.953e-03   -1.50
//   80  1.398e-03*  -1.50
//   fitted rate: -1.50 ± 0.00 (95% CI [-1.50, -1.50], R² = 1.000, 4 points)
//   * value flagged: at the round-off floor or from a singular Gram matrix

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/rates/rates.hpp"

namespace rkhs {

/// One line of the table: a point of the refinement axis and the metric measured there.
struct TableRow {
  double abscissa = 0.0;  ///< n, or whatever the axis is (fill distance h, ...)
  double value = 0.0;     ///< the metric; NaN / inf / non-positive values print as they are
  bool flagged = false;   ///< caller's doubt about the value; prints with a '*' marker
};

/// Formats the table as lines ending in '\n' (UTF-8: the footer uses ± and ²).
///
/// - First line: "<metric>, group <group>".
/// - Columns, right-aligned and separated by two spaces: the abscissa (header `abscissa_name`;
///   integral values print as integers, others with 4 significant digits), the value (header
///   `metric`; scientific with 4 significant digits, followed by '*' when flagged), and the
///   pairwise rate of `pairwise_model` (pairwise_rates for the power law,
///   pairwise_exponential_rates for the exponential model, so that the column matches the
///   footer's model; 2 decimals, 3 significant digits below 1; '-' in the first row and where the
///   rate is undefined). Rows print in the order given; rates compare neighbouring rows.
/// - Footer: the fitted rate from `fit`, which the caller computed from these rows (or a subset
///   of them, e.g. without flagged ones): "fitted rate: r ± se (95% CI [lo, hi], R² = q, m
///   points)", with "fitted rate (exponential in <abscissa_name>)" for RateModel::exponential.
///   The rate, its standard error and CI carry 2 decimals, more when |rate| < 1 (3 significant
///   digits, at most 6 decimals). A two-point fit prints its slope only. When `fit` is empty
///   the footer explains why no rate is available: `no_fit_reason` when given (the caller knows
///   what it excluded before fitting), otherwise a count of the rows with a finite, positive
///   value. A non-empty RateFit::note follows as "note: ...".
/// - When any row is flagged, a last line "* <flag_legend>".
///
/// Never throws except std::bad_alloc. Column widths count bytes, so non-ASCII metric or axis
/// names may misalign.
std::string format_convergence_table(
    std::string_view metric, std::string_view group, std::string_view abscissa_name,
    std::span<const TableRow> rows, const std::optional<RateFit>& fit,
    std::string_view flag_legend =
        "value flagged: at the round-off floor or from a singular Gram matrix",
    RateModel pairwise_model = RateModel::power_law, std::string_view no_fit_reason = {});

struct RateTable;   // rkhs/report/rate_table.hpp
struct GroupTable;  // rkhs/report/rate_table.hpp

/// The table of one RateTable of a run, formatted as above with the model's axis, its pairwise
/// rates (not recomputed: RateTableRow::rate, of the reported model), its fit or no-fit reason
/// and flagged_value_legend. The window and notes lines are console_tables' (output.hpp).
std::string format_convergence_table(const RateTable& table);

/// The fitted rates `run` prints: one row per group and metric (groups in order, metrics in
/// the study's order) with the group's title, the metric, "rate ± standard error" ("1.5 ±
/// 0.031", "(exp in n)" after an exponential rate, the rate alone without an uncertainty,
/// "const 3.769" for a constant series, "no fit") and the window (window_text; the constant's
/// text for a constant series), under the heading "fitted rates:"; columns left-aligned.
std::string format_rate_summary(const std::vector<GroupTable>& groups,
                                const std::vector<RateTable>& tables);

/// All metrics of one group in one table, as deal.II's ConvergenceTable prints several error
/// columns with a rate each:
///
///   kernel=bspline degree=1
///   (group kernel=bspline degree=1 r=1 n0=4 J=8 | target=sine ... | centres=uniform offset=0)
///    n  fill_distance   rate  power_function_sup   rate
///   10      1.257e+00      -           5.109e-01      -
///   20      6.283e-01  -1.00           3.612e-01  -0.50
///   fit                -1.00                      -0.50
///     fill_distance, fitted rate: -1.000 ± 0.000 (95% CI [...], R² = 1.000, 2 points); window ...
///
/// - Title: the group's label (GroupTable::label) and its key, or "group <key>" without a label.
/// - Columns: n, the fill distance h when the group shows it (4 significant digits), then per
///   metric of `group.columns` its value (scientific, 4 significant digits, "failed" for a failed
///   trial, '*' when flagged) and its pairwise rate under rate_heading ('-' where undefined; a
///   blank pair where the metric has no trial at that n). The last row, "fit", holds each
///   metric's fitted rate under its rate column.
/// - The columns are wrapped at `width` bytes: metrics that do not fit go to a further part of
///   the table below, which repeats n (and h).
/// - Then one line per metric: its fitted rate with the confidence interval (as in the one-metric
///   table), its window and model choice; its notes on further lines; the '*' legend last.
///
/// `tables` is the rate_tables vector the group indexes. Never throws except std::bad_alloc.
std::string format_group_table(const GroupTable& group, const std::vector<RateTable>& tables,
                               std::size_t width = 120);

/// The fitted rate of every group (rows, by label) and metric (columns, in study order) with its
/// confidence interval (fit_cell), under a line naming the confidence level; wrapped at `width`
/// as format_group_table, repeating the group column.
std::string format_fitted_rates(const std::vector<GroupTable>& groups,
                                const std::vector<RateTable>& tables, std::size_t width = 120);

}  // namespace rkhs
