#include "rkhs/core/printable.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace rkhs {

std::size_t utf8_sequence_length(std::string_view text) noexcept {
  if (text.empty()) return 0;
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = byte(0);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  unsigned char low = 0x80, high = 0xbf;  // the range of the second byte
  if (lead >= 0xc2 && lead <= 0xdf) {
    length = 2;
  } else if (lead >= 0xe0 && lead <= 0xef) {
    length = 3;
    if (lead == 0xe0) low = 0xa0;   // no overlong forms
    if (lead == 0xed) high = 0x9f;  // no surrogates
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    length = 4;
    if (lead == 0xf0) low = 0x90;
    if (lead == 0xf4) high = 0x8f;  // at most U+10FFFF
  } else {
    return 0;
  }
  if (text.size() < length) return 0;
  if (byte(1) < low || byte(1) > high) return 0;
  for (std::size_t i = 2; i < length; ++i)
    if (byte(i) < 0x80 || byte(i) > 0xbf) return 0;
  return length;
}

std::string printable(std::string_view text, bool keep_line_breaks) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (keep_line_breaks && (c == '\n' || c == '\t')) {
      out += static_cast<char>(c);
      ++i;
      continue;
    }
    if (c < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02x}", c);
      ++i;
      continue;
    }
    const std::size_t length = utf8_sequence_length(text.substr(i));
    // C1 controls (U+0080 to U+009F: U+009B is a terminal's CSI) are escaped too.
    const bool c1 = length == 2 && c == 0xc2 && static_cast<unsigned char>(text[i + 1]) < 0xa0;
    if (c1) {
      out += fmt::format("\\x{:02x}\\x{:02x}", c, static_cast<unsigned char>(text[i + 1]));
      i += 2;
      continue;
    }
    if (length == 0) {
      out += fmt::format("\\x{:02x}", c);
      ++i;
      continue;
    }
    out += text.substr(i, length);
    i += length;
  }
  return out;
}

namespace {

// `at`, moved back to the start of a UTF-8 sequence (never before 0).
std::size_t sequence_start(std::string_view text, std::size_t at) {
  at = std::min(at, text.size());
  while (at > 0 && at < text.size() && (static_cast<unsigned char>(text[at]) & 0xc0) == 0x80) --at;
  return at;
}

}  // namespace

std::string shortened(std::string_view text, std::size_t max_bytes) {
  max_bytes = std::max<std::size_t>(max_bytes, 16);
  if (text.size() <= max_bytes) return std::string(text);
  const std::size_t head = sequence_start(text, max_bytes / 2);
  const std::size_t tail = sequence_start(text, text.size() - max_bytes / 2);
  return fmt::format("{} ... [{} bytes left out] ... {}", text.substr(0, head), tail - head,
                     text.substr(tail));
}

std::string excerpt(std::string_view text, std::size_t position, std::size_t radius) {
  if (text.size() <= 2 * radius) return std::string(text);
  position = std::min(position, text.size());
  const std::size_t from = sequence_start(text, position > radius ? position - radius : 0);
  const std::size_t to = sequence_start(text, std::min(text.size(), position + radius));
  return fmt::format("{}{}{}", from > 0 ? "..." : "", text.substr(from, to - from),
                     to < text.size() ? "..." : "");
}

}  // namespace rkhs
