// The scheduler: bit-identical results for any thread count; failures recorded, study goes on.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <numeric>
#include <thread>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/run/trial_cost.hpp"
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

TEST_CASE("the cost estimate grows with n and with the horizon in laps", "[run][cost]") {
  for (std::size_t n = 1; n < 400; n = n * 3 / 2 + 1)
    CHECK(approximation_trial_cost(n + 1, 512) > approximation_trial_cost(n, 512));
  for (const bool implicit : {true, false}) {
    for (const bool lap_map : {false, true}) {
      INFO("implicit " << implicit << ", lap map " << lap_map);
      AdaptiveTrialShape shape{10, 4, 10.0, implicit, lap_map};
      for (std::size_t n = 1; n < 400; n = n * 3 / 2 + 1) {
        auto larger = shape;
        shape.n = n;
        larger.n = n + 1;
        CHECK(adaptive_trial_cost(larger, 256) > adaptive_trial_cost(shape, 256));
        // Adaptive work comes on top of an approximation trial's.
        CHECK(adaptive_trial_cost(shape, 256) > approximation_trial_cost(n, 256));
      }
    }
  }
  // Stepping through time: more laps cost more; a larger plant too.
  AdaptiveTrialShape shape{50, 4, 1.0, true, false};
  for (const double laps : {0.5, 1.0, 2.0, 10.0, 100.0}) {
    auto longer = shape;
    shape.laps = laps;
    longer.laps = laps * 1.5;
    CHECK(adaptive_trial_cost(longer, 256) > adaptive_trial_cost(shape, 256));
  }
  auto larger_plant = shape;
  larger_plant.plant_dimension = 8;
  CHECK(adaptive_trial_cost(larger_plant, 256) > adaptive_trial_cost(shape, 256));
  // An implicit integrator (an LU per step) costs more than an explicit one at the same n.
  auto explicit_shape = shape;
  explicit_shape.implicit_integrator = false;
  CHECK(adaptive_trial_cost(shape, 256) > adaptive_trial_cost(explicit_shape, 256));
  // With a lap map the horizon does not matter: about 2d + n laps, whatever `laps` says.
  auto mapped = shape;
  mapped.lap_map = true;
  mapped.laps = 1000;
  auto short_map = mapped;
  short_map.laps = 1;
  auto stepped = shape;
  stepped.laps = 2.0 * 4 + 50;
  CHECK(adaptive_trial_cost(mapped, 256) == adaptive_trial_cost(short_map, 256));
  CHECK(adaptive_trial_cost(mapped, 256) == adaptive_trial_cost(stepped, 256));
}

TEST_CASE("a study's trials are costed from their n, horizon, plant and integrator",
          "[run][cost]") {
  const auto adaptive = [](const std::string& laps) {
    return parse_study(R"([study]
name = "costs"
kind = "adaptive"
evaluation_points = 256
[domain]
radius = 4.0
[grid]
n = [20, 40]
[[kernel]]
name = "gaussian"
[[law]]
name = "rkhs"
[[plant]]
name = "linear"
[[plant]]
name = "quarter_car"
[[integrator]]
name = "rk4"
[[integrator]]
name = "rodas4"
[adaptive]
speed = 10.0
laps = )" + laps + "\n",
                       "costs.toml");
  };
  const auto study = adaptive("2");
  const auto trials = study.trials();
  REQUIRE(trials.size() == 8);
  for (const auto& trial : trials) {
    INFO(trial.key);
    const auto shape = adaptive_trial_shape(study, trial);
    CHECK(shape.n == trial.n);
    const auto& own = trial.adaptive_axes();
    CHECK(shape.plant_dimension == (own.plant.name == "quarter_car" ? 4u : 1u));
    CHECK(shape.laps == Approx(2.0));
    CHECK(shape.implicit_integrator == (own.integrator.name == "rodas4"));
    CHECK_FALSE(shape.lap_map);  // no study forces the lap map yet
    CHECK(estimated_trial_cost(study, trial) ==
          adaptive_trial_cost(shape, study.evaluation_points));
    // Each axis moves the estimate the way it moves the work.
    for (const auto& other : trials) {
      const bool same_but_n = other.adaptive_axes().plant.name == own.plant.name &&
                              other.adaptive_axes().integrator.name == own.integrator.name;
      if (same_but_n && other.n > trial.n)
        CHECK(estimated_trial_cost(study, other) > estimated_trial_cost(study, trial));
    }
  }
  // The same trials over a longer horizon (laps = 10 instead of 2) cost more.
  const auto longer = adaptive("10");
  const auto longer_trials = longer.trials();
  for (std::size_t i = 0; i < trials.size(); ++i)
    CHECK(estimated_trial_cost(longer, longer_trials[i]) > estimated_trial_cost(study, trials[i]));
  // A horizon given as a final time counts in laps too: one lap's time at 10 m/s is 1 lap.
  auto timed = study;
  timed.adaptive_axes().settings.final_time = study.domain.length / 10.0;
  CHECK(adaptive_trial_shape(timed, trials[0]).laps == Approx(1.0));
}

