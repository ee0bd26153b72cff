// Studies across MPI ranks (`mpirun -np 2 rkhs-study run STUDY --mpi`): the results equal a
// single-process run bit for bit, rank 0 alone writes, a rank killed midway loses only its
// trials in flight, and ranks that would disagree on the study (or a launch without --mpi)
// are refused before anything runs. In a build without MPI, --mpi says so.
#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <thread>

#include "cli_support.hpp"
#include "rkhs/run/result_store.hpp"
#include "rkhs/study/study.hpp"

namespace fs = std::filesystem;
using rkhs::test::read_text;
using rkhs::test::rkhs_study;

namespace {

// Approximation trials of several costs, and two that fail (matrices above the limit): their
// reasons travel between ranks too.
constexpr const char* approximation_study = R"([study]
name = "mpi_approximation"
evaluation_points = 1024
metrics = ["gram_condition_number", "power_function_sup", "l2_error", "sup_error"]
[domain]
radius = 4
[grid]
n = [8, 16, 32, 64, 128, 700]
[limits]
matrix_megabytes = 12
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 6
[[centres]]
name = "random"
)";

// Adaptive trials: time samples, road and snapshots of fhat travel too.
constexpr const char* adaptive_study = R"([study]
name = "mpi_adaptive"
kind = "adaptive"
evaluation_points = 256
[domain]
radius = 1.0
[grid]
n = [4, 8, 12]
[[kernel]]
name = "bspline"
degree = 1
J = 4
[[kernel]]
name = "gaussian"
sigma = 0.4
[[target]]
name = "sine"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 5.0
[adaptive]
speed = 1.0
laps = 2
samples_per_lap = 10
snapshot_laps = [1, 2]
snapshot_points = 64
)";

#ifdef RKHS_TEST_MPIEXEC

// mpirun of this build's rkhs-study; as root Open MPI needs to be told that is intended.
std::string mpirun(int ranks, const std::string& arguments) {
  return fmt::format("{} -np {} --oversubscribe --bind-to none {} {}", RKHS_TEST_MPIEXEC, ranks,
                     RKHS_STUDY_EXECUTABLE, arguments);
}
// Under AddressSanitizer (the asan preset) leak checking is off for the processes mpirun starts:
// Open MPI's components leak at MPI_Finalize and are unloaded before LeakSanitizer runs, so their
// leaks cannot be told from ours by a suppression (their frames are in no module); every other
// check stays on. Other builds ignore ASAN_OPTIONS.
const std::string mpi_environment =
    "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
    "OMPI_MCA_btl_vader_single_copy_mechanism=none "
    "ASAN_OPTIONS=\"${ASAN_OPTIONS:-}:detect_leaks=0\"";

// Runs `command` (a whole command line) in the MPI environment.
rkhs::test::CommandOutcome shell(const std::string& command) {
  return rkhs::test::run_command(mpi_environment + " " + command);
}

// Every stored trial of `study_file` in both stores, compared as exact text records (reals in
// their shortest round-trip form) with the wall time and the heap byte counts left out (both
// depend on the process, its load and its heap's history, not on the trial: docs/results.md,
// "Work counters"); every other work counter is compared.
void require_same_stored_trials(const fs::path& study_file, const fs::path& a, const fs::path& b) {
  const auto study = rkhs::load_study(study_file.string());
  const auto trials = study.trials();
  const auto hashes = rkhs::trial_hashes(study, trials);
  rkhs::ResultStore store_a(a), store_b(b);
  for (std::size_t i = 0; i < trials.size(); ++i) {
    INFO(trials[i].key);
    auto ra = store_a.find(hashes[i]);
    auto rb = store_b.find(hashes[i]);
    REQUIRE(ra);
    REQUIRE(rb);
    ra->seconds = rb->seconds = 0;
    REQUIRE(ra->work.has_value() == rb->work.has_value());
    if (ra->work) {
      ra->work->allocated_bytes = rb->work->allocated_bytes;
      ra->work->peak_bytes = rb->work->peak_bytes;
    }
    CHECK(rkhs::serialize_result(*ra) == rkhs::serialize_result(*rb));
  }
}

#endif

}  // namespace

#ifdef RKHS_TEST_MPIEXEC

