// The verdicts of a results folder's summary.json (read_results_folder, run_summary.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <utility>

#include "summary_reader.hpp"

namespace rkhs::report_detail {

namespace {

// "rate, theory, model, bound, constant or reference": the kinds, for messages.
std::string kind_names() {
  std::string names;
  const auto count = std::size(expectation_kinds);
  for (std::size_t k = 0; k < count; ++k)
    names += (k == 0           ? ""
              : k + 1 == count ? " or "
                               : ", ") +
             std::string(expectation_kind_name(expectation_kinds[k]));
  return names;
}

// Reads a field an expectation holds (OutcomeField::of_expectation) into `e`.
void read_expectation_field(const Reader& reader, const Json& entry, const std::string& path,
                            const OutcomeField& field, Expectation& e) {
  const std::string key(field.key);
  if (field.type == OutcomeFieldType::kind) {
    const auto kind = reader.text(entry, path, key.c_str());
    for (auto candidate : expectation_kinds)
      if (expectation_kind_name(candidate) == kind) {
        e.kind = candidate;
        return;
      }
    reader.fail(Reader::join(path, key.c_str()),
                fmt::format("\"{}\" is not an expectation kind; {}", kind, kind_names()));
  }
  e.*field.expectation_text = field.type == OutcomeFieldType::optional_text
                                  ? reader.optional_text(entry, path, key.c_str())
                                  : reader.text(entry, path, key.c_str());
}

// Reads a field of the outcome itself into `o` (nothing for those derived from others).
void read_outcome_field(const Reader& reader, const Json& entry, const std::string& path,
                        const OutcomeField& field, ExpectationOutcome& o) {
  const std::string key(field.key);
  switch (field.type) {
    case OutcomeFieldType::text:
      o.*field.outcome_text = reader.text(entry, path, key.c_str());
      return;
    case OutcomeFieldType::optional_text:
      o.*field.outcome_text = reader.optional_text(entry, path, key.c_str());
      return;
    case OutcomeFieldType::number:
    case OutcomeFieldType::seconds:
      o.*field.number = reader.number(entry, path, key.c_str());
      return;
    case OutcomeFieldType::verdict: {
      const auto verdict = reader.text(entry, path, key.c_str());
      if (verdict == "pass")
        o.verdict = Verdict::pass;
      else if (verdict == "fail")
        o.verdict = Verdict::fail;
      else if (verdict == "inconclusive")
        o.verdict = Verdict::inconclusive;
      else
        reader.fail(Reader::join(path, key.c_str()),
                    fmt::format("\"{}\"; pass, fail or inconclusive", verdict));
      return;
    }
    case OutcomeFieldType::window: {
      const auto& window = reader.member(entry, path, key.c_str());
      const auto window_path = Reader::join(path, key.c_str());
      o.window_points = reader.count(window, window_path, "points");
      const auto n_or_zero = [&](const char* end) -> std::size_t {
        const auto& value = reader.member(window, window_path, end);
        return value.is_null() ? 0 : reader.count(value, Reader::join(window_path, end));
      };
      o.window_from = n_or_zero("from");
      o.window_to = n_or_zero("to");
      return;
    }
    case OutcomeFieldType::kind:     // of the expectation: read_expectation_field
    case OutcomeFieldType::outcome:  // derived from the verdict and the xfail marker
    case OutcomeFieldType::summary:  // derived from the numbers
      return;
  }
}

}  // namespace

void read_summary_verdicts(const Reader& reader, const Json& json, ResultsFolder& folder) {
  if (!json.contains("expectations") || json["expectations"].is_null()) return;
  const auto& expectations = json["expectations"];
  folder.judged = true;
  auto& study = folder.study;
  folder.deselected = reader.count(reader.member(expectations, "expectations", "counts"),
                                   "expectations.counts", "deselected");
  const auto& outcomes = reader.array(expectations, "expectations", "outcomes");
  std::map<std::pair<std::string, std::string>, std::size_t> series_of;  // (group, metric)
  for (std::size_t s = 0; s < folder.rates.size(); ++s)
    series_of.emplace(
        std::pair{folder.trials[folder.rates[s].trials.front()].group_key, folder.rates[s].metric},
        s);
  std::vector<std::string> locations;
  for (std::size_t k = 0; k < outcomes.size(); ++k) {
    const auto path = Reader::at("expectations.outcomes", k);
    const auto location = reader.text(outcomes[k], path, "location");
    if (std::find(locations.begin(), locations.end(), location) != locations.end()) continue;
    locations.push_back(location);
    Expectation e;
    e.number = locations.size();
    e.location = location;
    for (const auto& field : outcome_fields)
      if (field.in(OutcomeField::in_summary_json) && field.of_expectation())
        read_expectation_field(reader, outcomes[k], path, field, e);
    study.expectations.push_back(std::move(e));
  }
  for (std::size_t k = 0; k < outcomes.size(); ++k) {
    const auto path = Reader::at("expectations.outcomes", k);
    const auto& entry = outcomes[k];
    ExpectationOutcome o;
    const auto location = reader.text(entry, path, "location");
    o.expectation = &study.expectations[static_cast<std::size_t>(
        std::find(locations.begin(), locations.end(), location) - locations.begin())];
    for (const auto& field : outcome_fields)
      if (field.in(OutcomeField::in_summary_json) && !field.of_expectation())
        read_outcome_field(reader, entry, path, field, o);
    if (const auto s = series_of.find({o.group, o.expectation->metric}); s != series_of.end())
      o.series = s->second;
    folder.verdicts.push_back(std::move(o));
  }
}

}  // namespace rkhs::report_detail