TEST_CASE("integrators declare what they do per step, and the cost estimate reads it",
          "[run][cost]") {
  // name -> factorisations per step, structured stage solves (at the defaults).
  const std::map<std::string, std::pair<int, bool>> declared = {
      {"rk4", {0, false}},         {"dopri5", {0, false}}, {"rk_fehlberg78", {0, false}},
      {"rosenbrock4", {1, false}}, {"rodas4", {1, true}},  {"radau5", {2, true}}};
  for (const auto& name : integrator_registry().names()) {
    INFO(name);
    const auto* entry = integrator_registry().find(name);
    const auto properties =
        entry->factory(ParameterSet::resolve(entry->info.parameters, {}))->properties();
    REQUIRE(declared.count(name) == 1);  // a new built-in integrator is declared here too
    CHECK(properties.factorisations_per_step == declared.at(name).first);
    CHECK(properties.structured_stage_solves == declared.at(name).second);
    CHECK(properties.implicit() == (declared.at(name).first > 0));
  }
  CHECK(describe_integrator({0, false}) == "explicit");
  CHECK(describe_integrator({2, true}) ==
        "implicit, 2 factorisations per step, structured stage solves");
  CHECK(describe_integrator({1, false}) ==
        "implicit, 1 factorisation per step, dense stage solves");

  // The scheduler reads them per trial, with the trial's own parameters: rodas4's dense stage
  // solves cost an N^3 factorisation per step, its structured ones do not.
  const auto study = parse_study(R"([study]
name = "integrator_costs"
kind = "adaptive"
evaluation_points = 64
[domain]
radius = 4.0
[grid]
n = [20]
[[kernel]]
name = "gaussian"
[[law]]
name = "rkhs"
[[plant]]
name = "linear"
[[integrator]]
name = "rodas4"
linear_solver = ["structured", "dense"]
[[integrator]]
name = "dopri5"
[adaptive]
laps = 2
)",
                                 "integrator_costs.toml");
  const auto trials = study.trials();
  REQUIRE(trials.size() == 3);
  for (const auto& trial : trials) {
    INFO(trial.key);
    const auto shape = adaptive_trial_shape(study, trial);
    const bool dense = trial.key.find("dense") != std::string::npos;
    const auto& integrator = trial.adaptive_axes().integrator;
    CHECK(shape.implicit_integrator == (integrator.name == "rodas4"));
    CHECK(shape.structured_solves == (integrator.name == "rodas4" && !dense));
  }
}

namespace {

// A study whose grid order is not its order by cost: n = 6, 30, 12, 24 for each of two kernels.
StudyDefinition unsorted_study() {
  return parse_study(R"([study]
name = "unsorted"
evaluation_points = 128
[domain]
radius = 2
[grid]
n = [6, 30, 12, 24]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
[[kernel]]
name = "wendland"
radius = 1.5
)", "unsorted.toml");
}

}  // namespace

TEST_CASE("trials start in decreasing estimated cost, for any thread count", "[run]") {
  const auto study = unsorted_study();
  const auto trials = study.trials();
  REQUIRE(trials.size() == 12);
  const auto order = largest_first_order(study, trials);
  // The order is by decreasing cost, and it is not the grid order (else this test proves nothing).
  for (std::size_t k = 0; k + 1 < order.size(); ++k)
    CHECK(estimated_trial_cost(study, trials[order[k]]) >=
          estimated_trial_cost(study, trials[order[k + 1]]));
  std::vector<std::size_t> grid(trials.size());
  std::iota(grid.begin(), grid.end(), std::size_t{0});
  REQUIRE(order != grid);
  for (const int threads : {1, 2, 3}) {
    INFO(threads << " threads");
    std::vector<std::size_t> started;  // appended under the scheduler's mutex
    RunOptions options;
    options.threads = threads;
    options.on_trial_started = [&](const TrialSpec& trial) { started.push_back(trial.index); };
    const auto results = run_trials(study, trials, options);
    CHECK(started == order);
    for (const auto& result : results) CHECK(result.ok);
  }
}

