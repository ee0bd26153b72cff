// Runs that survive: a study killed with SIGKILL midway resumes where it stopped and gives
// exactly the trials of an uninterrupted run; SIGINT stops cleanly (also inside a long trial),
// stores only finished trials and says how to resume; a changed parameter re-runs only the
// affected trials.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <thread>

#include "background_command.hpp"
#include "cli_support.hpp"
#include "rkhs/run/result_store.hpp"

namespace fs = std::filesystem;
using rkhs::test::read_text;
using rkhs::test::rkhs_study;

namespace {

std::string slow_study(const std::string& sigmas) {
  return rkhs::test::slow_study("store_cli", sigmas);
}


// Waits until the store holds at least `count` trials (or the process ended).
void wait_for_stored(const fs::path& store, std::size_t count, pid_t pid) {
  bool ended = false;
  const bool stored = rkhs::test::wait_until(
      [&] {
        ended = ended || waitpid(pid, nullptr, WNOHANG) == pid;
        return ended || (fs::exists(store) && rkhs::ResultStore(store).size() >= count);
      },
      30);
  if (ended) FAIL("the run ended before it could be interrupted");
  if (!stored) FAIL("no trial was stored within " << 30 * rkhs::test::patience << " s");
}

}  // namespace

TEST_CASE("a run killed with SIGKILL resumes and equals an uninterrupted run", "[cli][store]") {
  const auto dir = rkhs::test::scratch_directory("store_kill");
  std::ofstream(dir / "study.toml") << slow_study("[0.5, 0.7]");
  const auto store = dir / "store.sqlite";
  const pid_t pid = rkhs::test::start_rkhs_study({"run", (dir / "study.toml").string(), "--threads",
                                                  "1", "--quiet", "--store", store.string(),
                                                  "--out", (dir / "killed").string()});
  wait_for_stored(store, 2, pid);
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  const auto stored_before = rkhs::ResultStore(store).size();
  CHECK(stored_before >= 2);
  CHECK(stored_before < 10);

  const auto resumed = rkhs_study("run " + (dir / "study.toml").string() + " --threads 2 --store " +
                                  store.string() + " --out " + (dir / "resumed").string());
  INFO(resumed.output);
  REQUIRE(resumed.exit_code == 0);
  CHECK_THAT(resumed.output, Catch::Contains(rkhs::test::trials_text(stored_before) + " reused"));
  CHECK(rkhs::ResultStore(store).size() == 10);  // every trial exactly once

  const auto clean = rkhs_study("run " + (dir / "study.toml").string() +
                                " --quiet --no-store --out " + (dir / "clean").string());
  REQUIRE(clean.exit_code == 0);
  CHECK(read_text(dir / "resumed" / "trials.csv") == read_text(dir / "clean" / "trials.csv"));
  CHECK(read_text(dir / "resumed" / "rates.csv") == read_text(dir / "clean" / "rates.csv"));
}

TEST_CASE("SIGINT stops the run: what finished is stored, and it says how to resume",
          "[cli][store]") {
  const auto dir = rkhs::test::scratch_directory("store_sigint");
  std::ofstream(dir / "study.toml") << slow_study("[0.5, 0.7]");
  const auto store = dir / "store.sqlite";
  const auto log = dir / "log.txt";
  const pid_t pid = rkhs::test::start_rkhs_study(
      {"run", (dir / "study.toml").string(), "--threads", "1", "--quiet", "--store", store.string(),
       "--out", (dir / "out").string()},
      log);
  wait_for_stored(store, 1, pid);
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK_THAT(read_text(log), Catch::Contains("Run the same command again to resume"));
  // Exactly the finished trials are stored, and the message says how many.
  CHECK_THAT(
      read_text(log),
      Catch::Contains("interrupted: " + rkhs::test::trials_text(rkhs::ResultStore(store).size()) +
                      " finished and stored"));
  CHECK_FALSE(fs::exists(dir / "out" / "trials.csv"));  // outputs are for complete runs
  const auto resumed = rkhs_study("run " + (dir / "study.toml").string() + " --store " +
                                  store.string() + " --out " + (dir / "out").string());
  CHECK(resumed.exit_code == 0);
  CHECK(rkhs::ResultStore(store).size() == 10);
}

