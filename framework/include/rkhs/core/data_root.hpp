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

namespace rkhs {

struct DataRoot {
  std::filesystem::path directory;  ///< absolute
  std::string origin;               ///< "--data-dir", "RKHS_STUDY_DATA" or "default"
};

/// Sets the data root (an empty path restores the default resolution).
void set_data_root(const std::filesystem::path& directory);

/// The data root by the resolution order above.
DataRoot data_root();

/// The file `name` names: an absolute `name` as it is, a relative one below data_root().
/// Throws std::invalid_argument when no such regular file exists; the message names `name`, the
/// full path looked at, where the root came from and how to change it.
std::filesystem::path resolve_data_file(const std::string& name);

}  // namespace rkhs
