// Typed plugin parameters (rkhs/core/parameters.hpp): defaults (also "= another parameter"),
// types, ranges, choices, the canonical form, and the messages for each refusal.
#include <catch2/catch.hpp>

#include "rkhs/core/parameters.hpp"

using namespace rkhs;

TEST_CASE("parameters resolve with defaults, types and ranges", "[registry]") {
  const std::vector<ParameterSpec> specs{
      integer_parameter("degree", 1, "degree", 0, 3),
      [] {
        auto r = positive_parameter("r", 1.0, "smoothness");
        r.default_doc = "= degree";
        return r;
      }(),
      choice_parameter("convention", "a", "convention", {"a", "b"})};
  auto p = ParameterSet::resolve(specs, {{"degree", std::int64_t{2}}});
  CHECK(p.integer("degree") == 2);
  CHECK(p.real("r") == 2.0);  // "= degree"
  CHECK_FALSE(p.given("r"));
  CHECK(p.canonical() == "degree=2 r=2 convention=a");
  p = ParameterSet::resolve(specs, {{"r", 1.5}});
  CHECK(p.real("r") == 1.5);
  CHECK(p.given("r"));
  CHECK(ParameterSet::resolve(specs, {{"degree", 3.0}}).integer("degree") == 3);  // 3.0 is whole
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"degree", 2.5}}),
                    "parameter 'degree' must be an integer, found a number");
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"degree", std::int64_t{4}}}),
                    "parameter 'degree' must be in [0, 3], found 4");
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"convention", std::string("c")}}),
                    "parameter 'convention' must be one of \"a\", \"b\", found c");
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"degre", std::int64_t{1}}}),
                    "unknown parameter 'degre' (known: degree, r, convention)");
}