TEST_CASE("mpirun -np 2 --mpi gives the single-process results bit for bit", "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_equal");
  for (const auto* text : {approximation_study, adaptive_study}) {
    const fs::path study = dir / "study.toml";
    std::ofstream(study) << text;
    fs::remove_all(dir / "mpi");
    fs::remove_all(dir / "single");
    fs::remove(dir / "mpi.sqlite");
    fs::remove(dir / "single.sqlite");
    const auto distributed =
        shell(mpirun(2, "run " + study.string() + " --mpi --no-plots --store " +
                            (dir / "mpi.sqlite").string() + " --out " + (dir / "mpi").string()));
    INFO(distributed.output);
    const auto single =
        rkhs_study("run " + study.string() + " --threads 2 --no-plots --store " +
                   (dir / "single.sqlite").string() + " --out " + (dir / "single").string());
    INFO(single.output);
    // The same exit code (1 for the approximation study: two trials fail by design).
    REQUIRE(distributed.exit_code == single.exit_code);
    REQUIRE(single.exit_code == (text == approximation_study ? 1 : 0));
    // Rank 0 alone reports and writes.
    CHECK_THAT(distributed.output, Catch::Contains("on rank 0 of 2 MPI ranks"));
    CHECK_THAT(distributed.output, Catch::Contains("0 trials reused"));
    std::vector<std::string> outputs{"trials.csv", "rates.csv", "rates.md"};
    if (text == adaptive_study) outputs.insert(outputs.end(), {"estimates.csv", "timeseries.csv"});
    for (const auto& file : outputs) {
      INFO(file);
      const auto expected = read_text(dir / "single" / file);
      REQUIRE_FALSE(expected.empty());
      CHECK(read_text(dir / "mpi" / file) == expected);
    }
    require_same_stored_trials(study, dir / "mpi.sqlite", dir / "single.sqlite");
    // Both ranks ran trials, and the summary says how many.
    const auto summary = read_text(dir / "mpi" / "summary.json");
    CHECK_THAT(summary, Catch::Contains("\"mpi_ranks\": [{\"host\": "));
    CHECK_THAT(summary, !Catch::Contains("\"trials\": 0}"));
    CHECK_THAT(read_text(dir / "mpi" / "report.html"), Catch::Contains("MPI rank 1"));
  }
}

TEST_CASE("rkhs-study --version says that the MPI runner is built in", "[cli][mpi]") {
  const auto version = rkhs_study("--version");
  CHECK(version.exit_code == 0);
  CHECK_THAT(version.output, Catch::Contains("MPI runner: yes"));
}

TEST_CASE("rkhs-study check --mpi judges the same expectations", "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_check");
  const auto study = std::string(RKHS_STUDY_SOURCE_DIR) + "/studies/gram_and_power.toml";
  const auto distributed = shell(mpirun(
      2, "check " + study + " --tier quick --mpi --store " + (dir / "store.sqlite").string()));
  INFO(distributed.output);
  CHECK(distributed.exit_code == 0);
  CHECK_THAT(distributed.output, Catch::Contains("11 passed"));
}

TEST_CASE("rkhs-study check --mpi goes through several studies with every rank", "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_check_several");
  const std::string header = R"([study]
name = "NAME"
evaluation_points = 512
metrics = ["fill_distance", "separation_distance", "power_function_sup"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 60, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8
[[expect]]
metric = "power_function_sup"
theory = true
)";
  std::string files;
  for (const auto* name : {"mpi_first", "mpi_second", "mpi_third"}) {
    auto text = header;
    text.replace(text.find("NAME"), 4, name);
    std::ofstream(dir / (std::string(name) + ".toml")) << text;
    files += " " + (dir / (std::string(name) + ".toml")).string();
  }
  const auto xml = dir / "r.xml";
  const auto distributed = shell(mpirun(
      2, "check" + files + " -k 'degree=2 and not third' --mpi --no-plots --junit " + xml.string() +
             " --out " + (dir / "out").string() + " --store " + (dir / "store.sqlite").string()));
  INFO(distributed.output);
  CHECK(distributed.exit_code == 0);
  CHECK_THAT(distributed.output,
             Catch::Contains("mpi_third: not run: -k selects none of its 2 test cases"));
  CHECK_THAT(distributed.output,
             Catch::Contains("total over 3 studies: 2 passed, 0 failed, 0 inconclusive, 4 "
                             "deselected"));
  const auto junit = rkhs::test::read_text(xml);
  CHECK_THAT(junit, Catch::Contains("<testsuite name=\"mpi_first\" tests=\"1\""));
  CHECK_THAT(junit, Catch::Contains("<testsuite name=\"mpi_second\" tests=\"1\""));
  CHECK_THAT(junit, Catch::Contains("<testsuite name=\"mpi_third\" tests=\"0\""));
  CHECK(fs::exists(dir / "out" / "mpi_second" / "summary.json"));
}

