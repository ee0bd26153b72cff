#pragma once
// Files a user names for reading (a study file, a CSV data file, a result store), checked
// before they are read: a path that is not a regular file (a FIFO, a device, a directory, a
// socket) is refused by its type before it is opened, since opening a FIFO waits for a writer
// and /dev/zero never ends; a regular file larger than its kind's limit is refused by its size
// before it is read. Messages name the path, what was found and what is allowed:
//   "x.toml: is a FIFO, not a study file (a regular file)"
//   "big.toml: is 314572800 bytes, more than the 4194304 (4 MiB) a study file may have"
// docs/study-files.md lists the limits.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rkhs {

/// A file that cannot be read as the kind of input it was named as (what() is the message).
class InputFileError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The largest study file read (4 MiB; the shipped ones are below 20 KiB).
inline constexpr std::uintmax_t max_study_file_bytes = std::uintmax_t{4} << 20;
/// The largest CSV data file read (256 MiB; a road of 10^7 samples is about 200 MiB).
inline constexpr std::uintmax_t max_csv_file_bytes = std::uintmax_t{256} << 20;

/// "a FIFO", "a directory", "a character device", "a block device", "a socket", or "a special
/// file": what a path of this type is, for messages.
std::string_view file_kind(std::filesystem::file_type type) noexcept;

/// Whether `path` (symbolic links followed) is something other than a regular file: its kind
/// (file_kind) when it exists and is not a regular file, "" when it is a regular file or does
/// not exist (the caller says "not found" in its own words). Never opens `path`.
std::string not_regular_file_kind(const std::filesystem::path& path);

/// Checks `path` for reading as a `what` ("study file", "data file"): throws InputFileError
/// "<path>: is a FIFO, not a <what> (a regular file)" for a path that exists and is not a
/// regular file, "<path>: is N bytes, more than the M (K MiB) a <what> may have" for one larger
/// than `max_bytes`. Returns the size in bytes. A path that does not exist or cannot be
/// examined throws InputFileError "<path>: cannot read the <what>: <reason>". Never opens it.
std::uintmax_t check_input_file(const std::filesystem::path& path, std::string_view what,
                                std::uintmax_t max_bytes);

/// The whole content of `path`, checked as check_input_file does, then opened without waiting
/// (O_NONBLOCK) and checked again on the open file, so that a path replaced by a FIFO in
/// between is refused, not waited on; never more than `max_bytes` are read (a file that grows
/// beyond it while it is read is refused as too large). Throws InputFileError as above and
/// "<path>: cannot read the <what>: <reason>" for a failed open or read.
std::string read_input_file(const std::filesystem::path& path, std::string_view what,
                            std::uintmax_t max_bytes);

}  // namespace rkhs
