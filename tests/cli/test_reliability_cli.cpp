// Reliability as a user meets it: stored records that were edited or damaged are reported by
// store and trial and run again (trials.csv equals a clean run's); study files that ask for
// too much are refused at once with file:line:column; an output write that fails leaves no
// temporary behind; a store file copied alone after a run holds every trial.
#include <fcntl.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "cli_support.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/plugin/build_configuration.hpp"
#include "rkhs/run/result_store.hpp"

namespace fs = std::filesystem;
using rkhs::test::read_text;
using rkhs::test::rkhs_study;

namespace {

const char* const small_study = R"([study]
name = "reliable"
evaluation_points = 1024
[domain]
radius = 4
[grid]
n = [8, 16, 32, 64, 200]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
)";

// The rows of a store's table, by key: hash and record.
struct Row {
  std::string hash, key, record;
};
std::vector<Row> rows_of(const fs::path& store) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(store.c_str(), &db) == SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, "SELECT hash, key, result FROM trials ORDER BY key", -1,
                             &statement, nullptr) == SQLITE_OK);
  std::vector<Row> rows;
  while (sqlite3_step(statement) == SQLITE_ROW) {
    auto text = [&](int i) {
      return std::string(reinterpret_cast<const char*>(sqlite3_column_text(statement, i)));
    };
    rows.push_back({text(0), text(1), text(2)});
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return rows;
}

// Replaces the record of `hash` in the store, as someone editing the row would.
void edit_record(const fs::path& store, const std::string& hash, const std::string& record) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(store.c_str(), &db) == SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, "UPDATE trials SET result = ?1 WHERE hash = ?2", -1, &statement,
                             nullptr) == SQLITE_OK);
  sqlite3_bind_text(statement, 1, record.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement, 2, hash.c_str(), -1, SQLITE_TRANSIENT);
  REQUIRE(sqlite3_step(statement) == SQLITE_DONE);
  sqlite3_finalize(statement);
  sqlite3_close(db);
}

// A record's body (before its checksum line) sealed again with a valid checksum: the edit of
// someone who knows the format (docs/results.md), so that what is caught is the content.
// Format 3: SHA-256 of the hash, the study and the key (one line each) and the body.
std::string resealed(const std::string& hash, const std::string& key, const std::string& body) {
  return body + "checksum " + rkhs::sha256_hex(hash + "\nreliable\n" + key + "\n" + body) + "\n";
}
std::string body_of(const std::string& record) {
  return record.substr(0, record.rfind("checksum "));
}

std::vector<std::string> temporaries_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.path().filename().string().find(".tmp") != std::string::npos)
      out.push_back(entry.path().string());
  return out;
}

}  // namespace

