// studies/belgian_block.toml end to end on the held-out long sections of the same road (the
// wheel tracks at v = +-0.50 m, not used when the study's speed and gain were chosen), read
// from the repository's studies/data/ through the data root.
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>

#include "../study_data_support.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/approx/target.hpp"

using namespace rkhs;
namespace fs = std::filesystem;

namespace {

const fs::path studies = fs::path(RKHS_STUDY_SOURCE_DIR) / "studies";

// Sets the data root for one test and restores the default resolution afterwards.
struct DataRootScope {
  explicit DataRootScope(const fs::path& root) { set_data_root(root); }
  ~DataRootScope() { set_data_root({}); }
};

PluginChoice with_file(const PluginChoice& choice, const std::string& file) {
  std::map<std::string, ParameterValue> given;
  for (const auto& [name, value] : choice.parameters.values()) given[name] = value;
  given["file"] = file;
  return {choice.name,
          ParameterSet::resolve(target_registry().find(choice.name)->info.parameters, given),
          choice.tiers};
}

double l2_norm(const TargetFunction& f, const Domain& domain) {
  const auto points = domain.uniform_points(4096);
  std::vector<double> values(points.size());
  f.evaluate(points, values);
  return domain.l2_norm(values);
}

}  // namespace

TEST_CASE("belgian_block: the study's configuration learns the held-out long sections",
          "[belgian_block]") {
  const DataRootScope scope(testing::require_study_data());
  auto study = load_study(studies / "belgian_block.toml");
  REQUIRE(study.targets.size() == 1);
  // The same configuration on a smaller grid: the Gaussian and the first-order B-spline (the
  // second-order one does not learn in 10 laps), one n.
  study.kernels.erase(std::remove_if(study.kernels.begin(), study.kernels.end(),
                                     [](const PluginChoice& k) {
                                       return k.name == "bspline" &&
                                              k.parameters.integer("degree") != 1;
                                     }),
                      study.kernels.end());
  REQUIRE(study.kernels.size() == 2);
  study.n_values = {50};
  study.adaptive_axes().settings.snapshot_laps.clear();
  const auto original = study.targets.front();
  study.targets = {with_file(original, "belgian_block/long_section_v+0.50.csv"),
                   with_file(original, "belgian_block/long_section_v-0.50.csv")};
  const auto trials = study.trials();
  REQUIRE(trials.size() == 4);
  const auto results = run_trials(study, trials, {2, {}});

  for (std::size_t i = 0; i < trials.size(); ++i) {
    const auto& trial = trials[i];
    const auto& result = results[i];
    INFO(trial.key);
    REQUIRE(result.reason == "");
    REQUIRE(result.ok);
    const auto file = resolve_data_file(trial.target.parameters.text("file"));
    CHECK(result.data_provenance == "sha256:" + sha256_file(file));
    const auto road = target_registry().find("csv")->factory(trial.target.parameters, study.domain);
    const double norm = l2_norm(*road, study.domain);
    const double error = result.metrics[study.metric_index("l2_error")];
    const double interpolant = result.metrics[study.metric_index("interpolant_l2_error")];
    UNSCOPED_INFO(trial.kernel.label()
                  << " on " << trial.target.parameters.text("file") << ": ||f|| = " << norm
                  << ", l2_error = " << error << ", interpolant = " << interpolant);
    // Learnt: well below the size of the road itself (an estimate that learns nothing has an
    // error of about ||f||; measured 0.15-0.3 ||f||), and not better than what H_n allows by
    // more than a factor 2.
    CHECK(error < 0.4 * norm);
    CHECK(error > 0.5 * interpolant);
    CHECK(result.metrics[study.metric_index("final_state_error")] < 0.05);
  }
}

TEST_CASE("belgian_block_heldout.toml is belgian_block.toml but for the files and n",
          "[belgian_block]") {
  const DataRootScope scope(testing::require_study_data());
  const auto study = load_study(studies / "belgian_block.toml");
  const auto heldout = load_study(studies / "belgian_block_heldout.toml");
  auto labels = [](const std::vector<PluginChoice>& choices) {
    std::vector<std::string> out;
    for (const auto& c : choices) out.push_back(c.label());
    return out;
  };
  CHECK(labels(heldout.kernels) == labels(study.kernels));
  const auto& held = heldout.adaptive_axes();
  const auto& own = study.adaptive_axes();
  CHECK(labels(held.plants) == labels(own.plants));
  CHECK(labels(held.laws) == labels(own.laws));
  CHECK(labels(held.integrators) == labels(own.integrators));
  CHECK(labels(heldout.centres) == labels(study.centres));
  CHECK(heldout.domain.length == study.domain.length);
  CHECK(heldout.domain.periodic == study.domain.periodic);
  CHECK(heldout.metrics == study.metrics);
  CHECK(held.settings.speed == own.settings.speed);
  CHECK(held.settings.laps == own.settings.laps);
  CHECK(held.settings.q == own.settings.q);
  CHECK(held.settings.snapshot_laps == own.settings.snapshot_laps);
  REQUIRE(heldout.targets.size() == 2);
  for (const auto& target : heldout.targets) {
    CHECK(target.parameters.text("file") != study.targets.front().parameters.text("file"));
    CHECK(with_file(target, "x").label() == with_file(study.targets.front(), "x").label());
  }
}
