// The result store: exact round trips, content hashes, and reuse.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

#include "rkhs/run/result_store.hpp"

using namespace rkhs;

namespace {
const char* const study_text = R"([study]
name = "store"
evaluation_points = 128
[domain]
radius = 4
[grid]
n = [8, 16]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
)";
}  // namespace

TEST_CASE("a stored trial reads back bit for bit", "[store]") {
  TrialResult r;
  r.ok = true;
  r.reason = "line one\nline two \\ with a backslash";
  r.solve_method = "pseudo-inverse (rank 3 of 4, cutoff 8.882e-16 lambda_max)";
  r.flags = {"gram_singular", "power_function_at_floor"};
  r.seconds = 0.125;
  r.data_provenance = "sha256:abc";
  r.metrics = {0.1, 1.0 / 3.0, std::numeric_limits<double>::infinity(),
               std::numeric_limits<double>::quiet_NaN(), -2.5e-300, 5e-324};
  r.samples = {{0.0, 0.0, 1.5}, {2.0, 1e-7, 1.25}};
  r.road = {1.0, -1.0};
  r.snapshots = {{1.0, {0.5, 0.25}}, {10.0, {0.75, 0.125}}};
  const auto back = deserialize_result(serialize_result(r));
  CHECK(back.ok);
  CHECK(back.reason == r.reason);
  CHECK(back.solve_method == r.solve_method);
  CHECK(back.flags == r.flags);
  CHECK(back.data_provenance == r.data_provenance);
  REQUIRE(back.metrics.size() == r.metrics.size());
  for (std::size_t i = 0; i < r.metrics.size(); ++i) {
    if (std::isnan(r.metrics[i])) CHECK(std::isnan(back.metrics[i]));
    else CHECK(back.metrics[i] == r.metrics[i]);  // exact
  }
  REQUIRE(back.samples.size() == 2);
  CHECK(back.samples[1].state_error == 1e-7);
  CHECK(back.road == r.road);
  REQUIRE(back.snapshots.size() == 2);
  CHECK(back.snapshots[1].lap == 10.0);
  CHECK(back.snapshots[1].estimate == r.snapshots[1].estimate);
  CHECK_THROWS_WITH(deserialize_result("something else"),
                    "not a stored trial record (version line missing)");
}

TEST_CASE("trial hashes change with anything that changes a result", "[store]") {
  const auto study = parse_study(study_text, "store.toml");
  const auto trials = study.trials();
  const auto hashes = trial_hashes(study, trials);
  REQUIRE(hashes.size() == 4);
  CHECK(std::set<std::string>(hashes.begin(), hashes.end()).size() == 4);
  CHECK(hashes == trial_hashes(study, trials));  // deterministic
  auto other = study;
  other.evaluation_points = 256;
  CHECK(trial_hashes(other, trials)[0] != hashes[0]);
  std::string changed = study_text;
  changed.replace(changed.find("[0.5, 1.0]"), 10, "[0.5, 2.0]");
  const auto changed_study = parse_study(changed, "store.toml");
  const auto changed_hashes = trial_hashes(changed_study, changed_study.trials());
  CHECK(changed_hashes[0] == hashes[0]);  // sigma = 0.5, n = 8: unchanged
  CHECK(changed_hashes[1] == hashes[1]);
  CHECK(changed_hashes[2] != hashes[2]);  // sigma = 2.0
}

TEST_CASE("run_with_store runs only what the store lacks", "[store]") {
  const auto file = std::filesystem::temp_directory_path() / "rkhs_store_test" / "store.sqlite";
  std::filesystem::remove_all(file.parent_path());
  const auto study = parse_study(study_text, "store.toml");
  const auto trials = study.trials();
  RunOptions options;
  options.threads = 2;
  {
    ResultStore store(file);
    const auto first = run_with_store(study, trials, options, &store, false);
    CHECK(first.ran == 4);
    CHECK(first.reused == 0);
    CHECK(store.size() == 4);
    const auto second = run_with_store(study, trials, options, &store, false);
    CHECK(second.ran == 0);
    CHECK(second.reused == 4);
    for (std::size_t i = 0; i < trials.size(); ++i)
      // Bit for bit, NaN (a metric the study does not compute) equal to NaN.
      CHECK(std::equal(second.results[i].metrics.begin(), second.results[i].metrics.end(), first.results[i].metrics.begin(), first.results[i].metrics.end(),
                       [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); }));
    const auto fresh = run_with_store(study, trials, options, &store, true);
    CHECK(fresh.ran == 4);
    CHECK(store.size() == 4);  // replaced, not duplicated
  }
  // A store is reopened from disk.
  ResultStore reopened(file);
  CHECK(reopened.size() == 4);
  // Interruption: nothing starts once stop is requested.
  options.stop_requested = [] { return true; };
  const auto stopped = run_with_store(study, trials, options, nullptr, false);
  CHECK(stopped.skipped == 4);
  CHECK(stopped.ran == 0);
  CHECK_THROWS_WITH(ResultStore("/proc/no/such/dir/store.sqlite"),
                    Catch::Contains("cannot"));
}
