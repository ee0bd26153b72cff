// libFuzzer harness: a result store file of arbitrary bytes, opened and verified as
// `rkhs-study store check` does (rkhs::ResultStore: open, then every row read and its record
// verified by read_record), and merged into an empty store as `rkhs-study merge` does. A file that
// is not a store, or a damaged one, is refused with std::runtime_error naming the store (what
// ResultStore documents for any SQLite error); anything else is a bug.
//
// SQLite itself is Debian's (not instrumented: the coverage libFuzzer sees is rkhs-study's), and
// each input is a file of its own, written, opened and removed every time, in a directory of this
// process in /dev/shm (memory: SQLite's syncs cost nothing there) or, without it, below TMPDIR.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "fuzz_support.hpp"
#include "rkhs/run/result_store.hpp"

namespace {

namespace fs = std::filesystem;

// The directory of this process's store files, removed when the process exits.
class Directory {
 public:
  Directory() {
    std::error_code error;
    const fs::path base =
        fs::is_directory("/dev/shm", error) ? fs::path("/dev/shm") : fs::temp_directory_path();
    path_ = base / ("rkhs_fuzz_store_file." + std::to_string(getpid()));
    fs::create_directories(path_);
  }
  ~Directory() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

const fs::path& directory() {
  static const Directory instance;
  return instance.path();
}

void remove_store(const fs::path& file) {
  std::error_code ignored;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"})
    fs::remove(file.string() + suffix, ignored);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = directory() / "store.sqlite";
  const auto merged = directory() / "merged.sqlite";
  remove_store(file);
  remove_store(merged);
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  try {
    rkhs::ResultStore store(file);
    store.for_each([&](const rkhs::ResultStore::Entry& entry) {
      if (entry.check.sound() != entry.check.problem.empty()) std::abort();
      (void)store.lookup(entry.hash);
    });
    (void)store.size();
    // (A damaged file may count and list different rows without an error from SQLite: the
    // counts are not compared.)
    rkhs::ResultStore target(merged);
    (void)target.merge_from({file});
    (void)target.size();
  } catch (const std::runtime_error&) {
    // Not a store, or a damaged one: a correct refusal.
  } catch (const std::exception& e) {
    rkhs::fuzz::unexpected_exception(e);
  }
  remove_store(file);
  remove_store(merged);
  return 0;
}
