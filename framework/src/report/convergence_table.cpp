#include "rkhs/report/convergence_table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "rkhs/rates/asymptotic.hpp"
#include "rkhs/report/rate_table.hpp"

namespace rkhs {
namespace {

std::string format_abscissa(double a) {
  if (std::isfinite(a) && a == std::trunc(a) && std::fabs(a) < 1e15)
    return fmt::format("{:.0f}", a);
  return fmt::format("{:.4g}", a);
}

// Decimals for a rate: 2, or 3 significant digits when |rate| < 1, at most 6.
int rate_decimals(double rate) {
  if (!std::isfinite(rate) || rate == 0.0) return 2;
  const double wanted = 2.0 - std::floor(std::log10(std::fabs(rate)));
  return static_cast<int>(std::clamp(wanted, 2.0, 6.0));
}

std::string fit_footer(const std::optional<RateFit>& fit, std::span<const TableRow> rows,
                       std::string_view abscissa_name, std::string_view no_fit_reason) {
  if (!fit) {
    if (rows.empty()) return "fitted rate: not available (no points)";
    if (!no_fit_reason.empty())
      return fmt::format("fitted rate: not available ({})", no_fit_reason);
    const auto usable = std::count_if(rows.begin(), rows.end(), [](const TableRow& r) {
      return std::isfinite(r.value) && r.value > 0.0;
    });
    return fmt::format(
        "fitted rate: not available ({} of {} points have a finite, positive value; a fit needs "
        "at least 2, at distinct {})",
        usable, rows.size(), abscissa_name);
  }
  const std::string label = fit->model == RateModel::exponential
                                ? fmt::format("fitted rate (exponential in {})", abscissa_name)
                                : std::string("fitted rate");
  const int d = rate_decimals(fit->rate);
  if (!std::isfinite(fit->std_error))
    return fmt::format("{}: {:.{}f} ({} points, no confidence interval)", label, fit->rate, d,
                       fit->points);
  const std::string r_squared = std::isfinite(fit->r_squared)
                                    ? fmt::format("R² = {:.3f}", fit->r_squared)
                                    : std::string("R² undefined");
  return fmt::format("{}: {:.{}f} ± {:.{}f} ({:.4g}% CI [{:.{}f}, {:.{}f}], {}, {} points)", label,
                     fit->rate, d, fit->std_error, d, 100.0 * fit->confidence, fit->ci_low, d,
                     fit->ci_high, d, r_squared, fit->points);
}

// The table with the pairwise rates given (rates[i - 1] between rows i - 1 and i).
std::string render_table(std::string_view metric, std::string_view group,
                         std::string_view abscissa_name, std::span<const TableRow> rows,
                         std::span<const double> rates, const std::optional<RateFit>& fit,
                         std::string_view flag_legend, RateModel pairwise_model,
                         std::string_view no_fit_reason) {
  const bool any_flagged =
      std::any_of(rows.begin(), rows.end(), [](const TableRow& r) { return r.flagged; });

  // Cells first, then widths. With flags, every value cell carries a marker slot ('*' or ' ')
  // so the numbers stay right-aligned; the header gets the same slot.
  const std::string marker_slot = any_flagged ? " " : "";
  std::vector<std::array<std::string, 3>> cells;
  cells.push_back({std::string(abscissa_name), std::string(metric) + marker_slot, "rate"});
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const bool has_rate = i > 0 && std::isfinite(rates[i - 1]);
    cells.push_back(
        {format_abscissa(rows[i].abscissa),
         fmt::format("{:.3e}", rows[i].value) + (rows[i].flagged ? std::string("*") : marker_slot),
         has_rate
             ? fmt::format("{:.{}f}", rates[i - 1],
                           pairwise_model == RateModel::power_law ? 2 : rate_decimals(rates[i - 1]))
             : std::string("-")});
  }
  std::array<std::size_t, 3> width{};
  for (const auto& line : cells)
    for (std::size_t c = 0; c < 3; ++c) width[c] = std::max(width[c], line[c].size());

  std::string out = fmt::format("{}, group {}\n", metric, group);
  for (const auto& line : cells)
    out += fmt::format("{:>{}}  {:>{}}  {:>{}}\n", line[0], width[0], line[1], width[1], line[2],
                       width[2]);
  out += fit_footer(fit, rows, abscissa_name, no_fit_reason) + '\n';
  if (fit && !fit->note.empty()) out += fmt::format("note: {}\n", fit->note);
  if (any_flagged) out += fmt::format("* {}\n", flag_legend);
  return out;
}

}  // namespace

std::string format_convergence_table(std::string_view metric, std::string_view group,
                                     std::string_view abscissa_name, std::span<const TableRow> rows,
                                     const std::optional<RateFit>& fit,
                                     std::string_view flag_legend, RateModel pairwise_model,
                                     std::string_view no_fit_reason) {
  std::vector<double> x, y;
  for (const auto& row : rows) {
    x.push_back(row.abscissa);
    y.push_back(row.value);
  }
  const std::vector<double> rates = pairwise_model == RateModel::power_law
                                        ? pairwise_rates(x, y)
                                        : pairwise_exponential_rates(x, y);
  return render_table(metric, group, abscissa_name, rows, rates, fit, flag_legend, pairwise_model,
                      no_fit_reason);
}

std::string format_convergence_table(const RateTable& table) {
  std::vector<TableRow> rows;
  std::vector<double> rates;
  for (const auto& row : table.rows) {
    rows.push_back({row.abscissa, row.value, row.flagged});
    if (&row != &table.rows.front()) rates.push_back(row.rate);
  }
  return render_table(table.metric, table.group, table.axis, rows, rates, table.fit,
                      flagged_value_legend, table.model, table.no_fit_reason);
}

}  // namespace rkhs
