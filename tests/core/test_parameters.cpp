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

TEST_CASE("a plugin that takes parameters the user names resolves them after its own",
          "[registry]") {
  const std::vector<ParameterSpec> specs{text_parameter("f", "", "the expression")};
  const auto user = real_parameter("<name>", 0.0, "a constant", 0.0);
  const auto p = ParameterSet::resolve(
      specs, {{"f", std::string("a * s")}, {"k", std::int64_t{3}}, {"a", 0.5}}, &user);
  // Declared first, then the user's in the order of their names; integers become reals.
  REQUIRE(p.values().size() == 3);
  CHECK(p.canonical() == "f=a * s a=0.5 k=3");
  CHECK(p.real("k") == 3.0);
  CHECK(p.given("a"));
  // Checked against the user parameters' spec: type, range, and a name for columns.
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"a", std::string("x")}}, &user),
                    "parameter 'a' must be a number, found a string");
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"a", -1.0}}, &user),
                    "parameter 'a' must be >= 0, found -1");
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"a b", 1.0}}, &user),
                    "parameter name 'a b' is not a name: a letter or _ followed by letters, "
                    "digits and _");
  // Without them an undeclared name is unknown, as before.
  CHECK_THROWS_WITH(ParameterSet::resolve(specs, {{"a", 1.0}}), "unknown parameter 'a' (known: f)");
  CHECK(check_user_parameter_name("_k2") == "");
  CHECK(check_user_parameter_name("2k") != "");
  CHECK(check_user_parameter_name("") != "");
}
