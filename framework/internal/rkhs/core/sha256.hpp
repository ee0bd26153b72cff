#pragma once
// SHA-256 (FIPS 180-4) of bytes and files: the provenance of external data (a road profile's
// file) recorded with every trial that reads it.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace rkhs {

/// Incremental SHA-256. `update` any number of times, then `hex_digest` once (the object is
/// then spent: further updates throw std::logic_error).
class Sha256 {
 public:
  Sha256() noexcept;
  void update(const void* data, std::size_t size);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
  /// The 32-byte digest as 64 lower-case hexadecimal digits.
  std::string hex_digest();

 private:
  void compress(const unsigned char* block) noexcept;
  std::array<std::uint32_t, 8> state_;
  std::array<unsigned char, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t total_bytes_ = 0;
  bool finished_ = false;
};

/// SHA-256 of `bytes` as 64 lower-case hexadecimal digits.
std::string sha256_hex(std::string_view bytes);

/// SHA-256 of the file's bytes as 64 lower-case hexadecimal digits. Throws std::runtime_error
/// naming the file when it cannot be read.
std::string sha256_file(const std::filesystem::path& file);

}  // namespace rkhs
