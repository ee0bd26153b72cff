// The [study] keys about metrics: which metrics a study writes and fits (study.metrics), and
// whether its evaluation grid can measure those taken on it.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "rkhs/approx/projection.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/study_kind.hpp"
#include "study_file_parts.hpp"
#include "toml_reader.hpp"

namespace rkhs::detail {

// For each metric of the kind, a projection of `projections` that does not compute it ("" when
// all do): computed_metric_bits of each, the interpolation projection's when there are none.
std::vector<std::string> projection_lacking_each_metric(
    StudyKind kind, const std::vector<PluginChoice>& projections) {
  std::vector<std::string> lacking(metric_names(kind).size());
  if (kind != StudyKind::approximation) return lacking;  // an adaptive trial computes them all
  std::vector<PluginChoice> chosen = projections;
  if (chosen.empty()) chosen.push_back({std::string(default_projection), {}, {}});
  for (const auto& c : chosen) {
    std::uint64_t bits = ~std::uint64_t{0};
    try {
      bits = computed_metric_bits(
          projection_registry().find(c.name)->factory(c.parameters)->properties());
    } catch (const std::exception&) {  // reported with the projection's entry
    }
    for (std::size_t i = 0; i < lacking.size(); ++i)
      if (lacking[i].empty() && !((bits >> i) & 1u)) lacking[i] = c.name;
  }
  return lacking;
}

// [study] metrics: the metrics written and fitted, in output order. A file that names none gets
// the kind's metrics that every projection of the study computes (computed_metric_bits; the
// interpolation projection's without [[projection]]); a named metric that one of them does not
// compute is an error at its name.
void read_metrics(const Reporter& report, const toml::table& header, StudyDefinition& study,
                  const std::vector<PluginChoice>& projections) {
  const auto& all_metrics = metric_names(study.kind());
  const auto lacking = projection_lacking_each_metric(study.kind(), projections);
  const auto* metrics = header.get("metrics");
  if (!metrics) {
    for (std::size_t i = 0; i < all_metrics.size(); ++i)
      if (lacking[i].empty()) study.metrics.push_back(all_metrics[i]);
    return;
  }
  const auto* array = metrics->as_array();
  if (!array || array->empty())
    report.fail(metrics->source(), "study.metrics",
                fmt::format("expected a non-empty array of metric names (known: {})",
                            fmt::join(all_metrics, ", ")));
  std::set<std::string> chosen;
  for (const auto& item : *array) {
    if (!item.is_string())
      report.fail(item.source(), "study.metrics",
                  fmt::format("expected a metric name, found {}", describe(item)));
    const std::string metric = item.as_string()->get();
    const auto at = std::find(all_metrics.begin(), all_metrics.end(), metric);
    if (at == all_metrics.end())
      report.fail(
          item.source(), "study.metrics",
          fmt::format("unknown metric '{}' {}", metric, with_suggestion(metric, all_metrics)));
    if (const auto& projection = lacking[static_cast<std::size_t>(at - all_metrics.begin())];
        !projection.empty())
      report.fail(item.source(), "study.metrics",
                  fmt::format("projection '{}' does not compute '{}' ({}; `rkhs-study list "
                              "projection` names the metrics of each matrix-free projection)",
                              projection, metric,
                              study.kind_descriptor().find_metric(metric)->matrix_free_only
                                  ? "a metric of the matrix-free projections that declare it"
                                  : "a matrix-free projection computes only the metrics it "
                                    "declares"));
    chosen.insert(metric);
  }
  for (const auto& metric : all_metrics)  // output order is the canonical order
    if (chosen.contains(metric)) study.metrics.push_back(metric);
}

// Can the evaluation grid measure what the grid metrics mean? Sups and L2 norms over the domain
// are taken on M points; with M <= n the grid is no finer than the centres (uniform centres with
// n a multiple of M are all on it), so it sees the power function and the error at or next to
// the centres, where they vanish, and reports round-off as if it were the result: refused. With
// fewer than 4 points per centre spacing the sups may miss the peaks between centres: warned.
void check_evaluation_grid(const Reporter& report, const toml::table& header,
                           StudyDefinition& study) {
  std::vector<std::string> on_grid;
  for (const auto& metric : study.metrics)
    if (const auto* row = study.kind_descriptor().find_metric(metric); row && row->on_grid)
      on_grid.push_back(metric);
  if (on_grid.empty() || study.n_values.empty()) return;
  const std::size_t largest_n = study.n_values.back();
  // In d > 1: per axis, the grid's m points against the centres' n^(1/d) (4 per centre spacing
  // asks for 4^d n grid points); in d = 1 simply M against n.
  const int d = study.domain.dimension;
  const std::size_t per_axis = study.domain.points_per_axis(study.evaluation_points);
  const double centres_per_axis = std::pow(static_cast<double>(largest_n), 1.0 / d);
  const std::size_t points = study.evaluation_points;
  const double spacing = std::pow(4.0, d);
  if (d > 1) {
    const auto* node = header.get("evaluation_points");
    const auto where = node ? node->source() : header.source();
    const std::string given = node ? "" : " (the default)";
    const auto advised =
        static_cast<std::size_t>(std::ceil(spacing * static_cast<double>(largest_n)));
    if (static_cast<double>(per_axis) <= centres_per_axis)
      report.fail(where, "study.evaluation_points",
                  fmt::format("{} evaluation points{} ({} per axis of d = {}) for up to n = {} "
                              "centres ({:.4g} per axis): the grid is no finer than the centres, "
                              "so {} would be measured at or next to the centres, where they "
                              "vanish (round-off), not over the domain; use evaluation_points "
                              ">= {} (4 per centre spacing on every axis) or leave these metrics "
                              "out of study.metrics",
                              points, given, per_axis, d, largest_n, centres_per_axis,
                              fmt::join(on_grid, ", "), advised));
    if (static_cast<double>(per_axis) < 4.0 * centres_per_axis)
      study.warnings.push_back(report.locate(
          where, "study.evaluation_points",
          fmt::format("warning: {} evaluation points{} ({} per axis) give fewer than 4 per "
                      "centre spacing for n = {}: {} are taken on the grid and may miss the "
                      "peaks between centres; evaluation_points >= {} avoids it",
                      points, given, per_axis, largest_n, fmt::join(on_grid, ", "), advised)));
    return;
  }
  const auto* node = header.get("evaluation_points");
  const auto where = node ? node->source() : header.source();
  const std::string given = node ? "" : " (the default)";
  if (points <= largest_n)
    report.fail(
        where, "study.evaluation_points",
        fmt::format("{} evaluation points{} for up to n = {} centres: the grid is no finer than "
                    "the centres, so {} would be measured at or next to the centres, where they "
                    "vanish (round-off), not over the domain; use evaluation_points >= {} (4 per "
                    "centre spacing) or leave these metrics out of study.metrics",
                    points, given, largest_n, fmt::join(on_grid, ", "), 4 * largest_n));
  if (points < 4 * largest_n)
    study.warnings.push_back(report.locate(
        where, "study.evaluation_points",
        fmt::format("warning: {} evaluation points{} give fewer than 4 per centre spacing for "
                    "n > {}: {} are taken on the grid and may miss the peaks between centres; "
                    "evaluation_points >= {} avoids it",
                    points, given, points / 4, fmt::join(on_grid, ", "), 4 * largest_n)));
}

}  // namespace rkhs::detail

namespace rkhs {

std::vector<std::string> StudyDefinition::computable_metrics() const {
  const auto& names = all_metrics();
  const auto lacking = detail::projection_lacking_each_metric(kind(), projections);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < names.size(); ++i)
    if (lacking[i].empty()) out.push_back(names[i]);
  return out;
}

}  // namespace rkhs