namespace {

const std::string ten_slow_trials = rkhs::test::slow_study("mpi_kill");

// Starts `mpirun -np 2 [mpirun_options] rkhs-study <run>` with its output in `log`, kills rank 1
// with SIGKILL once rank 0 has stored two trials into `store`, and returns mpirun's wait status.
int run_and_kill_rank_1(const std::string& mpirun_options, const std::string& run,
                        const fs::path& store, const fs::path& log) {
  std::string command = mpirun(2, run);
  command.insert(command.find(" -np "), " " + mpirun_options);
  const pid_t launcher = fork();
  if (launcher == 0) {
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, 1);
    dup2(out, 2);
    execl("/bin/sh", "sh", "-c", ("exec env " + mpi_environment + " " + command).c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // Rank 1 is the launcher's child whose environment says so.
  pid_t rank1 = 0;
  rkhs::test::wait_until(
      [&] {
        REQUIRE(waitpid(launcher, nullptr, WNOHANG) == 0);
        if (!fs::exists(store) || rkhs::ResultStore(store).size() < 2) return false;
        for (const auto& entry : fs::directory_iterator("/proc")) {
          const auto status = read_text(entry.path() / "status");
          if (status.find("\nPPid:\t" + std::to_string(launcher) + "\n") == std::string::npos)
            continue;
          const auto variables = read_text(entry.path() / "environ");
          if (variables.find(std::string("OMPI_COMM_WORLD_RANK=1") + '\0') != std::string::npos)
            rank1 = static_cast<pid_t>(std::stol(entry.path().filename().string()));
        }
        return rank1 > 0;
      },
      30);
  REQUIRE(rank1 > 0);
  kill(rank1, SIGKILL);
  int status = 0;
  waitpid(launcher, &status, 0);
  return status;
}

}  // namespace

TEST_CASE("an MPI rank killed midway loses only its trials in flight", "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_kill");
  std::ofstream(dir / "study.toml") << ten_slow_trials;
  const auto store = dir / "store.sqlite";
  const auto run = "run " + (dir / "study.toml").string() +
                   " --mpi --threads 1 --no-plots --store " + store.string() + " --out " +
                   (dir / "out").string();
  // mpirun's default: the death of a rank ends the job.
  const int status = run_and_kill_rank_1("", run, store, dir / "killed.log");
  CHECK_FALSE((WIFEXITED(status) && WEXITSTATUS(status) == 0));  // the job failed
  const auto stored_before = rkhs::ResultStore(store).size();
  CHECK(stored_before >= 2);
  CHECK(stored_before < 10);

  const auto resumed = shell(mpirun(2, run));
  INFO(resumed.output);
  REQUIRE(resumed.exit_code == 0);
  CHECK_THAT(resumed.output, Catch::Contains(rkhs::test::trials_text(stored_before) + " reused"));
  CHECK(rkhs::ResultStore(store).size() == 10);
  const auto clean = rkhs_study("run " + (dir / "study.toml").string() +
                                " --quiet --no-plots --no-store --out " + (dir / "clean").string());
  REQUIRE(clean.exit_code == 0);
  CHECK(read_text(dir / "out" / "trials.csv") == read_text(dir / "clean" / "trials.csv"));
  CHECK(read_text(dir / "out" / "rates.csv") == read_text(dir / "clean" / "rates.csv"));
}

