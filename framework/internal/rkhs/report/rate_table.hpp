#pragma once
// The rate table of a run, built once: one RateTable per metric and group of trials, holding
// what every rate-table writer shows (in the manner of deal.II's ConvergenceTable, which is
// filled once and written as text, LaTeX or HTML). The console (console_tables), Markdown
// (markdown_tables), LaTeX (latex_tables) and HTML (html_report) writers render this model and
// compute nothing of their own: the axis, the pairwise rates, the fitted rate with its
// confidence level, the window and the notes all come from here.
//
// The model holds numbers; the writers choose their number formats. The document writers
// (Markdown, LaTeX, HTML) share the cell and fit texts below, so they agree digit for digit.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/rates/rates.hpp"
#include "rkhs/report/output.hpp"

namespace rkhs {

/// One point of the refinement axis of one table.
struct RateTableRow {
  double abscissa = 0.0;  ///< the table's axis: n, or the fill distance h (see RateTable::axis)
  std::size_t n = 0;      ///< the trial's number of centres, whatever the axis
  /// The metric; NaN for a failed trial and for a metric the trial's engine does not define
  /// (e.g. a lap-map metric of a trial stepped through time: NaN, the trial ok).
  double value = 0.0;
  bool flagged = false;   ///< excluded from the fit as numerically meaningless
  bool failed = false;    ///< the trial failed: a NaN value is "failed", not "n/a"
  /// The pairwise rate of the reported model between the previous row and this one
  /// (MetricSeries::pairwise); NaN in the first row and where it is undefined.
  double rate = 0.0;
};

/// One metric of one group: the rows in increasing n, the reported fit and its context.
struct RateTable {
  std::size_t series = 0;  ///< index of the MetricSeries in RunRecord::rates
  std::string metric;
  std::string group;  ///< the group's key (every axis but n)
  /// "n", or "h" when the study fits against the fill distance (StudyDefinition::abscissa);
  /// an exponential fit is in n whatever the study says, so its table's axis is "n".
  std::string axis;
  RateModel model = RateModel::power_law;  ///< the reported model; the pairwise rates are its own
  std::vector<RateTableRow> rows;
  std::optional<RateFit> fit;       ///< the reported fit, with its own confidence level
  std::string no_fit_reason;        ///< why there is no fit ("" when there is one)
  /// Set for a series that does not vary with n (SeriesAnalysis::constant): shown as its value
  /// and band, never as a rate; `fit` is empty then.
  std::optional<ConstantSeries> constant;
  /// constant->text() with the table's n: "3.7690 ± 0.00027 (0.0072 %) on n = 40..100".
  std::string constant_text;
  std::vector<std::size_t> window;  ///< rows of the reported model's asymptotic window
  std::string window_note;          ///< the model choice (SeriesAnalysis::note), "" when none
  std::string note;  ///< what was excluded and why (MetricSeries::note), "" when nothing