TEST_CASE("results are in grid order whatever order the trials ran in", "[run]") {
  const auto study = unsorted_study();
  const auto trials = study.trials();
  std::vector<std::size_t> finished;
  RunOptions options;
  options.threads = 3;
  options.on_trial_finished = [&](const TrialSpec& trial, const TrialResult&) {
    finished.push_back(trial.index);
  };
  const auto results = run_trials(study, trials, options);
  REQUIRE(results.size() == trials.size());
  CHECK(finished.size() == trials.size());
  // Slot i holds trial i's result: the one a lone run_trial of trial i gives, bit for bit.
  for (std::size_t i = 0; i < trials.size(); ++i) {
    INFO(trials[i].key);
    const auto alone = run_trial(study, trials[i]);
    REQUIRE(results[i].ok);
    CHECK(bitwise_equal(results[i].metrics, alone.metrics));
    CHECK(results[i].solve_method == alone.solve_method);
  }
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

TEST_CASE("a limits.trial_seconds too long for the clock is no limit, never a deadline in the past",
          "[run][hostile]") {
  // From 9.3e9 s on, start + limit overflowed steady_clock and every trial "exceeded
  // limits.trial_seconds" at 0.0 s (issue 36).
  for (const char* seconds : {"9.3e9", "1e12", "1e300", "9007199254740993"}) {
    const auto study = parse_study(std::string(R"([study]
name = "long_limit"
evaluation_points = 256
[domain]
radius = 4
[grid]
n = [16]
[[kernel]]
name = "gaussian"
[limits]
trial_seconds = )") + seconds + "\n",
                                   "s.toml");
    const auto result = rkhs::run_trial(study, study.trials().front());
    INFO(seconds << ": " << result.reason);
    CHECK(result.ok);
  }
}

TEST_CASE("GramSolver checks the trial's deadline before each symmetric eigenvalue solve",
          "[run][hostile]") {
  // A Gaussian n = 3000 trial with trial_seconds = 2 ran 25 s: two eigenvalue solves of its
  // singular Gram matrix, neither of which looked at the deadline (issue 36).
  const Eigen::MatrixXd singular = Eigen::MatrixXd::Ones(40, 40);
  const Eigen::MatrixXd regular = Eigen::MatrixXd::Identity(40, 40) + 0.1 * singular;
  const auto past = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  const std::function<bool()> never;
  {
    const rkhs::CancellationScope scope(never, past);
    CHECK_THROWS_AS(rkhs::GramSolver(singular, {}, rkhs::GramSpectrumMode::exact),
                    rkhs::TrialTimeLimitExceeded);
    CHECK_THROWS_AS(rkhs::GramSolver(regular, {}, rkhs::GramSpectrumMode::exact),
                    rkhs::TrialTimeLimitExceeded);
  }
  // Outside a trial nothing is checked, and the solves are those of before.
  const rkhs::GramSolver pseudo(singular, {}, rkhs::GramSpectrumMode::exact);
  CHECK(pseudo.spectrum().singular);
  CHECK(rkhs::GramSolver(regular, {}, rkhs::GramSpectrumMode::exact).method() == "cholesky");
}

TEST_CASE("limits.trial_seconds stops a trial inside the symmetric eigenvalue solve of its Gram",
          "[run][hostile]") {
  // A Gaussian Gram of n = 3000 centres on the paper's track, singular to working precision:
  // its eigenvalue solve was one uninterruptible call into Eigen, and with trial_seconds = 2
  // the trial ended after 7.6 s on the 2-core development machine (n = 6000: 227 s, under
  // load). The solve now checks the deadline between its O(n^2) steps (symmetric_eigen.hpp):
  // measured 1.02 s with trial_seconds = 1. Asserted below limit + 3 s, not + 1 s, so that a
  // loaded CI machine (the Gram's assembly and a step of the solve slowed several times) does
  // not make it flaky; the unpatched solve alone takes well over that.
  const auto study = parse_study(R"([study]
name = "deadline_in_eigen_solve"
evaluation_points = 256
metrics = ["gram_condition_number", "gram_min_eigenvalue", "gram_max_eigenvalue"]
[domain]
radius = 4
[grid]
n = [3000]
[[kernel]]
name = "gaussian"
sigma = 1.0
[limits]
trial_seconds = 1
)",
                                 "s.toml");
  const auto start = std::chrono::steady_clock::now();
  const auto result = rkhs::run_trial(study, study.trials().front());
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  INFO(result.reason << " after " << wall << " s");
  CHECK_FALSE(result.ok);
  CHECK_FALSE(result.skipped);
  CHECK_THAT(result.reason, Catch::StartsWith("exceeded limits.trial_seconds = 1 ("));
  CHECK(wall < 4.0);
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
  const double lap_time = axis.domain.length / axis.adaptive_axes().settings.speed;
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
TEST_CASE("a value that overflows fails its trial instead of being reported ok", "[run][hostile]") {
  // Amplitude 1e200: the error's squares overflow to +inf, which no trial may report as a
  // measurement (it was status ok with l2_error = inf); a singular Gram matrix's condition
  // number (+inf, flagged gram_singular) is a documented infinity and stays ok.
  auto study_with = [](const std::string& kernel, const std::string& amplitude) {
    return parse_study(R"([study]
name = "overflow"
evaluation_points = 256
[domain]
radius = 4
[grid]
n = [16]
[[kernel]]
)" + kernel + R"(
[[target]]
name = "sine"
amplitude = )" + amplitude +
                           "\n",
                       "s.toml");
  };
  const auto huge = study_with("name = \"bspline\"\ndegree = 1\nJ = 6", "1e200");
  const auto overflowed = rkhs::run_trial(huge, huge.trials().front());
  CHECK_FALSE(overflowed.ok);
  CHECK_THAT(
      overflowed.reason,
      Catch::Contains("overflowed to +inf: the trial's values exceed the range of a double"));
  const auto singular = study_with("name = \"gaussian\"\nsigma = 50.0", "1");
  const auto documented = rkhs::run_trial(singular, singular.trials().front());
  INFO(documented.reason);
  CHECK(documented.ok);
  const auto flags = documented.flags;
  CHECK(std::find(flags.begin(), flags.end(), "gram_singular") != flags.end());
  CHECK(std::isinf(documented.metrics[singular.metric_index("gram_condition_number")]));
}