TEST_CASE("edited stored records are reported by store and trial and run again",
          "[cli][store][reliability]") {
  const auto dir = rkhs::test::scratch_directory("reliable_records");
  std::ofstream(dir / "study.toml") << small_study;
  const auto study = (dir / "study.toml").string();
  const auto store = dir / "store.sqlite";
  const auto run = [&](const std::string& out) {
    return rkhs_study("run " + study + " --quiet --no-plots --store " + store.string() + " --out " +
                      (dir / out).string());
  };
  REQUIRE(run("first").exit_code == 0);
  REQUIRE(rkhs_study("run " + study + " --quiet --no-plots --no-store --out " +
                     (dir / "clean").string())
              .exit_code == 0);
  const auto rows = rows_of(store);
  REQUIRE(rows.size() == 10);
  // n = 200 first: its gram_condition_number (inf) would shift onto a finite value.
  const auto& too_many = rows[1];  // keys sort "n=16" < "n=200" < "n=32" < ...
  REQUIRE_THAT(too_many.key, Catch::EndsWith("n=200"));
  edit_record(store, too_many.hash, resealed(too_many.hash, too_many.key, [&] {
                auto body = body_of(too_many.record);
                return body.replace(body.find("\nmetrics "), 9, "\nmetrics 0.0628 ");
              }()));
  auto flipped = rows[2].record;
  flipped[flipped.rfind("checksum ") + 9] =
      flipped[flipped.rfind("checksum ") + 9] == '0' ? '1' : '0';
  edit_record(store, rows[2].hash, flipped);
  edit_record(store, rows[3].hash, resealed(rows[3].hash, rows[3].key, [&] {
                auto body = body_of(rows[3].record);
                const auto at = body.find("\nmetrics ") + 9;
                return body.replace(at, body.find(' ', at) - at, "x");
              }()));
  const auto& old = rows[4];  // a record of the previous format: the result alone
  edit_record(store, old.hash,
              body_of(old.record).substr(body_of(old.record).find("rkhs-trial 1")));

  // `store check` names every bad record by key and exits 1 (the edited record holds one value
  // more than an approximation trial has metrics).
  const auto metrics = rkhs::approximation_metric_names().size();
  const auto one_too_many = std::to_string(metrics + 1) + " metric values for " +
                            std::to_string(metrics) + " metric names";
  const auto check = rkhs_study("store check --store " + store.string());
  INFO(check.output);
  CHECK(check.exit_code == 1);
  CHECK_THAT(check.output, Catch::Contains(store.string() + ": trial " + too_many.key +
                                           " (study reliable, hash " + too_many.hash.substr(0, 12) +
                                           "): " + one_too_many));
  CHECK_THAT(check.output, Catch::Contains(": trial " + rows[2].key + " (study reliable, hash " +
                                           rows[2].hash.substr(0, 12) + "): checksum mismatch"));
  CHECK_THAT(check.output,
             Catch::Contains(": trial " + rows[3].key + " (study reliable, hash " +
                             rows[3].hash.substr(0, 12) + "): stored value 'x' is not a number"));
  CHECK_THAT(check.output,
             Catch::Contains(store.string() + ": 10 records, 6 verified, 3 bad, 1 in the old "
                                              "record format (no checksum)"));

  // A run reports them, runs them again and writes exactly what a clean run writes.
  const auto again = run("again");
  INFO(again.output);
  CHECK(again.exit_code == 0);
  CHECK_THAT(again.output, Catch::Contains("rkhs-study: warning: " + store.string() + ": trial " +
                                           too_many.key + ": " + one_too_many + "; run again"));
  CHECK_THAT(again.output, Catch::Contains(": trial " + rows[2].key + ": checksum mismatch"));
  CHECK_THAT(again.output,
             Catch::Contains(": trial " + rows[3].key + ": stored value 'x' is not a number"));
  CHECK_THAT(again.output, Catch::Contains(store.string() + ": 1 trial stored in the old record "
                                                            "format (no checksum): run again"));
  CHECK(read_text(dir / "again" / "trials.csv") == read_text(dir / "clean" / "trials.csv"));
  CHECK(read_text(dir / "again" / "rates.csv") == read_text(dir / "clean" / "rates.csv"));
  // Stored anew: the store verifies, and a third run reuses everything without a word.
  CHECK(rkhs_study("store check --store " + store.string()).exit_code == 0);
  const auto third = rkhs_study("run " + study + " --no-plots --store " + store.string() +
                                " --out " + (dir / "third").string());
  CHECK_THAT(third.output, Catch::Contains("10 trials reused"));
  CHECK_THAT(third.output, !Catch::Contains("warning: " + store.string()));
}

TEST_CASE("store vacuum removes what does not verify: store export writes CSV and JSON",
          "[cli][store][reliability]") {
  const auto dir = rkhs::test::scratch_directory("reliable_vacuum");
  std::ofstream(dir / "study.toml") << small_study;
  const auto store = dir / "store.sqlite";
  REQUIRE(rkhs_study("run " + (dir / "study.toml").string() + " --quiet --no-plots --store " +
                     store.string() + " --out " + (dir / "out").string())
              .exit_code == 0);
  const auto rows = rows_of(store);
  edit_record(store, rows[0].hash, "garbage");
  const auto vacuum = rkhs_study("store vacuum --store " + store.string());
  INFO(vacuum.output);
  CHECK(vacuum.exit_code == 0);
  CHECK_THAT(vacuum.output,
             Catch::Contains("removed " + store.string() + ": trial " + rows[0].key));
  CHECK_THAT(vacuum.output,
             Catch::Contains("removed 1 bad and 0 old-format records; it holds 9 trials"));
  CHECK(rkhs::ResultStore(store).size() == 9);

  const auto csv = rkhs_study("store export --store " + store.string());
  CHECK(csv.exit_code == 0);
  CHECK_THAT(csv.output, Catch::StartsWith("hash,study,key,stored,check,status,reason,solve,engine,"
                                           "flags,seconds,data,fill_distance,"));
  CHECK(std::count(csv.output.begin(), csv.output.end(), '\n') == 10);
  CHECK(rkhs_study("store export --format json --out " + (dir / "all.json").string() + " --store " +
                   store.string())
            .exit_code == 0);
  const auto json = read_text(dir / "all.json");
  CHECK_THAT(json, Catch::StartsWith("[\n  {\"hash\": \""));
  CHECK_THAT(json, Catch::Contains("\"gram_condition_number\": \"inf\""));
  CHECK(rkhs_study("store check --store " + (dir / "none.sqlite").string()).exit_code == 2);
  CHECK_FALSE(fs::exists(dir / "none.sqlite"));
}

