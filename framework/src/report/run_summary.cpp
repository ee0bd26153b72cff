#include "rkhs/report/run_summary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "summary_reader.hpp"

namespace rkhs {

RunSummary read_run_summary(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open (is it a results directory?)");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(
        fmt::format("{}: not a summary.json written by rkhs-study: {}", file.string(), e.what()));
  }
  const auto text = [&](const char* key) -> std::string {
    if (!json.is_object() || !json.contains(key) || !json[key].is_string()) return {};
    return json[key].get<std::string>();
  };
  RunSummary summary{text("study"), text("source"), text("tier")};
  if (summary.source.empty())
    throw std::runtime_error(file.string() + ": no \"source\" study file recorded");
  return summary;
}

RunRecord ResultsFolder::record() const {
  RunRecord record{study, trials, results, rates, threads, wall_seconds, started};
  record.tier = tier;
  record.verdicts = judged ? &verdicts : nullptr;
  record.deselected = deselected;
  return record;
}

namespace {

using namespace report_detail;

// The file's text, refused by type and size before it is read.
std::string read_bounded(const std::filesystem::path& file) {
  std::error_code error;
  const auto status = std::filesystem::status(file, error);
  if (error || !std::filesystem::exists(status))
    throw std::runtime_error(file.string() +
                             ": no such file (is the folder a results folder of rkhs-study?)");
  if (!std::filesystem::is_regular_file(status))
    throw std::runtime_error(
        file.string() + ": not a regular file (" +
        (std::filesystem::is_directory(status) ? "a directory" : "a device, FIFO or socket") +
        "); a results folder holds summary.json as a file");
  const auto size = std::filesystem::file_size(file, error);
  if (error) throw std::runtime_error(file.string() + ": cannot read its size: " + error.message());
  if (size > max_summary_bytes)
    throw std::runtime_error(fmt::format("{}: {} bytes; at most {} bytes are read", file.string(),
                                         size, max_summary_bytes));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  std::string content(static_cast<std::size_t>(size), '\0');
  in.read(content.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size)
    throw std::runtime_error(file.string() + ": cannot read (it changed while it was read?)");
  return content;
}

// A plugin as summary.json records it: {"name": ..., "parameters": {...}}, the parameters in
// their order, each declared with the type of its value.
PluginChoice read_plugin(const Reader& reader, const Json& object, const std::string& path) {
  PluginChoice choice;
  choice.name = reader.text(object, path, "name");
  const auto& parameters = reader.member(object, path, "parameters");
  const auto parameters_path = Reader::join(path, "parameters");
  if (!parameters.is_object())
    reader.fail(parameters_path, "expected an object; found " + type_text(parameters));
  std::vector<ParameterSpec> specs;
  std::map<std::string, ParameterValue> given;
  for (const auto& [name, value] : parameters.items()) {
    ParameterSpec spec;
    spec.name = name;
    if (value.is_number_integer()) {
      spec.type = ParameterType::integer;
      spec.default_value = value.get<std::int64_t>();
    } else if (value.is_number()) {
      spec.type = ParameterType::real;
      spec.default_value = value.get<double>();
    } else if (value.is_boolean()) {
      spec.type = ParameterType::boolean;
      spec.default_value = value.get<bool>();
    } else if (value.is_string()) {
      spec.type = ParameterType::text;
      spec.default_value = value.get<std::string>();
    } else {
      reader.fail(parameters_path + "." + name,
                  "expected a number, boolean or string; found " + type_text(value));
    }
    given[name] = spec.default_value;
    specs.push_back(std::move(spec));
  }
  try {
    choice.parameters = ParameterSet::resolve(specs, given);
  } catch (const std::exception& e) {
    reader.fail(parameters_path, e.what());
  }
  return choice;
}

// A plugin from its label in a trial key ("name p1=v1 p2=v2", PluginChoice::label): the axes
// summary.json records only in the key (projection, plant, law, integrator). A value with a
// space (a text parameter) continues up to the next "name=" word; numbers are read back as
// numbers, so that they print as they did.
PluginChoice plugin_from_label(const std::string& label) {
  PluginChoice choice;
  std::vector<std::string> words;
  std::size_t start = 0;
  while (start <= label.size()) {
    const auto end = std::min(label.find(' ', start), label.size());
    words.push_back(label.substr(start, end - start));
    start = end + 1;
  }
  choice.name = words.front();
  std::vector<std::pair<std::string, std::string>> parameters;
  for (std::size_t w = 1; w < words.size(); ++w) {
    const auto equals = words[w].find('=');
    if (equals != std::string::npos && equals > 0)
      parameters.emplace_back(words[w].substr(0, equals), words[w].substr(equals + 1));
    else if (!parameters.empty())
      parameters.back().second += " " + words[w];
  }
  std::vector<ParameterSpec> specs;
  std::map<std::string, ParameterValue> given;
  for (const auto& [name, text] : parameters) {
    ParameterSpec spec;
    spec.name = name;
    std::size_t used = 0;
    try {
      if (text.find_first_not_of("-0123456789") == std::string::npos) {
        spec.type = ParameterType::integer;
        spec.default_value = static_cast<std::int64_t>(std::stoll(text, &used));
      } else {
        spec.type = ParameterType::real;
        spec.default_value = std::stod(text, &used);
      }
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || text.empty()) {
      spec.type = ParameterType::text;
      spec.default_value = text;
    }
    given[name] = spec.default_value;
    specs.push_back(std::move(spec));
  }
  try {
    choice.parameters = ParameterSet::resolve(specs, given);
  } catch (const std::exception&) {
    choice.parameters = {};  // shown without its parameters
  }
  return choice;
}

// The axes of a group key that summary.json holds only there: " | projection=...",
// " | plant=...", " | law=...", " | integrator=...", " | laps=..." (the last four of an
// adaptive trial: `trial.kind_axes` says which kind it is).
void read_key_axes(TrialSpec& trial) {
  const std::string separator = " | ";
  std::size_t start = 0;
  while (start < trial.group_key.size()) {
    auto end = trial.group_key.find(separator, start);
    if (end == std::string::npos) end = trial.group_key.size();
    const auto segment = trial.group_key.substr(start, end - start);
    start = end + separator.size();
    const auto equals = segment.find('=');
    if (equals == std::string::npos) continue;
    const auto axis = segment.substr(0, equals);
    const auto value = segment.substr(equals + 1);
    auto* adaptive = trial.adaptive_axes_if();
    if (axis == "projection")
      trial.projection = plugin_from_label(value);
    else if (axis == "plant" && adaptive)
      adaptive->plant = plugin_from_label(value);
    else if (axis == "law" && adaptive)
      adaptive->law = plugin_from_label(value);
    else if (axis == "integrator" && adaptive)
      adaptive->integrator = plugin_from_label(value);
    else if (axis == "laps" && adaptive)
      adaptive->laps = value == "limit" ? std::numeric_limits<double>::infinity()
                                        : std::strtod(value.c_str(), nullptr);
  }
}

// Why a series has no fit, as fit_series says it (summary.json does not record it): from the
// usable points, and the window a [rates] table set when the note names one.
std::string no_fit_reason(const MetricSeries& series) {
  std::size_t usable = 0, excluded = 0;
  for (std::size_t k = 0; k < series.values.size(); ++k) {
    const bool kept = !series.failed[k] && !series.flagged[k];
    excluded += !kept;
    usable += kept && std::isfinite(series.values[k]) && series.values[k] > 0.0;
  }
  const std::string set_by = "window set by ";
  const auto where = series.note.find(set_by);
  const auto in_window = series.analysis.reported_analysis().window.points.size();
  if (where != std::string::npos && in_window < usable) {
    const auto from = where + set_by.size();
    const auto to = series.note.find(": n = ", from);
    return fmt::format("{} of {} usable points in the window set by {}; a fit needs at least 2",
                       in_window, usable, series.note.substr(from, to - from));
  }
  return fmt::format("{} of {} points usable{}; a fit needs at least 2", usable,
                     series.values.size(),
                     excluded > 0 ? fmt::format(" after excluding {} failed or flagged", excluded)
                                  : std::string());
}

// Positions in `n` of the values of an n list ("window": [10, 20]).
std::vector<std::size_t> positions_of(const Reader& reader, const Json& list,
                                      const std::string& path, const std::vector<double>& n) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < reader.array(list, path).size(); ++k) {
    const auto value = static_cast<double>(reader.count(list[k], Reader::at(path, k)));
    const auto found = std::find(n.begin(), n.end(), value);
    if (found == n.end())
      reader.fail(Reader::at(path, k), fmt::format("n = {} is not an n of the group", value));
    out.push_back(static_cast<std::size_t>(found - n.begin()));
  }
  return out;
}

