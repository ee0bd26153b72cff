// Text from users as messages show it: control bytes and bytes that are not UTF-8 as escapes.
#include <catch2/catch.hpp>
#include <string>

#include "rkhs/core/printable.hpp"

using rkhs::printable;
using rkhs::utf8_sequence_length;

TEST_CASE("printable shows control bytes and invalid UTF-8 as hexadecimal escapes", "[core][messages]") {
  CHECK(printable("plain text, 'quoted' and \"double\"") == "plain text, 'quoted' and \"double\"");
  CHECK(printable("\x1b[31mred\x1b[0m") == "\\x1b[31mred\\x1b[0m");
  CHECK(printable("a\nb\tc\rd\x7f") == "a\\x0ab\\x09c\\x0dd\\x7f");
  CHECK(printable("a\nb\tc", true) == "a\nb\tc");
  CHECK(printable("a\x1b"
                  "b\n",
                  true) == "a\\x1bb\n");
  CHECK(printable(std::string("nul\0byte", 8)) == "nul\\x00byte");
  // UTF-8 stays; what is not UTF-8 is escaped byte by byte.
  CHECK(printable("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80") ==
        "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80");
  CHECK(printable("caf\xe9") == "caf\\xe9");
  CHECK(printable("\xc0\xaf") == "\\xc0\\xaf");                    // overlong '/'
  CHECK(printable("\xed\xa0\x80") == "\\xed\\xa0\\x80");           // a surrogate
  CHECK(printable("\xf4\x90\x80\x80") == "\\xf4\\x90\\x80\\x80");  // beyond U+10FFFF
  CHECK(printable("\xe2\x82") == "\\xe2\\x82");                    // cut short
  CHECK(printable("\xc2\x9b[2J") == "\\xc2\\x9b[2J");              // U+009B, a C1 control (CSI)
}

TEST_CASE("utf8_sequence_length", "[core][messages]") {
  CHECK(utf8_sequence_length("") == 0);
  CHECK(utf8_sequence_length("a") == 1);
  CHECK(utf8_sequence_length("\xc3\xa9x") == 2);
  CHECK(utf8_sequence_length("\xe2\x82\xac") == 3);
  CHECK(utf8_sequence_length("\xf0\x9f\x98\x80") == 4);
  CHECK(utf8_sequence_length("\x80") == 0);
  CHECK(utf8_sequence_length("\xff") == 0);
}
