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

/// The [[expect]] tables of `root`, validated against `study` (which must be complete: its
/// metrics, axes and domain are used to check metrics, selectors and theory).
std::vector<Expectation> parse_expectations(const toml::table& root, const StudyDefinition& study);

/// A `tier` value: a tier name or a non-empty array of them (letters, digits, '_', '-').
std::vector<std::string> parse_tiers(const toml::node& node, const std::string& source,
                                     std::string_view key);

}  // namespace rkhs::detail
