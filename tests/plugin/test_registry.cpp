// Registries: every built-in is registered (the static-library trap), registration errors are
// recorded instead of thrown (with the reason when a plugin's info() throws), names are suggested
// for misspellings, and the table of plugin kinds agrees with the registries.
#include <algorithm>
#include <catch2/catch.hpp>
#include <stdexcept>

#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"

using namespace rkhs;

TEST_CASE("every built-in plugin is registered and no registration failed", "[registry]") {
  CHECK(missing_builtin_plugins().empty());
  CHECK(registration_errors().empty());
  for_each_plugin_kind([](auto kind) {
    using Kind = decltype(kind);
    INFO(Kind::singular);
    const std::vector<std::string> builtins(std::begin(Kind::builtins), std::end(Kind::builtins));
    if constexpr (std::is_same_v<Kind, KernelKind>) {
      // Kernel tests may register temporary kernels; the built-ins must be there.
      for (const auto& name : builtins) CHECK(Kind::registry().find(name));
    } else {
      CHECK(Kind::registry().names() == builtins);
    }
  });
}

TEST_CASE("the table of plugin kinds names every registry", "[registry]") {
  std::vector<std::string> singular;
  for_each_plugin_kind([&](auto kind) {
    using Kind = decltype(kind);
    CHECK(Kind::registry().kind() == Kind::singular);
    CHECK(std::is_sorted(std::begin(Kind::builtins), std::end(Kind::builtins)));
    singular.emplace_back(Kind::singular);
  });
  CHECK(singular ==
        std::vector<std::string>{"kernel", "centres", "target", "projection", "plant", "law",
                                 "integrator"});
  const auto names = plugin_kind_names();
  REQUIRE(names.size() == plugin_kind_count);
  CHECK(names[0].plural == "kernels");
  CHECK(names[1].plural == "centres");
  CHECK(names[3].plural == "projections");
  CHECK(names[6].plural == "integrators");
}

TEST_CASE("a bad registration is recorded, not thrown", "[registry]") {
  Registry<CentrePlacement> registry("centres");
  auto factory = [](const ParameterSet&) -> std::unique_ptr<CentrePlacement> { return nullptr; };
  CHECK(registry.add({"a", "doc", {}, {}}, factory));
  CHECK_FALSE(registry.add({"a", "again", {}, {}}, factory));
  CHECK_FALSE(registry.add({"", "no name", {}, {}}, factory));
  auto bad = real_parameter("x", -1.0, "must be positive", 0.0);
  CHECK_FALSE(registry.add({"b", "bad default", {bad}, {}}, factory));
  CHECK_FALSE(registry.add({"d", "bad user parameters", {}, {}, bad}, factory));
  registry.freeze();
  CHECK_FALSE(registry.add({"c", "late", {}, {}}, factory));
  const auto errors = registry.errors();
  REQUIRE(errors.size() == 5);
  CHECK(errors[0] == "centres plugin 'a': duplicate name");
  CHECK(errors[1] == "centres plugin '': empty plugin name");
  CHECK(errors[2] == "centres plugin 'b': parameter 'x': default must be >= 0");
  CHECK(errors[3] == "centres plugin 'd': user parameters: default must be >= 0");
  CHECK(errors[4] == "centres plugin 'c': registered after the registry was frozen");
  CHECK(registry.names() == std::vector<std::string>{"a"});
}

namespace registry_test {

struct Fine : CentrePlacement {
  explicit Fine(const ParameterSet&) {}
  static PluginInfo info() { return {"fine", "places nothing", {}, {}}; }
  void place_into(const Domain&, std::uint64_t, std::span<double>) const override {}
};
struct ThrowingInfo : Fine {
  using Fine::Fine;
  static PluginInfo info() { throw std::runtime_error("the declaration cannot be built"); }
};
struct ThrowingSomethingElse : Fine {
  using Fine::Fine;
  static PluginInfo info() { throw 42; }
};
struct ThrowingKernel {
  static PluginInfo info() { throw std::invalid_argument("bad kernel metadata"); }
  ThrowingKernel(const ParameterSet&, const Domain&) {}
  double operator()(double, double) const noexcept { return 1; }
  KernelProperties properties() const noexcept { return {}; }
};

}  // namespace registry_test

TEST_CASE("a plugin whose info() throws is recorded with the exception's message", "[registry]") {
  Registry<CentrePlacement> registry("centres");
  CHECK(register_plugin<registry_test::Fine>(registry));
  CHECK_FALSE(register_plugin<registry_test::ThrowingInfo>(registry));
  CHECK_FALSE(register_plugin<registry_test::ThrowingSomethingElse>(registry));
  CHECK(registry.names() == std::vector<std::string>{"fine"});
  const auto errors = registry.errors();
  REQUIRE(errors.size() == 2);
  CHECK(errors[0] ==
        "centres registration failed: registry_test::ThrowingInfo: the declaration cannot be "
        "built");
  CHECK(errors[1] ==
        "centres registration failed: registry_test::ThrowingSomethingElse: unknown exception");
  const auto made = registry.find("fine")->factory({});
  CHECK(made != nullptr);

  // Through the kernel registrar, as RKHS_REGISTER_KERNEL does: start-up reports it.
  const auto kept = kernel_registry().error_count();
  CHECK_FALSE(register_kernel<registry_test::ThrowingKernel>());
  const auto reported = registration_errors();
  const auto taken = kernel_registry().take_errors_after(kept);
  REQUIRE(taken.size() == 1);
  CHECK(taken[0] ==
        "kernel registration failed: registry_test::ThrowingKernel: bad kernel metadata");
  CHECK(std::find(reported.begin(), reported.end(), taken[0]) != reported.end());
  CHECK(registration_errors().empty());
}

TEST_CASE("misspelt names get a suggestion, unrelated ones do not", "[registry]") {
  const std::vector<std::string> names{"bspline", "gaussian", "matern", "wendland"};
  CHECK(closest_name("gausian", names) == "gaussian");
  CHECK(closest_name("bsplines", names) == "bspline");
  CHECK(closest_name("Matern", names) == "matern");
  CHECK(closest_name("polyharmonic", names).empty());
  CHECK(edit_distance("kitten", "sitting") == 3);
}

