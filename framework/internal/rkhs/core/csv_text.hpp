#pragma once
// Reading a CSV text so that every error can name the file's own line and column: the line
// splitter and field splitter shared by the CSV targets (`csv`, `surface_csv`) and the
// reference values of expectations (study/reference_values.cpp), reading a file
// a block at a time with the line limit applied as it is read (its SHA-256, computed on the
// way, is the target's provenance), and fields quoted in messages (control characters
// escaped). A file is refused by type and size before it is read (open_file), and never more
// than max_csv_file_bytes (256 MiB) of it are read.

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/input_file.hpp"
#include "rkhs/core/printable.hpp"
#include "rkhs/core/sha256.hpp"

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

// The lines of a CSV text or file, split as fast-cpp-csv-parser's LineReader split a file
// (which read the files before, with a buffer of 48 MB each time): a UTF-8 byte-order mark at
// the start is skipped; a line ends at '\n' (the last one may lack it), less one '\r' before
// it, and at its first NUL byte; at most 2^24 - 1 bytes. A file is read a block at a time, and
// the limit applies while it is read: a line too long is an error once its first 2^24 bytes
// are read, so no more than one line of the limit and one block are ever held (a file of
// gigabytes without a line break fails after 16 MiB).
class Lines {
 public:
  static constexpr std::size_t max_length = std::size_t{1} << 24;
  static constexpr std::size_t block_size = std::size_t{1} << 16;

  /// The lines of `text` (`file` names it in messages).
  Lines(std::string_view text, const std::string& file) : rest_(text), file_(file) {
    if (rest_.starts_with("\xEF\xBB\xBF")) rest_.remove_prefix(3);
  }
  /// The lines of the stream `in`, read in blocks of block_size bytes; `digest`, when given, is
  /// updated with every byte read (the whole file's once next() has returned std::nullopt).
  Lines(std::istream& in, const std::string& file, Sha256* digest = nullptr)
      : file_(file), in_(&in), digest_(digest) {
    buffer_.resize(block_size);
  }

  /// The next line, or std::nullopt after the last. The view lasts until the next call.
  std::optional<std::string_view> next() {
    std::string_view line;
    if (!in_) {
      if (rest_.empty()) return std::nullopt;
      const std::size_t end = std::min(rest_.find('\n'), rest_.size());
      if (end >= max_length) too_long(number_ + 1);
      line = rest_.substr(0, end);
      rest_.remove_prefix(end == rest_.size() ? end : end + 1);
    } else {
      line_.clear();
      bool any = false;
      while (true) {
        if (rest_.empty()) {
          if (!fill()) break;
          continue;
        }
        any = true;
        const std::size_t newline = rest_.find('\n');
        const std::size_t take = std::min(newline, rest_.size());
        if (line_.size() + take >= max_length) too_long(number_ + 1);
        line_.append(rest_.substr(0, take));
        if (newline != std::string_view::npos) {
          rest_.remove_prefix(newline + 1);
          break;
        }
        rest_ = {};
      }
      if (!any) return std::nullopt;
      line = line_;
    }
    ++number_;
    if (line.ends_with('\r')) line.remove_suffix(1);
    return line.substr(0, line.find('\0'));
  }
  /// The number of the line next() returned last (1-based; 0 before the first).
  unsigned number() const { return number_; }
  /// The bytes read from the stream so far (0 for a text).
  std::uint64_t bytes_read() const { return bytes_read_; }

 private:
  [[noreturn]] void too_long(unsigned line) const {
    throw std::invalid_argument(
        fmt::format("{}:{}:1: the line is longer than {} bytes", file_, line, max_length - 1));
  }
  // The next block of the stream into rest_; false at its end.
  bool fill() {
    in_->read(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    const auto got = static_cast<std::size_t>(in_->gcount());
    if (got == 0) {
      if (in_->bad()) throw std::invalid_argument(fmt::format("{}: cannot read the file", file_));
      return false;
    }
    if (bytes_read_ + got > max_csv_file_bytes)  // a file that grew after open_file's check
      throw std::invalid_argument(fmt::format(
          "{}: is more than the {} bytes a CSV data file may have", file_, max_csv_file_bytes));
    if (digest_) digest_->update(buffer_.data(), got);
    rest_ = std::string_view(buffer_.data(), got);
    if (bytes_read_ == 0 && rest_.starts_with("\xEF\xBB\xBF")) rest_.remove_prefix(3);
    bytes_read_ += got;
    return true;
  }

  std::string_view rest_;
  const std::string& file_;
  unsigned number_ = 0;
  std::istream* in_ = nullptr;
  Sha256* digest_ = nullptr;
  std::string buffer_, line_;
  std::uint64_t bytes_read_ = 0;
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

/// `path` opened for reading in binary, once check_input_file (rkhs/core/input_file.hpp) has
/// found it a regular file of at most max_csv_file_bytes: InputFileError (a
/// std::invalid_argument) "<path>: is a FIFO, not a CSV data file (a regular file)" or "<path>:
/// is N bytes, more than the 268435456 bytes (256 MiB) a CSV data file may have" before it is
/// opened; std::invalid_argument "<file>: cannot open the file: <why>" when it cannot be opened
/// (`file` names it in messages).
inline std::ifstream open_file(const std::filesystem::path& path, const std::string& file) {
  check_input_file(path, "CSV data file", max_csv_file_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::invalid_argument(
        fmt::format("{}: cannot open the file: {}", file, std::strerror(errno)));
  return in;
}

}  // namespace rkhs::csv_text
