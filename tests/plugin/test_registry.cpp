// Registries: every built-in is registered (the static-library trap), registration errors are
// recorded instead of thrown, and names are suggested for misspellings.
#include <catch2/catch.hpp>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/approx/target.hpp"

using namespace rkhs;

TEST_CASE("every built-in plugin is registered and no registration failed", "[registry]") {
  CHECK(missing_builtin_plugins().empty());
  CHECK(registration_errors().empty());
  CHECK(centre_registry().names() == builtin_plugin_names().centres);
  CHECK(target_registry().names() == builtin_plugin_names().targets);
  for (const auto& name : builtin_plugin_names().kernels) CHECK(kernel_registry().find(name));
  CHECK(plant_registry().names() == builtin_plugin_names().plants);
  CHECK(law_registry().names() == builtin_plugin_names().laws);
  CHECK(integrator_registry().names() == builtin_plugin_names().integrators);
}

TEST_CASE("a bad registration is recorded, not thrown", "[registry]") {
  Registry<CentrePlacement> registry("centres");
  auto factory = [](const ParameterSet&) -> std::unique_ptr<CentrePlacement> { return nullptr; };
  CHECK(registry.add({"a", "doc", {}, {}}, factory));
  CHECK_FALSE(registry.add({"a", "again", {}, {}}, factory));
  CHECK_FALSE(registry.add({"", "no name", {}, {}}, factory));
  auto bad = real_parameter("x", -1.0, "must be positive", 0.0);
  CHECK_FALSE(registry.add({"b", "bad default", {bad}, {}}, factory));
  registry.freeze();
  CHECK_FALSE(registry.add({"c", "late", {}, {}}, factory));
  const auto errors = registry.errors();
  REQUIRE(errors.size() == 4);
  CHECK(errors[0] == "centres plugin 'a': duplicate name");
  CHECK(errors[1] == "centres plugin '': empty plugin name");
  CHECK(errors[2] == "centres plugin 'b': parameter 'x': default must be >= 0");
  CHECK(errors[3] == "centres plugin 'c': registered after the registry was frozen");
  CHECK(registry.names() == std::vector<std::string>{"a"});
}

TEST_CASE("misspelt names get a suggestion, unrelated ones do not", "[registry]") {
  const std::vector<std::string> names{"bspline", "gaussian", "matern", "wendland"};
  CHECK(closest_name("gausian", names) == "gaussian");
  CHECK(closest_name("bsplines", names) == "bspline");
  CHECK(closest_name("Matern", names) == "matern");
  CHECK(closest_name("polyharmonic", names).empty());
  CHECK(edit_distance("kitten", "sitting") == 3);
}

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
