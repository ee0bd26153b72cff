#include "rkhs/report/rate_table.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "rkhs/rates/asymptotic.hpp"

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
      table.axis = in_n ? "n" : "h";
      for (std::size_t k = 0; k < series.trials.size(); ++k)
        table.rows.push_back(
            {in_n ? series.n[k] : series.abscissa[k], run.trials[series.trials[k]].n,
             series.values[k], static_cast<bool>(series.flagged[k]),
             k == 0 ? std::numeric_limits<double>::quiet_NaN() : series.pairwise[k - 1]});
      table.fit = series.fit;
      table.no_fit_reason = series.no_fit_reason;
      table.window = series.analysis.reported_analysis().window.points;
      table.window_note = series.analysis.note;
      table.note = series.note;
      out.push_back(std::move(table));
    }
  return out;
}

std::string document_abscissa(const RateTable& table, const RateTableRow& row) {
  return table.axis_is_n() ? fmt::format("{}", row.n) : fmt::format("{:.4g}", row.abscissa);
}

std::string document_value(const RateTableRow& row) {
  return (std::isnan(row.value) ? std::string("failed") : fmt::format("{:.4g}", row.value)) +
         (row.flagged ? "*" : "");
}

std::string document_rate(const RateTableRow& row, std::string_view missing) {
  return std::isfinite(row.rate) ? fmt::format("{:.2f}", row.rate) : std::string(missing);
}

std::string document_fit(const RateTable& table) {
  const auto& fit = table.fit;
  if (!fit) return "no fit: " + table.no_fit_reason;
  if (!std::isfinite(fit->std_error))
    return fmt::format("{:.3g} ({} points, no uncertainty)", fit->rate, fit->points);
  return fmt::format("{:.3g} ± {:.2g} ({:.4g}% CI [{:.3g}, {:.3g}], R² = {:.3f}, {} points){}",
                     fit->rate, fit->std_error, 100.0 * fit->confidence, fit->ci_low, fit->ci_high,
                     fit->r_squared, fit->points,
                     fit->model == RateModel::exponential ? ", exponential in n" : "");
}

std::string window_text(const RateTable& table) {
  if (table.window.empty()) return "";
  std::vector<double> n;
  for (const auto& row : table.rows) n.push_back(static_cast<double>(row.n));
  return fmt::format("n = {}, {} of {} points", label_range(n, table.window), table.window.size(),
                     table.rows.size());
}

}  // namespace rkhs
