#pragma once
// Where tests find the measured road data: studies/data/ in the source tree, the data root's
// default location (docs/roads.md). A test that needs it and cannot find it fails and says where
// it looked; it never skips.
#include <catch2/catch.hpp>
#include <filesystem>

namespace rkhs::testing {

/// studies/data/ of the source tree: the repository's own copy of the measured roads.
inline std::filesystem::path study_data_root() {
  return (std::filesystem::path(RKHS_STUDY_SOURCE_DIR) / "studies" / "data").lexically_normal();
}

/// The study data root, after checking that the Belgian block profiles are there.
inline std::filesystem::path require_study_data() {
  const auto root = study_data_root();
  const auto probe = root / "belgian_block" / "long_section_v+0.00.csv";
  if (!std::filesystem::is_regular_file(probe))
    FAIL("the road data this test needs is missing: looked for "
         << probe.string() << " (it is part of the repository: studies/data/belgian_block/)");
  return root;
}

}  // namespace rkhs::testing