TEST_CASE(
    "limits.memory_megabytes keeps the trials running at once within their predicted matrices",
    "[run]") {
  // Dense trials of n = 400, 300, 200 with E = 4096 points: 8 (3 n^2 + 2 n E) bytes, 28.7,
  // 20.8 and 13.4 MB. A limit of 40 MB lets the largest run beside the smallest only.
  const char* text = R"(
[study]
name = "memory"
evaluation_points = 4096
[domain]
radius = 4
[grid]
n = [200, 300, 400]
[[kernel]]
name = "gaussian"
sigma = [0.5, 0.7]
[limits]
memory_megabytes = 40
)";
  const auto study = parse_study(text, "memory.toml");
  CHECK(study.limits.memory_megabytes == 40);
  const auto trials = study.trials();
  std::mutex mutex;
  double in_use = 0, most = 0, largest = 0;
  std::map<std::string, double> footprint;
  for (const auto& trial : trials) {
    footprint[trial.key] = trial_footprint(study, trial).megabytes;
    largest = std::max(largest, footprint[trial.key]);
  }
  REQUIRE(largest < 40);
  RunOptions options{2, {}};
  options.on_trial_started = [&](const TrialSpec& trial) {
    std::lock_guard lock(mutex);
    in_use += footprint[trial.key];
    most = std::max(most, in_use);
  };
  options.on_trial_finished = [&](const TrialSpec& trial, const TrialResult&) {
    std::lock_guard lock(mutex);
    in_use -= footprint[trial.key];
  };
  const auto limited = run_trials(study, trials, options);
  CHECK(most <= 40);
  CHECK(most > largest);  // two trials did run at once
  // The same results as without the limit.
  const auto unlimited =
      run_trials(parse_study(std::string(text).replace(std::string(text).find("memory_megabytes"),
                                                       21, "trials = 1000"),
                             "memory.toml"),
                 trials, {2, {}});
  for (std::size_t i = 0; i < trials.size(); ++i) {
    INFO(trials[i].key);
    CHECK(limited[i].ok);
    CHECK(bitwise_equal(limited[i].metrics, unlimited[i].metrics));
  }
}
