// The CSV targets' line reader: a file read a block at a time gives the lines a text gives, and
// a line longer than the limit fails once the limit is read, however long the file.
#include <catch2/catch.hpp>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "rkhs/core/csv_text.hpp"
#include "rkhs/core/sha256.hpp"

using rkhs::csv_text::Lines;

namespace {

std::vector<std::string> all_lines(Lines& lines) {
  std::vector<std::string> out;
  while (const auto line = lines.next()) out.emplace_back(*line);
  return out;
}

// An endless stream of one byte, counting what it hands out.
class Endless final : public std::streambuf {
 public:
  explicit Endless(char byte) { block_.assign(4096, byte); }
  std::uint64_t handed_out = 0;

 protected:
  int_type underflow() override {
    setg(block_.data(), block_.data(), block_.data() + block_.size());
    handed_out += block_.size();
    return traits_type::to_int_type(block_.front());
  }

 private:
  std::string block_;
};

}  // namespace

TEST_CASE("CSV lines read from a stream in blocks equal the lines of the whole text",
          "[csv_road][csv_text]") {
  // A byte-order mark, CRLF, a NUL inside a line, blank lines, lines across block boundaries
  // (longer than a block, too), and no line break at the end.
  std::string text("\xEF\xBB\xBFu,z\r\n0,1\n\n1,2\0junk\n", 22);
  text.append(Lines::block_size - 3, '7');
  text += ",3\n" + std::string(3 * Lines::block_size + 11, '8') + ",4\r\n5,6";
  const std::string file = "t.csv";
  Lines from_text(text, file);
  const auto expected = all_lines(from_text);
  REQUIRE(expected.size() == 7);
  CHECK(expected[0] == "u,z");
  CHECK(expected[3] == "1,2");
  std::istringstream in(text);
  rkhs::Sha256 digest;
  Lines from_stream(in, file, &digest);
  CHECK(all_lines(from_stream) == expected);
  CHECK(from_stream.number() == 7);
  CHECK(from_stream.bytes_read() == text.size());
  CHECK(digest.hex_digest() == rkhs::sha256_hex(text));
  // Only a byte-order mark, or nothing: no line.
  for (const std::string& empty : {std::string(), std::string("\xEF\xBB\xBF")}) {
    std::istringstream none(empty);
    Lines lines(none, file);
    CHECK_FALSE(lines.next());
  }
  // A text that ends with a line break has no empty line after it.
  std::istringstream ended("a\nb\n");
  Lines two(ended, file);
  CHECK(all_lines(two) == std::vector<std::string>{"a", "b"});
}

TEST_CASE("a CSV line longer than the limit fails after reading the limit and one block",
          "[csv_road][csv_text][limits]") {
  Endless source('x');
  std::istream in(&source);
  const std::string file = "endless.csv";
  Lines lines(in, file);
  CHECK_THROWS_WITH(lines.next(), "endless.csv:1:1: the line is longer than 16777215 bytes");
  CHECK(lines.bytes_read() <= Lines::max_length + Lines::block_size);
  CHECK(source.handed_out <= Lines::max_length + 2 * Lines::block_size);
  // The same limit on a text, and on the line after a short one.
  const std::string text = "u,z\n" + std::string(Lines::max_length, '1');
  Lines from_text(text, file);
  CHECK(from_text.next() == std::optional<std::string_view>("u,z"));
  CHECK_THROWS_WITH(from_text.next(), "endless.csv:2:1: the line is longer than 16777215 bytes");
  // One byte under the limit is a line.
  std::istringstream longest(std::string(Lines::max_length - 1, '2') + "\n3");
  Lines fits(longest, file);
  CHECK(fits.next()->size() == Lines::max_length - 1);
  CHECK(fits.next() == std::optional<std::string_view>("3"));
}
