// Input files checked by type and size before they are read (rkhs/core/input_file.hpp).
#include "rkhs/core/input_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "rkhs/core/printable.hpp"

namespace rkhs {

namespace fs = std::filesystem;

namespace {

// "4 MiB", "256 MiB", or the bytes when not a whole number of MiB.
std::string limit_text(std::uintmax_t bytes) {
  constexpr std::uintmax_t mib = std::uintmax_t{1} << 20;
  return bytes % mib == 0 ? fmt::format("{} bytes ({} MiB)", bytes, bytes / mib)
                          : fmt::format("{} bytes", bytes);
}

[[noreturn]] void too_large(const fs::path& path, std::string_view what, std::uintmax_t size,
                            std::uintmax_t max_bytes, bool at_least) {
  throw InputFileError(fmt::format("{}: is {}{} bytes, more than the {} a {} may have",
                                   printable(path.string()), at_least ? "at least " : "", size,
                                   limit_text(max_bytes), what));
}

[[noreturn]] void not_regular(const fs::path& path, std::string_view what, std::string_view kind) {
  throw InputFileError(
      fmt::format("{}: is {}, not a {} (a regular file)", printable(path.string()), kind, what));
}

[[noreturn]] void cannot_read(const fs::path& path, std::string_view what, std::string_view why) {
  throw InputFileError(
      fmt::format("{}: cannot read the {}: {}", printable(path.string()), what, why));
}

}  // namespace

std::string_view file_kind(fs::file_type type) noexcept {
  switch (type) {
    case fs::file_type::directory:
      return "a directory";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::socket:
      return "a socket";
    case fs::file_type::character:
      return "a character device";
    case fs::file_type::block:
      return "a block device";
    default:
      return "a special file";
  }
}

std::string not_regular_file_kind(const fs::path& path) {
  std::error_code error;
  const auto type = fs::status(path, error).type();
  if (type == fs::file_type::regular || type == fs::file_type::not_found ||
      type == fs::file_type::none || type == fs::file_type::unknown)
    return {};
  return std::string(file_kind(type));
}

std::uintmax_t check_input_file(const fs::path& path, std::string_view what,
                                std::uintmax_t max_bytes) {
  std::error_code error;
  const auto status = fs::status(path, error);
  if (error) cannot_read(path, what, error.message());
  if (status.type() != fs::file_type::regular) not_regular(path, what, file_kind(status.type()));
  const auto size = fs::file_size(path, error);
  if (error) cannot_read(path, what, error.message());
  if (size > max_bytes) too_large(path, what, size, max_bytes, false);
  return size;
}

std::string read_input_file(const fs::path& path, std::string_view what, std::uintmax_t max_bytes) {
  check_input_file(path, what, max_bytes);
  // O_NONBLOCK: should the path have become a FIFO since the check, open returns at once.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) cannot_read(path, what, std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0) cannot_read(path, what, std::strerror(errno));
  if (!S_ISREG(info.st_mode))
    not_regular(path, what,
                S_ISDIR(info.st_mode)    ? "a directory"
                : S_ISFIFO(info.st_mode) ? "a FIFO"
                : S_ISCHR(info.st_mode)  ? "a character device"
                : S_ISBLK(info.st_mode)  ? "a block device"
                : S_ISSOCK(info.st_mode) ? "a socket"
                                         : "a special file");
  const auto size = static_cast<std::uintmax_t>(info.st_size);
  if (size > max_bytes) too_large(path, what, size, max_bytes, false);
  // A regular file's reads never block; O_NONBLOCK is harmless for the rest.
  std::string text;
  text.reserve(static_cast<std::size_t>(size));
  char block[1 << 16];
  while (true) {
    const ssize_t got = ::read(fd, block, sizeof block);
    if (got < 0) {
      if (errno == EINTR) continue;
      cannot_read(path, what, std::strerror(errno));
    }
    if (got == 0) break;
    if (text.size() + static_cast<std::size_t>(got) > max_bytes)
      too_large(path, what, text.size() + static_cast<std::size_t>(got), max_bytes, true);
    text.append(block, static_cast<std::size_t>(got));
  }
  return text;
}

}  // namespace rkhs
