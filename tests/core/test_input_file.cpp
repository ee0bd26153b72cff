// Input files refused by type and size before they are read (rkhs/core/input_file.hpp), and
// echoed input cut with an ellipsis (rkhs/core/printable.hpp). Issue 50: `validate /dev/zero`
// grew to 23.8 GB, a FIFO as study file blocked forever, a 10 MB expression was echoed whole.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "rkhs/core/input_file.hpp"
#include "rkhs/core/printable.hpp"

namespace fs = std::filesystem;
using rkhs::check_input_file;
using rkhs::InputFileError;
using rkhs::max_study_file_bytes;
using rkhs::read_input_file;

namespace {

fs::path scratch() {
  const auto dir = fs::temp_directory_path() / "rkhs_input_file";
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string error_of(const fs::path& path, std::uintmax_t limit = max_study_file_bytes) {
  try {
    read_input_file(path, "study file", limit);
  } catch (const InputFileError& e) {
    return e.what();
  }
  return "read";
}

}  // namespace

TEST_CASE("input files that are not regular files are refused by type, never opened",
          "[core][input]") {
  const auto dir = scratch();
  const auto fifo = dir / "study.toml";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  // Opening the FIFO for reading would wait for a writer: the test would hang, not fail.
  CHECK(error_of(fifo) == fifo.string() + ": is a FIFO, not a study file (a regular file)");
  CHECK(error_of(dir) == dir.string() + ": is a directory, not a study file (a regular file)");
  CHECK(error_of("/dev/zero") ==
        "/dev/zero: is a character device, not a study file (a regular file)");
  CHECK(rkhs::not_regular_file_kind(fifo) == "a FIFO");
  CHECK(rkhs::not_regular_file_kind(dir / "absent").empty());
  CHECK_THAT(error_of(dir / "absent"),
             Catch::StartsWith((dir / "absent").string() + ": cannot read the study file: "));
}

TEST_CASE("input files above their limit are refused by size before they are read",
          "[core][input]") {
  const auto dir = scratch();
  const auto big = dir / "big.toml";
  std::ofstream(big) << "x";
  fs::resize_file(big, 5 << 20);  // sparse: 5 MiB of zeros
  CHECK(error_of(big) == big.string() +
                             ": is 5242880 bytes, more than the 4194304 bytes (4 MiB) a study "
                             "file may have");
  CHECK_THROWS_AS(check_input_file(big, "study file", max_study_file_bytes), InputFileError);
  CHECK(check_input_file(big, "CSV data file", rkhs::max_csv_file_bytes) == 5u << 20);
  fs::resize_file(big, max_study_file_bytes);
  CHECK(read_input_file(big, "study file", max_study_file_bytes).size() == max_study_file_bytes);
  CHECK(error_of(big, 1000) == big.string() +
                                   ": is 4194304 bytes, more than the 1000 bytes a study file "
                                   "may have");
}

TEST_CASE("echoed input is cut with an ellipsis", "[core][messages]") {
  CHECK(rkhs::shortened("short", 100) == "short");
  const std::string huge(10'000'000, 'x');
  const auto cut = rkhs::shortened("head " + huge + " tail", 100);
  CHECK(cut.size() < 150);
  CHECK_THAT(cut, Catch::StartsWith("head xxx") && Catch::EndsWith("xxx tail") &&
                      Catch::Contains(" ... [9999910 bytes left out] ... "));
  // Never inside a UTF-8 sequence: the cut moves back to its start.
  const auto greek =
      rkhs::shortened(std::string(20, 'a') + "\xce\xb1\xce\xb2" + std::string(20, 'b'), 42);
  CHECK(rkhs::printable(greek) == greek);
  CHECK(rkhs::excerpt("abcdefghij", 5, 10) == "abcdefghij");
  CHECK(rkhs::excerpt(std::string(100, 'a') + "X" + std::string(100, 'b'), 100, 3) ==
        "...aaaXbb...");
  CHECK(rkhs::excerpt("abcdefghij", 0, 2) == "ab...");
  CHECK(rkhs::excerpt("abcdefghij", 10, 2) == "...ij");
}
