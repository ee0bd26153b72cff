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
    // A constant series (MetricSeries::no_fit_reason "constant ...: not a rate") is its value.
    if (no_fit_reason.starts_with("constant ")) return std::string(no_fit_reason);
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

namespace {

// A text table of right-aligned columns (left-aligned where `left` says), two spaces apart, its
// first `fixed` columns repeated in every part when the others do not fit in `width`: the rest
// is cut between blocks (block_sizes: how many columns each block holds, e.g. a metric's value
// and rate) into parts, each as wide as fits, at least one block per part.
std::string wrapped_table(const std::vector<std::vector<std::string>>& lines, std::size_t fixed,
                          const std::vector<std::size_t>& block_sizes,
                          const std::vector<bool>& left, std::size_t width) {
  if (lines.empty()) return {};
  const std::size_t columns = lines.front().size();
  std::vector<std::size_t> widths(columns, 0);
  for (const auto& line : lines)
    for (std::size_t c = 0; c < columns && c < line.size(); ++c)
      widths[c] = std::max(widths[c], line[c].size());
  const auto span = [&](std::size_t from, std::size_t count) {
    std::size_t total = 0;
    for (std::size_t c = from; c < from + count; ++c) total += widths[c] + 2;
    return total;
  };
  // Parts: [first block, end block).
  std::vector<std::pair<std::size_t, std::size_t>> parts;
  const std::size_t fixed_width = span(0, fixed);
  for (std::size_t b = 0, column = fixed; b < block_sizes.size();) {
    std::size_t end = b, used = fixed_width, end_column = column;
    while (end < block_sizes.size() &&
           (end == b || used + span(end_column, block_sizes[end]) <= width + 2)) {
      used += span(end_column, block_sizes[end]);
      end_column += block_sizes[end];
      ++end;
    }
    parts.emplace_back(b, end);
    b = end;
    column = end_column;
  }
  if (parts.empty()) parts.emplace_back(0, 0);
  std::string out;
  std::size_t first_column = fixed;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    std::size_t last_column = first_column;
    for (std::size_t b = parts[p].first; b < parts[p].second; ++b) last_column += block_sizes[b];
    if (p > 0) out += '\n';
    for (const auto& line : lines) {
      std::string text;
      const auto cell = [&](std::size_t c) {
        const std::string& value = c < line.size() ? line[c] : std::string();
        if (!text.empty()) text += "  ";
        text += left[c] ? fmt::format("{:<{}}", value, widths[c])
                        : fmt::format("{:>{}}", value, widths[c]);
      };
      for (std::size_t c = 0; c < fixed; ++c) cell(c);
      for (std::size_t c = first_column; c < last_column; ++c) cell(c);
      while (!text.empty() && text.back() == ' ') text.pop_back();
      out += text + '\n';
    }
    first_column = last_column;
  }
  return out;
}

std::string fixed_rate(double rate, RateModel model) {
  return fmt::format("{:.{}f}", rate, model == RateModel::power_law ? 2 : rate_decimals(rate));
}

}  // namespace