TEST_CASE("with mpirun --enable-recovery the other ranks finish a killed rank's trials",
          "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_recovery");
  std::ofstream(dir / "study.toml") << ten_slow_trials;
  const auto store = dir / "store.sqlite";
  const auto log = dir / "run.log";
  const auto run = "run " + (dir / "study.toml").string() +
                   " --mpi --threads 1 --rank-timeout 2 --no-plots --store " + store.string() +
                   " --out " + (dir / "out").string();
  const int status = run_and_kill_rank_1("--enable-recovery", run, store, log);
  const auto output = read_text(log);
  INFO(output);
  // Rank 0 noticed the silence, ran the lost trials itself and completed the study.
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK_THAT(output, Catch::Contains("MPI rank 1 (") &&
                         Catch::Contains("sent nothing for 2 s: taken as lost"));
  CHECK_THAT(output, Catch::Contains("10 trials, 10 ok, 0 failed"));
  CHECK(rkhs::ResultStore(store).size() == 10);
  CHECK_THAT(read_text(dir / "out" / "summary.json"), Catch::Contains("\"lost\": true"));
  const auto clean = rkhs_study("run " + (dir / "study.toml").string() +
                                " --quiet --no-plots --no-store --out " + (dir / "clean").string());
  REQUIRE(clean.exit_code == 0);
  CHECK(read_text(dir / "out" / "trials.csv") == read_text(dir / "clean" / "trials.csv"));
  CHECK(read_text(dir / "out" / "rates.csv") == read_text(dir / "clean" / "rates.csv"));
}

TEST_CASE("Ctrl-C to mpirun: finished trials are stored, rank 0 says how to resume", "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_sigint");
  // 39 trials, so that the run is far from its end when the first trial is stored.
  std::string study = rkhs::test::slow_study("mpi_sigint", "[0.5, 0.7, 0.9]");
  study.replace(study.find("step = 150"), 10, "step = 50");
  std::ofstream(dir / "study.toml") << study;
  const auto store = dir / "store.sqlite";
  const auto log = dir / "log.txt";
  const auto run = "run " + (dir / "study.toml").string() +
                   " --mpi --threads 1 --no-plots --store " + store.string() + " --out " +
                   (dir / "out").string();
  const pid_t launcher = fork();
  if (launcher == 0) {
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, 1);
    dup2(out, 2);
    // mpirun waits odls_base_sigkill_timeout seconds, passes the signal on as SIGTERM and
    // kills the ranks as long again later (Open MPI's default: 1 s; docs/cluster.md): on a
    // loaded machine that can be less than the trials in flight need to stop, so the test gives
    // the ranks the 3 s a user would give them (the study is far from done 3 s after the signal),
    // times the patience of a sanitizer build, whose ranks run several times slower.
    const std::string grace = std::to_string(3 * rkhs::test::patience);
    execl("/bin/sh", "sh", "-c",
          ("exec env " + mpi_environment + " OMPI_MCA_odls_base_sigkill_timeout=" + grace + " " +
           mpirun(2, run))
              .c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  REQUIRE(rkhs::test::wait_until(
      [&] {
        REQUIRE(waitpid(launcher, nullptr, WNOHANG) == 0);
        return fs::exists(store) && rkhs::ResultStore(store).size() >= 1;
      },
      30));
  kill(launcher, SIGINT);
  int status = 0;
  waitpid(launcher, &status, 0);
  const auto output = read_text(log);
  INFO(output);
  CHECK_FALSE((WIFEXITED(status) && WEXITSTATUS(status) == 0));
  CHECK_THAT(output, Catch::Contains("Run the same command again to resume"));
  CHECK_FALSE(fs::exists(dir / "out" / "trials.csv"));  // outputs are for complete runs
  const auto stored = rkhs::ResultStore(store).size();
  CHECK(stored >= 1);
  CHECK(stored < 39);
  CHECK_THAT(output, Catch::Contains("interrupted: " + rkhs::test::trials_text(stored) +
                                     " finished and stored"));
  const auto resumed = shell(mpirun(2, run));
  INFO(resumed.output);
  CHECK(resumed.exit_code == 0);
  CHECK_THAT(resumed.output, Catch::Contains(rkhs::test::trials_text(stored) + " reused"));
  CHECK(rkhs::ResultStore(store).size() == 39);
}

