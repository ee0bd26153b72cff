#pragma once
// summary.json of an earlier run read back (rkhs-study report): the fields a later command
// needs, parsed as JSON (nlohmann::json), not searched for as text.

#include <filesystem>
#include <string>

namespace rkhs {

struct RunSummary {
  std::string study;   ///< the study's name
  std::string source;  ///< the study file the run read, as it was given
  std::string tier;    ///< the tier the run was restricted to (`check --tier`), "" for none
};

/// Reads `file` (summary.json, as summary_json() writes it; "tier" may be absent or null, as
/// in files written before it was recorded). Throws std::runtime_error naming
/// the file when it cannot be opened, is not JSON (with the byte offset), or has no "source".
RunSummary read_run_summary(const std::filesystem::path& file);

}  // namespace rkhs
