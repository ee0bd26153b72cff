#include "rkhs/report/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <utility>

#include "rkhs/core/build_info.hpp"
#include "rkhs/report/convergence_in_time.hpp"
#include "rkhs/report/plots.hpp"
#include "rkhs/report/rate_table.hpp"

namespace rkhs {

namespace {

std::string escape_html(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    for (int s : {18, 12, 6, 0}) out += table[(v >> s) & 63];
  }
  if (const std::size_t rest = bytes.size() - i; rest) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += rest == 2 ? table[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// A plot to embed: "" unless `file` is a regular file itself (not a link: a results folder from
// elsewhere must not put another file of this machine into the page, nor a FIFO hang it) of at
// most 64 MiB. An empty result is left out of the page.
std::string read_file(const std::filesystem::path& file) {
  std::error_code error;
  const auto status = std::filesystem::symlink_status(file, error);
  if (error || !std::filesystem::is_regular_file(status)) return {};
  const auto size = std::filesystem::file_size(file, error);
  if (error || size > (std::uintmax_t{64} << 20)) return {};
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Document text in HTML: escaped, with entities for the fit's ± and R².
std::string html_text(std::string_view text) {
  std::string out = escape_html(text);
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"±", "&plusmn;"}, {"²", "&sup2;"}}) {
    for (auto p = out.find(from); p != std::string::npos; p = out.find(from, p + to.size()))
      out.replace(p, from.size(), to);
  }
  return out;
}

// A number of a verdict for its table cell: 3 significant digits, "" for NaN.
std::string verdict_number(double value) {
  return std::isnan(value) ? std::string() : fmt::format("{:.3g}", value);
}

// The verdicts as a table, a row per test case coloured by its outcome: the fitted rate, its CI,
// the accepted interval, the window and the reason, with what was expected and found below the
// case's name.
std::string verdicts_table(const std::vector<ExpectationOutcome>& verdicts,
                           std::size_t deselected) {
  std::string out =
      "<table class=\"verdicts\"><tr><th>outcome</th><th>case</th><th>rate</th><th>CI</th>"
      "<th>accepted</th><th>window</th><th>reason</th></tr>\n";
  for (const auto& o : verdicts) {
    const auto outcome = case_outcome(o);
    const auto interval = [](double low, double high) {
      if (std::isnan(low) && std::isnan(high)) return std::string();
      return fmt::format("[{}, {}]", std::isfinite(low) ? fmt::format("{:.3g}", low) : "-&infin;",
                         std::isfinite(high) ? fmt::format("{:.3g}", high) : "&infin;");
    };
    std::string detail = "expected: " + html_text(o.expected) + "<br>found: " + html_text(o.found);
    if (!o.expectation->xfail.empty()) detail += "<br>xfail: " + html_text(o.expectation->xfail);
    out += fmt::format(
        "<tr class=\"{0}\"><td class=\"outcome\">{1}</td><td class=\"text\"><b>{2}</b> <span "
        "class=\"where\">{3}</span><div class=\"detail\">{4}</div></td><td>{5}</td><td>{6}</td>"
        "<td>{7}</td><td>{8}</td><td class=\"text\">{9}</td></tr>\n",
        case_outcome_id(outcome), case_outcome_name(outcome), escape_html(o.name),
        escape_html(o.expectation->location), detail, verdict_number(o.rate),
        interval(o.ci_low, o.ci_high), interval(o.accepted_low, o.accepted_high),
        o.window_points
            ? fmt::format("n = {}..{} ({} points)", o.window_from, o.window_to, o.window_points)
            : std::string(),
        html_text(o.reason));
  }
  auto counts = count_verdicts(verdicts);
  counts.deselected = deselected;
  return out + "</table>\n<p class=\"counts\">" + escape_html(format_counts(counts)) + "</p>\n";
}

// The answer, first on the page: the verdict counts, then every failure and inconclusive case
// (with its reason and advice), then whether an adaptive study's estimate has converged in time.
std::string answer_section(const RunRecord& run, const std::vector<ExpectationOutcome>* verdicts) {
  std::string out = "<div class=\"answer\">\n";
  if (run.study.expectations.empty())
    out += "<p class=\"counts\">No expectations.</p>\n";
  else if (!verdicts)
    out += "<p class=\"counts\">Expectations not judged in this report.</p>\n";
  else {
    auto counts = count_verdicts(*verdicts);
    counts.deselected = run.deselected;
    out += "<p class=\"counts\"><b>" + escape_html(format_counts(counts)) + "</b></p>\n";
    std::string problems;
    for (const auto& o : *verdicts) {
      const auto outcome = case_outcome(o);
      if (outcome != CaseOutcome::failed && outcome != CaseOutcome::inconclusive) continue;
      problems += fmt::format(
          "<li class=\"{}\"><b>{}</b> {}: {}; {}{}</li>\n", case_outcome_id(outcome),
          case_outcome_name(outcome), escape_html(o.name), html_text(verdict_numbers(o)),
          html_text(o.reason), o.advice.empty() ? "" : "<br>advice: " + html_text(o.advice));
    }
    if (!problems.empty()) out += "<ul class=\"problems\">\n" + problems + "</ul>\n";
  }
  if (const auto convergence = time_convergence(run); !convergence.empty()) {
    out += "<p>Convergence in time:</p>\n<ul class=\"convergence\">\n";
    for (const auto& group : convergence)
      out += fmt::format("<li>{}: {}</li>\n", escape_html(group.label), html_text(group.sentence));
    out += "</ul>\n";
  }
  return out + "</div>\n";
}

// The fitted rates of every group and metric in one table.
std::string fitted_rates_table(const std::vector<GroupTable>& groups,
                               const std::vector<RateTable>& tables,
                               const std::vector<std::string>& metrics) {
  std::string out = "<div class=\"wide\"><table class=\"summary\"><tr><th>group</th>";
  for (const auto& metric : metrics)
    out += fmt::format("<th><a href=\"#{0}\">{0}</a></th>", escape_html(metric));
  out += "</tr>\n";
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const auto& group = groups[g];
    out += fmt::format("<tr><td class=\"text\"><a href=\"#group{}\">{}</a></td>", g + 1,
                       escape_html(group.title()));
    for (const auto& metric : metrics) {
      std::string cell;
      for (auto t : group.columns)
        if (tables[t].metric == metric) cell = html_text(fit_cell(tables[t]));
      out += "<td>" + cell + "</td>";
    }
    out += "</tr>\n";
  }
  return out + "</table></div>\n";
}

