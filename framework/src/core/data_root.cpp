#include "rkhs/core/data_root.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <mutex>
#include <stdexcept>

#include "rkhs/core/input_file.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs {
namespace {

struct Setting {
  std::mutex mutex;
  std::optional<std::filesystem::path> directory;
};

Setting& setting() {
  static Setting instance;
  return instance;
}

}  // namespace

void set_data_root(const std::filesystem::path& directory) {
  auto& s = setting();
  std::lock_guard lock(s.mutex);
  if (directory.empty())
    s.directory.reset();
  else
    s.directory = std::filesystem::absolute(directory).lexically_normal();
}

DataRoot data_root() {
  {
    auto& s = setting();
    std::lock_guard lock(s.mutex);
    if (s.directory) return {*s.directory, "--data-dir"};
  }
  if (const char* environment = std::getenv("RKHS_STUDY_DATA"); environment && *environment)
    return {std::filesystem::absolute(environment).lexically_normal(), "RKHS_STUDY_DATA"};
  return {std::filesystem::absolute("studies/data").lexically_normal(), "default"};
}

bool leaves_data_root(std::string_view name) {
  const std::filesystem::path given{std::string(name)};
  if (given.is_absolute()) return false;
  const auto normal = given.lexically_normal();
  return !normal.empty() && *normal.begin() == "..";
}

std::string data_root_escape_message(std::string_view name) {
  return fmt::format(
      "data file '{}' leaves the data root through '..': a relative data path names a file "
      "below the data root (--data-dir DIR, RKHS_STUDY_DATA or studies/data/); give a file "
      "outside it by its absolute path",
      printable(name));
}

std::filesystem::path resolve_data_file(const std::string& name) {
  if (name.empty()) throw std::invalid_argument("no data file given (file = \"...\")");
  if (leaves_data_root(name)) throw std::invalid_argument(data_root_escape_message(name));
  const std::filesystem::path given(name);
  std::error_code error;
  // By type first: a FIFO, a device or a directory is named as what it is, not "not found".
  const auto not_regular = [&](const std::filesystem::path& path) {
    if (const auto kind = not_regular_file_kind(path); !kind.empty())
      throw std::invalid_argument(
          fmt::format("data file '{}' is {}, not a data file (a regular file; looked at {})",
                      printable(name), kind, printable(path.string())));
  };
  if (given.is_absolute()) {
    not_regular(given);
    if (std::filesystem::is_regular_file(given, error)) return given;
    throw std::invalid_argument(fmt::format("data file '{}' not found (looked at {})",
                                            printable(name), printable(given.string())));
  }
  const auto root = data_root();
  const auto path = (root.directory / given).lexically_normal();
  not_regular(path);
  if (std::filesystem::is_regular_file(path, error)) return path;
  const std::string origin = root.origin == "default"
                                 ? "the default data root studies/data/ below the current directory"
                                 : fmt::format("the data root from {}", root.origin);
  throw std::invalid_argument(fmt::format(
      "data file '{}' not found (looked at {}, in {}{}; set the data root with --data-dir DIR or "
      "RKHS_STUDY_DATA)",
      printable(name), printable(path.string()), origin,
      std::filesystem::is_directory(root.directory, error) ? "" : ", which does not exist"));
}

}  // namespace rkhs
