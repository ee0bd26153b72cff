// The Markdown, LaTeX and console writers of the rate tables: each renders rate_tables(run)
// (rkhs/report/rate_table.hpp) and computes nothing of its own.
#include <fmt/format.h>

#include <string>
#include <utility>

#include "rkhs/report/convergence_table.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/rate_table.hpp"

namespace rkhs {

namespace {

std::string latex_escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '_' || c == '%' || c == '&' || c == '#' || c == '$') out += '\\';
    if (c == '|') {
      out += "$|$";
      continue;
    }
    out += c;
  }
  return out;
}

}  // namespace

std::string markdown_tables(const RunRecord& run) {
  std::string out = fmt::format("# {}: rates\n\n", run.study.name);
  for (const auto& t : rate_tables(run)) {
    std::string group = t.group;
    for (std::size_t p = group.find('|'); p != std::string::npos; p = group.find('|', p + 2))
      group.replace(p, 1, "\\|");
    out += fmt::format("## {}\n\n{}\n\n| {} | {} | rate |\n|---:|---:|---:|\n", t.metric, group,
                       t.axis, t.metric);
    for (const auto& row : t.rows)
      out += fmt::format("| {} | {} | {} |\n", document_abscissa(t, row), document_value(row),
                         document_rate(row));
    out += fmt::format("\nFitted rate: {}\n\n", document_fit(t));
  }
  out += fmt::format("\\* {}; not fitted.\n", flagged_value_legend);
  return out;
}

std::string latex_tables(const RunRecord& run) {
  std::string out = fmt::format("% {}: rate tables (needs \\usepackage{{booktabs}})\n",
                                latex_escape(run.study.name));
  for (const auto& t : rate_tables(run)) {
    out += fmt::format(
        "\\begin{{table}}[ht]\n\\centering\n\\caption{{{}: {}}}\n\\begin{{tabular}}{{rrr}}\n"
        "\\toprule\n${}$ & {} & rate \\\\\n\\midrule\n",
        latex_escape(t.metric), latex_escape(t.group), t.axis, latex_escape(t.metric));
    for (const auto& row : t.rows)
      out += fmt::format("{} & {} & {} \\\\\n", document_abscissa(t, row), document_value(row),
                         document_rate(row, "--"));
    std::string fit = latex_escape(document_fit(t));
    for (const auto& [from, to] :
         {std::pair<std::string, std::string>{"±", "$\\pm$"}, {"R²", "$R^2$"}}) {
      for (auto p = fit.find(from); p != std::string::npos; p = fit.find(from, p + to.size()))
        fit.replace(p, from.size(), to);
    }
    out += fmt::format(
        "\\bottomrule\n\\end{{tabular}}\n\n\\smallskip fitted rate: {}\n\\end{{table}}\n\n", fit);
  }
  return out;
}

std::string console_tables(const RunRecord& run) {
  std::string out;
  for (const auto& t : rate_tables(run)) {
    out += format_convergence_table(t);
    if (const auto window = window_text(t); !window.empty())
      out += fmt::format("  window: {}{}{}\n", window, t.window_note.empty() ? "" : "; ",
                         t.window_note);
    if (!t.note.empty()) out += "  note: " + t.note + "\n";
    out += "\n";
  }
  return out;
}

}  // namespace rkhs