// One group's convergence table: every metric's value and pairwise rate, the fits at the foot,
// then each fit with its window and notes.
std::string group_table(const GroupTable& group, const std::vector<RateTable>& tables,
                        std::size_t number) {
  std::string out = fmt::format("<h3 id=\"group{}\">{}</h3>\n<p class=\"group\">group {}</p>\n",
                                number, escape_html(group.title()), escape_html(group.group));
  const std::string axes = group.shows_h() ? "<th rowspan=\"2\">n</th><th rowspan=\"2\">h</th>"
                                           : "<th rowspan=\"2\">n</th>";
  std::string metrics, headings;
  for (auto t : group.columns) {
    metrics += fmt::format("<th colspan=\"2\">{}</th>", escape_html(tables[t].metric));
    headings += fmt::format("<th>value</th><th>{}</th>", escape_html(rate_heading(tables[t])));
  }
  out += fmt::format("<div class=\"wide\"><table class=\"rates\"><tr>{}{}</tr>\n<tr>{}</tr>\n",
                     axes, metrics, headings);
  bool any_flagged = false;
  for (std::size_t r = 0; r < group.n.size(); ++r) {
    out += fmt::format("<tr><td>{}</td>", group.n[r]);
    if (group.shows_h())
      out += std::isfinite(group.h[r]) ? fmt::format("<td>{:.4g}</td>", group.h[r]) : "<td></td>";
    for (auto t : group.columns) {
      const auto* row = row_at(tables[t], group.n[r]);
      if (!row) {
        out += "<td></td><td></td>";
        continue;
      }
      any_flagged = any_flagged || row->flagged;
      out += fmt::format("<td{}>{}</td><td>{}</td>", row->flagged ? " class=\"flagged\"" : "",
                         document_value(*row), document_rate(*row, "&ndash;"));
    }
    out += "</tr>\n";
  }
  out += fmt::format("<tr class=\"fit\"><td{}>fit</td>", group.shows_h() ? " colspan=\"2\"" : "");
  for (auto t : group.columns)
    out += tables[t].fit
               ? fmt::format("<td></td><td>{}</td>", document_rate({.rate = tables[t].fit->rate}))
           : tables[t].constant ? std::string("<td></td><td>const</td>")
                                : std::string("<td></td><td>&ndash;</td>");
  out += "</tr>\n</table></div>\n<ul class=\"fits\">\n";
  for (auto t : group.columns) {
    const auto& table = tables[t];
    std::string fit = (table.fit ? "fitted rate " : "") + html_text(document_fit(table));
    if (const auto window = window_text(table); !window.empty())
      fit += "; window " + html_text(window) +
             (table.window_note.empty() ? "" : "; " + html_text(table.window_note));
    if (!table.note.empty()) fit += "<br>" + html_text(table.note);
    out += fmt::format("<li><b>{}</b>: {}</li>\n", escape_html(table.metric), fit);
  }
  out += "</ul>\n";
  if (any_flagged) out += "<p class=\"fit\">* " + html_text(flagged_value_legend) + "</p>\n";
  return out;
}