RateModel read_model(const Reader& reader, const Json& object, const std::string& path,
                     const char* key) {
  const auto name = reader.text(object, path, key);
  if (name == "power_law") return RateModel::power_law;
  if (name == "exponential") return RateModel::exponential;
  reader.fail(Reader::join(path, key),
              fmt::format("\"{}\" is not a rate model; power_law or exponential", name));
}

// One model's fields of a rates entry (summary_json's model_fields).
ModelAnalysis read_model_analysis(const Reader& reader, const Json& object, const std::string& path,
                                  const std::vector<double>& n) {
  ModelAnalysis analysis;
  analysis.model = read_model(reader, object, path, "model");
  analysis.window.points =
      positions_of(reader, reader.member(object, path, "window"), Reader::join(path, "window"), n);
  analysis.window.head =
      positions_of(reader, reader.member(object, path, "head"), Reader::join(path, "head"), n);
  analysis.window.floor =
      positions_of(reader, reader.member(object, path, "floor"), Reader::join(path, "floor"), n);
  analysis.advantage = reader.number(object, path, "delta_aic");
  analysis.advantage_floor = reader.number(object, path, "delta_aic_floor");
  const double rate = reader.number(object, path, "rate");
  if (!std::isnan(rate)) {
    RateFit fit;
    fit.model = analysis.model;
    fit.rate = rate;
    fit.std_error = reader.number(object, path, "std_error");
    fit.ci_low = reader.number(object, path, "ci_low");
    fit.ci_high = reader.number(object, path, "ci_high");
    fit.r_squared = reader.number(object, path, "r_squared");
    fit.points = reader.count(object, path, "points");
    fit.used = analysis.window.points;
    analysis.floors.rate = reader.number(object, path, "rate_floor");
    analysis.floors.r_squared = reader.number(object, path, "r_squared_floor");
    analysis.fit = std::move(fit);
  }
  return analysis;
}

