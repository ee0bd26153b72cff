#include "rkhs/report/rate_table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/verify/expectation_cases.hpp"

namespace rkhs {

std::vector<RateTable> rate_tables(const RunRecord& run) {
  std::vector<RateTable> out;
  for (const auto& metric : run.study.metrics)
    for (std::size_t s = 0; s < run.rates.size(); ++s) {
      const auto& series = run.rates[s];
      if (series.metric != metric || series.trials.empty()) continue;
      RateTable table;
      table.series = s;
      table.metric = metric;
      table.group = run.trials[series.trials.front()].group_key;
      table.model = series.analysis.reported;
      // An exponential fit is in n whatever the study's abscissa: the table's axis follows it.
      const bool in_n = table.model == RateModel::exponential || run.study.abscissa == Abscissa::n;
      table.axis = std::string(in_n ? "n" : "h");
      for (std::size_t k = 0; k < series.trials.size(); ++k)
        table.rows.push_back(
            {in_n ? series.n[k] : series.abscissa[k], run.trials[series.trials[k]].n,
             series.values[k], static_cast<bool>(series.flagged[k]),
             static_cast<bool>(series.failed[k]),
             k == 0 ? std::numeric_limits<double>::quiet_NaN() : series.pairwise[k - 1]});
      table.fit = series.fit;
      table.no_fit_reason = series.no_fit_reason;
      table.constant = series.analysis.constant;
      if (table.constant) table.constant_text = table.constant->text(series.n);
      table.window = table.constant ? table.constant->points
                                    : series.analysis.reported_analysis().window.points;
      table.window_note = table.constant ? std::string() : series.analysis.note;
      table.note = series.note;
      out.push_back(std::move(table));
    }
  return out;
}

std::string document_abscissa(const RateTable& table, const RateTableRow& row) {
  return table.axis_is_n() ? fmt::format("{}", row.n) : fmt::format("{:.4g}", row.abscissa);
}

std::string_view missing_value(const RateTableRow& row) {
  return row.failed ? "failed" : "n/a";
}

std::string document_value(const RateTableRow& row) {
  return (std::isnan(row.value) ? std::string(missing_value(row))
                                : fmt::format("{:.4g}", row.value)) +
         (row.flagged ? "*" : "");
}

std::string document_rate(const RateTableRow& row, std::string_view missing) {
  return std::isfinite(row.rate) ? fmt::format("{:.2f}", row.rate) : std::string(missing);
}

std::string document_fit(const RateTable& table) {
  const auto& fit = table.fit;
  if (table.constant) return "constant " + table.constant_text;
  if (!fit) return "no fit: " + table.no_fit_reason;
  if (!std::isfinite(fit->std_error))
    return fmt::format("{:.3g} ({} points, no uncertainty)", fit->rate, fit->points);
  return fmt::format("{:.3g} ± {:.2g} ({:.4g}% CI [{:.3g}, {:.3g}], R² = {:.3f}, {} points){}",
                     fit->rate, fit->std_error, 100.0 * fit->confidence, fit->ci_low, fit->ci_high,
                     fit->r_squared, fit->points,
                     fit->model == RateModel::exponential ? ", exponential in n" : "");
}

std::string window_text(const RateTable& table) {
  if (table.window.empty() || table.constant) return "";  // constant_text names its points
  std::vector<double> n;
  for (const auto& row : table.rows) n.push_back(static_cast<double>(row.n));
  return fmt::format("n = {}, {} of {} points", label_range(n, table.window), table.window.size(),
                     table.rows.size());
}

namespace {
// `value` with `decimals` decimals, "0.000" rather than "-0.000".
std::string fixed(double value, int decimals) {
  auto text = fmt::format("{:.{}f}", value, decimals);
  if (text.starts_with('-') && text.find_first_not_of("-0.") == std::string::npos) text.erase(0, 1);
  return text;
}
}  // namespace

std::optional<FitCell> fit_cell_parts(const RateTable& table) {
  const auto& fit = table.fit;
  if (!fit) return std::nullopt;
  FitCell cell;
  cell.exponential = fit->model == RateModel::exponential;
  const double half_width = 0.5 * (fit->ci_high - fit->ci_low);
  if (std::isfinite(fit->std_error) && std::isfinite(half_width) && half_width >= 0) {
    const int decimals =
        half_width > 0 ? std::clamp(1 - static_cast<int>(std::floor(std::log10(half_width))), 0, 3)
                       : 3;
    cell.rate = fixed(fit->rate, decimals);
    cell.low = fixed(fit->ci_low, decimals);
    cell.high = fixed(fit->ci_high, decimals);
  } else {
    const double magnitude = std::fabs(fit->rate);
    const int decimals =
        magnitude > 0 ? std::clamp(2 - static_cast<int>(std::floor(std::log10(magnitude))), 0, 3)
                      : 3;
    cell.rate = fixed(fit->rate, decimals);
  }
  return cell;
}

std::string fit_cell(const RateTable& table) {
  if (table.constant) return fmt::format("const {:.4g}", table.constant->value);
  const auto cell = fit_cell_parts(table);
  if (!cell) return "no fit";
  std::string out = cell->rate;
  if (!cell->low.empty()) out += fmt::format(" [{}, {}]", cell->low, cell->high);
  return cell->exponential ? out + " exp" : out;
}

std::vector<GroupTable> group_tables(const RunRecord& run, const std::vector<RateTable>& tables) {
  const auto labels = group_labels(run.trials);
  std::vector<GroupTable> out;
  std::map<std::string, std::size_t> position;  // group key -> index in out
  for (const auto& trial : run.trials)
    if (!position.contains(trial.group_key)) {
      position[trial.group_key] = out.size();
      GroupTable table;
      table.group = trial.group_key;
      if (const auto label = labels.find(trial.group_key); label != labels.end())
        table.label = label->second;
      out.push_back(std::move(table));
    }
  for (std::size_t t = 0; t < tables.size(); ++t)
    if (const auto found = position.find(tables[t].group); found != position.end())
      out[found->second].columns.push_back(t);
  std::erase_if(out, [](const GroupTable& table) { return table.columns.empty(); });
  for (auto& group : out) {
    std::map<std::size_t, double> h;  // n -> fill distance (NaN until a column on h has it)
    bool any_h = false;
    for (auto t : group.columns) {
      const auto& table = tables[t];
      any_h = any_h || !table.axis_is_n();
      for (const auto& row : table.rows) {
        auto& at = h.try_emplace(row.n, std::numeric_limits<double>::quiet_NaN()).first->second;
        if (!table.axis_is_n()) at = row.abscissa;
      }
    }
    for (const auto& [n, fill] : h) {
      group.n.push_back(n);
      if (any_h) group.h.push_back(fill);
    }
  }
  return out;
}

std::vector<std::string> table_metrics(const std::vector<RateTable>& tables) {
  std::vector<std::string> metrics;
  for (const auto& table : tables)
    if (std::find(metrics.begin(), metrics.end(), table.metric) == metrics.end())
      metrics.push_back(table.metric);
  return metrics;
}

std::optional<double> shared_confidence(const std::vector<RateTable>& tables) {
  std::set<double> levels;
  for (const auto& table : tables)
    if (table.fit && std::isfinite(table.fit->std_error)) levels.insert(table.fit->confidence);
  if (levels.size() != 1) return std::nullopt;
  return *levels.begin();
}

const RateTableRow* row_at(const RateTable& table, std::size_t n) {
  const auto found = std::find_if(table.rows.begin(), table.rows.end(),
                                  [n](const RateTableRow& row) { return row.n == n; });
  return found == table.rows.end() ? nullptr : &*found;
}

std::string rate_heading(const RateTable& table) {
  return table.model == RateModel::exponential ? "rate (exp in n)" : "rate";
}

}  // namespace rkhs