TEST_CASE("a changed parameter re-runs only the affected trials", "[cli][store]") {
  const auto dir = rkhs::test::scratch_directory("store_change");
  const auto store = dir / "store.sqlite";
  std::ofstream(dir / "a.toml") << slow_study("[0.5, 0.7]");
  std::ofstream(dir / "b.toml") << slow_study("[0.5, 0.9]");
  auto first = rkhs_study("run " + (dir / "a.toml").string() + " --store " + store.string() +
                          " --out " + (dir / "a").string());
  REQUIRE(first.exit_code == 0);
  CHECK_THAT(first.output, Catch::Contains("0 trials reused"));
  auto second = rkhs_study("run " + (dir / "b.toml").string() + " --store " + store.string() +
                           " --out " + (dir / "b").string());
  INFO(second.output);
  REQUIRE(second.exit_code == 0);
  CHECK_THAT(second.output,
             Catch::Contains("5 trials reused from " + store.string() + ", 5 run now"));
  auto fresh = rkhs_study("run " + (dir / "b.toml").string() + " --fresh --store " +
                          store.string() + " --out " + (dir / "b").string());
  CHECK_THAT(fresh.output,
             Catch::Contains("0 trials reused from " + store.string() + ", 10 run now"));
}

TEST_CASE("shards run disjoint subsets: merged stores reproduce a single run", "[cli][store]") {
  const auto dir = rkhs::test::scratch_directory("store_shards");
  std::ofstream(dir / "study.toml") << R"([study]
name = "shards"
evaluation_points = 512
[domain]
radius = 4
[grid]
n = { from = 8, to = 64, step = 8 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 5
)";
  const auto study = (dir / "study.toml").string();
  for (int k = 1; k <= 3; ++k) {
    const auto shard =
        rkhs_study("run " + study + " --quiet --shard " + std::to_string(k) + "/3 --store " +
                   (dir / ("shard" + std::to_string(k) + ".sqlite")).string());
    INFO(shard.output);
    REQUIRE(shard.exit_code == 0);
    CHECK_THAT(shard.output, Catch::Contains("shard " + std::to_string(k) + "/3:"));
  }
  // 16 trials: indices 0..15 split 6, 5, 5.
  CHECK(rkhs::ResultStore(dir / "shard1.sqlite").size() == 6);
  CHECK(rkhs::ResultStore(dir / "shard2.sqlite").size() == 5);
  const auto merged =
      rkhs_study("merge " + (dir / "all.sqlite").string() + " " + (dir / "shard1.sqlite").string() +
                 " " + (dir / "shard2.sqlite").string() + " " + (dir / "shard3.sqlite").string());
  INFO(merged.output);
  REQUIRE(merged.exit_code == 0);
  CHECK_THAT(merged.output, Catch::Contains("holds 16 trials"));
  const auto from_shards = rkhs_study("run " + study + " --store " + (dir / "all.sqlite").string() +
                                      " --no-plots --out " + (dir / "from_shards").string());
  CHECK_THAT(from_shards.output, Catch::Contains("16 trials reused"));
  CHECK_THAT(from_shards.output, Catch::Contains("0 run now"));
  REQUIRE(rkhs_study("run " + study + " --quiet --no-store --no-plots --out " +
                     (dir / "single").string())
              .exit_code == 0);
  CHECK(read_text(dir / "from_shards" / "trials.csv") == read_text(dir / "single" / "trials.csv"));
  CHECK(rkhs_study("run " + study + " --shard 4/3").exit_code == 2);
  CHECK(rkhs_study("merge " + (dir / "x.sqlite").string() + " " + study).exit_code == 2);
  // K/N parsed strictly: digits only, one '/', 1 <= K <= N, nothing before or after; the
  // refusal names what was found and what is allowed, and nothing runs or is stored.
  const std::pair<const char*, const char*> refused[] = {
      {"1/-2", "N is '-2', not a whole number of digits"},
      {"1/2/3", "more than one '/'"},
      {"0/2", "K is 0"},
      {"3/2", "K = 3 is greater than N = 2"},
      {" 1/2", "K is ' 1', not a whole number of digits"},
      {"1/2 ", "N is '2 ', not a whole number of digits"},
      {"+1/2", "K is '+1'"},
      {"1/0", "N is 0"},
      {"2", "no '/'"},
      {"1/", "N is empty"},
      {"1/99999999999999999999", "N is larger than 4294967295"}};
  for (const auto& [shard, why] : refused) {
    const auto run = rkhs_study("run " + study + " --quiet --shard '" + shard + "' --store " +
                                (dir / "refused.sqlite").string());
    INFO(shard << ": " << run.output);
    CHECK(run.exit_code == 2);
    CHECK_THAT(run.output, Catch::Contains(std::string("--shard '") + shard + "': " + why));
    CHECK_THAT(run.output, Catch::Contains("two whole numbers (digits only) with 1 <= K <= N"));
  }
  CHECK_FALSE(fs::exists(dir / "refused.sqlite"));
}