StudyDefinition read_study(const Reader& reader, const Json& json) {
  StudyDefinition study;
  study.name = reader.text(json, "", "study");
  study.description = reader.optional_text(json, "", "description");
  study.source = reader.optional_text(json, "", "source");
  const auto kind = reader.text(json, "", "kind");
  const auto parsed_kind = study_kind_from_name(kind);
  if (!parsed_kind)
    reader.fail("kind", fmt::format("\"{}\" is not a study kind; approximation or adaptive", kind));
  study.kind_axes = study_kind_axes(*parsed_kind);
  const auto abscissa = reader.text(json, "", "abscissa");
  if (abscissa != "n" && abscissa != "h")
    reader.fail("abscissa", fmt::format("\"{}\" is not an abscissa; n or h", abscissa));
  study.abscissa = abscissa == "n" ? Abscissa::n : Abscissa::fill_distance;
  const auto& n = reader.array(json, "", "n");
  for (std::size_t k = 0; k < n.size(); ++k)
    study.n_values.push_back(reader.count(n[k], Reader::at("n", k)));
  study.evaluation_points = reader.count(json, "", "evaluation_points");
  const auto& domain = reader.member(json, "", "domain");
  if (domain.is_object() && domain.contains("length"))
    study.domain.length = reader.number(domain, "domain", "length");
  if (domain.is_object() && domain.contains("periodic") && domain["periodic"].is_boolean())
    study.domain.periodic = domain["periodic"].get<bool>();
  return study;
}

