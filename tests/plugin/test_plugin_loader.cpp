// Loading plugin modules at run time: the example plugin loads and registers its kernel, loading is
// idempotent, and each way a module can be wrong is refused with its own message, leaving the
// registries as they were.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "plugin_test_support.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/plugin/build_configuration.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/module.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/run/trial_identity.hpp"
#include "rkhs/study/study.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;
using namespace rkhs;

namespace {

fs::path module(const std::string& name) {
  return test::test_plugin(name);
}

fs::path scratch(const std::string& name) {
  auto dir = fs::temp_directory_path() / ("rkhs_plugin_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The message of the PluginError that loading `file` throws, and that the registries are unchanged.
std::string refusal(const fs::path& file) {
  const auto kernels = kernel_registry().names();
  const std::string gaussian_doc = kernel_registry().find("gaussian")->info.doc;
  std::string message = "(loaded without error)";
  try {
    load_plugin(file);
  } catch (const PluginError& e) {
    message = e.what();
  }
  CHECK(kernel_registry().names() == kernels);
  CHECK(kernel_registry().find("gaussian")->info.doc == gaussian_doc);
  CHECK(registration_errors().empty());
  return message;
}

}  // namespace

TEST_CASE("the example plugin loads, registers its kernel once and says what it is", "[plugin]") {
  const test::ScopedPlugin scoped(module("inverse_multiquadric"));
  const auto& plugin = scoped.plugin();
  CHECK(plugin.name == "inverse_multiquadric");
  CHECK(plugin.abi_version == RKHS_PLUGIN_ABI_VERSION);
  CHECK(plugin.rkhs_study_version == build_info().version);
  CHECK(plugin.file == fs::canonical(module("inverse_multiquadric")));
  CHECK(plugin.registered.at("kernel") == std::vector<std::string>{"inverse_multiquadric"});
  CHECK(plugin.registered.at("centres").empty());
  CHECK(plugin.registered.at("target").empty());
  REQUIRE(kernel_registry().find("inverse_multiquadric"));
  CHECK(registration_errors().empty());

  // Again, through another spelling of the same file: the first load.
  const auto again = load_plugin(fs::path(RKHS_TEST_PLUGIN_DIR) / "." / "inverse_multiquadric.so");
  CHECK(again.file == plugin.file);
  const auto loaded = loaded_plugins();
  CHECK(std::count_if(loaded.begin(), loaded.end(),
                      [](const auto& p) { return p.name == "inverse_multiquadric"; }) == 1);

  // Its kernel is used like a built-in.
  const Domain interval{10.0, false};
  auto kernel = make_kernel(
      "inverse_multiquadric",
      ParameterSet::resolve(kernel_registry().find("inverse_multiquadric")->info.parameters,
                            {{"beta", 0.5}, {"c", 2.0}}),
      interval);
  CHECK(kernel->evaluate(1.0, 4.0) == Approx(1.0 / std::sqrt(1.0 + 2.25)).epsilon(1e-15));
  CHECK(kernel->properties().analytic);
  CHECK_FALSE(kernel->properties().sobolev_order);
}

TEST_CASE("plugin error: file not found", "[plugin]") {
  const auto file = module("no_such_plugin");
  CHECK(refusal(file) == file.string() + ": plugin file not found");
}

TEST_CASE("plugin error: not a plugin (no ABI entry point, or not a shared library)", "[plugin]") {
  const auto file = module("no_abi_symbol");
  CHECK(refusal(file) ==
        file.string() +
            ": not an rkhs-study plugin (it exports no rkhs_plugin_abi_version; declare the module "
            "with RKHS_PLUGIN_MODULE(name) from rkhs/plugin/module.hpp)");

  const auto text = scratch("text") / "notes.so";
  std::ofstream(text) << std::string(200, '#') << "\nnot an ELF file, longer than an ELF header\n";
  CHECK_THAT(refusal(text),
             Catch::StartsWith(text.string() + ": not an rkhs-study plugin (cannot be loaded as a "
                                               "shared library: ") &&
                 Catch::Contains("invalid ELF header"));
}

TEST_CASE("plugin error: built against another plugin ABI, refused before it registers",
          "[plugin]") {
  // wrong_abi.so aborts if its rkhs_plugin_register is ever called.
  const auto file = module("wrong_abi");
  CHECK(refusal(file) ==
        file.string() + ": built against plugin ABI 999 (rkhs-study 9.9.9), this rkhs-study " +
            build_info().version + " has plugin ABI " + std::to_string(RKHS_PLUGIN_ABI_VERSION) +
            "; rebuild the plugin against this rkhs-study");
}

TEST_CASE(
    "plugin error: built with other flags than rkhs-study, refused naming both "
    "configurations",
    "[plugin]") {
  const BuildConfiguration framework = framework_build_configuration();
  CHECK(framework == RKHS_BUILD_CONFIGURATION);  // the tests are built like the framework
  CHECK_FALSE(describe(framework).empty());
#if defined(RKHS_TEST_AVX_PLUGIN)
  // inverse_multiquadric_avx.so: the example plugin compiled with -mavx. Its static
  // initialisers may use AVX, so it is opened only on a processor that has it.
  if (framework.vectorisation != static_cast<int>(VectorisationClass::sse2) ||
      !__builtin_cpu_supports("avx")) {
    WARN("not checked: this build is not for generic x86-64, or the processor has no AVX");
    return;
  }
  const auto file = module("inverse_multiquadric_avx");
  const auto message = refusal(file);
  BuildConfiguration avx = framework;
  avx.vectorisation = static_cast<int>(VectorisationClass::avx);
  avx.max_align_bytes = 32;
  CHECK_THAT(message,
             Catch::StartsWith(file.string() + ": built for " + describe(avx) +
                               ", this rkhs-study is built for " + describe(framework) + " ("));
  CHECK_THAT(message, Catch::Contains("vectorisation AVX against SSE2"));
  CHECK_THAT(message, Catch::Contains("Eigen alignment 32 bytes against 16 bytes"));
#endif
}

TEST_CASE("plugin error: duplicate names (a kernel, a module)", "[plugin]") {
  const auto file = module("duplicate_kernel_name");
  CHECK(refusal(file) == file.string() + ": kernel plugin 'gaussian': duplicate name");

  // A copy of a loaded module under another path: same module name.
  const test::ScopedPlugin scoped(module("inverse_multiquadric"));
  const auto& original = scoped.plugin();
  const auto copy = scratch("copy") / "imq_copy.so";
  fs::copy_file(module("inverse_multiquadric"), copy);
  CHECK(refusal(copy) == copy.string() +
                             ": duplicate plugin name 'inverse_multiquadric' (already "
                             "loaded from " +
                             original.file.string() + ")");
}

TEST_CASE("plugin error: invalid metadata, and the module's valid kernels are rolled back",
          "[plugin]") {
  const auto file = module("invalid_metadata");
  CHECK(refusal(file) ==
        file.string() +
            ": kernel plugin 'invalid_metadata_kernel': parameter 'width': default must be > 0");
  CHECK_FALSE(kernel_registry().find("valid_before_invalid"));
  CHECK_FALSE(kernel_registry().find("invalid_metadata_kernel"));
}

TEST_CASE("plugin error: a plugin whose info() throws is refused with the exception's message",
          "[plugin]") {
  const auto file = module("info_throws");
  const auto message = refusal(file);
  using Catch::Matchers::EndsWith;
  using Catch::Matchers::StartsWith;
  CHECK_THAT(message, StartsWith(file.string() + ": kernel registration failed: "));
  CHECK_THAT(message, Catch::Matchers::Contains("TinyKernel<"));
  CHECK_THAT(message, EndsWith("Throws>: cannot read the declaration"));
  CHECK_FALSE(kernel_registry().find("valid_before_throwing"));
}

TEST_CASE("plugin error: a module that registers nothing, or registers inside dlopen", "[plugin]") {
  const auto nothing = module("registers_nothing");
  CHECK(refusal(nothing) ==
        nothing.string() +
            ": registered nothing (use RKHS_REGISTER_KERNEL(Type), or _CENTRES, _TARGET, "
            "_PROJECTION, _PLANT, _LAW, _INTEGRATOR, in the module's sources)");
  const auto early = module("registers_early");
  CHECK(refusal(early) ==
        early.string() +
            ": registered plugins while being loaded, before its ABI could be checked: compile "
            "every source of the module with RKHS_BUILDING_PLUGIN defined (rkhs_study_add_plugin() "
            "and rkhs_study::plugin do)");
  CHECK_FALSE(kernel_registry().find("registers_early_kernel"));
}

TEST_CASE("RKHS_STUDY_PLUGIN_PATH: files and directories, separated by colons", "[plugin]") {
  const auto dir = scratch("path");
  fs::create_directories(dir / "b");
  for (const char* name : {"b/z.so", "b/a.so", "b/readme.txt", "single.so"})
    std::ofstream(dir / name) << "x";
  const auto files =
      plugin_path_files((dir / "b").string() + "::" + (dir / "single.so").string() + ":");
  CHECK(files == std::vector<fs::path>{dir / "b" / "a.so", dir / "b" / "z.so", dir / "single.so"});
  CHECK(plugin_path_files("").empty());
  CHECK_THROWS_WITH(plugin_path_files((dir / "missing").string()),
                    (dir / "missing").string() + ": no such plugin file or directory");

  ::setenv("RKHS_STUDY_PLUGIN_PATH", (dir / "missing").string().c_str(), 1);
  CHECK_THROWS_WITH(load_plugins_from_environment(),
                    "RKHS_STUDY_PLUGIN_PATH: " + (dir / "missing").string() +
                        ": no such plugin file or directory");
  ::setenv("RKHS_STUDY_PLUGIN_PATH", module("inverse_multiquadric").string().c_str(), 1);
  load_plugins_from_environment();
  CHECK(kernel_registry().find("inverse_multiquadric"));
  ::unsetenv("RKHS_STUDY_PLUGIN_PATH");
  CHECK(unload_plugin(module("inverse_multiquadric")));
}

TEST_CASE("a plugin unloaded by a test leaves the registries as they were and loads again",
          "[plugin]") {
  const auto kernels = kernel_registry().names();
  for (int round = 0; round < 2; ++round) {
    const auto plugin = load_plugin(module("inverse_multiquadric"));
    CHECK(plugin.registered.at("kernel") == std::vector<std::string>{"inverse_multiquadric"});
    CHECK(kernel_registry().find("inverse_multiquadric"));
    CHECK(unload_plugin(module("inverse_multiquadric")));
    CHECK(kernel_registry().names() == kernels);
    CHECK(loaded_plugins().empty());
  }
  CHECK_FALSE(unload_plugin(module("inverse_multiquadric")));
}

TEST_CASE("a module may register plants and learning laws: a study runs with them", "[plugin]") {
  const auto plants = plant_registry().names();
  const auto laws = law_registry().names();
  const auto plugin = load_plugin(module("adaptive_parts"));
  CHECK(plugin.registered.at("plant") == std::vector<std::string>{"test_mass_spring"});
  CHECK(plugin.registered.at("law") == std::vector<std::string>{"test_scaled_gradient"});
  CHECK(plugin.registered.at("kernel").empty());
  CHECK(plugin.registered.at("integrator").empty());
  // The plugin's plant and law are the built-in linear plant and gradient law with the same A,
  // B and Gamma: the trials must agree bit for bit.
  const std::string common = R"(
[study]
name = "plugin_parts"
kind = "adaptive"
evaluation_points = 128
[domain]
radius = 1.0
[grid]
n = [6, 10]
[[kernel]]
name = "gaussian"
sigma = 0.5
[adaptive]
speed = 1.0
laps = 1
samples_per_lap = 8
)";
  const auto with_plugin = test::run_study_text(common + R"(
[[plant]]
name = "test_mass_spring"
k = 4.0
c = 2.0
[[law]]
name = "test_scaled_gradient"
gamma = 0.5
scale = 0.25
)");
  const auto built_in = test::run_study_text(common + R"(
[[plant]]
name = "linear"
A = "0 1; -4 -2"
B = "0; 1"
[[law]]
name = "gradient"
gamma = 0.125
)");
  REQUIRE(with_plugin.results.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& a = with_plugin.results[i].metrics;
    const auto& b = built_in.results[i].metrics;
    REQUIRE(a.size() == b.size());
    for (std::size_t m = 0; m < a.size(); ++m) {
      INFO(with_plugin.study.all_metrics()[m]);
      if (std::isnan(a[m]))
        CHECK(std::isnan(b[m]));
      else
        CHECK(a[m] == b[m]);
    }
  }
  CHECK(unload_plugin(module("adaptive_parts")));
  CHECK(plant_registry().names() == plants);
  CHECK(law_registry().names() == laws);
}

TEST_CASE("a plugin module's projection runs in a study like the built-in one", "[plugin]") {
  const auto projections = projection_registry().names();
  const auto plugin = load_plugin(module("projection_part"));
  CHECK(plugin.registered.at("projection") ==
        std::vector<std::string>{"test_plain_interpolation"});
  CHECK(plugin.registered.at("kernel").empty());
  const std::string common = R"(
[study]
name = "plugin_projection"
evaluation_points = 512
[domain]
radius = 1.0
[grid]
n = [6, 12, 24]
[[kernel]]
name = "wendland"
)";
  const auto with_plugin =
      test::run_study_text(common + "[[projection]]\nname = \"test_plain_interpolation\"\n");
  const auto built_in = test::run_study_text(common + "[[projection]]\nname = \"interpolation\"\n");
  REQUIRE(with_plugin.results.size() == 3);
  // The generic measurement (G = G_B, P_n from the basis' Gram matrix, errors of W f(S)) and the
  // interpolation path (Cholesky solves) compute the same numbers in other orders.
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& a = with_plugin.results[i].metrics;
    const auto& b = built_in.results[i].metrics;
    REQUIRE(a.size() == b.size());
    for (const auto* metric : {"fill_distance", "gram_condition_number", "power_function_sup",
                               "l2_error", "sup_error", "interpolant_native_norm",
                               "projection_norm_H_to_C", "projection_operator_norm"}) {
      const auto m = with_plugin.study.metric_index(metric);
      INFO(metric << " n = " << with_plugin.trials[i].n);
      CHECK(a[m] == Approx(b[m]).epsilon(1e-8));
    }
  }
  CHECK(unload_plugin(module("projection_part")));
  CHECK(projection_registry().names() == projections);
}

