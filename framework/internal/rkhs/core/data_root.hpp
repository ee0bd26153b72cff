#pragma once
// The data root: the directory study files name their data files (road profiles) relative to.
//
// Resolution order, first that applies:
//   1. set_data_root(dir)  (the command line's --data-dir DIR),
//   2. the environment variable RKHS_STUDY_DATA,
//   3. studies/data/ relative to the current directory.
// A relative root is taken relative to the current directory when it is set or first read.
// The setting is process-wide; set it before trials start (it is read, never written, by
// worker threads). docs/roads.md describes how studies use it.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace rkhs {

struct DataRoot {
  std::filesystem::path directory;  ///< absolute
  std::string origin;               ///< "--data-dir", "RKHS_STUDY_DATA" or "default"
};

/// Sets the data root (an empty path restores the default resolution).
void set_data_root(const std::filesystem::path& directory);

/// The data root by the resolution order above.
DataRoot data_root();

/// Whether the relative path `name` leaves the data root through "..": its lexically normal form
/// starts with ".." ("../x", "a/../../x"). An absolute path never does (it is taken as given).
/// Lexical only: a symbolic link below the root is followed wherever it points.
bool leaves_data_root(std::string_view name);

/// The message for a `name` that leaves_data_root: what was refused and what to write instead.
std::string data_root_escape_message(std::string_view name);

/// The file `name` names: an absolute `name` as it is, a relative one below data_root().
/// Throws std::invalid_argument when no such regular file exists (a path that exists and is not
/// a regular file, a FIFO or a device such as /dev/stdin, is named as what it is: "data file
/// 'x' is a FIFO, not a data file (a regular file; ...)"), and for a relative `name`
/// that leaves the root through ".." (leaves_data_root); the message names `name` (control
/// characters escaped), the full path looked at, where the root came from and how to change it.
std::filesystem::path resolve_data_file(const std::string& name);

}  // namespace rkhs
