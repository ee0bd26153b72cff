// The one reader of study files' TOML (rkhs/study/toml_reader.hpp): messages in the form
// "file:line:column: key: message".
#include "toml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rkhs/core/registry.hpp"

namespace rkhs::detail {


std::string with_suggestion(const std::string& found, const std::vector<std::string>& known) {
  std::string out = fmt::format("(known: {}", fmt::join(known, ", "));
  if (auto guess = closest_name(found, known); !guess.empty())
    out += fmt::format("; did you mean '{}'?", guess);
  return out + ")";
}

std::string_view describe(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::array: return "an array";
    case toml::node_type::table: return "a table";
    default: return "a date or time";
  }
}

std::string show(const toml::node& node) {
  std::ostringstream out;
  node.visit([&](auto&& v) { out << v; });
  return out.str();
}

// Rejects keys of `table` that are not in `allowed`.
void check_keys(const Reporter& report, const toml::table& table, std::string_view prefix,
                const std::vector<std::string>& allowed) {
  for (auto&& [key, value] : table) {
    const std::string name(key.str());
    if (std::find(allowed.begin(), allowed.end(), name) == allowed.end())
      report.fail(key.source(), std::string(prefix) + name,
                  "unknown key " + with_suggestion(name, allowed));
  }
}

const toml::table* optional_table(const Reporter& report, const toml::table& root,
                                  std::string_view key) {
  const auto* node = root.get(key);
  if (!node) return nullptr;
  if (!node->is_table())
    report.fail(node->source(), key, fmt::format("expected a table, found {}", describe(*node)));
  return node->as_table();
}

std::string get_string(const Reporter& report, const toml::table& table, std::string_view key,
                       std::string_view prefix, std::optional<std::string> fallback) {
  const auto* node = table.get(key);
  if (!node) {
    if (fallback) return *fallback;
    report.fail(table.source(), fmt::format("{}{}", prefix, key), "missing (a string is required)");
  }
  if (!node->is_string())
    report.fail(node->source(), fmt::format("{}{}", prefix, key),
                fmt::format("expected a string, found {} ({})", describe(*node), show(*node)));
  return node->as_string()->get();
}

double get_number(const Reporter& report, const toml::table& table, std::string_view key,
                  std::string_view prefix, double fallback, double min_exclusive) {
  const auto* node = table.get(key);
  if (!node) return fallback;
  if (!node->is_number())
    report.fail(node->source(), fmt::format("{}{}", prefix, key),
                fmt::format("expected a number, found {} ({})", describe(*node), show(*node)));
  const double value = node->value<double>().value();
  if (!(value > min_exclusive) || !std::isfinite(value))
    report.fail(node->source(), fmt::format("{}{}", prefix, key),
                fmt::format("must be a finite number > {}, found {}", format_real(min_exclusive),
                            show(*node)));
  return value;
}

bool get_bool(const Reporter& report, const toml::table& table, std::string_view key,
              std::string_view prefix, bool fallback) {
  const auto* node = table.get(key);
  if (!node) return fallback;
  if (!node->is_boolean())
    report.fail(node->source(), fmt::format("{}{}", prefix, key),
                fmt::format("expected true or false, found {} ({})", describe(*node), show(*node)));
  return node->as_boolean()->get();
}

std::optional<ParameterValue> scalar_value(const toml::node& node) {
  if (auto v = node.as_integer()) return ParameterValue(v->get());
  if (auto v = node.as_floating_point()) return ParameterValue(v->get());
  if (auto v = node.as_string()) return ParameterValue(v->get());
  if (auto v = node.as_boolean()) return ParameterValue(v->get());
  return std::nullopt;
}

[[noreturn]] void fail(const std::string& source, const toml::source_region& where,
                       std::string_view key, std::string_view message) {
  Reporter(source).fail(where, key, message);
}

}  // namespace rkhs::detail