// summary.json's text as JSON; refused with the line and column where parsing stopped.
Json parse_summary(const std::filesystem::path& file, const std::string& text) {
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    // Line and column of the byte where parsing stopped.
    const auto offset = std::min<std::size_t>(e.byte ? e.byte - 1 : 0, text.size());
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(offset), '\n');
    const auto line_start = text.rfind('\n', offset ? offset - 1 : 0);
    const auto column =
        offset - (line_start == std::string::npos || offset == 0 ? 0 : line_start + 1) + 1;
    throw std::runtime_error(
        fmt::format("{}:{}:{}: not JSON (not a summary.json written by "
                    "rkhs-study)",
                    file.string(), line, column));
  }
}

// Trial `t` of summary.json's "trials": its plugins, n and key, and its result aligned with
// `all`, the metrics of the study's kind. Trial 0 sets study.metrics; the others must match it.
std::pair<TrialSpec, TrialResult> read_trial(const Reader& reader, const Json& trials,
                                             std::size_t t, const std::vector<std::string>& all,
                                             StudyDefinition& study) {
  const auto path = Reader::at("trials", t);
  const auto& entry = trials[t];
  TrialSpec trial;
  trial.kind_axes = trial_kind_axes(study.kind());
  trial.index = reader.count(entry, path, "index");
  if (trial.index != t)
    reader.fail(Reader::join(path, "index"),
                fmt::format("{} where {} was expected", trial.index, t));
  trial.key = reader.text(entry, path, "key");
  trial.kernel =
      read_plugin(reader, reader.member(entry, path, "kernel"), Reader::join(path, "kernel"));
  trial.target =
      read_plugin(reader, reader.member(entry, path, "target"), Reader::join(path, "target"));
  trial.centres =
      read_plugin(reader, reader.member(entry, path, "centres"), Reader::join(path, "centres"));
  trial.n = reader.count(entry, path, "n");
  const auto suffix = fmt::format(" | n={}", trial.n);
  if (!trial.key.ends_with(suffix))
    reader.fail(Reader::join(path, "key"), fmt::format("does not end in \"{}\"", suffix));
  trial.group_key = trial.key.substr(0, trial.key.size() - suffix.size());
  read_key_axes(trial);

  TrialResult result;
  const auto status = reader.text(entry, path, "status");
  if (status != "ok" && status != "failed")
    reader.fail(Reader::join(path, "status"), fmt::format("\"{}\"; ok or failed", status));
  result.ok = status == "ok";
  result.reason = reader.text(entry, path, "reason");
  result.solve_method = reader.text(entry, path, "solve");
  if (const auto engine = reader.optional_text(entry, path, "engine"); !engine.empty()) {
    result.engine = adaptive_engine_from_name(engine);
    if (!result.engine)
      reader.fail(Reader::join(path, "engine"),
                  fmt::format("\"{}\"; lap_map or time_stepping", engine));
  }
  result.seconds = reader.number(entry, path, "seconds");
  const auto& flags = reader.array(entry, path, "flags");
  for (std::size_t k = 0; k < flags.size(); ++k)
    result.flags.push_back(reader.text(flags[k], Reader::at(Reader::join(path, "flags"), k)));
  result.metrics.assign(all.size(), std::numeric_limits<double>::quiet_NaN());
  result.floors = result.metrics;
  const auto& metrics = reader.member(entry, path, "metrics");
  const auto metrics_path = Reader::join(path, "metrics");
  if (!metrics.is_object())
    reader.fail(metrics_path, "expected an object; found " + type_text(metrics));
  std::vector<std::string> names;
  for (const auto& [name, value] : metrics.items()) {
    const auto position = std::find(all.begin(), all.end(), name);
    if (position == all.end())
      reader.fail(metrics_path + "." + name,
                  fmt::format("not a metric of an {} study", study_kind_name(study.kind())));
    result.metrics[static_cast<std::size_t>(position - all.begin())] =
        reader.number(value, metrics_path + "." + name);
    names.push_back(name);
  }
  if (t == 0)
    study.metrics = names;
  else if (names != study.metrics)
    reader.fail(metrics_path, "names other metrics than trials[0].metrics");
  if (entry.contains("floors") && entry["floors"].is_object())
    for (const auto& [name, value] : entry["floors"].items()) {
      const auto position = std::find(all.begin(), all.end(), name);
      if (position != all.end())
        result.floors[static_cast<std::size_t>(position - all.begin())] =
            reader.number(value, Reader::join(path, "floors") + "." + name);
    }
  return {std::move(trial), std::move(result)};
}

