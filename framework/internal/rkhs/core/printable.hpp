#pragma once
// Text from a user (a study file, a data file) as it may appear in a message on a terminal:
// control bytes and bytes that are not UTF-8 shown as escapes ("\x1b"), so that a message
// cannot carry terminal escape sequences or break into lines that are not its own.

#include <cstddef>
#include <string>
#include <string_view>

namespace rkhs {

/// The length of the well-formed UTF-8 sequence `text` starts with (1 to 4; no overlong forms,
/// surrogates or code points beyond U+10FFFF), 0 when it does not start with one.
std::size_t utf8_sequence_length(std::string_view text) noexcept;

/// `text` with every byte below 0x20, 0x7f, the C1 controls U+0080 to U+009F (both bytes) and
/// every byte outside a well-formed UTF-8 sequence written as \xNN (lower-case hex); everything
/// else as it is. With `keep_line_breaks`, '\n' and
/// '\t' stay as they are (a whole message of several lines).
std::string printable(std::string_view text, bool keep_line_breaks = false);

/// `text` as it is when it has at most `max_bytes` bytes; otherwise cut with an ellipsis, so
/// that a message that echoes input (a 10 MB expression) stays readable: its first and last
/// max_bytes / 2 bytes (cuts moved back to the start of a UTF-8 sequence) joined by
/// " ... [N bytes left out] ... ", keeping both what a message says first and its end ("found
/// ..., expected ..."). `max_bytes` below 16 is taken as 16.
std::string shortened(std::string_view text, std::size_t max_bytes);

/// The part of `text` within `radius` bytes of byte `position` (clamped to the text), with
/// "..." where the text goes on: "...s+s+s+s+s+s..." (cuts at the start of a UTF-8 sequence).
/// The whole text when it has at most 2 x `radius` bytes.
std::string excerpt(std::string_view text, std::size_t position, std::size_t radius);

}  // namespace rkhs
