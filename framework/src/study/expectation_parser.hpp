#pragma once
// Internal to the framework library (toml++ is a private dependency): reading [[expect]] tables
// and `tier` keys of a study file. Errors are StudyError in the parser's format,
// "file:line:column: key: message".

#include <string>
#include <string_view>
#include <toml++/toml.h>
#include <vector>

#include "rkhs/study/expectation.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::detail {

/// The [[expect]] tables of `root`, checked against `outline` in everything but the groups they
/// select: keys, metrics, tiers, selectors, kinds. `outline` is the study with at least one
/// plugin choice per entry of the file (the axis columns of the whole grid), so a mistake is
/// found before a large grid is expanded.
std::vector<Expectation> read_expectations(const toml::table& root, const StudyDefinition& outline);

/// Checks that every expectation (read_expectations of the same `root`) selects a group of the
/// complete `study`, each value of a selector list too, and that a theory expectation has a
/// theory for every kernel it selects.
void check_expectation_selections(const toml::table& root, const StudyDefinition& study,
                                  const std::vector<Expectation>& expectations);

/// A `tier` value: a tier name or a non-empty array of them (letters, digits, '_', '-').
std::vector<std::string> parse_tiers(const toml::node& node, const std::string& source,
                                     std::string_view key);

}  // namespace rkhs::detail
