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
    e.name = reader.optional_text(outcomes[k], path, "expectation_name");
    e.metric = reader.text(outcomes[k], path, "metric");
    e.xfail = reader.optional_text(outcomes[k], path, "xfail");
    const auto kind = reader.text(outcomes[k], path, "kind");
    bool known = false;
    for (auto candidate : expectation_kinds)
      if (expectation_kind_name(candidate) == kind) {
        e.kind = candidate;
        known = true;
      }
    if (!known)
      reader.fail(Reader::join(path, "kind"),
                  fmt::format("\"{}\" is not an expectation kind; {}", kind, kind_names()));
    study.expectations.push_back(std::move(e));
  }
  for (std::size_t k = 0; k < outcomes.size(); ++k) {
    const auto path = Reader::at("expectations.outcomes", k);
    const auto& entry = outcomes[k];
    ExpectationOutcome o;
    const auto location = reader.text(entry, path, "location");
    o.expectation = &study.expectations[static_cast<std::size_t>(
        std::find(locations.begin(), locations.end(), location) - locations.begin())];
    o.name = reader.text(entry, path, "name");
    o.group = reader.text(entry, path, "group");
    o.group_label = reader.text(entry, path, "group_label");
    const auto verdict = reader.text(entry, path, "verdict");
    if (verdict == "pass")
      o.verdict = Verdict::pass;
    else if (verdict == "fail")
      o.verdict = Verdict::fail;
    else if (verdict == "inconclusive")
      o.verdict = Verdict::inconclusive;
    else
      reader.fail(Reader::join(path, "verdict"),
                  fmt::format("\"{}\"; pass, fail or inconclusive", verdict));
    o.rate = reader.number(entry, path, "rate");
    o.ci_low = reader.number(entry, path, "ci_low");
    o.ci_high = reader.number(entry, path, "ci_high");
    o.accepted_low = reader.number(entry, path, "accepted_low");
    o.accepted_high = reader.number(entry, path, "accepted_high");
    o.effectivity_min = reader.number(entry, path, "effectivity_min");
    o.effectivity_max = reader.number(entry, path, "effectivity_max");
    const auto& window = reader.member(entry, path, "window");
    const auto window_path = Reader::join(path, "window");
    o.window_points = reader.count(window, window_path, "points");
    const auto n_or_zero = [&](const char* key) -> std::size_t {
      const auto& value = reader.member(window, window_path, key);
      return value.is_null() ? 0 : reader.count(value, Reader::join(window_path, key));
    };
    o.window_from = n_or_zero("from");
    o.window_to = n_or_zero("to");
    o.expected = reader.text(entry, path, "expected");
    o.found = reader.text(entry, path, "found");
    o.reason = reader.text(entry, path, "reason");
    o.advice = reader.optional_text(entry, path, "advice");
    o.seconds = reader.number(entry, path, "seconds");
    if (const auto s = series_of.find({o.group, o.expectation->metric}); s != series_of.end())
      o.series = s->second;
    folder.verdicts.push_back(std::move(o));
  }
}

}  // namespace rkhs::report_detail
