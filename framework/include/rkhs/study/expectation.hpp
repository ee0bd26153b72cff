#pragma once
// Expectations: what a study file says its results must show ([[expect]] tables), checked by
// `rkhs-study check` (rkhs/verify/verification.hpp). docs/verification.md is the reference.
//
//   [[expect]]
//   metric = "power_function_sup"     # a metric of the study
//   kernel = "bspline"                # group selector: any axis column of trials.csv
//   degree = 1                        #   (a list accepts any of its values)
//   theory = true                     # what is expected: theory = true | rate | model | bound
//                                     #   | constant | reference
//   tier = "quick"                    # optional: the tiers this expectation belongs to
//   xfail = "why"                     # optional: a known deviation (a fail does not fail check)
//
// An expectation applies to every group (all axes but n) its selector matches; each
// (expectation, group) pair gets its own verdict.

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/parameters.hpp"
#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/rates/rates.hpp"

namespace rkhs {

struct TrialSpec;

/// One term of a group selector: an axis column of trials.csv ("kernel", "degree",
/// "target_amplitude", "centres", ...) and the values it accepts (any of them).
struct AxisSelector {
  std::string column;
  std::vector<ParameterValue> values;
};

enum class ExpectationKind {
  rate,       ///< the fitted rate lies in an interval
  theory,     ///< the rate the kernel's metadata predicts (rkhs/rates/theory.hpp)
  model,      ///< a rate model describes the series better than the other
  bound,      ///< metric <= constant * by [* times] at every n
  constant,   ///< the series does not vary with n (at a given value, or any)
  reference,  ///< the series equals published values (a CSV file) within a relative tolerance
};

/// Every kind, in the order of the enum (for reading a kind back by its name).
inline constexpr ExpectationKind expectation_kinds[] = {
    ExpectationKind::rate,  ExpectationKind::theory,   ExpectationKind::model,
    ExpectationKind::bound, ExpectationKind::constant, ExpectationKind::reference};

/// constant = true: the series is constant (rkhs/rates/asymptotic.hpp, detect_constant);
/// constant = { value = v, within = w }: |metric(n) - v| <= w + floor(n) at every usable n.
struct ConstantSpec {
  std::optional<double> value;  ///< absent: constant = true (any value)
  double within = 0.0;          ///< absolute; 0: within the values' floors
};

/// metric(n) <= constant * by(n) * times(n) at every usable n (by and times optional; without
/// them the bound is the constant); with at_least also metric(n) >= at_least * by(n) * times(n),
/// a two-sided bracket (e.g. a ratio that theory says is 1).
struct BoundSpec {
  std::string by;     ///< "" when absent
  std::string times;  ///< "" when absent (needs by)
  double constant = 1.0;
  std::optional<double> at_least;  ///< the lower constant; absent: one-sided
};

/// reference = { file = "paper/table1.csv", value = "condition_number", where = { kernel =
/// "bspline_first_order" }, within = 0.05 }: at every n of the file's rows that `where` selects,
/// |metric(n) / value(n) - 1| <= within + the measured value's relative floor. The file (below
/// the data root, rkhs/core/data_root.hpp) is read when the study file is: a header line naming
/// the columns, a column `n` and the `value` column; `where` compares each named column's text
/// with the value as written (numbers numerically). docs/verification.md, "Reference values".
struct ReferenceSpec {
  std::string file;                                        ///< as the study file names it
  std::string value_column;                                ///< the column of the published values
  std::vector<std::pair<std::string, std::string>> where;  ///< column, value as written
  double within = 0.0;          ///< relative half-width about a ratio of 1
  std::vector<std::size_t> n;   ///< the selected rows' n, ascending and distinct
  std::vector<double> values;   ///< their published values (finite, nonzero)
  std::vector<unsigned> lines;  ///< each row's line in the file, for messages
  /// "paper/table1.csv, condition_number where kernel = bspline_first_order"
  std::string text() const;
};

/// One [[expect]] table, validated against the study it belongs to.
struct Expectation {
  std::size_t number = 0;    ///< 1-based position among the file's [[expect]] tables
  std::string location;      ///< "file:line:column" of the table, for messages
  std::string name;          ///< optional label (`name = "..."`), "" when absent
  std::string metric;
  std::vector<AxisSelector> selectors;  ///< all must match; empty selects every group
  ExpectationKind kind = ExpectationKind::rate;
  /// rate: the model whose fit is judged (default power law); model: the model required.
  RateModel model = RateModel::power_law;
  RateInterval interval;            ///< rate: the accepted interval
  std::optional<double> expected;   ///< rate = x: x (the interval is x +- tolerance)
  /// rate = { at_least = "metric" }: the interval is derived from that metric's fitted rate in
  /// the same group (at least as fast, within the tolerance); "" otherwise.
  std::string rate_reference;
  double tolerance = 0.1;           ///< rate = x and theory: half-width of the accepted interval
  BoundSpec bound;                  ///< bound only
  ConstantSpec constant;            ///< constant only
  ReferenceSpec reference;          ///< reference only
  /// n_from, n_to, h_from, h_to, last: the points judged (a rate: the window of the fit,
  /// replacing the automatic one; a bound: the n where it must hold). Empty: the study's.
  FitWindow window;
  std::vector<std::string> tiers;   ///< empty: belongs to no named tier
  /// `xfail = "reason"`: the expectation is known not to hold (pytest's xfail marker): a fail
  /// is reported as XFAIL and does not fail `check`, a pass as XPASS. "" when absent.
  std::string xfail;

  /// Whether `trial`'s group satisfies every selector (values compared as printed in
  /// trials.csv, so `sigma = 1` matches the real 1.0).
  bool selects(const TrialSpec& trial) const;
  /// "kernel=bspline degree=1" (the selector as written), "every group" when empty.
  std::string selector_text() const;
  /// Whether the expectation is in `tier` ("" means every expectation).
  bool in_tier(std::string_view tier) const;
  /// The stable part of the names of its test cases, which does not depend on the table's
  /// position in the file: `name` when given, else "<metric> <selector_text()>" ("<metric>"
  /// without selectors).
  std::string id() const;
};

/// The kind as the study file's key names it: "rate", "theory", "model", "bound", "constant",
/// "reference".
std::string_view expectation_kind_name(ExpectationKind kind);

/// The default tolerance of rate = x and theory expectations: 0.1 on the slope.
inline constexpr double default_rate_tolerance = 0.1;

}  // namespace rkhs
