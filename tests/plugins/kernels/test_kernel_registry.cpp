// The built-in kernels are all registered (the static-library trap: a linker that drops a
// plugin's object file drops its registrar silently) and declare themselves completely.

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "rkhs/kernel/kernel.hpp"

TEST_CASE("the kernel registry holds exactly the built-in kernels", "[kernel][registry]") {
  const std::vector<std::string> expected{"bspline", "gaussian", "matern", "wendland"};
  CHECK(rkhs::kernel_registry().names() == expected);  // names() is sorted
  CHECK(rkhs::kernel_registry().errors().empty());
}

TEST_CASE("built-in kernels document themselves and their parameters", "[kernel][registry]") {
  for (const auto& name : rkhs::kernel_registry().names()) {
    INFO(name);
    const auto* entry = rkhs::kernel_registry().find(name);
    REQUIRE(entry != nullptr);
    CHECK(entry->info.name == name);
    CHECK_FALSE(entry->info.doc.empty());
    CHECK(entry->info.doc.find('\n') == std::string::npos);  // one line
    CHECK_FALSE(entry->info.parameters.empty());
    for (const auto& spec : entry->info.parameters) {
      INFO(spec.name);
      CHECK_FALSE(spec.doc.empty());
      CHECK(rkhs::validate_spec(spec).empty());
    }
    std::vector<std::string> traits;
    for (const auto& [key, value] : entry->info.traits) traits.push_back(key);
    // How the kernel is made periodic is documented; what properties() states is not repeated
    // as text (one source: `list` prints the properties).
    CHECK(std::find(traits.begin(), traits.end(), "periodic") != traits.end());
    for (const char* key : {"positive definite", "smoothness", "support"})
      CHECK(std::find(traits.begin(), traits.end(), key) == traits.end());
    const auto defaults = rkhs::ParameterSet::resolve(entry->info.parameters, {});
    const auto properties = rkhs::kernel_properties(name, defaults, rkhs::Domain{});
    const auto words = rkhs::describe_properties(properties);
    CHECK_THAT(words, Catch::Contains(fmt::format("d = {}", properties.dimension)));
    CHECK_THAT(words, Catch::Contains(properties.support_radius > 0 ? "support radius"
                                                                    : "global support"));
  }
}