  /// True when the axis is n (abscissa == n for every row).
  bool axis_is_n() const { return axis == "n"; }
};

/// The tables of `run`: for each metric of the study in its order, the non-empty series of
/// that metric in RunRecord::rates order. Never throws except std::bad_alloc.
std::vector<RateTable> rate_tables(const RunRecord& run);

/// The legend of the '*' marker on flagged values.
inline constexpr std::string_view flagged_value_legend =
    "value flagged: at the round-off floor or from a singular Gram matrix";

// Texts shared by the document writers (Markdown, LaTeX, HTML), UTF-8, unescaped.

/// The axis cell: n as an integer on an n axis, otherwise 4 significant digits.
std::string document_abscissa(const RateTable& table, const RateTableRow& row);
/// The value cell: 4 significant digits, "failed" for a failed trial or "n/a" for a metric its
/// engine does not define (missing_value), followed by '*' when flagged.
std::string document_value(const RateTableRow& row);
/// The text of a value that is not a number: "failed" for a failed trial, "n/a" for a metric
/// the trial's engine does not define (a NaN value of an ok trial).
std::string_view missing_value(const RateTableRow& row);
/// The rate cell: 2 decimals, or `missing` where there is no rate.
std::string document_rate(const RateTableRow& row, std::string_view missing = "-");
/// The fitted rate: "-1.5 ± 0.03 (95% CI [-1.53, -1.47], R² = 0.999, 10 points)" with the
/// fit's own confidence level (4 significant digits of the percentage), then
/// ", exponential in n" for the exponential model; "r (m points, no uncertainty)" without a
/// standard error; "constant <constant_text>" for a constant series; "no fit: <reason>"
/// without a fit.
std::string document_fit(const RateTable& table);
/// The window of the reported model: "n = 10..80, 4 of 4 points", "" when it is empty or the
/// series is constant (its constant_text names its points).
std::string window_text(const RateTable& table);
/// The fitted rate and its confidence interval rounded to the interval: as many decimals as
/// show the interval's half-width to two significant digits, between 0 and 3 ("3.94", "[3.72,
/// 4.15]"; "-21", "[-102, 61]"; a rate of 1e-15 with a CI of 1e-15 is "0.000"); without an
/// interval, 3 significant digits up to 3 decimals. No "-0".
struct FitCell {
  std::string rate, low, high;  ///< low and high are "" without an interval
  bool exponential = false;     ///< the exponential model's rate (in n)
};
/// The fit's FitCell; nullopt without a fit.
std::optional<FitCell> fit_cell_parts(const RateTable& table);
/// The fitted rate with its confidence interval in a few characters, for a cell of a table of
/// fitted rates: "-1.47 [-1.52, -1.43]", "-1.47" without an interval, "-0.287 [-0.363, -0.211]
/// exp" for the exponential model, "const 3.769" for a constant series (4 significant digits),
/// "no fit" without a fit (fit_cell_parts).
std::string fit_cell(const RateTable& table);

/// All metrics of one group of trials side by side: the layout of deal.II's ConvergenceTable,
/// one refinement column (n, and the fill distance h when the study fits against it), then a
/// value and a rate column per metric, the fitted rates at the foot. It indexes the RateTables
/// of the run and computes nothing of its own.
struct GroupTable {
  std::string group;  ///< the group's key (every axis but n)
  /// The axes that tell this group from the study's other groups ("kernel=bspline degree=2";
  /// group_labels of rkhs/verify/expectation_cases.hpp): the title a reader needs.
  std::string label;
  std::vector<std::size_t> n;  ///< the rows: every n a column has, increasing
  /// The fill distance of each row when a column's axis is h (NaN where none has the row);
  /// empty when every column's axis is n.
  std::vector<double> h;
  std::vector<std::size_t> columns;  ///< positions in the rate_tables vector, in metric order

  bool shows_h() const { return !h.empty(); }
  /// What to call the group: its label, or its key when it has none.
  const std::string& title() const { return label.empty() ? group : label; }
};

/// The group tables of `run` in the order of their groups' first trial; `tables` is
/// rate_tables(run). Never throws except std::bad_alloc.
std::vector<GroupTable> group_tables(const RunRecord& run, const std::vector<RateTable>& tables);

/// The metrics of `tables`, each once, in their (the study's) order.
std::vector<std::string> table_metrics(const std::vector<RateTable>& tables);

/// The confidence level every fit with an interval shares (0.95); nullopt when they differ or
/// none has one.
std::optional<double> shared_confidence(const std::vector<RateTable>& tables);

/// The row of `table` at `n`; nullptr when the metric has no trial there.
const RateTableRow* row_at(const RateTable& table, std::size_t n);

/// The heading of a metric's rate column in a group table: "rate" for the study's axis, "rate
/// (exp in n)" for a column whose reported model is exponential.
std::string rate_heading(const RateTable& table);

}  // namespace rkhs