TEST_CASE("a study file that asks for too much is refused at once", "[cli][reliability]") {
  const auto dir = rkhs::test::scratch_directory("reliable_limits");
  // 200 x 300 x 360 = 21.6 million trials from a few kB.
  std::string sigmas, amplitudes;
  for (int i = 0; i < 200; ++i) sigmas += (i ? ", " : "") + std::to_string(0.1 + 0.01 * i);
  for (int i = 0; i < 300; ++i) amplitudes += (i ? ", " : "") + std::to_string(1 + 0.01 * i);
  std::ofstream(dir / "huge.toml")
      << "[study]\nname = \"huge\"\nevaluation_points = 2048\n[domain]\nradius = 4\n[grid]\n"
         "n = { from = 1, to = 360, step = 1 }\n[[kernel]]\nname = \"gaussian\"\nsigma = ["
      << sigmas << "]\n[[target]]\nname = \"sine\"\namplitude = [" << amplitudes << "]\n";
  std::ofstream(dir / "range.toml")
      << "[study]\nname = \"range\"\n[domain]\nradius = 4\n[grid]\n"
         "n = { from = 9223372036854775000, to = 9223372036854775807, step = 500 }\n"
         "[[kernel]]\nname = \"gaussian\"\n";
  const std::string run_options = " --no-store --out " + (dir / "out").string();
  for (const std::string command : {"validate", "run"}) {
    const auto options = command == "run" ? run_options : std::string();
    const auto start = std::chrono::steady_clock::now();
    // Under 1 GB of address space: expanding the grid would need about 10 GB. AddressSanitizer
    // reserves terabytes of shadow address space at start, so under it there is no cap (the
    // other builds check the memory claim).
    const std::string cap =
        RKHS_DETAIL_SANITIZER == rkhs::SanitizerKind::address ? "" : "ulimit -v 1000000; ";
    const auto huge =
        rkhs::test::run_command("bash -c '" + cap + "exec " + std::string(RKHS_STUDY_EXECUTABLE) +
                                " " + command + " " + (dir / "huge.toml").string() + options + "'");
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    INFO(command << ": " << huge.output);
    CHECK(huge.exit_code == 2);
    CHECK(seconds < 1);
    CHECK_THAT(huge.output,
               Catch::StartsWith((dir / "huge.toml").string() +
                                 ":7:5: grid.n: the grid has 21600000 trials, more than [limits] "
                                 "trials = 1000000: 200 kernels ([[kernel]] 'gaussian' at line "
                                 "8: sigma 200) x 300 targets ([[target]] 'sine' at line 11: "
                                 "amplitude 300) x 1 centre placement (the default) x 360 values "
                                 "of n"));
    const auto range = rkhs_study(command + " " + (dir / "range.toml").string() + options);
    CHECK(range.exit_code == 2);
    CHECK(range.output == (dir / "range.toml").string() +
                              ":6:14: grid.n.from: must be between 1 and 1000000000 (centres), "
                              "found 9223372036854775000\n");
  }
}

TEST_CASE("an output write that fails leaves no temporary behind", "[cli][reliability]") {
  const auto dir = rkhs::test::scratch_directory("reliable_full_disk");
  std::ofstream(dir / "study.toml") << small_study;
  // A full disk, as the file size limit makes it (2 kB: summary.json does not fit).
  const auto full = rkhs::test::run_command(
      "bash -c \"trap '' XFSZ; ulimit -f 2; exec " + std::string(RKHS_STUDY_EXECUTABLE) + " run " +
      (dir / "study.toml").string() + " --quiet --no-plots --no-store --out " +
      (dir / "out").string() + "\"");
  INFO(full.output);
  CHECK(full.exit_code != 0);
  CHECK_THAT(full.output, Catch::Contains("rkhs-study: cannot write " + (dir / "out").string()));
  CHECK_THAT(full.output, Catch::Contains("File too large"));
  CHECK(temporaries_in(dir / "out").empty());
}

