#pragma once
// The one reader of study files' TOML, shared by the study parser (study_file.cpp) and the
// [[expect]] parser (expectation_parser.cpp). Internal to the framework library (toml++ is a
// private dependency). Every error is a StudyError "file:line:column: key: message", and an
// unknown name comes with the known ones and the closest of them.

#include <fmt/format.h>
#include <toml++/toml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/parameters.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::detail {

// Raises StudyError at a node's position.
class Reporter {
 public:
  explicit Reporter(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const toml::source_region& where, std::string_view key,
                         std::string_view message) const {
    throw StudyError(locate(where, key, message));
  }
  const std::string& source() const { return source_; }
  /// The same position and form as fail(), for a warning.
  /// Control characters and bytes that are not UTF-8 in the key and the message (which quote
  /// the study file's text) are shown as escapes ("\x1b"): a message is one line, and carries
  /// no terminal escape sequences. A message longer than max_message_bytes is shortened
  /// (rkhs/core/printable.hpp): one that quotes a huge value stays readable.
  std::string locate(const toml::source_region& where, std::string_view key,
                     std::string_view message) const {
    std::string out = printable(source_);
    if (where.begin.line > 0) out += fmt::format(":{}:{}", where.begin.line, where.begin.column);
    out += ": ";
    if (!key.empty()) out += printable(shortened(key, 200)) + ": ";
    return out + printable(shortened(message, max_message_bytes));
  }
  static constexpr std::size_t max_message_bytes = 2000;

 private:
  std::string source_;
};

/// StudyError at `where` in `source` (the form of Reporter::fail).
[[noreturn]] void fail(const std::string& source, const toml::source_region& where,
                       std::string_view key, std::string_view message);

/// How deep the tables of a study file's TOML may nest, counting every level a dotted key
/// ("a.b.c = 1", "[a.b.c]") opens as well as arrays and inline tables: toml++ bounds arrays and
/// inline tables (TOML_MAX_NESTED_VALUES, 256) but not dotted keys, and a key of 100,000 parts
/// overflows the stack when its tables are built or destroyed.
inline constexpr std::size_t max_toml_nesting = 256;

/// Fails (StudyError "file:line:column: invalid TOML: ... nested more than 256 deep") at the
/// first place where `text` nests deeper than max_toml_nesting, found by a scan of its keys,
/// brackets, strings and comments before toml++ parses it. Text that is not TOML passes as far
/// as the scan can tell: toml++ reports its errors.
void check_toml_nesting(const Reporter& report, std::string_view text);

/// "(known: a, b, c; did you mean 'b'?)" for a name `found` that is not among `known`.
std::string with_suggestion(const std::string& found, const std::vector<std::string>& known);

/// "a string", "an integer", "a number", "a boolean", "an array", "a table", "a date or time".
std::string_view describe(const toml::node& node);

/// The node as TOML text, for "found ..." in messages; at most 200 bytes (shortened,
/// rkhs/core/printable.hpp).
std::string show(const toml::node& node);

/// Fails at the first key of `table` not in `allowed` ("unknown key", with a suggestion);
/// `prefix` ("adaptive.") qualifies the key in the message.
void check_keys(const Reporter& report, const toml::table& table, std::string_view prefix,
                const std::vector<std::string>& allowed);

/// The table `root[key]`, nullptr when absent; fails when it is not a table.
const toml::table* optional_table(const Reporter& report, const toml::table& root,
                                  std::string_view key);

/// `table[key]` as a string; `fallback` when absent (fails when absent and no fallback, or when
/// not a string).
std::string get_string(const Reporter& report, const toml::table& table, std::string_view key,
                       std::string_view prefix, std::optional<std::string> fallback);

/// A number node as a double: a floating-point value as it is, an integer as the nearest double
/// (an integer above 2^53, such as 9007199254740993, is rounded like the same digits written
/// with a decimal point; toml++'s value<double>() gives no value for it). std::nullopt for a
/// node that is not a number. Every real-valued key of a study file is read through it.
std::optional<double> real_of(const toml::node& node);

/// `table[key]` as a finite number > `min_exclusive`; `fallback` when absent.
double get_number(const Reporter& report, const toml::table& table, std::string_view key,
                  std::string_view prefix, double fallback, double min_exclusive);

/// `table[key]` as a whole number in [low, high]; `fallback` when absent. Every refusal (not a
/// number, not whole, out of range) names both bounds: "must be a whole number between LOW and
/// HIGH<why>, found X".
std::uint64_t get_whole_number(const Reporter& report, const toml::table& table,
                               std::string_view key, std::string_view prefix,
                               std::uint64_t fallback, std::uint64_t low, std::uint64_t high,
                               std::string_view why = {});

/// `table[key]` as a boolean; `fallback` when absent.
bool get_bool(const Reporter& report, const toml::table& table, std::string_view key,
              std::string_view prefix, bool fallback);

/// An integer, number, string or boolean node as a parameter value; std::nullopt otherwise.
std::optional<ParameterValue> scalar_value(const toml::node& node);

/// The fit-window keys of `table` (n_from, n_to, h_from, h_to, last; docs/verification.md),
/// checked against the study: numbers, from <= to, h_* only with abscissa = "h", `last` a whole
/// number >= 2, and a window that holds at least 2 of the grid's n (n_from, n_to, last).
/// Other keys are the caller's to check. `prefix` ("rates.", "expect.") qualifies keys.
FitWindow read_fit_window(const Reporter& report, const toml::table& table, std::string_view prefix,
                          const StudyDefinition& study);

/// The keys read_fit_window reads.
inline const std::vector<std::string> fit_window_keys{"n_from", "n_to", "h_from", "h_to", "last"};

}  // namespace rkhs::detail