std::string format_group_table(const GroupTable& group, const std::vector<RateTable>& tables,
                               std::size_t width) {
  bool any_flagged = false;
  for (auto t : group.columns)
    for (const auto& row : tables[t].rows) any_flagged = any_flagged || row.flagged;
  const std::string marker_slot = any_flagged ? " " : "";

  std::vector<std::vector<std::string>> lines(1);
  std::vector<bool> left;
  auto& header = lines.front();
  header.push_back("n");
  if (group.shows_h()) header.push_back("h");
  const std::size_t fixed = header.size();
  std::vector<std::size_t> blocks;
  for (auto t : group.columns) {
    header.push_back(tables[t].metric + marker_slot);
    header.push_back(rate_heading(tables[t]));
    blocks.push_back(2);
  }
  left.assign(header.size(), false);
  for (std::size_t r = 0; r < group.n.size(); ++r) {
    auto& line = lines.emplace_back();
    line.push_back(fmt::format("{}", group.n[r]));
    if (group.shows_h())
      line.push_back(std::isfinite(group.h[r]) ? fmt::format("{:.4g}", group.h[r]) : "");
    for (auto t : group.columns) {
      const auto* row = row_at(tables[t], group.n[r]);
      if (!row) {
        line.insert(line.end(), {"", ""});
        continue;
      }
      line.push_back((std::isnan(row->value) ? std::string(missing_value(*row))
                                             : fmt::format("{:.3e}", row->value)) +
                     (row->flagged ? std::string("*") : marker_slot));
      line.push_back(std::isfinite(row->rate) ? fixed_rate(row->rate, tables[t].model) : "-");
    }
  }
  // The foot: each metric's fitted rate under its rate column.
  auto& foot = lines.emplace_back();
  foot.push_back("fit");
  if (group.shows_h()) foot.push_back("");
  for (auto t : group.columns) {
    foot.push_back("");
    foot.push_back(tables[t].fit        ? fixed_rate(tables[t].fit->rate, tables[t].model)
                   : tables[t].constant ? "const"
                                        : "-");
  }

  std::string out = (group.label.empty() ? "group " + group.group : group.label) + '\n';
  if (!group.label.empty()) out += "(group " + group.group + ")\n";
  out += wrapped_table(lines, fixed, blocks, left, width);
  for (auto t : group.columns) {
    const auto& table = tables[t];
    std::vector<TableRow> rows;
    for (const auto& row : table.rows) rows.push_back({row.abscissa, row.value, row.flagged});
    out +=
        fmt::format("  {}, {}", table.metric,
                    table.constant ? "constant " + table.constant_text + ", not a rate"
                                   : fit_footer(table.fit, rows, table.axis, table.no_fit_reason));
    if (const auto window = window_text(table); !window.empty())
      out += fmt::format("; window {}{}{}", window, table.window_note.empty() ? "" : "; ",
                         table.window_note);
    out += '\n';
    if (table.fit && !table.fit->note.empty())
      out += fmt::format("    note: {}\n", table.fit->note);
    if (!table.note.empty()) out += fmt::format("    note: {}\n", table.note);
  }
  if (any_flagged) out += fmt::format("* {}\n", flagged_value_legend);
  return out;
}

std::string format_fitted_rates(const std::vector<GroupTable>& groups,
                                const std::vector<RateTable>& tables, std::size_t width) {
  const auto metrics = table_metrics(tables);
  const auto confidence = shared_confidence(tables);

  std::vector<std::vector<std::string>> lines(1);
  lines.front().push_back("group");
  for (const auto& metric : metrics) lines.front().push_back(metric);
  for (const auto& group : groups) {
    auto& line = lines.emplace_back(metrics.size() + 1);
    line[0] = group.title();
    for (auto t : group.columns) {
      const auto m = static_cast<std::size_t>(
          std::find(metrics.begin(), metrics.end(), tables[t].metric) - metrics.begin());
      line[m + 1] = fit_cell(tables[t]);
    }
  }
  std::vector<bool> left(metrics.size() + 1, false);
  left[0] = true;
  const std::string level = confidence
                                ? fmt::format("{:.4g}% confidence intervals", 100.0 * *confidence)
                                : std::string("confidence intervals at the levels of the tables");
  return fmt::format("fitted rates with {} (exp: exponential in n)\n", level) +
         wrapped_table(lines, 1, std::vector<std::size_t>(metrics.size(), 1), left, width);
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

std::string format_rate_summary(const std::vector<GroupTable>& groups,
                                const std::vector<RateTable>& tables) {
  std::vector<std::array<std::string, 4>> lines{{"group", "metric", "rate", "window"}};
  for (const auto& group : groups)
    for (auto t : group.columns) {
      const auto& table = tables[t];
      std::string rate = "no fit", window = window_text(table);
      if (table.constant) {
        rate = fmt::format("const {:.4g}", table.constant->value);
        window = table.constant_text;
      } else if (const auto& fit = table.fit) {
        rate = std::isfinite(fit->std_error)
                   ? fmt::format("{:.3g} ± {:.2g}", fit->rate, fit->std_error)
                   : fmt::format("{:.3g}", fit->rate);
        if (fit->model == RateModel::exponential) rate += " (exp in n)";
      }
      lines.push_back({group.title(), table.metric, rate, window});
    }
  // Widths in characters, not bytes: "±" is one.
  const auto length = [](const std::string& text) {
    return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) {
      return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    }));
  };
  std::array<std::size_t, 3> width{};
  for (const auto& line : lines)
    for (std::size_t c = 0; c < width.size(); ++c) width[c] = std::max(width[c], length(line[c]));
  std::string out = "fitted rates:\n";
  for (const auto& line : lines) {
    std::string text = "  ";
    for (std::size_t c = 0; c < width.size(); ++c)
      text += line[c] + std::string(width[c] - length(line[c]) + 2, ' ');
    text += line[3];
    while (!text.empty() && text.back() == ' ') text.pop_back();
    out += text + '\n';
  }
  return out;
}

}  // namespace rkhs
