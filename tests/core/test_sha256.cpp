// SHA-256 against the FIPS 180-4 / NIST test vectors.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "rkhs/core/sha256.hpp"

using namespace rkhs;

TEST_CASE("SHA-256 of the NIST test vectors", "[sha256]") {
  CHECK(sha256_hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(sha256_hex("abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnop"
                   "qklmnopqrlmnopqrsmnopqrstnopqrstu") ==
        "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
  Sha256 million;
  const std::string chunk(1000, 'a');
  for (int i = 0; i < 1000; ++i) million.update(chunk);
  CHECK(million.hex_digest() == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  CHECK_THROWS_AS(million.update("more"), std::logic_error);
}

TEST_CASE("SHA-256: incremental updates at every split and files agree", "[sha256]") {
  std::string text;
  for (int i = 0; i < 200; ++i) text += static_cast<char>(i * 7 + 3);  // crosses block boundaries
  const auto whole = sha256_hex(text);
  for (std::size_t split = 0; split <= text.size(); split += 13) {
    Sha256 hash;
    hash.update(std::string_view(text).substr(0, split));
    hash.update(std::string_view(text).substr(split));
    CHECK(hash.hex_digest() == whole);
  }
  const auto file = std::filesystem::temp_directory_path() / "rkhs_sha256_test.bin";
  std::ofstream(file, std::ios::binary) << text;
  CHECK(sha256_file(file) == whole);
  std::filesystem::remove(file);
  CHECK_THROWS_WITH(sha256_file("/nonexistent/file"), "cannot read '/nonexistent/file' to hash it");
}