TEST_CASE("after a run the store file alone holds every trial", "[cli][store][reliability]") {
  // Another connection keeps the store open, so SQLite does not checkpoint on close: only the
  // run's own checkpoint moves its trials from the -wal file into the store file.
  const auto dir = rkhs::test::scratch_directory("reliable_copy");
  std::ofstream(dir / "study.toml") << small_study;
  const auto store = dir / "store.sqlite";
  rkhs::ResultStore holder(store);
  const auto run =
      rkhs_study("run " + (dir / "study.toml").string() + " --quiet --no-plots --store " +
                 store.string() + " --out " + (dir / "out").string());
  REQUIRE(run.exit_code == 0);
  fs::copy_file(store, dir / "copy.sqlite");  // without store.sqlite-wal
  CHECK(rkhs::ResultStore(dir / "copy.sqlite").size() == 10);
}

TEST_CASE("SIGTERM ends a run within 2 s while every thread is inside a long trial",
          "[cli][store][reliability]") {
  // Two trials of minutes each (eigendecompositions of 4000 x 4000 Gram matrices, without
  // cancellation points), one per thread: the machine is busy when the signal arrives.
  const auto dir = rkhs::test::scratch_directory("reliable_sigterm");
  std::ofstream(dir / "study.toml") << R"([study]
name = "busy"
evaluation_points = 16384
metrics = ["gram_condition_number", "power_function_sup"]
[domain]
radius = 4
[grid]
n = [4000, 4001]
[[kernel]]
name = "matern"
nu = 2.5
)";
  const auto log = dir / "log.txt";
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, 1);
    dup2(out, 2);
    const std::string study = (dir / "study.toml").string(), store = (dir / "s.sqlite").string();
    execl(RKHS_STUDY_EXECUTABLE, RKHS_STUDY_EXECUTABLE, "run", study.c_str(), "--threads", "2",
          "--store", store.c_str(), nullptr);
    _exit(127);
  }
  // Until both trials are running (the progress line says so), then 2 s more inside them.
  REQUIRE(rkhs::test::wait_until(
      [&] {
        REQUIRE(waitpid(pid, nullptr, WNOHANG) == 0);
        return read_text(log).find("running 2: ") != std::string::npos;
      },
      30));
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const auto signalled = std::chrono::steady_clock::now();
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  INFO(read_text(log));
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK(seconds < 2);
  CHECK_THAT(read_text(log), Catch::Contains("2 stopped while running"));
}

// Issue 50: `validate /dev/zero` grew to 23.8 GB, a FIFO as the study file blocked forever, a
// 300 MB study file was read whole, and a store that is a directory was "no such result
// store". Each command runs under `timeout`: a hang fails.
TEST_CASE(
    "study files and stores that are not regular files are refused by type, huge ones by size",
    "[cli][reliability][hostile]") {
  const auto dir = rkhs::test::scratch_directory("reliable_special_files");
  const auto fifo = dir / "study.toml";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  const auto refused = [](const std::string& arguments, const std::string& why) {
    const auto out = rkhs_study(arguments, "timeout 20");
    INFO(arguments << ": " << out.output);
    CHECK(out.exit_code == 2);
    CHECK_THAT(out.output, Catch::Contains(why));
  };
  const std::string out = " --no-store --out " + (dir / "out").string();
  for (const std::string command : {"validate ", "check ", "run "}) {
    const std::string options = command == "validate " ? "" : out;
    refused(command + "/dev/zero" + options,
            "/dev/zero: is a character device, not a study file (a regular file)");
    refused(command + fifo.string() + options,
            fifo.string() + ": is a FIFO, not a study file (a regular file)");
    refused(command + dir.string() + options,
            dir.string() + ": is a directory, not a study file (a regular file)");
  }
  const auto big = dir / "big.toml";
  std::ofstream(big) << small_study;
  fs::resize_file(big, std::uintmax_t{300} << 20);  // sparse
  refused("validate " + big.string(),
          big.string() +
              ": is 314572800 bytes, more than the 4194304 bytes (4 MiB) a study file may have");

  std::ofstream(dir / "small.toml") << small_study;
  const std::string store_fifo = (dir / "store.sqlite").string();
  REQUIRE(mkfifo(store_fifo.c_str(), 0600) == 0);
  for (const auto& [store, kind] : {std::pair{store_fifo, std::string("a FIFO")},
                                    std::pair{dir.string(), std::string("a directory")}}) {
    const std::string why = store + ": is " + kind + ", not a result store";
    refused("store check --store " + store, why);
    refused("run " + (dir / "small.toml").string() + " --store " + store + " --out " +
                (dir / "out").string(),
            why);
    refused("merge " + (dir / "into.sqlite").string() + " " + store, why);
  }
}

