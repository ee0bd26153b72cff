// The one reader of study files' TOML (rkhs/study/toml_reader.hpp): messages in the form
// "file:line:column: key: message".
#include "toml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

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

std::optional<double> real_of(const toml::node& node) {
  if (const auto* integer = node.as_integer()) return static_cast<double>(integer->get());
  if (const auto* real = node.as_floating_point()) return real->get();
  return std::nullopt;
}

double get_number(const Reporter& report, const toml::table& table, std::string_view key,
                  std::string_view prefix, double fallback, double min_exclusive) {
  const auto* node = table.get(key);
  if (!node) return fallback;
  if (!node->is_number())
    report.fail(node->source(), fmt::format("{}{}", prefix, key),
                fmt::format("expected a number, found {} ({})", describe(*node), show(*node)));
  const double value = *real_of(*node);
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

FitWindow read_fit_window(const Reporter& report, const toml::table& table,
                          std::string_view prefix, const StudyDefinition& study) {
  FitWindow window;
  auto key_of = [&](std::string_view key) { return std::string(prefix) + std::string(key); };
  auto number = [&](std::string_view key) -> std::optional<double> {
    const auto* node = table.get(key);
    if (!node) return std::nullopt;
    const auto value = real_of(*node);
    if (!value || !std::isfinite(*value) || !(*value > 0.0))
      report.fail(node->source(), key_of(key),
                  fmt::format("expected a positive number, found {}", show(*node)));
    if ((key == "h_from" || key == "h_to") && study.abscissa != Abscissa::fill_distance)
      report.fail(node->source(), key_of(key),
                  fmt::format("a window in h needs study.abscissa = \"h\" (this study fits against "
                              "n: use n_{} instead)",
                              key == "h_from" ? "from" : "to"));
    return *value;
  };
  window.n_from = number("n_from");
  window.n_to = number("n_to");
  window.h_from = number("h_from");
  window.h_to = number("h_to");
  for (auto [from, to, name] : {std::tuple{window.n_from, window.n_to, "n"},
                                std::tuple{window.h_from, window.h_to, "h"}})
    if (from && to && *from > *to)
      report.fail(table.get(std::string(name) + "_to")->source(), key_of(std::string(name) + "_to"),
                  fmt::format("{}_to = {} is below {}_from = {}: the window is empty", name,
                              format_real(*to), name, format_real(*from)));
  if (const auto* node = table.get("last")) {
    const auto value = node->value<std::int64_t>();
    if (!node->is_integer() || !value || *value < 2)
      report.fail(node->source(), key_of("last"),
                  fmt::format("expected a whole number of points >= 2 (a fit needs 2, a CI 3), "
                              "found {}",
                              show(*node)));
    window.last = static_cast<std::size_t>(*value);
  }
  // The grid's n in the window (h is known only once the trials ran).
  std::size_t inside = 0;
  for (auto n : study.n_values) {
    const double value = static_cast<double>(n);
    inside += (!window.n_from || value >= *window.n_from) && (!window.n_to || value <= *window.n_to);
  }
  if (window.last) inside = std::min(inside, *window.last);
  if ((window.n_from || window.n_to) && inside < 2) {
    const auto* node = table.get(window.n_from ? "n_from" : "n_to");
    report.fail(node->source(), key_of(window.n_from ? "n_from" : "n_to"),
                fmt::format("the window n = {}..{} holds {} of the grid's n ({}..{}); a fit "
                            "needs at least 2",
                            window.n_from ? format_real(*window.n_from) : "",
                            window.n_to ? format_real(*window.n_to) : "", inside,
                            study.n_values.front(), study.n_values.back()));
  }
  if (window.last && *window.last > study.n_values.size())
    report.fail(table.get("last")->source(), key_of("last"),
                fmt::format("last = {} but the grid has {} values of n", *window.last,
                            study.n_values.size()));
  return window;
}

}  // namespace rkhs::detail