TEST_CASE("ranks that disagree on the study, or a launch without --mpi, run nothing",
          "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_refuse");
  std::ofstream(dir / "a.toml") << approximation_study;
  std::string other = approximation_study;
  other.replace(other.find("sigma = [0.5, 1.0]"), 18, "sigma = [0.5, 0.9]");
  std::ofstream(dir / "b.toml") << other;
  const auto store = (dir / "store.sqlite").string();
  // Open MPI's MPMD form: rank 0 reads a.toml, rank 1 b.toml (same name, other trials).
  const auto mixed = shell(fmt::format(
      "{0} --oversubscribe -np 1 {1} run {2} --mpi --store {4} --out {5} : -np 1 {1} run {3} --mpi "
      "--store {4} --out {5}",
      RKHS_TEST_MPIEXEC, RKHS_STUDY_EXECUTABLE, (dir / "a.toml").string(),
      (dir / "b.toml").string(), store, (dir / "out").string()));
  INFO(mixed.output);
  CHECK(mixed.exit_code == 2);
  CHECK_THAT(mixed.output,
             Catch::Contains("the MPI ranks do not agree on the study's trials, nothing was run"));
  CHECK_THAT(mixed.output, Catch::Contains("rank 1 sees other trials than rank 0"));
  CHECK_FALSE(fs::exists(store));
  CHECK_FALSE(fs::exists(dir / "out"));

  const auto without = shell(mpirun(2, "run " + (dir / "a.toml").string() + " --store " + store +
                                           " --out " + (dir / "out").string()));
  INFO(without.output);
  CHECK(without.exit_code == 2);
  CHECK_THAT(without.output, Catch::Contains("started as 2 MPI processes without --mpi"));
  CHECK_FALSE(fs::exists(store));

  const auto broken = shell(mpirun(2, "run " + (dir / "missing.toml").string() + " --mpi"));
  CHECK(broken.exit_code == 2);

  // A study file error that every rank meets is said once, by rank 0, in its own form.
  std::ofstream(dir / "bad.toml") << "[study]\nname = \"bad\"\n";
  const auto bad = shell(mpirun(2, "run " + (dir / "bad.toml").string() + " --mpi --store " +
                                       store + " --out " + (dir / "out").string()));
  INFO(bad.output);
  CHECK(bad.exit_code == 2);
  const std::string error = (dir / "bad.toml").string() + ": domain: missing [domain] table";
  REQUIRE_THAT(bad.output, Catch::Contains(error));
  CHECK(bad.output.find(error) == bad.output.rfind(error));
  CHECK_THAT(bad.output, !Catch::Contains("MPI ranks cannot go on"));
  CHECK_FALSE(fs::exists(store));
  // Likewise a plugin that no rank can load.
  const auto plugin = shell(mpirun(2, "run " + (dir / "a.toml").string() + " --mpi --plugin " +
                                          (dir / "missing.so").string() + " --store " + store));
  INFO(plugin.output);
  CHECK(plugin.exit_code == 2);
  const std::string plugin_error = (dir / "missing.so").string() + ": plugin file not found";
  REQUIRE_THAT(plugin.output, Catch::Contains(plugin_error));
  CHECK(plugin.output.find(plugin_error) == plugin.output.rfind(plugin_error));
  CHECK_THAT(plugin.output, !Catch::Contains("MPI ranks cannot go on"));
  CHECK_FALSE(fs::exists(store));

  const auto shard = rkhs_study("run " + (dir / "a.toml").string() + " --mpi --shard 1/2");
  CHECK(shard.exit_code == 2);
  CHECK_THAT(shard.output, Catch::Contains("--mpi and --shard exclude each other"));
}

#else

TEST_CASE("a build without MPI says that --mpi is not available", "[cli][mpi]") {
  const auto dir = rkhs::test::scratch_directory("mpi_none");
  std::ofstream(dir / "a.toml") << approximation_study;
  const auto outcome = rkhs_study("run " + (dir / "a.toml").string() + " --mpi --no-store");
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains("built without MPI"));
  CHECK_THAT(rkhs_study("--version").output, Catch::Contains("MPI runner: no"));
  (void)adaptive_study;
}

#endif
