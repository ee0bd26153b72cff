// The one reader of study files' TOML (rkhs/study/toml_reader.hpp): messages in the form
// "file:line:column: key: message".
#include "toml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>
#include <vector>

#include "rkhs/core/registry.hpp"

namespace rkhs::detail {

void check_toml_nesting(const Reporter& report, std::string_view text) {
  // One open array or inline table: whether it holds keys (an inline table) and the dots of
  // the key being read in it.
  struct Level {
    bool table;  // an inline table (else an array)
    bool key;    // reading a key (inline tables only)
    std::size_t key_dots = 0;
  };
  std::vector<Level> open;
  std::size_t header_dots = 0, top_key_dots = 0, depth = 0;  // depth: every level counted
  bool top_key = true;                                       // at top level, reading a key
  std::uint32_t line = 1, column = 0;
  const auto deeper = [&] {
    if (++depth <= max_toml_nesting) return;
    const toml::source_position at{line, column};
    report.fail({at, at, nullptr}, "",
                fmt::format("invalid TOML: keys, arrays and inline tables nested more than {} deep",
                            max_toml_nesting));
  };
  const auto in_key = [&] { return open.empty() ? top_key : open.back().key; };
  std::size_t i = 0;
  const auto next = [&] {
    const char c = text[i++];
    if (c == '\n') {
      ++line;
      column = 0;
    } else {
      ++column;
    }
    return c;
  };
  const auto skip_string = [&](char quote) {
    const bool multi = text.substr(i, 2) == std::string_view(quote == '"' ? "\"\"" : "''");
    if (multi) {
      next();
      next();
    }
    while (i < text.size()) {
      const char c = next();
      if (c == '\\' && quote == '"' && i < text.size()) {
        next();
      } else if (c == quote &&
                 (!multi || text.substr(i, 2) == std::string_view(quote == '"' ? "\"\"" : "''"))) {
        if (multi) {
          next();
          next();
        }
        return;
      } else if (c == '\n' && !multi) {
        return;
      }
    }
  };
  bool line_start = true;
  while (i < text.size()) {
    const char c = next();
    if (c == ' ' || c == '\t' || c == '\r') continue;
    const bool was_line_start = line_start;
    line_start = false;
    if (c == '#') {
      while (i < text.size() && text[i] != '\n') next();
    } else if (c == '"' || c == '\'') {
      skip_string(c);
    } else if (c == '\n') {
      line_start = true;
      if (open.empty()) {
        depth -= top_key_dots;
        top_key_dots = 0;
        top_key = true;
      }
    } else if (c == '[' && open.empty() && top_key && was_line_start) {
      // A table header [a.b.c] or [[a.b.c]]: its dots are the depth of the keys below it.
      depth -= header_dots + top_key_dots;
      header_dots = top_key_dots = 0;
      while (i < text.size() && text[i] != ']' && text[i] != '\n' && text[i] != '#') {
        const char h = next();
        if (h == '"' || h == '\'') {
          skip_string(h);
        } else if (h == '.') {
          ++header_dots;
          deeper();
        }
      }
      while (i < text.size() && text[i] != '\n') next();  // ] or ]] and what follows
    } else if (c == '.' && in_key()) {
      ++(open.empty() ? top_key_dots : open.back().key_dots);
      deeper();
    } else if (c == '=' && in_key()) {
      if (open.empty())
        top_key = false;
      else
        open.back().key = false;  // its value now; ',' returns to a key
    } else if (c == '{' && !in_key()) {
      open.push_back({true, true});
      deeper();
    } else if (c == '[' && !in_key()) {
      open.push_back({false, false});
      deeper();
    } else if ((c == '}' || c == ']') && !open.empty()) {
      depth -= open.back().key_dots + 1;
      open.pop_back();
    } else if (c == ',' && !open.empty()) {
      // The next key of an inline table (an array stays with values).
      auto& level = open.back();
      depth -= level.key_dots;
      level.key_dots = 0;
      level.key = level.table;
    }
  }
}

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
  return shortened(out.str(), 200);
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

std::uint64_t get_whole_number(const Reporter& report, const toml::table& table,
                               std::string_view key, std::string_view prefix,
                               std::uint64_t fallback, std::uint64_t low, std::uint64_t high,
                               std::string_view why) {
  const auto* node = table.get(key);
  if (!node) return fallback;
  const auto value = real_of(*node);
  if (!value || !std::isfinite(*value) || *value != std::floor(*value) ||
      *value < static_cast<double>(low) || *value > static_cast<double>(high))
    report.fail(
        node->source(), fmt::format("{}{}", prefix, key),
        fmt::format("must be a whole number between {} and {}{}, found {}", low, high, why,
                    node->is_number() ? show(*node)
                                      : fmt::format("{} ({})", describe(*node), show(*node))));
  return static_cast<std::uint64_t>(*value);
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
