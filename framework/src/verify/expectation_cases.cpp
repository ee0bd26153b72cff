#include "rkhs/verify/expectation_cases.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "rkhs/study/trial_grid.hpp"

namespace rkhs {

namespace {

// What the expectation expects, as the study file writes it: tells apart two expectations of
// the same metric and groups.
std::string expected_form(const Expectation& e);

// The same with the points it judges (n_from, n_to, h_from, h_to, last) when they are set.
std::string written_form(const Expectation& e) {
  return e.window.empty() ? expected_form(e) : expected_form(e) + ", " + e.window.text();
}

std::string expected_form(const Expectation& e) {
  const auto model = [&] {
    return e.model == RateModel::exponential ? std::string("model = \"exponential\"")
                                             : std::string("model = \"power_law\"");
  };
  const auto tolerance = [&] {
    return e.tolerance == default_rate_tolerance
               ? std::string()
               : fmt::format(", tolerance = {}", format_real(e.tolerance));
  };
  switch (e.kind) {
    case ExpectationKind::theory:
      return "theory = true" + tolerance();
    case ExpectationKind::model:
      return model();
    case ExpectationKind::bound: {
      std::string inner;
      const auto add = [&](const std::string& item) {
        inner += (inner.empty() ? "" : ", ") + item;
      };
      if (!e.bound.by.empty()) add(fmt::format("by = \"{}\"", e.bound.by));
      if (!e.bound.times.empty()) add(fmt::format("times = \"{}\"", e.bound.times));
      if (e.bound.by.empty() || e.bound.constant != 1.0)
        add("constant = " + format_real(e.bound.constant));
      if (e.bound.at_least) add("at_least = " + format_real(*e.bound.at_least));
      return fmt::format("bound = {{ {} }}", inner);
    }
    case ExpectationKind::constant:
      if (!e.constant.value) return "constant = true";
      return e.constant.within == 0.0
                 ? fmt::format("constant = {{ value = {} }}", format_real(*e.constant.value))
                 : fmt::format("constant = {{ value = {}, within = {} }}",
                               format_real(*e.constant.value), format_real(e.constant.within));
    case ExpectationKind::rate:
      break;
  }
  std::string rate;
  if (!e.rate_reference.empty()) {
    rate = fmt::format("rate = {{ at_least = \"{}\" }}", e.rate_reference) + tolerance();
  } else if (e.expected) {
    rate = "rate = " + format_real(*e.expected) + tolerance();
  } else {
    std::string inner;
    if (std::isfinite(e.interval.low)) inner = "min = " + format_real(e.interval.low);
    if (std::isfinite(e.interval.high))
      inner += (inner.empty() ? "" : ", ") + std::string("max = ") + format_real(e.interval.high);
    rate = fmt::format("rate = {{ {} }}", inner);
  }
  return e.model == RateModel::exponential ? rate + ", " + model() : rate;
}

std::string case_name(const std::string& id, const std::string& label) {
  return label.empty() ? id : fmt::format("{} [{}]", id, label);
}

}  // namespace

std::map<std::string, std::string> group_labels(const std::vector<TrialSpec>& trials) {
  const auto columns = axis_columns(trials);
  std::map<std::string, std::vector<std::string>> values;  // group key -> axis values
  for (const auto& trial : trials)
    if (!values.contains(trial.group_key)) values[trial.group_key] = axis_values(columns, trial);
  std::vector<std::size_t> shown;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    std::set<std::string> distinct;
    for (const auto& [key, v] : values)
      if (!v[c].empty()) distinct.insert(v[c]);
    if (distinct.size() > 1 || columns[c] == "kernel") shown.push_back(c);
  }
  std::map<std::string, std::string> labels;
  for (const auto& [key, v] : values) {
    std::string label;
    for (auto c : shown) {
      if (v[c].empty()) continue;
      if (!label.empty()) label += ' ';
      label += columns[c];
      label += '=';
      label += v[c];
    }
    labels[key] = label;
  }
  return labels;
}

std::vector<ExpectationCase> expectation_cases(const StudyDefinition& study,
                                               const std::vector<TrialSpec>& trials) {
  const auto labels = group_labels(trials);
  std::vector<const TrialSpec*> groups;  // the first trial of each group, in trial order
  std::set<std::string> seen;
  for (const auto& trial : trials)
    if (seen.insert(trial.group_key).second) groups.push_back(&trial);

  std::vector<ExpectationCase> cases;
  for (const auto& e : study.expectations)
    for (const auto* group : groups)
      if (e.selects(*group)) {
        ExpectationCase c;
        c.expectation = &e;
        c.group = group->group_key;
        c.group_label = labels.at(c.group);
        c.name = case_name(e.id(), c.group_label);
        cases.push_back(std::move(c));
      }

  // Names shared by several cases: first what each expects, then the position in the file.
  const auto shared = [&cases] {
    std::map<std::string, std::vector<std::size_t>> by_name;
    for (std::size_t k = 0; k < cases.size(); ++k) by_name[cases[k].name].push_back(k);
    std::vector<std::vector<std::size_t>> out;
    for (auto& [name, members] : by_name)
      if (members.size() > 1) out.push_back(std::move(members));
    return out;
  };
  for (const auto& members : shared())
    for (auto k : members)
      cases[k].name = case_name(
          fmt::format("{} ({})", cases[k].expectation->id(), written_form(*cases[k].expectation)),
          cases[k].group_label);
  for (const auto& members : shared())
    for (std::size_t i = 0; i < members.size(); ++i)
      cases[members[i]].name += fmt::format(" #{}", i + 1);

  const auto stem = std::filesystem::path(study.source).stem().string();
  for (auto& c : cases) {
    const auto& e = *c.expectation;
    c.keywords = {c.name, e.metric, study.name, stem, std::string(expectation_kind_name(e.kind))};
    if (!e.name.empty()) c.keywords.push_back(e.name);
    c.keywords.insert(c.keywords.end(), e.tiers.begin(), e.tiers.end());
    if (!e.xfail.empty()) c.keywords.push_back("xfail");
  }
  return cases;
}

CaseSelection select_cases(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                           const KeywordExpression* expression) {
  CaseSelection selection;
  for (const auto& c : expectation_cases(study, trials)) {
    if (!expression || expression->matches(c.keywords))
      selection.selected.emplace(c.expectation->number, c.group);
    else
      ++selection.deselected;
  }
  return selection;
}

void keep_selected(std::vector<ExpectationOutcome>& outcomes, const CaseSelection& selection) {
  std::erase_if(outcomes, [&](const ExpectationOutcome& o) {
    return !selection.selected.contains({o.expectation->number, o.group});
  });
}

}  // namespace rkhs
