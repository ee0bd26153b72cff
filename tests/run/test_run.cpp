// The scheduler: bit-identical results for any thread count; failures recorded, study goes on.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

using namespace rkhs;

namespace {

// A kernel that misbehaves on purpose: throws for x beyond `throw_beyond`, or returns NaN.
struct MisbehavingKernel {
  static PluginInfo info() {
    return {"test_misbehaving", "throws or returns NaN, for scheduler tests",
            {choice_parameter("mode", "throw", "what goes wrong", {"throw", "nan"})}, {}};
  }
  MisbehavingKernel(const ParameterSet& p, const Domain&) : nan_(p.choice("mode") == "nan") {}
  double operator()(double x, double y) const {
    if (nan_) return std::numeric_limits<double>::quiet_NaN();
    if (x > 5.0) throw std::runtime_error("kernel evaluated beyond 5");
    return std::exp(-(x - y) * (x - y));
  }
  KernelProperties properties() const { return {}; }
  bool nan_;
};

// Registers the test kernel for the lifetime of the object.
struct ScopedTestKernel {
  ScopedTestKernel() { REQUIRE(register_kernel<MisbehavingKernel>()); }
  ~ScopedTestKernel() { kernel_registry().remove("test_misbehaving"); }
};

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

TEST_CASE("results are bit-identical for 1, 2 and 4 threads", "[run]") {
  const auto study = parse_study(R"(
[study]
name = "determinism"
evaluation_points = 512
[domain]
radius = 4
[grid]
n = [5, 9, 17, 33]
[[kernel]]
name = "gaussian"
sigma = [0.7, 1.3]
[[kernel]]
name = "bspline"
degree = [1, 2]
[[kernel]]
name = "wendland"
radius = 3.0
[[centres]]
name = "random"
seed = [1, 2]
)", "determinism.toml");
  const auto trials = study.trials();
  const auto one = run_trials(study, trials, {1, {}});
  for (int threads : {2, 4}) {
    const auto many = run_trials(study, trials, {threads, {}});
    REQUIRE(many.size() == one.size());
    for (std::size_t i = 0; i < one.size(); ++i) {
      INFO("trial " << trials[i].key << " with " << threads << " threads");
      CHECK(one[i].ok);
      CHECK(bitwise_equal(one[i].metrics, many[i].metrics));
      CHECK(one[i].flags == many[i].flags);
      CHECK(one[i].solve_method == many[i].solve_method);
    }
  }
  // Different seeds give different centre sets (and so different fill distances).
  CHECK(one[0].metrics[0] != one[4].metrics[0]);
}

TEST_CASE("a throwing or NaN trial is recorded as failed and the others go on", "[run]") {
  ScopedTestKernel scoped;
  const auto study = parse_study(R"(
[study]
name = "failures"
evaluation_points = 64
[domain]
length = 10
periodic = false
[grid]
n = [4, 8]
[[kernel]]
name = "test_misbehaving"
mode = ["throw", "nan"]
[[kernel]]
name = "gaussian"
)", "failures.toml");
  const auto trials = study.trials();
  std::size_t reported = 0;
  const auto results = run_trials(study, trials, {2, [&](const TrialSpec&, const TrialResult&) { ++reported; }});
  CHECK(reported == trials.size());
  REQUIRE(results.size() == 6);
  CHECK_FALSE(results[0].ok);
  CHECK(results[0].reason == "kernel evaluated beyond 5");
  CHECK_FALSE(results[2].ok);
  CHECK_THAT(results[2].reason, Catch::Contains("non-finite"));
  for (double v : results[2].metrics) CHECK(std::isnan(v));
  CHECK(results[4].ok);
  CHECK(results[5].ok);
}

TEST_CASE("a trial above its matrix limit fails up front", "[run]") {
  const auto study = parse_study(R"(
[study]
name = "limits"
[domain]
radius = 4
[grid]
n = [10, 4000]
[[kernel]]
name = "gaussian"
[limits]
matrix_megabytes = 50
)", "limits.toml");
  const auto results = run_trials(study, study.trials(), {1, {}});
  CHECK(results[0].ok);
  CHECK_FALSE(results[1].ok);
  CHECK_THAT(results[1].reason, Catch::Contains("above limits.matrix_megabytes = 50"));
}

TEST_CASE("trials start largest first: by estimated cost, ties in grid order", "[run]") {
  const auto study = parse_study(R"([study]
name = "order"
evaluation_points = 256
[domain]
radius = 1
[grid]
n = [10, 40, 20]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
)", "order.toml");
  const auto trials = study.trials();
  REQUIRE(trials.size() == 6);
  const auto order = largest_first_order(study, trials);
  // Cost grows with n; the two kernels tie at each n and keep their grid order.
  std::vector<std::size_t> by_n;
  for (const auto k : order) by_n.push_back(trials[k].n);
  CHECK(by_n == std::vector<std::size_t>{40, 40, 20, 20, 10, 10});
  for (std::size_t k = 0; k + 1 < order.size(); k += 2) CHECK(order[k] < order[k + 1]);
  // A permutation of every trial.
  auto sorted = order;
  std::sort(sorted.begin(), sorted.end());
  CHECK(sorted == std::vector<std::size_t>{0, 1, 2, 3, 4, 5});
}

namespace {

// One adaptive trial that takes tens of seconds when left alone (the Gaussian with the rkhs law
// at n = 100 in the learning configuration of studies/paper_synthetic.toml).
rkhs::StudyDefinition long_adaptive_trial(const std::string& limits = "") {
  return rkhs::parse_study(R"(
[study]
name = "long"
kind = "adaptive"
metrics = ["l2_error"]
[domain]
radius = 4.0
[grid]
n = [100]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[law]]
name = "rkhs"
gamma = 2e4
[adaptive]
speed = 1e-4
laps = 10
)" + limits,
                           "long.toml");
}

}  // namespace

