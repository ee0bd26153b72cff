// summary.json: the run's study, provenance, trials, fitted rates and verdicts as one JSON
// document (docs/results.md), written by summary_json (rkhs/report/output.hpp).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>

#include "output_fields.hpp"
#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/report/output.hpp"

namespace rkhs {

using report_detail::abscissa_name;
using report_detail::model_id;
using report_detail::reported_flags;

namespace {

std::string json_value(const ParameterValue& value) {
  if (std::holds_alternative<std::string>(value)) return json_string(std::get<std::string>(value));
  if (std::holds_alternative<bool>(value)) return std::get<bool>(value) ? "true" : "false";
  return format_value(value);
}

std::string json_parameters(const ParameterSet& parameters) {
  std::vector<std::string> items;
  for (const auto& [name, value] : parameters.values())
    items.push_back(fmt::format("{}: {}", json_string(name), json_value(value)));
  return fmt::format("{{{}}}", fmt::join(items, ", "));
}

std::string json_plugin(const PluginChoice& choice) {
  return fmt::format("{{\"name\": {}, \"parameters\": {}}}", json_string(choice.name),
                     json_parameters(choice.parameters));
}

// The value of one field of an outcome (outcome_fields) as summary.json writes it.
std::string outcome_field_json(const OutcomeField& field, const ExpectationOutcome& o) {
  const auto n_or_null = [](std::size_t n) { return n ? std::to_string(n) : std::string("null"); };
  switch (field.type) {
    case OutcomeFieldType::text:
      return json_string(field.text(o));
    case OutcomeFieldType::optional_text:
      return field.text(o).empty() ? std::string("null") : json_string(field.text(o));
    case OutcomeFieldType::number:
      return json_number(o.*field.number);
    case OutcomeFieldType::seconds:
      return json_number(std::round(o.*field.number * 1e4) / 1e4);
    case OutcomeFieldType::verdict: {
      std::string verdict(verdict_name(o.verdict));
      for (auto& c : verdict) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return json_string(verdict);
    }
    case OutcomeFieldType::kind:
      return json_string(expectation_kind_name(o.expectation->kind));
    case OutcomeFieldType::window:
      return fmt::format("{{\"from\": {}, \"to\": {}, \"points\": {}}}", n_or_null(o.window_from),
                         n_or_null(o.window_to), o.window_points);
    case OutcomeFieldType::outcome:
      return json_string(case_outcome_id(case_outcome(o)));
    case OutcomeFieldType::summary:
      return json_string(verdict_numbers(o));
  }
  return "null";
}

// "expectations": the verdicts of RunRecord::verdicts, one object per test case.
std::string expectations_json(const RunRecord& run) {
  auto counts = count_verdicts(*run.verdicts);
  counts.deselected = run.deselected;
  std::string out = fmt::format(
      "  \"expectations\": {{\n    \"counts\": {{\"passed\": {}, \"failed\": {}, "
      "\"inconclusive\": {}, \"xfailed\": {}, \"xpassed\": {}, \"deselected\": {}}},\n"
      "    \"outcomes\": [\n",
      counts.passed, counts.failed, counts.inconclusive, counts.xfailed, counts.xpassed,
      counts.deselected);
  for (std::size_t k = 0; k < run.verdicts->size(); ++k) {
    const auto& o = (*run.verdicts)[k];
    std::vector<std::string> items;
    for (const auto& field : outcome_fields)
      if (field.in(OutcomeField::in_summary_json))
        items.push_back(json_string(field.key) + ": " + outcome_field_json(field, o));
    out += fmt::format("      {{{}}}{}\n", fmt::join(items, ", "),
                       k + 1 < run.verdicts->size() ? "," : "");
  }
  return out + "    ]\n  }\n";
}

// Per trial: the work counters as a JSON object, or null. `source` says whether they were
// counted in this run or when the stored record was written (the same code: a trial's hash
// includes the code version, docs/results.md).
std::string trial_work_json(const StudyDefinition& study, const TrialResult& result) {
  if (!result.work) return "null";
  std::string out =
      fmt::format("{{\"source\": {}, {}", json_string(result.reused ? "store" : "run"),
                  work_counts_json(*result.work));
  // The counts of work the kind's metrics hold already (an adaptive trial's steps): reported
  // with the work counters, not counted twice.
  for (const auto metric : study.kind_descriptor().outputs().work_metrics)
    out += fmt::format(", {}: {}", json_string(metric),
                       json_number(result.metrics[study.metric_index(metric)]));
  return out + "}";
}

// Why a trial has no work counters (null when it has them).
std::string missing_work_json(const TrialResult& result) {
  if (result.work) return "null";
  return json_string(result.reused
                         ? "reused from the result store: its record holds no work counters "
                           "(stored by an older rkhs-study); run with --fresh to count them"
                         : "not counted");
}

// The study's work: sums of every counter over the trials that have counters, the largest
// peak_bytes, and how many trials have none.
std::string study_work_json(const StudyDefinition& study, const std::vector<TrialResult>& results) {
  WorkCounts total;
  total.allocations_tracked = true;
  std::size_t counted = 0, from_store = 0;
  const auto& work_metrics = study.kind_descriptor().outputs().work_metrics;
  std::vector<double> sums(work_metrics.size(), 0.0);
  for (const auto& r : results) {
    if (!r.work) continue;
    ++counted;
    from_store += r.reused ? 1 : 0;
    // Sums of every counter but the peak, which is the largest.
    for (const auto& field : work_count_fields)
      if (field.member != &WorkCounts::peak_bytes) total.*field.member += (*r.work).*field.member;
    total.allocations_tracked = total.allocations_tracked && r.work->allocations_tracked;
    total.peak_bytes = std::max(total.peak_bytes, r.work->peak_bytes);
    for (std::size_t i = 0; i < work_metrics.size(); ++i) {
      const double value = r.metrics[study.metric_index(work_metrics[i])];
      sums[i] += std::isfinite(value) ? value : 0;
    }
  }
  total.allocations_tracked = total.allocations_tracked && counted > 0;
  std::string out = fmt::format(
      "{{\"trials_counted\": {}, \"trials_from_store\": {}, \"trials_without_counters\": {}, {}",
      counted, from_store, results.size() - counted, work_counts_json(total));
  for (std::size_t i = 0; i < work_metrics.size(); ++i)
    out += fmt::format(", {}: {}", json_string(work_metrics[i]), json_number(sums[i]));
  return out + "}";
}

}  // namespace

std::string work_counts_json(const WorkCounts& work) {
  std::string out;
  for (const auto& field : work_count_fields)
    out += fmt::format("{}\"{}\": {}", out.empty() ? "" : ", ", field.name,
                       field.allocation && !work.allocations_tracked
                           ? std::string("null")
                           : std::to_string(work.*field.member));
  return out;
}

std::string summary_json(const RunRecord& run) {
  const auto& study = run.study;
  const auto& build = build_info();
  std::string out = "{\n";
  out +=
      fmt::format("  \"study\": {},\n  \"description\": {},\n  \"source\": {},\n  \"kind\": {},\n",
                  json_string(study.name), json_string(study.description),
                  json_string(study.source), json_string(study_kind_name(study.kind())));
  // A distributed run names its ranks: host, threads and trials run on each.
  std::string mpi;
  if (!run.ranks.empty()) {
    std::vector<std::string> ranks;
    for (const auto& r : run.ranks)
      ranks.push_back(fmt::format("{{\"host\": {}, \"threads\": {}, \"trials\": {}{}}}",
                                  json_string(r.host), r.threads, r.trials,
                                  r.lost ? ", \"lost\": true" : ""));
    mpi = fmt::format(", \"mpi_ranks\": [{}]", fmt::join(ranks, ", "));
  }
  out += fmt::format(
      "  \"provenance\": {{\"version\": {}, \"git_commit\": {}, \"compiler\": {}, "
      "\"build_type\": {}, \"threads\": {}, \"started\": {}, \"wall_seconds\": {}{}}},\n",
      json_string(build.version), json_string(build.git_commit), json_string(build.compiler),
      json_string(build.build_type), run.threads, json_string(run.started),
      json_number(std::round(run.wall_seconds * 1000) / 1000), mpi);
  if (study.domain.dimension == 1) {
    out += fmt::format("  \"domain\": {{\"length\": {}, \"periodic\": {}}},\n",
                       json_number(study.domain.length), study.domain.periodic ? "true" : "false");
  } else {
    std::vector<std::string> lengths;
    for (int a = 0; a < study.domain.dimension; ++a)
      lengths.push_back(json_number(study.domain.extent(a)));
    out += fmt::format(
        "  \"domain\": {{\"dimension\": {}, \"lengths\": [{}], \"periodic\": {}}},\n",
        study.domain.dimension, fmt::join(lengths, ", "), study.domain.periodic ? "true" : "false");
  }
  std::vector<std::string> n_values;
  for (auto n : study.n_values) n_values.push_back(std::to_string(n));
  out += fmt::format("  \"n\": [{}],\n  \"evaluation_points\": {},\n  \"abscissa\": {},\n",
                     fmt::join(n_values, ", "), study.evaluation_points,
                     json_string(abscissa_name(study)));
  std::size_t failed = 0;
  for (const auto& r : run.results) failed += r.ok ? 0 : 1;
  out += fmt::format("  \"counts\": {{\"trials\": {}, \"ok\": {}, \"failed\": {}}},\n",
                     run.trials.size(), run.trials.size() - failed, failed);
  out += fmt::format("  \"tier\": {},\n", run.tier.empty() ? "null" : json_string(run.tier));
  out += fmt::format("  \"work\": {},\n", study_work_json(study, run.results));

  out += "  \"trials\": [\n";
  for (const auto& trial : run.trials) {
    const auto& result = run.results[trial.index];
    std::vector<std::string> metrics, flags, floors;
    for (const auto& metric : study.metrics) {
      const auto position = study.metric_index(metric);
      metrics.push_back(json_string(metric) + ": " + json_number(result.metrics[position]));
      if (metric_floor_rule(study.kind(), metric) != FloorRule::exact)
        floors.push_back(json_string(metric) + ": " +
                         json_number(position < result.floors.size()
                                         ? result.floors[position]
                                         : std::numeric_limits<double>::quiet_NaN()));
    }
    for (const auto& flag : reported_flags(study, result.flags)) flags.push_back(json_string(flag));
    out += fmt::format(
        "    {{\"index\": {}, \"key\": {}, \"kernel\": {}, \"target\": {}, \"centres\": {}, "
        "\"n\": {}, \"data\": {}, \"status\": {}, \"reason\": {}, \"solve\": {}, "
        "\"flags\": [{}],{} \"seconds\": {}, \"metrics\": {{{}}}, \"floors\": {{{}}}, \"work\": "
        "{}, "
        "\"work_missing\": {}}}{}\n",
        trial.index, json_string(trial.key), json_plugin(trial.kernel), json_plugin(trial.target),
        json_plugin(trial.centres), trial.n,
        result.data_provenance.empty() ? std::string("null") : json_string(result.data_provenance),
        json_string(result.ok ? "ok" : "failed"), json_string(result.reason),
        json_string(result.solve_method), fmt::join(flags, ", "),
        !result.engine ? std::string() : " \"engine\": " + json_string(engine_text(result)) + ",",
        json_number(std::round(result.seconds * 1e4) / 1e4), fmt::join(metrics, ", "),
        fmt::join(floors, ", "), trial_work_json(study, result), missing_work_json(result),
        trial.index + 1 < run.trials.size() ? "," : "");
  }
  out += "  ],\n  \"rates\": [\n";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t s = 0; s < run.rates.size(); ++s) {
    const auto& series = run.rates[s];
    const auto n_list = [&](const std::vector<std::size_t>& positions) {
      std::vector<std::string> items;
      for (auto k : positions) items.push_back(std::to_string(run.trials[series.trials[k]].n));
      return fmt::format("[{}]", fmt::join(items, ", "));
    };
    // A model's fit on its window: the fields common to the reported and the alternative fit.
    const auto model_fields = [&](const ModelAnalysis& analysis) {
      const auto& fit = analysis.fit;
      return fmt::format(
          "\"model\": {}, \"rate\": {}, \"std_error\": {}, \"ci_low\": {}, \"ci_high\": {}, "
          "\"r_squared\": {}, \"points\": {}, \"window\": {}, \"head\": {}, \"floor\": {}, "
          "\"delta_aic\": {}, \"rate_floor\": {}, \"r_squared_floor\": {}, "
          "\"delta_aic_floor\": {}",
          json_string(model_id(analysis.model)), json_number(fit ? fit->rate : nan),
          json_number(fit ? fit->std_error : nan), json_number(fit ? fit->ci_low : nan),
          json_number(fit ? fit->ci_high : nan), json_number(fit ? fit->r_squared : nan),
          fit ? fit->points : 0, n_list(analysis.window.points), n_list(analysis.window.head),
          n_list(analysis.window.floor), json_number(analysis.advantage),
          json_number(fit ? analysis.floors.rate : nan),
          json_number(fit ? analysis.floors.r_squared : nan),
          json_number(analysis.advantage_floor));
    };
    const auto reported = series.analysis.reported;
    const auto& alternative = series.analysis.analysis(
        reported == RateModel::power_law ? RateModel::exponential : RateModel::power_law);
    std::vector<std::size_t> flagged;
    for (std::size_t k = 0; k < series.flagged.size(); ++k)
      if (series.flagged[k]) flagged.push_back(k);
    std::vector<std::string> pairwise;
    for (double r : series.pairwise) pairwise.push_back(json_number(r));
    const auto& constant = series.analysis.constant;
    const auto constant_json =
        constant ? fmt::format(
                       "{{\"value\": {}, \"band\": {}, \"floor\": {}, "
                       "\"within_floors\": {}, \"within\": {}, \"window\": {}, "
                       "\"head\": {}, \"text\": {}}}",
                       json_number(constant->value), json_number(constant->band),
                       json_number(constant->floor), constant->within_floors ? "true" : "false",
                       json_number(constant->within), n_list(constant->points),
                       n_list(constant->head), json_string(constant->text(series.n)))
                 : std::string("null");
    out += fmt::format(
        "    {{\"group\": {}, \"metric\": {}, \"constant\": {}, {}, \"preferred\": {}, "
        "\"decisive\": {}, \"model_note\": {}, \"flagged\": {}, \"pairwise\": [{}], "
        "\"note\": {}, \"alternative\": {{{}}}}}{}\n",
        json_string(run.trials[series.trials.front()].group_key), json_string(series.metric),
        constant_json, model_fields(series.analysis.reported_analysis()),
        series.analysis.preferred ? json_string(model_id(*series.analysis.preferred)) : "null",
        series.analysis.decisive() ? "true" : "false", json_string(series.analysis.note),
        n_list(flagged), fmt::join(pairwise, ", "), json_string(series.note),
        model_fields(alternative), s + 1 < run.rates.size() ? "," : "");
  }
  out += run.verdicts ? "  ],\n" + expectations_json(run) : "  ]\n";
  return out + "}\n";
}

}  // namespace rkhs