TEST_CASE("a trial's identity holds the content hash of the module its plugin comes from",
          "[plugin][store]") {
  const std::string text = R"(
[study]
name = "module_identity"
metrics = ["power_function_sup"]
[domain]
radius = 4
[grid]
n = [8, 16]
[[kernel]]
name = "scaled_gaussian"
[[kernel]]
name = "gaussian"
)";
  std::vector<std::string> first, second;
  StudyDefinition study;
  {
    test::ScopedPlugin plugin(module("scaled_kernel_1"));
    CHECK(plugin.plugin().sha256 == sha256_file(module("scaled_kernel_1")));
    study = parse_study(text, "module_identity.toml");
    first = trial_hashes(study, study.trials());
    CHECK(first == trial_hashes(study, study.trials()));  // deterministic
  }
  {
    // The same kernel, module and trial keys from another build of the module.
    test::ScopedPlugin plugin(module("scaled_kernel_2"));
    second = trial_hashes(study, study.trials());
  }
  const auto trials = study.trials();
  REQUIRE(trials.size() == 4);
  for (std::size_t i = 0; i < trials.size(); ++i) {
    INFO(trials[i].key);
    // The plugin's trials change identity with its module; the built-in Gaussian's do not.
    if (trials[i].kernel.name == "scaled_gaussian")
      CHECK(first[i] != second[i]);
    else
      CHECK(first[i] == second[i]);
  }
  // A built-in trial's identity is the same with no module loaded at all.
  const auto unloaded = trial_hashes(study, trials);
  for (std::size_t i = 0; i < trials.size(); ++i)
    if (trials[i].kernel.name == "gaussian") CHECK(unloaded[i] == first[i]);
}
