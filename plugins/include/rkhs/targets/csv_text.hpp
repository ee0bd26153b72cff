#pragma once
// Reading a CSV text so that every error can name the file's own line and column: the line
// splitter and field splitter shared by the CSV targets (`csv`, `surface_csv`), and reading a
// file whole (its SHA-256 is the target's provenance).

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rkhs::csv_text {

// One field of a line: its text (blanks and surrounding double quotes removed) and the 1-based
// column of its first character in the line.
struct Field {
  std::string_view text;
  std::size_t column;
};

inline std::vector<Field> split(std::string_view line, char delimiter) {
  std::vector<Field> fields;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = std::min(line.find(delimiter, begin), line.size());
    std::size_t first = begin, last = end;
    while (first < last && (line[first] == ' ' || line[first] == '\t')) ++first;
    while (last > first && (line[last - 1] == ' ' || line[last - 1] == '\t')) --last;
    if (last - first >= 2 && line[first] == '"' && line[last - 1] == '"') ++first, --last;
    fields.push_back({line.substr(first, last - first), first + 1});
    if (end == line.size()) break;
    begin = end + 1;
  }
  return fields;
}

// The lines of a CSV text, split as fast-cpp-csv-parser's LineReader split a file (which read
// the files before, with a buffer of 48 MB each time): a UTF-8 byte-order mark at the start is
// skipped; a line ends at '\n' (the last one may lack it), less one '\r' before it, and at its
// first NUL byte; at most 2^24 - 1 bytes.
class Lines {
 public:
  Lines(std::string_view text, const std::string& file) : rest_(text), file_(file) {
    if (rest_.starts_with("\xEF\xBB\xBF")) rest_.remove_prefix(3);
  }
  /// The next line, or std::nullopt after the last.
  std::optional<std::string_view> next() {
    if (rest_.empty()) return std::nullopt;
    ++number_;
    const std::size_t end = std::min(rest_.find('\n'), rest_.size());
    if (end >= max_length)
      throw std::invalid_argument(
          fmt::format("{}:{}:1: the line is longer than {} bytes", file_, number_, max_length - 1));
    auto line = rest_.substr(0, end);
    rest_.remove_prefix(end == rest_.size() ? end : end + 1);
    if (line.ends_with('\r')) line.remove_suffix(1);
    return line.substr(0, line.find('\0'));
  }
  /// The number of the line next() returned last (1-based; 0 before the first).
  unsigned number() const { return number_; }

 private:
  static constexpr std::size_t max_length = std::size_t{1} << 24;
  std::string_view rest_;
  const std::string& file_;
  unsigned number_ = 0;
};

inline bool blank_or_comment(std::string_view line) {
  const auto first = line.find_first_not_of(" \t");
  return first == std::string_view::npos || line[first] == '#';
}

/// The number a whole field holds (a leading '+' allowed, which from_chars does not take), or
/// nothing when the field is empty or is not one number. NaN and infinities are numbers here:
/// the caller says whether it takes them.
inline std::optional<double> parse_number(std::string_view text) {
  if (text.empty()) return std::nullopt;
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (*begin == '+') ++begin;
  double value = 0;
  const auto [stop, error] = std::from_chars(begin, end, value);
  if (error != std::errc() || stop != end) return std::nullopt;
  return value;
}

/// The bytes of `path`; std::invalid_argument "<file>: cannot open the file: <why>" otherwise
/// (`file` names it in messages).
inline std::string read_whole_file(const std::filesystem::path& path, const std::string& file) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::invalid_argument(
        fmt::format("{}: cannot open the file: {}", file, std::strerror(errno)));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw std::invalid_argument(fmt::format("{}: cannot read the file", file));
  return std::move(bytes).str();
}

}  // namespace rkhs::csv_text