TEST_CASE("a stop request ends a running trial at its next cancellation point: not run, not failed",
          "[run]") {
  const auto study = long_adaptive_trial();
  const auto trials = study.trials();
  std::atomic<bool> stop{false};
  rkhs::RunOptions options;
  options.threads = 1;
  options.stop_requested = [&] { return stop.load(); };
  std::size_t started = 0, finished = 0;
  options.on_trial_started = [&](const rkhs::TrialSpec&) { ++started; };
  options.on_trial_finished = [&](const rkhs::TrialSpec&, const rkhs::TrialResult&) { ++finished; };
  std::thread interrupter([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    stop = true;
  });
  // No abandonment: run_trials returns only when the trial itself has stopped.
  const auto results = rkhs::run_trials(study, trials, options);
  interrupter.join();
  REQUIRE(results.size() == 1);
  CHECK(results[0].skipped);
  CHECK(results[0].stopped_while_running);
  CHECK_FALSE(results[0].ok);
  CHECK(results[0].reason == "not run: the run was interrupted while the trial ran");
  CHECK(started == 1);
  CHECK(finished == 0);  // a stopped trial is not reported as finished (so never stored)
  CHECK_FALSE(rkhs::trials_abandoned());

  // Outside a trial check_cancelled() does nothing; inside a scope it throws once asked to.
  CHECK_NOTHROW(rkhs::check_cancelled());
  const std::function<bool()> always = [] { return true; };
  const rkhs::CancellationScope scope(always, std::nullopt);
  CHECK_THROWS_AS(rkhs::check_cancelled(), rkhs::TrialCancelled);
}

TEST_CASE("limits.trial_seconds stops a trial as it runs, and it fails with the reason", "[run]") {
  const auto study = long_adaptive_trial("[limits]\ntrial_seconds = 0.3\n");
  const auto result = rkhs::run_trial(study, study.trials().front());
  CHECK_FALSE(result.ok);
  CHECK_FALSE(result.skipped);
  CHECK_THAT(result.reason, Catch::StartsWith("exceeded limits.trial_seconds = 0.3 ("));
  // It was stopped near its limit, not left to end (it takes tens of seconds unlimited).
  CHECK(result.seconds < 10);
}

TEST_CASE("a trial of a laps axis runs with its own lap count, as a study with that one count",
          "[run][laps]") {
  const auto study_with = [](const std::string& laps, const std::string& snapshots) {
    return parse_study(R"([study]
name = "laps_run"
kind = "adaptive"
evaluation_points = 64
[domain]
radius = 1.0
[grid]
n = [4]
[[kernel]]
name = "gaussian"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
[adaptive]
speed = 0.5
samples_per_lap = 4
snapshot_points = 8
)" + laps + "\nsnapshot_laps = " + snapshots + "\n",
                       "laps_run.toml");
  };
  const auto axis = study_with("laps = [1, 2]", "[1, 2]");
  const auto trials = axis.trials();
  REQUIRE(trials.size() == 2);
  const double lap_time = axis.domain.length / axis.adaptive.speed;
  for (std::size_t i = 0; i < 2; ++i) {
    const double laps = static_cast<double>(i + 1);
    const auto result = run_trial(axis, trials[i]);
    INFO(trials[i].key << ": " << result.reason);
    REQUIRE(result.ok);
    REQUIRE_FALSE(result.samples.empty());
    CHECK(result.samples.back().t == Approx(laps * lap_time));
    CHECK(result.samples.size() == static_cast<std::size_t>(4 * laps) + 1);
    // The snapshots it reaches: lap 1 for the one-lap trial, laps 1 and 2 for the other.
    REQUIRE(result.snapshots.size() == i + 1);
    for (const auto& snapshot : result.snapshots) CHECK(snapshot.estimate.size() == 8);
    // The same as the trial of a study with that one lap count, bit for bit.
    const auto single_study =
        study_with("laps = " + std::to_string(i + 1), i == 0 ? "[1]" : "[1, 2]");
    const auto single = run_trial(single_study, single_study.trials().front());
    REQUIRE(single.ok);
    CHECK(std::memcmp(single.metrics.data(), result.metrics.data(),
                      result.metrics.size() * sizeof(double)) == 0);
  }
}