// The convergence plots of a metric: convergence_<metric>.svg, or its parts in order
// (convergence_<metric>_part1.svg, part2, ...) when it has too many panels for one figure.
std::vector<std::filesystem::path> convergence_plots(const std::filesystem::path& plots,
                                                     const std::string& metric) {
  std::vector<std::filesystem::path> out;
  if (plots.empty()) return out;
  if (auto whole = plots / ("convergence_" + metric + ".svg"); std::filesystem::exists(whole))
    out.push_back(std::move(whole));
  for (std::size_t part = 1;; ++part) {
    auto file = plots / fmt::format("convergence_{}_part{}.svg", metric, part);
    if (!std::filesystem::exists(file)) break;
    out.push_back(std::move(file));
  }
  return out;
}

}  // namespace

std::string html_report(const RunRecord& run, const std::filesystem::path& plots,
                        const std::vector<ExpectationOutcome>* verdicts) {
  const auto& study = run.study;
  const auto& build = build_info();
  std::string mpi_rows;  // a distributed run: one row per MPI rank
  for (std::size_t r = 0; r < run.ranks.size(); ++r)
    mpi_rows += fmt::format(
        "<tr><th>MPI rank {}</th><td class=\"text\">{}: {} threads, {} trials{}</td></tr>\n", r,
        escape_html(run.ranks[r].host), run.ranks[r].threads, run.ranks[r].trials,
        run.ranks[r].lost ? " (lost during the run; its trials ran elsewhere)" : "");
  std::string page = fmt::format(
      R"(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{0}: rkhs-study report</title>
<style>
body {{ font-family: sans-serif; margin: 2em auto; max-width: 70em; color: #222; }}
table {{ border-collapse: collapse; margin: 0.5em 0 1em; }}
th, td {{ border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }}
th {{ background: #eee; }}
td.text {{ text-align: left; }}
.flagged {{ color: #a50; }}
.fit {{ margin: 0 0 1.5em; }}
img {{ max-width: 100%; border: 1px solid #ddd; }}
pre {{ background: #f6f6f6; padding: 0.8em; overflow-x: auto; }}
table.rates tr.fit td {{ border-top: 2px solid #888; font-weight: bold; }}
table.verdicts td {{ vertical-align: top; }}
table.verdicts td:nth-child(n+3):nth-child(-n+6) {{ white-space: nowrap; }}
table.verdicts th:nth-child(2), table.verdicts th:nth-child(7) {{ text-align: left; }}
div.wide {{ overflow-x: auto; }}
table.rates td, table.summary td {{ white-space: nowrap; }}
table.summary th:first-child {{ text-align: left; }}
table.verdicts td.outcome {{ font-weight: bold; text-align: center; }}
table.verdicts .where, p.group {{ color: #666; font-size: 85%; }}
table.verdicts .detail {{ color: #444; font-size: 85%; margin-top: 0.2em; }}
tr.passed td.outcome {{ background: #c8e6c9; color: #1b5e20; }}
tr.failed td.outcome {{ background: #ffcdd2; color: #b71c1c; }}
tr.inconclusive td.outcome {{ background: #fff3c4; color: #7a5b00; }}
tr.xfailed td.outcome {{ background: #e0e0e0; color: #424242; }}
tr.xpassed td.outcome {{ background: #e1bee7; color: #4a148c; }}
div.answer {{ border: 1px solid #bbb; padding: 0 1em; margin: 0.5em 0 1em; }}
li.failed b {{ color: #b71c1c; }}
li.inconclusive b {{ color: #7a5b00; }}
</style></head>
<body>
<h1>{0}</h1>
{13}<p>{1}</p>
<h2>Provenance</h2>
<table class="provenance">
<tr><th>study file</th><td class="text">{2}</td></tr>
<tr><th>kind</th><td class="text">{3}</td></tr>
<tr><th>rkhs-study</th><td class="text">{4} (commit {5}; {6}, {7})</td></tr>
<tr><th>started</th><td class="text">{8}</td></tr>
<tr><th>threads, wall time</th><td class="text">{9}, {10:.2f} s</td></tr>
<tr><th>trials</th><td class="text">{11}</td></tr>
{12}</table>
)",
      escape_html(study.name), escape_html(study.description), escape_html(study.source),
      escape_html(std::string(study_kind_name(study.kind()))), build.version, build.git_commit,
      build.compiler, build.build_type, escape_html(run.started), run.threads, run.wall_seconds,
      run.trials.size(), mpi_rows, answer_section(run, verdicts));

  // Failed trials first: they are what a reader must not miss.
  std::string failed;
  for (const auto& trial : run.trials)
    if (const auto& r = run.results[trial.index]; !r.ok)
      failed += fmt::format("<tr><td class=\"text\">{}</td><td class=\"text\">{}</td></tr>\n",
                            escape_html(trial.key), escape_html(r.reason));
  page += failed.empty() ? "<h2>Failed trials</h2>\n<p>None.</p>\n"
                         : "<h2>Failed trials</h2>\n<table "
                           "class=\"failed\"><tr><th>trial</th><th>reason</th></tr>\n" +
                               failed + "</table>\n";

  if (!study.expectations.empty()) {
    page += "<h2>Expectations</h2>\n";
    page += verdicts ? verdicts_table(*verdicts, run.deselected)
                     : "<p>Not judged in this report (<code>rkhs-study check</code> judges "
                       "them).</p>\n";
  }

  const auto tables = rate_tables(run);
  const auto groups = group_tables(run, tables);
  const auto metrics = table_metrics(tables);
  page += "<h2>Rates</h2>\n";
  if (!groups.empty()) {
    page +=
        "<p>Fitted rate [confidence interval] of each metric and group (exp: exponential in "
        "n); the groups' tables follow the plots.</p>\n" +
        fitted_rates_table(groups, tables, metrics);
  }
  page += "<h2>Convergence plots</h2>\n";
  for (const auto& metric : convergence_plot_order(study.metrics)) {  // the errors first
    page += fmt::format("<h3 id=\"{0}\">{0}</h3>\n", escape_html(metric));
    bool shown = false;
    for (const auto& svg : convergence_plots(plots, metric)) {
      const auto content = read_file(svg);
      if (content.empty()) continue;
      page += fmt::format(
          "<p><img class=\"plot\" alt=\"convergence of {}\" "
          "src=\"data:image/svg+xml;base64,{}\"></p>\n",
          escape_html(metric), base64(content));
      shown = true;
    }
    if (!shown) page += "<p>No plot.</p>\n";
  }
  page += "<h2>Convergence tables</h2>\n";
  for (std::size_t g = 0; g < groups.size(); ++g) page += group_table(groups[g], tables, g + 1);
  // Other plots (adaptive studies): work precision (a study with a reference integrator),
  // then estimates and state errors. In name order, so that panels come in a stable order.
  std::string work_precision, others;
  std::vector<std::filesystem::path> svgs;
  if (!plots.empty() && std::filesystem::exists(plots))
    for (const auto& entry : std::filesystem::directory_iterator(plots))
      if (entry.path().extension() == ".svg") svgs.push_back(entry.path());
  std::sort(svgs.begin(), svgs.end());
  for (const auto& svg : svgs) {
    const auto name = svg.filename().string();
    if (name.starts_with("convergence_")) continue;
    const auto content = read_file(svg);
    if (content.empty()) continue;
    (name.starts_with("work_precision_") ? work_precision : others) += fmt::format(
        "<p><img class=\"plot\" alt=\"{0}\" src=\"data:image/svg+xml;base64,{1}\"></p>\n",
        escape_html(name), base64(content));
  }
  if (!work_precision.empty())
    page +=
        fmt::format(
            "<h2 id=\"work-precision\">Work precision</h2>\n<p class=\"caption\">integration_error "
            "(the relative L2 distance of fhat(T) from the reference integration with {}) against "
            "each trial's wall time and against its accepted steps, one line per integrator, "
            "points labelled with their rtol. Wall time is not deterministic: it depends on the "
            "machine, its load and the {} threads the trials shared (and includes the trial's "
            "static part; the reference integration is not counted in steps, but it is in wall "
            "time); steps and errors are reproducible.</p>\n",
            escape_html(study.adaptive_axes_if() ? study.adaptive_axes_if()->reference.label()
                                                 : std::string()),
            run.threads) +
        work_precision;
  if (!others.empty()) page += "<h2>Estimates and state errors</h2>\n" + others;
  // The page reports whether every plot loaded (read by the project's browser test).
  page += R"(<script>
window.addEventListener('load', function () {
  var images = document.images, loaded = 0;
  for (var i = 0; i < images.length; ++i) if (images[i].complete && images[i].naturalWidth > 0) ++loaded;
  document.body.setAttribute('data-images-loaded', loaded + '/' + images.length);
});
</script>
</body></html>
)";
  return page;
}

}  // namespace rkhs