// Issue 50: while gnuplot hung, `run` ignored SIGTERM and SIGINT (alive after 11 minutes). A
// gnuplot on PATH that never ends (it waits for a child of its own): SIGTERM ends the run
// within 2 s, gnuplot's whole process group is killed, and without a signal the plot's time
// limit ends it.
TEST_CASE("a hanging gnuplot is killed at SIGTERM and at its time limit",
          "[cli][reliability][plots][hostile]") {
  const auto dir = rkhs::test::scratch_directory("reliable_gnuplot_hangs");
  fs::create_directories(dir / "bin");
  const auto gnuplot = dir / "bin" / "gnuplot";
  std::ofstream(gnuplot) << "#!/bin/sh\nsleep 1000 &\necho $! > " << (dir / "sleep.pid").string()
                         << "\nwait\n";
  fs::permissions(gnuplot, fs::perms::owner_all);
  std::ofstream(dir / "study.toml") << R"([study]
name = "plotted"
evaluation_points = 512
metrics = ["gram_condition_number"]
[domain]
radius = 4
[grid]
n = [8, 16, 32]
[[kernel]]
name = "gaussian"
sigma = 1.0
)";
  const auto start = [&](const std::string& seconds) {
    fs::remove(dir / "sleep.pid");
    const pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      const int out = ::open((dir / "log.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(out, 1);
      dup2(out, 2);
      setenv("PATH", ((dir / "bin").string() + ":/usr/bin:/bin").c_str(), 1);
      if (!seconds.empty()) setenv("RKHS_STUDY_GNUPLOT_SECONDS", seconds.c_str(), 1);
      const std::string study = (dir / "study.toml").string(), out_dir = (dir / "out").string();
      execl(RKHS_STUDY_EXECUTABLE, RKHS_STUDY_EXECUTABLE, "run", study.c_str(), "--no-store",
            "--out", out_dir.c_str(), nullptr);
      _exit(127);
    }
    // Until the fake gnuplot runs (its child's pid is written).
    REQUIRE(rkhs::test::wait_until(
        [&] {
          REQUIRE(waitpid(pid, nullptr, WNOHANG) == 0);
          return !read_text(dir / "sleep.pid").empty();
        },
        30));
    return pid;
  };
  const auto sleep_alive = [&] {
    const auto pid = std::stoi(read_text(dir / "sleep.pid"));
    // Reaped by init once killed; a zombie of our own it cannot be (not our child).
    return kill(pid, 0) == 0 &&
           read_text("/proc/" + std::to_string(pid) + "/stat").find(") Z") == std::string::npos;
  };

  {
    const pid_t pid = start("");
    const auto signalled = std::chrono::steady_clock::now();
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
    INFO(read_text(dir / "log.txt"));
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
    CHECK(seconds < 2);
    CHECK_THAT(read_text(dir / "log.txt"),
               Catch::Contains("gnuplot was killed: the command was interrupted") &&
                   Catch::Contains("interrupted while rendering plots"));
    CHECK(rkhs::test::wait_until([&] { return !sleep_alive(); }, 2));
    CHECK(fs::exists(dir / "out" / "trials.csv"));
  }
  {
    const pid_t pid = start("1");
    int status = 0;
    waitpid(pid, &status, 0);
    INFO(read_text(dir / "log.txt"));
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 0);
    CHECK_THAT(read_text(dir / "log.txt"),
               Catch::Contains("gnuplot did not finish within 1 s and was killed"));
    CHECK(rkhs::test::wait_until([&] { return !sleep_alive(); }, 2));
  }
}
