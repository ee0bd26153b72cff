#include "rkhs/report/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <utility>

#include "rkhs/core/build_info.hpp"
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

std::string read_file(const std::filesystem::path& file) {
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

// One rate table and its fit, window and notes.
std::string rates_table(const RateTable& table) {
  std::string out = fmt::format(
      "<p>{}</p>\n<table class=\"rates\"><tr><th>{}</th><th>{}</th><th>rate</th></tr>\n",
      escape_html(table.group), escape_html(table.axis), escape_html(table.metric));
  bool any_flagged = false;
  for (const auto& row : table.rows) {
    any_flagged = any_flagged || row.flagged;
    out += fmt::format("<tr{}><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                       row.flagged ? " class=\"flagged\"" : "", document_abscissa(table, row),
                       document_value(row), document_rate(row, "&ndash;"));
  }
  out += "</table>\n";
  std::string fit = (table.fit ? "fitted rate " : "") + html_text(document_fit(table));
  if (const auto window = window_text(table); !window.empty())
    fit += "; window " + html_text(window) +
           (table.window_note.empty() ? "" : "; " + html_text(table.window_note));
  if (!table.note.empty()) fit += "<br>" + html_text(table.note);
  if (any_flagged) fit += "<br>* " + html_text(flagged_value_legend);
  return out + "<p class=\"fit\">" + fit + "</p>\n";
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
</style></head>
<body>
<h1>{0}</h1>
<p>{1}</p>
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
      escape_html(std::string(study_kind_name(study.kind))), build.version, build.git_commit, build.compiler, build.build_type,
      escape_html(run.started), run.threads, run.wall_seconds, run.trials.size(), mpi_rows);

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
    page += verdicts
                ? "<pre class=\"verdicts\">" +
                      escape_html(format_verification(*verdicts, {}, run.deselected)) + "</pre>\n"
                : "<p>Not judged in this report (<code>rkhs-study check</code> judges "
                  "them).</p>\n";
  }

  page += "<h2>Rates</h2>\n";
  const auto tables = rate_tables(run);
  for (const auto& metric : study.metrics) {
    page += fmt::format("<h3 id=\"{0}\">{0}</h3>\n", escape_html(metric));
    // One figure, or its parts when the metric has too many panels for one
    // (convergence_<metric>_part1.svg, ...).
    std::vector<std::filesystem::path> figures{plots / ("convergence_" + metric + ".svg")};
    for (std::size_t part = 1; !plots.empty(); ++part) {
      auto file = plots / fmt::format("convergence_{}_part{}.svg", metric, part);
      if (!std::filesystem::exists(file)) break;
      figures.push_back(std::move(file));
    }
    for (const auto& svg : figures)
      if (!plots.empty() && std::filesystem::exists(svg))
        page += fmt::format(
            "<p><img class=\"plot\" alt=\"convergence of {}\" "
            "src=\"data:image/svg+xml;base64,{}\"></p>\n",
            escape_html(metric), base64(read_file(svg)));
    for (const auto& table : tables)
      if (table.metric == metric) page += rates_table(table);
  }
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
    (name.starts_with("work_precision_") ? work_precision : others) += fmt::format(
        "<p><img class=\"plot\" alt=\"{0}\" src=\"data:image/svg+xml;base64,{1}\"></p>\n",
        escape_html(name), base64(read_file(svg)));
  }
  if (!work_precision.empty())
    page += fmt::format(
        "<h2 id=\"work-precision\">Work precision</h2>\n<p class=\"caption\">integration_error "
        "(the relative L2 distance of fhat(T) from the reference integration with {}) against "
        "each trial's wall time and against its accepted steps, one line per integrator, "
        "points labelled with their rtol. Wall time is not deterministic: it depends on the "
        "machine, its load and the {} threads the trials shared (and includes the trial's "
        "static part; the reference integration is not counted in steps, but it is in wall "
        "time); steps and errors are reproducible.</p>\n",
        escape_html(study.reference.label()), run.threads) +
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
