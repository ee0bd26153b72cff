// The Markdown, LaTeX and console writers of the rate tables: each renders rate_tables(run) and
// its group_tables (rkhs/report/rate_table.hpp) and computes nothing of its own.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <utility>

#include "rkhs/core/printable.hpp"
#include "rkhs/report/convergence_in_time.hpp"
#include "rkhs/report/convergence_table.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/rate_table.hpp"

namespace rkhs {

namespace {

// Metrics per LaTeX table (two columns each beside n, and h when shown): wider tables do not
// fit the text width of a page, so a group with more metrics continues in further tables.
constexpr std::size_t latex_metrics_per_table = 3, latex_metrics_per_table_with_h = 2;
// The note on rates of the exponential model, marked with a superscript e.
constexpr std::string_view latex_exponential_note =
    "$^{\\mathrm{e}}$ rate of the exponential model: the slope of $\\ln$ value against $n$.";
// Metrics per tabular of the fitted rates (a rate and its interval each).
constexpr std::size_t latex_fits_per_tabular = 2;

// Text from a study or data file (a CSV road's file name, a study name): control bytes and
// bytes that are not UTF-8 first written as \xNN (printable), so that a newline cannot end a
// table row or a LaTeX comment and put the rest of the text on a line of its own.
std::string latex_escape(std::string_view raw) {
  const auto text = printable(raw);
  std::string out;
  for (char c : text) {
    if (c == '_' || c == '%' || c == '&' || c == '#' || c == '$' || c == '{' || c == '}')
      out += '\\';
    if (c == '|') {
      out += "$|$";
      continue;
    }
    if (c == '\\' || c == '~' || c == '^') {
      out += c == '\\'  ? "\\textbackslash{}"
             : c == '~' ? "\\textasciitilde{}"
                        : "\\textasciicircum{}";
      continue;
    }
    out += c;
  }
  return out;
}

std::string markdown_escape(std::string_view raw) {
  std::string out;
  for (char c : printable(raw)) {
    if (c == '|' || c == '*') out += '\\';
    out += c;
  }
  return out;
}

// `raw` as a Markdown code span: printable, fenced by one backtick more than the longest run of
// backticks in it (and a space inside the fence when it has any), so that it cannot end early.
std::string markdown_code(std::string_view raw) {
  const auto text = printable(raw);
  std::size_t longest = 0, run = 0;
  for (char c : text) {
    run = c == '`' ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  const std::string fence(longest + 1, '`');
  const std::string pad = longest ? " " : "";
  return fence + pad + text + pad + fence;
}

// The column of `group` that holds `metric`, or nullptr.
const RateTable* column(const GroupTable& group, const std::vector<RateTable>& tables,
                        const std::string& metric) {
  for (auto t : group.columns)
    if (tables[t].metric == metric) return &tables[t];
  return nullptr;
}

// The confidence level the fits share, as "95%"; "" when they differ or none has one.
std::string shared_level(const std::vector<RateTable>& tables) {
  const auto level = shared_confidence(tables);
  return level ? fmt::format("{:.4g}%", 100.0 * *level) : "";
}

// --- LaTeX ---------------------------------------------------------------------------------

// siunitx's table-format of a column of numbers as fmt wrote them ("-1.257e-05", "12.34"):
// the widest integer part, fraction and exponent, and a sign slot when any is negative.
std::string table_format(const std::vector<std::string>& numbers) {
  std::size_t integer = 1, fraction = 0, exponent = 0;
  bool negative = false, exponent_negative = false;
  for (const auto& text : numbers) {
    std::string_view s = text;
    if (s.starts_with('-')) {
      negative = true;
      s.remove_prefix(1);
    }
    const auto e = s.find('e');
    const auto mantissa = s.substr(0, e);
    const auto dot = mantissa.find('.');
    integer = std::max(integer, dot == std::string_view::npos ? mantissa.size() : dot);
    if (dot != std::string_view::npos) fraction = std::max(fraction, mantissa.size() - dot - 1);
    if (e != std::string_view::npos) {
      auto power = s.substr(e + 1);
      if (power.starts_with('-')) exponent_negative = true;
      if (power.starts_with('-') || power.starts_with('+')) power.remove_prefix(1);
      exponent = std::max(exponent, power.size());
    }
  }
  std::string out = fmt::format("{}{}", negative ? "-" : "", integer);
  if (fraction) out += fmt::format(".{}", fraction);
  if (exponent) out += fmt::format("e{}{}", exponent_negative ? "-" : "", exponent);
  return out;
}

bool is_number(const std::string& cell) {
  return !cell.empty() && (std::isdigit(static_cast<unsigned char>(cell.front())) ||
                           (cell.size() > 1 && cell.front() == '-'));
}

// A fitted rate in LaTeX: "\num{-1.50 +- 0.03} (95\,\% CI [\num{-1.53}, \num{-1.47}],
// $R^2 = \num{0.999}$, 10 points)", with siunitx's real minus signs.
std::string latex_fit(const RateTable& table) {
  const auto& fit = table.fit;
  if (table.constant) return "constant " + latex_escape(table.constant_text);
  if (!fit) return "no fit: " + latex_escape(table.no_fit_reason);
  const std::string model = fit->model == RateModel::exponential ? ", exponential in $n$" : "";
  if (!std::isfinite(fit->std_error))
    return fmt::format("\\num{{{:.3g}}} ({} points, no uncertainty){}", fit->rate, fit->points,
                       model);
  return fmt::format(
      "\\num{{{:.3g}}} $\\pm$ \\num{{{:.2g}}} ({:.4g}\\,\\% CI [\\num{{{:.3g}}}, \\num{{{:.3g}}}], "
      "$R^2 = "
      "\\num{{{:.3f}}}$, {} points){}",
      fit->rate, fit->std_error, 100.0 * fit->confidence, fit->ci_low, fit->ci_high, fit->r_squared,
      fit->points, model);
}

std::string latex_fit_cell(const RateTable& table) {
  if (table.constant) return fmt::format("const \\num{{{:.4g}}}", table.constant->value);
  const auto cell = fit_cell_parts(table);
  if (!cell) return "--";
  std::string out = fmt::format("\\num{{{}}}", cell->rate);
  if (!cell->low.empty()) out += fmt::format(" [\\num{{{}}}, \\num{{{}}}]", cell->low, cell->high);
  return cell->exponential ? out + "$^{\\mathrm{e}}$" : out;
}

std::string latex_label(std::string_view study, std::string_view what) {
  std::string out = "tab:";
  for (char c : study) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
  return out + "-" + std::string(what);
}

// One tabular of a group table: n, h when shown, and the given metrics' value and rate columns.
std::string latex_tabular(const GroupTable& group, const std::vector<RateTable>& tables,
                          const std::vector<std::size_t>& columns) {
  const auto rate_text = [](const RateTable& table, double rate) {
    return table.model == RateModel::power_law ? fmt::format("{:.2f}", rate)
                                               : fmt::format("{:.3g}", rate);
  };
  // Cells as text, then each numeric column's table-format from its numbers.
  std::vector<std::vector<std::string>> body;  // rows, then the fit row
  for (std::size_t r = 0; r < group.n.size(); ++r) {
    auto& line = body.emplace_back();
    line.push_back(fmt::format("{}", group.n[r]));
    if (group.shows_h())
      line.push_back(std::isfinite(group.h[r]) ? fmt::format("{:.3e}", group.h[r]) : "");
    for (auto t : columns) {
      const auto* row = row_at(tables[t], group.n[r]);
      if (!row) {
        line.insert(line.end(), {"", ""});
        continue;
      }
      // Numbers go to the S column as they are; anything else is text in braces.
      const char* marker = row->flagged ? "*" : "";
      std::string value = std::isnan(row->value)
                              ? fmt::format("{{{}{}}}", missing_value(*row), marker)
                          : std::isinf(row->value)
                              ? fmt::format("{{${}\\infty${}}}", row->value > 0 ? "" : "-", marker)
                          : row->flagged ? fmt::format("{{\\num{{{:.3e}}}*}}", row->value)
                                         : fmt::format("{:.3e}", row->value);
      line.push_back(value);
      line.push_back(std::isfinite(row->rate) ? rate_text(tables[t], row->rate) : "{--}");
    }
  }
  auto& foot = body.emplace_back();
  foot.push_back("{fit}");
  if (group.shows_h()) foot.push_back("");
  for (auto t : columns) {
    foot.push_back("");
    foot.push_back(tables[t].fit ? rate_text(tables[t], tables[t].fit->rate) : "{--}");
  }
  const std::size_t width = body.front().size();
  std::string spec = "r";
  for (std::size_t c = 1; c < width; ++c) {
    std::vector<std::string> numbers;
    for (const auto& line : body)
      if (is_number(line[c])) numbers.push_back(line[c]);
    spec += fmt::format(" S[table-format={}]", table_format(numbers));
  }
  const std::size_t first = group.shows_h() ? 3 : 2;  // first metric column, 1-based
  std::string over = group.shows_h() ? " & " : "", rule,
              heads = group.shows_h() ? "{$n$} & {$h$}" : "{$n$}";
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const auto& table = tables[columns[k]];
    over += fmt::format(" & \\multicolumn{{2}}{{c}}{{{}}}", latex_escape(table.metric));
    rule += fmt::format("\\cmidrule(lr){{{}-{}}}", first + 2 * k, first + 2 * k + 1);
    heads += fmt::format(" & {{value}} & {{{}}}",
                         table.model == RateModel::exponential ? "rate$^{\\mathrm{e}}$" : "rate");
  }
  std::string out =
      fmt::format("\\begin{{tabular}}{{{}}}\n\\toprule\n{} \\\\\n{}\n{} \\\\\n\\midrule\n", spec,
                  over, rule, heads);
  for (std::size_t r = 0; r < body.size(); ++r) {
    if (r + 1 == body.size()) out += "\\midrule\n";
    std::string line;
    for (std::size_t c = 0; c < width; ++c) line += (c ? " & " : "") + body[r][c];
    out += line + " \\\\\n";
  }
  return out + "\\bottomrule\n\\end{tabular}\n";
}

}  // namespace

std::string markdown_tables(const RunRecord& run) {
  const auto tables = rate_tables(run);
  const auto groups = group_tables(run, tables);
  const auto metrics = table_metrics(tables);
  std::string out = fmt::format("# {}: rates\n\n", run.study.name);
  if (groups.empty()) return out + "No rate table: no metric has a series.\n";

  // The fitted rates at a glance: a row per group, a column per metric.
  const auto level = shared_level(tables);
  out += fmt::format(
      "## Fitted rates\n\nFitted rate [{} confidence interval] of each metric "
      "(exp: exponential in n).\n\n| group |",
      level.empty() ? "its" : level);
  for (const auto& metric : metrics) out += fmt::format(" {} |", markdown_escape(metric));
  out += "\n|:---|";
  for (std::size_t m = 0; m < metrics.size(); ++m) out += "---:|";
  out += "\n";
  for (const auto& group : groups) {
    out += fmt::format("| {} |", markdown_escape(group.title()));
    for (const auto& metric : metrics) {
      const auto* table = column(group, tables, metric);
      out += fmt::format(" {} |", table ? fit_cell(*table) : std::string());
    }
    out += "\n";
  }

  // Adaptive studies: whether the estimate has converged in time, per group.
  if (const auto convergence = time_convergence(run); !convergence.empty()) {
    out += "\n## Convergence in time\n\n";
    for (const auto& group : convergence)
      out += fmt::format("- {}: {}\n", markdown_escape(group.label), group.sentence);
  }

  // The convergence table of each group: every metric's value and pairwise rate.
  for (const auto& group : groups) {
    out += fmt::format("\n## {}\n\nGroup {}\n\n| n |", markdown_escape(group.title()),
                       markdown_code(group.group));
    std::string align = "|---:|";
    if (group.shows_h()) {
      out += " h |";
      align += "---:|";
    }
    for (auto t : group.columns) {
      out += fmt::format(" {} | {} |", markdown_escape(tables[t].metric), rate_heading(tables[t]));
      align += "---:|---:|";
    }
    out += "\n" + align + "\n";
    for (std::size_t r = 0; r < group.n.size(); ++r) {
      out += fmt::format("| {} |", group.n[r]);
      if (group.shows_h())
        out += std::isfinite(group.h[r]) ? fmt::format(" {:.4g} |", group.h[r]) : " |";
      for (auto t : group.columns) {
        const auto* row = row_at(tables[t], group.n[r]);
        out += row ? fmt::format(" {} | {} |", markdown_escape(document_value(*row)),
                                 document_rate(*row))
                   : std::string(" | |");
      }
      out += "\n";
    }
    out += "| **fit** |";
    if (group.shows_h()) out += " |";
    for (auto t : group.columns)
      out += tables[t].fit ? fmt::format(" | **{:.3g}** |", tables[t].fit->rate) : " | - |";
    out += "\n\n";
    for (auto t : group.columns) {
      const auto& table = tables[t];
      out += fmt::format("- {}: {}", markdown_escape(table.metric), document_fit(table));
      if (const auto window = window_text(table); !window.empty())
        out += fmt::format("; window {}{}{}", window, table.window_note.empty() ? "" : "; ",
                           table.window_note);
      if (!table.note.empty()) out += "; " + table.note;
      out += "\n";
    }
  }
  out += fmt::format("\n\\* {}; not fitted.\n", flagged_value_legend);
  return out;
}

std::string latex_tables(const RunRecord& run) {
  const auto tables = rate_tables(run);
  const auto groups = group_tables(run, tables);
  const auto metrics = table_metrics(tables);
  std::string out = fmt::format(
      "% {}: convergence tables (needs \\usepackage{{booktabs}} and \\usepackage{{siunitx}})\n",
      latex_escape(run.study.name));
  if (groups.empty()) return out;

  // The fitted rates: a row per group, metrics in tabulars of a few columns each.
  const auto level = shared_level(tables);
  out += fmt::format(
      "\\begin{{table}}[ht]\n\\centering\n\\caption{{{}: fitted rates with their {} confidence "
      "intervals}}\n\\label{{{}}}\n",
      latex_escape(run.study.name), level.empty() ? "" : latex_escape(level),
      latex_label(run.study.name, "rates"));
  for (std::size_t from = 0; from < metrics.size(); from += latex_fits_per_tabular) {
    const auto to = std::min(metrics.size(), from + latex_fits_per_tabular);
    if (from > 0) out += "\\par\\medskip\n";
    out += "\\begin{tabular}{l" + std::string(to - from, 'c') + "}\n\\toprule\ngroup";
    for (std::size_t m = from; m < to; ++m) out += " & " + latex_escape(metrics[m]);
    out += " \\\\\n\\midrule\n";
    for (const auto& group : groups) {
      out += latex_escape(group.title());
      for (std::size_t m = from; m < to; ++m) {
        const auto* table = column(group, tables, metrics[m]);
        out += " & " + (table ? latex_fit_cell(*table) : std::string());
      }
      out += " \\\\\n";
    }
    out += "\\bottomrule\n\\end{tabular}\n";
  }
  if (std::any_of(tables.begin(), tables.end(), [](const RateTable& t) {
        return t.fit && t.fit->model == RateModel::exponential;
      }))
    out += fmt::format("\\par\\smallskip\n{{\\footnotesize {}}}\n", latex_exponential_note);
  out += "\\end{table}\n\n";

  // One table per group: every metric's value and pairwise rate, the fits below; a group with
  // more metrics than a tabular holds continues in further tables, so that each fits a page.
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const auto& group = groups[g];
    const auto per_table =
        group.shows_h() ? latex_metrics_per_table_with_h : latex_metrics_per_table;
    for (std::size_t from = 0; from < group.columns.size(); from += per_table) {
      const std::vector<std::size_t> part(
          group.columns.begin() + static_cast<std::ptrdiff_t>(from),
          group.columns.begin() +
              static_cast<std::ptrdiff_t>(std::min(group.columns.size(), from + per_table)));
      const auto label = from > 0 ? fmt::format("group{}-{}", g + 1, from / per_table + 1)
                                  : fmt::format("group{}", g + 1);
      out += fmt::format(
          "% group {}\n\\begin{{table}}[ht]\n\\centering\n\\caption{{{}: {}{}}}\n\\label{{{}}}\n",
          printable(group.group), latex_escape(run.study.name), latex_escape(group.title()),
          from > 0 ? " (continued)" : "", latex_label(run.study.name, label));
      out += latex_tabular(group, tables, part) + "\\par\\smallskip\n{\\footnotesize\n";
      bool any_flagged = false, any_exponential = false;
      for (auto t : part) {
        const auto& table = tables[t];
        for (const auto& row : table.rows) any_flagged = any_flagged || row.flagged;
        any_exponential = any_exponential || table.model == RateModel::exponential;
        out += fmt::format("{}: {}{}", latex_escape(table.metric),
                           table.constant ? "" : "fitted rate ", latex_fit(table));
        if (const auto window = window_text(table); !window.empty())
          out += fmt::format("; window {}", latex_escape(window));
        out += ".\\\\\n";
      }
      if (any_exponential) out += fmt::format("{}\\\\\n", latex_exponential_note);
      if (any_flagged)
        out += fmt::format("* {}; not fitted.\\\\\n", latex_escape(flagged_value_legend));
      out += "}\n\\end{table}\n\n";
    }
  }
  return out;
}

std::string console_tables(const RunRecord& run, std::size_t group_tables_shown) {
  const auto tables = rate_tables(run);
  const auto groups = group_tables(run, tables);
  std::string out;
  if (groups.size() > 1) out += format_fitted_rates(groups, tables) + "\n";
  if (groups.size() > group_tables_shown)
    return out + fmt::format(
                     "The convergence table of each of the {} groups is in rates.md, "
                     "rates.tex and report.html.\n\n",
                     groups.size());
  for (const auto& group : groups) out += format_group_table(group, tables) + "\n";
  return out;
}

std::string console_answer(const RunRecord& run, const std::vector<ExpectationOutcome>& verdicts,
                           bool verdicts_only) {
  std::string out;
  if (!verdicts_only) {
    const auto tables = rate_tables(run);
    const auto groups = group_tables(run, tables);
    if (!groups.empty()) out += format_rate_summary(groups, tables);
    out += format_time_convergence(time_convergence(run));
  }
  return out + format_verdict_lines(verdicts);
}

}  // namespace rkhs