// The "constant" member of a rates entry: the series' value, band and the points they hold on.
ConstantSeries read_constant(const Reader& reader, const Json& entry, const std::string& path,
                             const std::vector<double>& n) {
  const auto where = Reader::join(path, "constant");
  const auto& object = reader.member(entry, path, "constant");
  ConstantSeries constant;
  constant.value = reader.number(object, where, "value");
  constant.band = reader.number(object, where, "band");
  constant.floor = reader.number(object, where, "floor");
  constant.within = reader.number(object, where, "within");
  const auto& within_floors = reader.member(object, where, "within_floors");
  if (!within_floors.is_boolean())
    reader.fail(Reader::join(where, "within_floors"),
                "expected true or false; found " + type_text(within_floors));
  constant.within_floors = within_floors.get<bool>();
  constant.points = positions_of(reader, reader.member(object, where, "window"),
                                 Reader::join(where, "window"), n);
  constant.head = positions_of(reader, reader.member(object, where, "head"),
                               Reader::join(where, "head"), n);
  if (constant.points.empty())
    reader.fail(Reader::join(where, "window"), "a constant needs its points");
  return constant;
}

// Series `s` of summary.json's "rates": one group and metric, its trials those of the group
// (`group_trials`) in increasing n; `groups` numbers the groups in order of first appearance.
MetricSeries read_series(const Reader& reader, const Json& rates, std::size_t s,
                         const ResultsFolder& folder, const std::vector<std::string>& all,
                         const std::map<std::string, std::vector<std::size_t>>& group_trials,
                         std::map<std::string, std::size_t>& groups) {
  const auto& study = folder.study;
  const auto path = Reader::at("rates", s);
  const auto& entry = rates[s];
  MetricSeries series;
  const auto group = reader.text(entry, path, "group");
  series.metric = reader.text(entry, path, "metric");
  if (std::find(study.metrics.begin(), study.metrics.end(), series.metric) == study.metrics.end())
    reader.fail(Reader::join(path, "metric"),
                fmt::format("\"{}\" is not a metric of the trials", series.metric));
  // The group's number, in order of first appearance.
  const auto [position, added] = groups.emplace(group, groups.size());
  series.group = position->second;
  if (const auto members = group_trials.find(group); members != group_trials.end())
    series.trials = members->second;
  if (series.trials.empty()) reader.fail(Reader::join(path, "group"), "no trial of this group");
  std::stable_sort(series.trials.begin(), series.trials.end(),
                   [&](auto a, auto b) { return folder.trials[a].n < folder.trials[b].n; });
  const auto metric =
      static_cast<std::size_t>(std::find(all.begin(), all.end(), series.metric) - all.begin());
  const auto fill = std::find(all.begin(), all.end(), "fill_distance");
  for (const auto index : series.trials) {
    const auto& result = folder.results[index];
    series.n.push_back(static_cast<double>(folder.trials[index].n));
    series.abscissa.push_back(study.abscissa == Abscissa::n || fill == all.end()
                                  ? series.n.back()
                                  : result.metrics[static_cast<std::size_t>(fill - all.begin())]);
    series.values.push_back(result.metrics[metric]);
    series.floors.push_back(result.floors[metric]);
    series.failed.push_back(!result.ok);
  }
  series.flagged.assign(series.trials.size(), false);
  for (const auto k : positions_of(reader, reader.member(entry, path, "flagged"),
                                   Reader::join(path, "flagged"), series.n))
    series.flagged[k] = true;
  const auto& pairwise = reader.array(entry, path, "pairwise");
  if (pairwise.size() + 1 != series.trials.size())
    reader.fail(Reader::join(path, "pairwise"),
                fmt::format("{} rates for {} trials; expected one fewer", pairwise.size(),
                            series.trials.size()));
  for (std::size_t k = 0; k < pairwise.size(); ++k)
    series.pairwise.push_back(
        reader.number(pairwise[k], Reader::at(Reader::join(path, "pairwise"), k)));
  auto reported = read_model_analysis(reader, entry, path, series.n);
  auto alternative = read_model_analysis(reader, reader.member(entry, path, "alternative"),
                                         Reader::join(path, "alternative"), series.n);
  if (alternative.model == reported.model)
    reader.fail(Reader::join(path, "alternative.model"), "the same model as the reported fit");
  series.analysis.reported = reported.model;
  series.fit = reported.fit;
  const auto preferred = reader.member(entry, path, "preferred");
  if (!preferred.is_null())
    series.analysis.preferred = read_model(reader, entry, path, "preferred");
  series.analysis.note = reader.text(entry, path, "model_note");
  (reported.model == RateModel::power_law ? series.analysis.power_law
                                          : series.analysis.exponential) = std::move(reported);
  (alternative.model == RateModel::power_law ? series.analysis.power_law
                                             : series.analysis.exponential) =
      std::move(alternative);
  series.note = reader.text(entry, path, "note");
  // A constant series (the optional member "constant"): its value and band replace the fit, as
  // fit_series does.
  if (entry.is_object() && entry.contains("constant") && !entry["constant"].is_null()) {
    series.analysis.constant = read_constant(reader, entry, path, series.n);
    series.fit.reset();
    series.no_fit_reason =
        fmt::format("constant {}: not a rate", series.analysis.constant->text(series.n));
  }
  if (!series.fit && !series.constant()) series.no_fit_reason = no_fit_reason(series);
  series.theory = series_theory(study, folder.trials[series.trials.front()].kernel, series.metric);
  return series;
}

}  // namespace

