#pragma once
// Provenance of this build, recorded in every run's summary.json.

namespace rkhs {

struct BuildInfo {
  const char* version;     ///< rkhs-study version (CMake project version)
  const char* git_commit;  ///< commit of the source tree, "-dirty" appended when modified
  const char* compiler;    ///< compiler id and version
  const char* build_type;  ///< CMake build type (Release, Debug, ...)
};

/// The provenance of the running binary. Generated at build time (cmake/WriteBuildInfo.cmake).
const BuildInfo& build_info() noexcept;

}  // namespace rkhs