namespace {

// Waits until `log` contains `text` (fails if the process ends or `seconds` pass first).
void wait_for_text(const fs::path& log, const std::string& text, pid_t pid, int seconds) {
  bool ended = false;
  const bool appeared = rkhs::test::wait_until(
      [&] {
        ended = ended || waitpid(pid, nullptr, WNOHANG) == pid;
        return ended || read_text(log).find(text) != std::string::npos;
      },
      seconds);
  if (read_text(log).find(text) != std::string::npos) return;
  if (ended) FAIL("the run ended first:\n" << read_text(log));
  if (!appeared)
    FAIL("'" << text << "' did not appear within " << seconds * rkhs::test::patience << " s:\n"
             << read_text(log));
}

}  // namespace

TEST_CASE("SIGINT stops a single long trial at once: not stored, exit 130, resumable",
          "[cli][store]") {
  // One trial that computes for minutes (the eigendecomposition of a 4000 x 4000 Gram matrix,
  // which has no cancellation point inside).
  const auto dir = rkhs::test::scratch_directory("store_long_trial");
  std::ofstream(dir / "study.toml") << R"([study]
name = "long_trial"
evaluation_points = 16384
metrics = ["gram_condition_number", "power_function_sup"]
[domain]
radius = 4
[grid]
n = [4000]
[[kernel]]
name = "matern"
nu = 2.5
)";
  const auto store = dir / "store.sqlite";
  const auto log = dir / "log.txt";
  const pid_t pid =
      rkhs::test::start_rkhs_study({"run", (dir / "study.toml").string(), "--threads", "1",
                                    "--store", store.string(), "--out", (dir / "out").string()},
                                   log);
  // Alive inside the long trial: the progress line shows the trial in flight and its time.
  wait_for_text(log, "0/1 trials, 0 failed, ", pid, 30);
  CHECK_THAT(read_text(log), Catch::Contains("; running 1: "));
  const auto signalled = std::chrono::steady_clock::now();
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  const auto output = read_text(log);
  INFO(output);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK(seconds < 15);  // the trial alone needs minutes; the run gives it 1.5 s, then ends
  CHECK_THAT(output, Catch::Contains("rkhs-study: interrupted: 0 trials finished and stored, 1 "
                                     "stopped while running and 0 not started (not stored). Run "
                                     "the same command again to resume"));
  CHECK(rkhs::ResultStore(store).size() == 0);  // never stored as failed (or as ok)
  CHECK_FALSE(fs::exists(dir / "out" / "trials.csv"));
}

TEST_CASE("an interrupted --no-store run says that nothing was stored, and where its results are",
          "[cli][store]") {
  const auto dir = rkhs::test::scratch_directory("store_interrupt_no_store");
  std::ofstream(dir / "study.toml") << slow_study("[0.5, 0.7]");
  const auto log = dir / "log.txt";
  const auto journal = dir / "out" / "journal.csv";
  const pid_t pid =
      rkhs::test::start_rkhs_study({"run", (dir / "study.toml").string(), "--threads", "1",
                                    "--quiet", "--no-store", "--out", (dir / "out").string()},
                                   log);
  // Until the journal holds a finished trial (header + 1 line).
  REQUIRE(rkhs::test::wait_until(
      [&] {
        REQUIRE(waitpid(pid, nullptr, WNOHANG) == 0);
        const auto text = read_text(journal);
        return std::count(text.begin(), text.end(), '\n') >= 2;
      },
      30));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  const auto output = read_text(log);
  INFO(output);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK_THAT(output, Catch::Contains("rkhs-study: interrupted: "));
  CHECK_THAT(output, Catch::Contains(" finished, "));
  CHECK_THAT(output, !Catch::Contains("stored,"));
  CHECK_THAT(output, Catch::Contains("Nothing was stored (--no-store); the finished trials' "
                                     "metrics are in " +
                                     journal.string() +
                                     ": the same command runs every trial "
                                     "again."));
}