ResultsFolder read_results_folder(const std::filesystem::path& directory) {
  const auto file = directory / "summary.json";
  const auto text = read_bounded(file);
  const Json json = parse_summary(file, text);
  const Reader reader(file.string());
  if (!json.is_object()) reader.fail("(top level)", "expected an object; found " + type_text(json));

  ResultsFolder folder;
  folder.study = read_study(reader, json);
  auto& study = folder.study;
  folder.tier = reader.optional_text(json, "", "tier");
  const auto& provenance = reader.member(json, "", "provenance");
  folder.started = reader.optional_text(provenance, "provenance", "started");
  if (provenance.is_object() && provenance.contains("threads"))
    folder.threads = static_cast<int>(std::max<std::size_t>(
        1, reader.count(provenance["threads"], "provenance.threads", 1 << 20)));
  if (provenance.is_object() && provenance.contains("wall_seconds"))
    folder.wall_seconds = reader.number(provenance, "provenance", "wall_seconds");

  // Trials: their plugins, n and keys; their results aligned with the kind's metrics.
  const auto& all = metric_names(study.kind());
  const auto& trials = reader.array(json, "", "trials");
  for (std::size_t t = 0; t < trials.size(); ++t) {
    auto [trial, result] = read_trial(reader, trials, t, all, study);
    folder.trials.push_back(std::move(trial));
    folder.results.push_back(std::move(result));
  }

  // Rates: one series per group and metric, its trials those of the group in increasing n.
  std::map<std::string, std::vector<std::size_t>> group_trials;
  for (const auto& trial : folder.trials) group_trials[trial.group_key].push_back(trial.index);
  std::map<std::string, std::size_t> groups;
  const auto& rates = reader.array(json, "", "rates");
  for (std::size_t s = 0; s < rates.size(); ++s)
    folder.rates.push_back(read_series(reader, rates, s, folder, all, group_trials, groups));

  read_summary_verdicts(reader, json, folder);
  return folder;
}

}  // namespace rkhs
