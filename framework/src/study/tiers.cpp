#include "rkhs/study/tiers.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <set>

namespace rkhs {
namespace {

bool in_tier(const std::vector<std::string>& tiers, std::string_view tier) {
  return std::find(tiers.begin(), tiers.end(), tier) != tiers.end();
}

}  // namespace

std::vector<std::string> study_tiers(const StudyDefinition& study) {
  std::set<std::string> tiers;
  for (const auto& axis : study.plugin_axes())
    for (const auto& choice : *axis.second) tiers.insert(choice.tiers.begin(), choice.tiers.end());
  for (const auto& expectation : study.expectations)
    tiers.insert(expectation.tiers.begin(), expectation.tiers.end());
  for (const auto& entry : study.tier_n_values) tiers.insert(entry.first);
  return {tiers.begin(), tiers.end()};
}

StudyDefinition restrict_to_tier(StudyDefinition study, std::string_view tier) {
  const auto known = study_tiers(study);
  if (!in_tier(known, tier))
    throw StudyError(fmt::format("{}: tier '{}' is not named in this study (tiers: {})",
                                 study.source, tier,
                                 known.empty() ? std::string("none") : fmt::format("{}", fmt::join(known, ", "))));
  for (auto [section, axis] : study.plugin_axes()) {
    const bool marked = std::any_of(axis->begin(), axis->end(),
                                    [](const PluginChoice& c) { return !c.tiers.empty(); });
    if (!marked) continue;
    std::erase_if(*axis, [&](const PluginChoice& c) { return !in_tier(c.tiers, tier); });
    if (axis->empty())
      throw StudyError(fmt::format("{}: tier '{}' has no [[{}]] entry (entries of this axis name "
                                   "tiers, none names '{}')",
                                   study.source, tier, section, tier));
  }
  if (const auto n = study.tier_n_values.find(tier); n != study.tier_n_values.end())
    study.n_values = n->second;
  std::erase_if(study.expectations, [&](const Expectation& e) { return !e.in_tier(tier); });
  const auto trials = study.trials();
  for (const auto& expectation : study.expectations)
    if (std::none_of(trials.begin(), trials.end(),
                     [&](const TrialSpec& t) { return expectation.selects(t); }))
      throw StudyError(fmt::format("{}: expect: in tier '{}', {} selects no group the tier runs",
                                   expectation.location, tier, expectation.selector_text()));
  return study;
}

}  // namespace rkhs
