#pragma once
// Where tests find the shared data (../shared/data beside the repository, or RKHS_STUDY_DATA).
// A test that needs it and cannot find it fails and says where it looked; it never skips.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>

namespace rkhs::testing {

/// RKHS_STUDY_DATA when set, else shared/data beside the source tree.
inline std::filesystem::path shared_data_root() {
  if (const char* environment = std::getenv("RKHS_STUDY_DATA"); environment && *environment)
    return environment;
  return (std::filesystem::path(RKHS_STUDY_SOURCE_DIR).parent_path() / "shared" / "data")
      .lexically_normal();
}

/// The shared data root, after checking that the Belgian block profiles are there.
inline std::filesystem::path require_shared_data() {
  const auto root = shared_data_root();
  const auto probe = root / "belgian_block" / "long_section_v+0.00.csv";
  if (!std::filesystem::is_regular_file(probe))
    FAIL("the shared data this test needs is missing: looked for "
         << probe.string()
         << " (the data lives outside the repository in ../shared/data; set RKHS_STUDY_DATA to "
            "the directory that holds belgian_block/)");
  return root;
}

}  // namespace rkhs::testing
