// The work counters of trials (TrialResult::work): filled by run_trial, attributed to the right
// trial when trials run side by side, kept by a stored record and missing from an old one.
#include <catch2/catch.hpp>

#include "rkhs/run/result_store.hpp"
#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

using namespace rkhs;

namespace {

constexpr const char* small_study = R"(
[study]
name = "work"
evaluation_points = 200
[domain]
radius = 4
[grid]
n = [8, 16, 32]
[[kernel]]
name = "gaussian"
sigma = [0.7, 1.3]
[[kernel]]
name = "bspline"
degree = [1, 2]
)";

}  // namespace

TEST_CASE("a trial counts at least its Gram, cross and diagonal evaluations", "[run][work]") {
  const auto study = parse_study(small_study, "work.toml");
  const auto trials = study.trials();
  const auto result = run_trial(study, trials.front());
  REQUIRE(result.ok);
  REQUIRE(result.work);
  const std::uint64_t n = trials.front().n, M = study.evaluation_points;
  // An interpolation trial assembles its Gram matrix, the cross matrix at the evaluation points
  // and the kernel's diagonal there, at least once each.
  CHECK(result.work->kernel_evaluations >= n * (n + 1) / 2 + M * n + M);
  CHECK(result.work->allocations_tracked == allocation_tracking_enabled());
  if (allocation_tracking_enabled()) {
    CHECK(result.work->peak_bytes >= 8 * M * n);  // the cross matrix
    CHECK(result.work->allocated_bytes >= result.work->peak_bytes);
    CHECK(result.work->allocations > 0);
  }
}

TEST_CASE("work counters are the same for 1, 2 and 4 threads: each trial counts its own",
          "[run][work]") {
  const auto study = parse_study(small_study, "work.toml");
  const auto trials = study.trials();
  const auto one = run_trials(study, trials, {1, {}});
  for (int threads : {2, 4}) {
    const auto many = run_trials(study, trials, {threads, {}});
    for (std::size_t i = 0; i < one.size(); ++i) {
      INFO("trial " << trials[i].key << " with " << threads << " threads");
      REQUIRE(one[i].work);
      REQUIRE(many[i].work);
      const auto &a = *one[i].work, &b = *many[i].work;
      CHECK(a.kernel_evaluations == b.kernel_evaluations);
      CHECK(a.kernel_derivative_evaluations == b.kernel_derivative_evaluations);
      CHECK(a.factorisations == b.factorisations);
      CHECK(a.allocations == b.allocations);
      // Byte counts are exact on one thread; glibc may hand a block 16 bytes more from a
      // thread's arena that another trial shaped, so across thread counts they agree to 1 %.
      CHECK(static_cast<double>(b.allocated_bytes) ==
            Approx(static_cast<double>(a.allocated_bytes)).epsilon(0.01));
      CHECK(static_cast<double>(b.peak_bytes) ==
            Approx(static_cast<double>(a.peak_bytes)).epsilon(0.01));
    }
  }
  // Larger trials do more work: the counters see the trial, not the thread.
  CHECK(one[2].work->kernel_evaluations > one[0].work->kernel_evaluations);
}

TEST_CASE("a stored record keeps the work counters, an old record has none", "[run][work]") {
  TrialResult result;
  result.ok = true;
  result.metrics = {1.0, 2.0};
  result.work = WorkCounts{.kernel_evaluations = 123,
                           .kernel_derivative_evaluations = 4,
                           .factorisations = 1,
                           .sparse_nonzeros = 89,
                           .factor_nonzeros = 144,
                           .sparse_solve_columns = 233,
                           .allocations_tracked = true,
                           .allocations = 56,
                           .allocated_bytes = 7890,
                           .peak_bytes = 4567};
  const auto text = serialize_result(result);
  CHECK_THAT(text, Catch::Contains("\nwork kernel_evaluations=123 kernel_derivative_evaluations=4 "
                                   "factorisations=1 sparse_nonzeros=89 factor_nonzeros=144 "
                                   "sparse_solve_columns=233 allocations=56 "
                                   "allocated_bytes=7890 peak_bytes=4567\n"));
  CHECK(deserialize_result(text).work == result.work);
  result.work->allocations_tracked = false;  // a sanitizer build: no allocation counts
  const auto untracked = serialize_result(result);
  CHECK_THAT(untracked, !Catch::Contains("allocations="));
  auto without_allocations = *result.work;
  without_allocations.allocations = without_allocations.allocated_bytes =
      without_allocations.peak_bytes = 0;
  CHECK(deserialize_result(untracked).work == without_allocations);
  result.work.reset();  // a record written before work counters existed
  const auto old = serialize_result(result);
  CHECK_THAT(old, !Catch::Contains("work"));
  CHECK_FALSE(deserialize_result(old).work);
  // A stored record round-trips them under its checksum.
  result.work = WorkCounts{.kernel_evaluations = 1,
                           .kernel_derivative_evaluations = 2,
                           .factorisations = 3,
                           .sparse_nonzeros = 7,
                           .factor_nonzeros = 8,
                           .sparse_solve_columns = 9,
                           .allocations_tracked = true,
                           .allocations = 4,
                           .allocated_bytes = 5,
                           .peak_bytes = 6};
  const auto check =
      read_record("hash", "s", "k", store_record("hash", "s", "k", result, {"a", "b"}));
  REQUIRE(check.result);
  CHECK(check.result->work == result.work);
  // Malformed counters are a bad record, not zeros.
  for (const char* line : {"work kernel_evaluations=1",
                           "work kernel_evaluations=x "
                           "kernel_derivative_evaluations=0 "
                           "factorisations=0",
                           "work kernel_evaluations=1 kernel_derivative_evaluations=0 "
                           "factorisations=0 sparse_nonzeros=0 factor_nonzeros=0 "
                           "sparse_solve_columns=0 bogus=1"}) {
    INFO(line);
    CHECK_THROWS_AS(deserialize_result("rkhs-trial 1\nok 1\n" + std::string(line) + "\n"),
                    std::invalid_argument);
  }
}
