// The store proves what it holds (issue 36): `store check` runs SQLite's integrity check, the
// record checksum covers the key and study columns, `merge` verifies what it copies, refuses
// conflicts unless told which record wins and is all-or-nothing, the commands that only read
// open the database read-only and refuse a database that is not a store, and a full disk ends a
// run with exit 2 and a message (the trials committed before it kept), never with SIGABRT.
#include <fcntl.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <optional>

#include "background_command.hpp"
#include "cli_support.hpp"
#include "rkhs/core/sha256.hpp"

namespace fs = std::filesystem;
using rkhs::test::read_text;
using rkhs::test::rkhs_study;

namespace {

const char* const proof_study = R"([study]
name = "proof"
evaluation_points = 256
[domain]
radius = 4
[grid]
n = [8, 16, 32, 64, 128]
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
)";

// A store of the ten trials of `proof_study` (the study file is dir/study.toml, the run's
// outputs dir/out).
fs::path make_store(const fs::path& dir, const std::string& name = "store.sqlite") {
  if (!fs::exists(dir / "study.toml")) std::ofstream(dir / "study.toml") << proof_study;
  const auto store = dir / name;
  const auto run =
      rkhs_study("run " + (dir / "study.toml").string() + " --quiet --no-plots --store " +
                 store.string() + " --out " + (dir / "out").string());
  INFO(run.output);
  REQUIRE(run.exit_code == 0);
  return store;
}

std::string bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs `sql` on the database `file` (a connection of its own, as another program would).
void execute(const fs::path& file, const std::string& sql) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(file.c_str(), &db) == SQLITE_OK);
  char* message = nullptr;
  const int status = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message);
  INFO((message ? message : ""));
  sqlite3_free(message);
  sqlite3_close(db);
  REQUIRE(status == SQLITE_OK);
}

// The rows of `SELECT ...` on `file`, each a vector of its columns as text.
std::vector<std::vector<std::string>> rows(const fs::path& file, const std::string& sql) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) == SQLITE_OK);
  std::vector<std::vector<std::string>> out;
  while (sqlite3_step(statement) == SQLITE_ROW) {
    std::vector<std::string> row;
    for (int i = 0; i < sqlite3_column_count(statement); ++i) {
      const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement, i));
      row.emplace_back(text ? text : "");
    }
    out.push_back(std::move(row));
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return out;
}

// A record of format 3 sealed again after an edit of its body, as docs/results.md describes the
// checksum: SHA-256 of the hash, the study, the key (each on a line of its own) and the body.
std::string resealed(const std::string& hash, const std::string& study, const std::string& key,
                     const std::string& body) {
  return body + "checksum " + rkhs::sha256_hex(hash + "\n" + study + "\n" + key + "\n" + body) +
         "\n";
}

bool has_side_files(const fs::path& file) {
  return fs::exists(file.string() + "-wal") || fs::exists(file.string() + "-shm") ||
         fs::exists(file.string() + "-journal");
}

// `rkhs-study ARGS` as a user who cannot write `dir` or the files in it when the tests run as
// root (where file modes do not keep a process from writing): as nobody, through setpriv.
constexpr const char* unprivileged = "/usr/bin/setpriv --reuid=65534 --regid=65534 --clear-groups";

// Whether user nobody can run the binary and read `store` (a checkout in a folder only root
// may enter, such as mktemp's, hides both from it).
bool nobody_can_read(const fs::path& store) {
  if (geteuid() != 0 || !fs::exists("/usr/bin/setpriv")) return false;
  if (rkhs_study("--version", unprivileged).exit_code != 0) return false;
  const std::string probe =
      std::string(unprivileged) + " /usr/bin/test -r '" + store.string() + "' 2>/dev/null";
  return std::system(probe.c_str()) == 0;
}

// As user nobody when it can (root reads any file whatever its mode), otherwise as this user.
rkhs::test::CommandOutcome as_reader(const std::string& arguments, const fs::path& store) {
  if (!nobody_can_read(store)) return rkhs_study(arguments);
  return rkhs_study(arguments, unprivileged);
}

// `file` with `count` more records: copies of its first record under hashes and keys of their
// own, each sealed with the documented checksum (so that every one verifies), in one
// transaction.
void add_copies(const fs::path& file, std::size_t count) {
  const auto row = rows(file, "SELECT study, key, result FROM trials ORDER BY key LIMIT 1")[0];
  const auto body = row[2].substr(0, row[2].rfind("checksum "));
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(file.c_str(), &db) == SQLITE_OK);
  REQUIRE(sqlite3_exec(db, "BEGIN", nullptr, nullptr, nullptr) == SQLITE_OK);
  sqlite3_stmt* insert = nullptr;
  REQUIRE(sqlite3_prepare_v2(db,
                             "INSERT INTO trials (hash, study, key, result, stored) "
                             "VALUES (?1, ?2, ?3, ?4, '2024-01-01 00:00:00')",
                             -1, &insert, nullptr) == SQLITE_OK);
  bool inserted = true;
  for (std::size_t i = 0; i < count && inserted; ++i) {
    const auto hash = rkhs::sha256_hex("copy " + std::to_string(i));
    const auto key = row[1] + " | copy=" + std::to_string(i);
    const auto record = resealed(hash, row[0], key, body);
    sqlite3_reset(insert);
    sqlite3_bind_text(insert, 1, hash.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert, 2, row[0].c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert, 3, key.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert, 4, record.c_str(), -1, SQLITE_TRANSIENT);
    inserted = sqlite3_step(insert) == SQLITE_DONE;
  }
  sqlite3_finalize(insert);
  const int committed = sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  REQUIRE(inserted);
  REQUIRE(committed == SQLITE_OK);
}


// The size of `file`, 0 when it does not exist.
std::uintmax_t size_of(const fs::path& file) {
  std::error_code error;
  const auto size = fs::file_size(file, error);
  return error ? 0 : size;
}

}  // namespace

TEST_CASE("store check runs SQLite's integrity check: a flipped byte of the index fails it",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_integrity");
  const auto store = make_store(dir);
  // The page of the primary key's index (SQLite's dbstat), and a stored hash in it.
  const auto pages = rows(store,
                          "SELECT pageno FROM dbstat WHERE name = 'sqlite_autoindex_trials_1' "
                          "AND pagetype = 'leaf' ORDER BY pageno LIMIT 1");
  REQUIRE(pages.size() == 1);
  const auto page_size = std::stoul(rows(store, "PRAGMA page_size")[0][0]);
  const auto hash = rows(store, "SELECT hash FROM trials ORDER BY hash LIMIT 1 OFFSET 4")[0][0];
  auto bytes = bytes_of(store);
  const auto page_start = (std::stoul(pages[0][0]) - 1) * page_size;
  const auto at = bytes.find(hash, page_start);
  REQUIRE(at != std::string::npos);
  REQUIRE(at < page_start + page_size);
  bytes[at + 20] = bytes[at + 20] == 'a' ? 'b' : 'a';  // still a hex digit
  std::ofstream(store, std::ios::binary | std::ios::trunc) << bytes;

  const auto check = rkhs_study("store check --store " + store.string());
  INFO(check.output);
  CHECK(check.exit_code == 1);
  CHECK_THAT(check.output, Catch::Contains(store.string() + ": SQLite's integrity check failed"));
  CHECK_THAT(check.output, !Catch::Contains("10 verified"));
}

TEST_CASE("the store's record checksum covers the key and study columns", "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_key_study");
  const auto store = make_store(dir);
  const auto hashes = rows(store, "SELECT hash, key FROM trials ORDER BY key");
  REQUIRE(hashes.size() == 10);
  execute(store, "UPDATE trials SET key = 'kernel=gaussian sigma=9 | n=8' WHERE hash = '" +
                     hashes[0][0] + "'");
  execute(store, "UPDATE trials SET study = 'another' WHERE hash = '" + hashes[1][0] + "'");
  const auto check = rkhs_study("store check --store " + store.string());
  INFO(check.output);
  CHECK(check.exit_code == 1);
  CHECK_THAT(check.output, Catch::Contains("trial kernel=gaussian sigma=9 | n=8 (study proof"));
  CHECK_THAT(check.output, Catch::Contains("(study another, hash " + hashes[1][0].substr(0, 12) +
                                           "): checksum mismatch"));
  CHECK_THAT(check.output, Catch::Contains("10 records, 8 verified, 2 bad"));
}

TEST_CASE("store merge verifies what it copies and leaves the destination as it was on failure",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_merge_verify");
  const auto good = make_store(dir, "good.sqlite");
  fs::copy_file(good, dir / "bad.sqlite");
  const auto bad = dir / "bad.sqlite";
  const auto hash = rows(bad, "SELECT hash FROM trials ORDER BY key LIMIT 1")[0][0];
  execute(bad,
          "UPDATE trials SET result = replace(result, 'metrics ', 'metrics 1') WHERE hash = '" +
              hash + "'");
  const auto before = bytes_of(good);

  // A bad record is refused, by source and trial: nothing is copied.
  const auto merged = rkhs_study("merge " + good.string() + " " + bad.string());
  INFO(merged.output);
  CHECK(merged.exit_code == 2);
  CHECK_THAT(merged.output, Catch::Contains(bad.string() + ": trial "));
  CHECK_THAT(merged.output, Catch::Contains("checksum mismatch"));
  CHECK(bytes_of(good) == before);
  CHECK(rkhs_study("store check --store " + good.string()).exit_code == 0);

  // All or nothing: a good source before a failing one leaves the destination unchanged, and
  // one that did not exist is not created.
  const auto fresh = dir / "fresh.sqlite";
  const auto partial =
      rkhs_study("merge " + fresh.string() + " " + good.string() + " " + bad.string());
  INFO(partial.output);
  CHECK(partial.exit_code == 2);
  CHECK_FALSE(fs::exists(fresh));
  fs::copy_file(good, dir / "half.sqlite");
  execute(dir / "half.sqlite", "DELETE FROM trials WHERE rowid % 2 = 0");
  const auto half_before = bytes_of(dir / "half.sqlite");
  const auto not_store = dir / "study.toml";
  CHECK(rkhs_study("merge " + (dir / "half.sqlite").string() + " " + good.string() + " " +
                   not_store.string())
            .exit_code == 2);
  CHECK(bytes_of(dir / "half.sqlite") == half_before);
  // Without the failing source it merges.
  const auto whole = rkhs_study("merge " + (dir / "half.sqlite").string() + " " + good.string());
  INFO(whole.output);
  CHECK(whole.exit_code == 0);
  CHECK_THAT(whole.output, Catch::Contains("holds 10 trials"));
}

TEST_CASE("SIGINT or SIGTERM during a large merge rolls it back: the destination as it was",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_merge_signal");
  const auto into = make_store(dir, "into.sqlite");
  fs::copy_file(into, dir / "large.sqlite");
  const auto large = dir / "large.sqlite";
  // About 60 MB: a merge of some seconds, most of them reading and verifying the records, then
  // writing them (the WAL grows past SQLite's cache in the uncommitted transaction).
  add_copies(large, 40000);
  const auto before = bytes_of(into);
  const auto wal = dir / "into.sqlite-wal";
  const auto log = dir / "log.txt";
  const auto finish = [&](pid_t pid) {
    int status = 0;
    waitpid(pid, &status, 0);
    INFO(read_text(log));
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
    CHECK_THAT(read_text(log), Catch::Contains("interrupted: nothing merged"));
  };

  SECTION("SIGINT while the records are written into an existing store") {
    const pid_t pid = rkhs::test::start_rkhs_study({"merge", into.string(), large.string()}, log);
    // Frames of the open transaction in the WAL: the merge is writing and has not committed.
    const bool writing = rkhs::test::wait_until(
        [&] { return size_of(wal) > (8u << 20) || waitpid(pid, nullptr, WNOHANG) == pid; }, 60);
    REQUIRE(writing);
    REQUIRE(kill(pid, SIGINT) == 0);
    finish(pid);
    CHECK_THAT(read_text(log), Catch::Contains(into.string() + " is left as it was"));
    const auto check = rkhs_study("store check --store " + into.string());
    INFO(check.output);
    CHECK(check.exit_code == 0);
    CHECK_THAT(check.output, Catch::Contains("10 records, 10 verified"));
    CHECK(bytes_of(into) == before);
    // Uninterrupted, the same merge completes.
    const auto merged = rkhs_study("merge " + into.string() + " " + large.string());
    INFO(merged.output);
    CHECK(merged.exit_code == 0);
    CHECK_THAT(merged.output, Catch::Contains("holds 40010 trials"));
  }
  SECTION("SIGTERM while the sources are read, into a new store") {
    const auto fresh = dir / "fresh.sqlite";
    const pid_t pid = rkhs::test::start_rkhs_study({"merge", fresh.string(), large.string()}, log);
    // The new store exists once its schema is written, before the source is read.
    REQUIRE(rkhs::test::wait_until([&] { return fs::exists(fresh); }, 30));
    REQUIRE(kill(pid, SIGTERM) == 0);
    finish(pid);
    CHECK_THAT(read_text(log), Catch::Contains("no " + fresh.string() + " was created"));
    CHECK_FALSE(fs::exists(fresh));
    CHECK_FALSE(has_side_files(fresh));
  }
  SECTION("SIGINT ignored by the shell that started it (a background job) still stops it") {
    const auto fresh = dir / "fresh.sqlite";
    const pid_t pid = fork();
    if (pid == 0) {
      signal(SIGINT, SIG_IGN);
      const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(out, 1);
      dup2(out, 2);
      execl(RKHS_STUDY_EXECUTABLE, RKHS_STUDY_EXECUTABLE, "merge", fresh.c_str(), large.c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    REQUIRE(rkhs::test::wait_until([&] { return fs::exists(fresh); }, 30));
    REQUIRE(kill(pid, SIGINT) == 0);
    finish(pid);
    CHECK_FALSE(fs::exists(fresh));
  }
}

// Issue 50: records resealed with the documented checksum carried "nan(0x123)" (read by
// from_chars, never written by rkhs-study) and raw ESC bytes into trials.csv.
TEST_CASE("stored records resealed with foreign numbers or control bytes reach no output raw",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_resealed_bytes");
  const auto store = make_store(dir);
  const auto all = rows(store, "SELECT hash, study, key, result FROM trials ORDER BY key");
  REQUIRE(all.size() == 10);
  const auto edit = [&](const std::vector<std::string>& row, const std::string& field,
                        const std::string& line) {
    auto body = row[3].substr(0, row[3].rfind("checksum "));
    const auto at = body.find("\n" + field + " ") + 1;
    body.replace(at, body.find('\n', at) - at, line);
    sqlite3* db = nullptr;
    REQUIRE(sqlite3_open(store.c_str(), &db) == SQLITE_OK);
    sqlite3_stmt* update = nullptr;
    REQUIRE(sqlite3_prepare_v2(db, "UPDATE trials SET result = ?1 WHERE hash = ?2", -1, &update,
                               nullptr) == SQLITE_OK);
    const auto record = resealed(row[0], row[1], row[2], body);
    sqlite3_bind_text(update, 1, record.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(update, 2, row[0].c_str(), -1, SQLITE_TRANSIENT);
    CHECK(sqlite3_step(update) == SQLITE_DONE);
    sqlite3_finalize(update);
    sqlite3_close(db);
  };
  // Numbers from_chars reads but format_real never writes: the record does not verify.
  const std::vector<std::string> foreign{"nan(0x123)", "NaN", "infinity", "INF", "-nan"};
  for (std::size_t i = 0; i < foreign.size(); ++i) {
    auto body = all[i][3];
    const auto metrics = body.find("\nmetrics ") + 9;
    edit(all[i], "metrics",
         "metrics " + foreign[i] +
             body.substr(body.find(' ', metrics),
                         body.find('\n', metrics) - body.find(' ', metrics)));
  }
  // Text fields with ESC and BEL: the record verifies, the bytes are escaped in trials.csv.
  edit(all[5], "reason", "reason \x1b[31mred\x1b[0m");
  edit(all[6], "solve",
       "solve chol\x1b]0;title\x07"
       "esky");
  const auto check = rkhs_study("store check --store " + store.string());
  INFO(check.output);
  CHECK(check.exit_code == 1);
  CHECK_THAT(check.output, Catch::Contains("10 records, 5 verified, 5 bad"));
  CHECK_THAT(check.output, Catch::Contains("stored value 'nan(0x123)' is not a number"));
  CHECK_THAT(check.output, Catch::Contains("stored value 'infinity' is not a number"));
  const auto run = rkhs_study("run " + (dir / "study.toml").string() + " --no-plots --store " +
                              store.string() + " --out " + (dir / "again").string());
  INFO(run.output);
  CHECK(run.exit_code == 0);
  CHECK_THAT(run.output, Catch::Contains("5 trials reused from " + store.string() + ", 5 run now"));
  const auto trials = read_text(dir / "again" / "trials.csv");
  CHECK(trials.find('\x1b') == std::string::npos);
  CHECK(trials.find('\x07') == std::string::npos);
  CHECK(trials.find("nan(") == std::string::npos);
  CHECK_THAT(trials, Catch::Contains(",\\x1b[31mred\\x1b[0m,"));
  CHECK_THAT(trials, Catch::Contains(",chol\\x1b]0;title\\x07esky,"));
  const auto csv = rkhs_study("store export --store " + store.string());
  CHECK(csv.output.find('\x1b') == std::string::npos);
}

TEST_CASE("store merge refuses two different records of one trial unless told which wins",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_merge_conflict");
  const auto into = make_store(dir, "into.sqlite");
  fs::copy_file(into, dir / "other.sqlite");
  const auto other = dir / "other.sqlite";
  const auto row = rows(other, "SELECT hash, study, key, result FROM trials ORDER BY key")[0];
  // A record that verifies but holds another result (resealed with the documented checksum).
  auto body = row[3].substr(0, row[3].rfind("checksum "));
  body.replace(body.find("\nmetrics ") + 9, 0, "0.125 ");
  body.replace(body.find("\nfloors ") + 8, 0, "nan ");  // one floor per metric
  body.replace(body.find("metric_names "), 13, "metric_names extra ");
  const auto conflicting = resealed(row[0], row[1], row[2], body);
  execute(other, "UPDATE trials SET result = '" + conflicting + "' WHERE hash = '" + row[0] + "'");
  REQUIRE(rkhs_study("store check --store " + other.string()).exit_code == 0);
  const auto before = bytes_of(into);
  const auto record_in_into = [&] {
    return rows(into, "SELECT result FROM trials WHERE hash = '" + row[0] + "'")[0][0];
  };
  const auto original = record_in_into();

  const auto refused = rkhs_study("merge " + into.string() + " " + other.string());
  INFO(refused.output);
  CHECK(refused.exit_code == 2);
  CHECK_THAT(refused.output, Catch::Contains("trial " + row[2]));
  CHECK_THAT(refused.output, Catch::Contains("--prefer"));
  CHECK(bytes_of(into) == before);

  const auto kept =
      rkhs_study("merge --prefer destination " + into.string() + " " + other.string());
  INFO(kept.output);
  CHECK(kept.exit_code == 0);
  CHECK(record_in_into() == original);

  const auto replaced = rkhs_study("merge --prefer source " + into.string() + " " + other.string());
  INFO(replaced.output);
  CHECK(replaced.exit_code == 0);
  CHECK(record_in_into() == conflicting);
  CHECK(rkhs_study("store check --store " + into.string()).exit_code == 0);
}

TEST_CASE("no command writes over what it reads, nor calls a failed write a success",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_own_input");
  const auto store = make_store(dir);
  const auto before = bytes_of(store);
  fs::create_symlink(store, dir / "link.sqlite");
  // --out onto the store, by its own path, another spelling of it, or a link to it: refused
  // before anything is read or written; the store is as it was and verifies.
  for (const auto& out :
       {store.string(), (dir / "." / "store.sqlite").string(), (dir / "link.sqlite").string()}) {
    for (const char* format : {"csv", "json"}) {
      const auto refused = rkhs_study("store export --format " + std::string(format) +
                                      " --store " + store.string() + " --out " + out);
      INFO(refused.output);
      CHECK(refused.exit_code == 2);
      CHECK_THAT(refused.output, Catch::Contains("--out " + out + " is the store " +
                                                 store.string() + ": writing it would replace"));
    }
  }
  CHECK(fs::is_symlink(dir / "link.sqlite"));
  CHECK(bytes_of(store) == before);
  CHECK(rkhs_study("store check --store " + store.string()).exit_code == 0);
  // --junit onto a study file being checked.
  const auto study = dir / "study.toml";
  const auto study_text = bytes_of(study);
  const auto junit = rkhs_study("check " + study.string() + " --no-store -q --junit " +
                                (dir / "." / "study.toml").string());
  INFO(junit.output);
  CHECK(junit.exit_code == 2);
  CHECK_THAT(junit.output, Catch::Contains("is the study file " + study.string()));
  CHECK(bytes_of(study) == study_text);

  // A standard output that cannot be written: exit 1 with the reason, for every command that
  // writes there (/dev/full: every write fails with ENOSPC).
  if (!fs::exists("/dev/full")) return;
  for (const auto& command :
       {"store export --store " + store.string(),
        "store export --format json --store " + store.string(),
        "store check --store " + store.string(), "validate " + study.string(),
        "report " + (dir / "out").string() + " --format md",
        "report " + (dir / "out").string() + " --format text", std::string("list kernels"),
        std::string("--help")}) {
    // Grouped, so that only standard output goes to /dev/full (run_command adds 2>&1).
    const auto full = rkhs::test::run_command("{ " + std::string(RKHS_STUDY_EXECUTABLE) + " " +
                                              command + " > /dev/full; }");
    INFO(command << ": " << full.output);
    CHECK(full.exit_code == 1);
    CHECK_THAT(full.output,
               Catch::Contains("cannot write to standard output: No space left on device"));
  }
  // A closed standard output too.
  const auto closed = rkhs::test::run_command("{ " + std::string(RKHS_STUDY_EXECUTABLE) +
                                              " validate " + study.string() + " >&-; }");
  CHECK(closed.exit_code == 1);
  CHECK_THAT(closed.output, Catch::Contains("cannot write to standard output: Bad file descriptor"));
  // A writable one still exits 0.
  CHECK(rkhs::test::run_command(std::string(RKHS_STUDY_EXECUTABLE) + " validate " +
                                study.string() + " > /dev/null")
            .exit_code == 0);
}

TEST_CASE("a store that is a directory or truncated is named as such", "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_store_kinds");
  const auto store = make_store(dir);
  const auto study = (dir / "study.toml").string();
  // A directory: refused by its type, exit 2, by every command that takes a store.
  fs::create_directories(dir / "folder.sqlite");
  const auto folder = (dir / "folder.sqlite").string();
  for (const auto& command : {"store check --store " + folder, "store export --store " + folder,
                              "run " + study + " --quiet --no-plots --store " + folder,
                              "merge " + folder + " " + store.string()}) {
    const auto refused = rkhs_study(command);
    INFO(command << ": " << refused.output);
    CHECK(refused.exit_code == 2);
    CHECK_THAT(refused.output, Catch::Contains(folder + ": is a directory, not a result store (an SQLite database file"));
  }
  // Truncated anywhere: damaged (exit 1, with the size its header gives), not "not a store".
  const auto whole = bytes_of(store);
  REQUIRE(whole.size() > 8192);
  for (const std::size_t size : {std::size_t{50}, std::size_t{100}, std::size_t{4096},
                                 whole.size() / 2, whole.size() - 1}) {
    const auto cut = dir / ("cut" + std::to_string(size) + ".sqlite");
    std::ofstream(cut, std::ios::binary) << whole.substr(0, size);
    for (const auto& command :
         {"store check --store " + cut.string(), "store export --store " + cut.string(),
          "run " + study + " --quiet --no-plots --store " + cut.string(),
          "merge " + (dir / "into.sqlite").string() + " " + cut.string()}) {
      const auto damaged = rkhs_study(command);
      INFO(command << ": " << damaged.output);
      CHECK(damaged.exit_code == 1);
      CHECK_THAT(damaged.output, Catch::Contains(cut.string() + ": damaged result store: truncated: " +
                                                 std::to_string(size) + " bytes"));
      CHECK_THAT(damaged.output, !Catch::Contains("not an rkhs-study result store"));
    }
    CHECK(bytes_of(cut) == whole.substr(0, size));
  }
  // A file that is not SQLite's stays "not a store" (exit 2).
  const auto text = rkhs_study("store check --store " + study);
  CHECK(text.exit_code == 2);
  CHECK_THAT(text.output, Catch::Contains("not an rkhs-study result store"));
}

TEST_CASE("read-only store commands open the store read-only and leave it as it was",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_read_only");
  const auto source = make_store(dir);
  const auto shelf = dir / "shelf";
  fs::create_directories(shelf);
  const auto store = shelf / "store.sqlite";
  fs::copy_file(source, store);
  const auto before = bytes_of(store);
  fs::permissions(store, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  // The folder read-only too: nothing can be created beside the store (a read-only mount).
  fs::permissions(shelf, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                             fs::perms::group_exec | fs::perms::others_read |
                             fs::perms::others_exec);
  if (geteuid() == 0 && !nobody_can_read(store))
    WARN(
        "user nobody cannot reach this build or its scratch folder: the read-only commands "
        "run as root (only the byte and side-file checks then prove they wrote nothing)");
  const auto check = as_reader("store check --store " + store.string(), store);
  INFO(check.output);
  CHECK(check.exit_code == 0);
  CHECK_THAT(check.output, Catch::Contains("10 records, 10 verified"));
  const auto csv = as_reader("store export --store " + store.string(), store);
  INFO(csv.output);
  CHECK(csv.exit_code == 0);
  CHECK_THAT(csv.output, Catch::StartsWith("hash,study,key,"));
  // `report` opens no store at all (it reads the folder's summary.json).
  const auto report = as_reader("report " + (dir / "out").string() + " --format md", store);
  INFO(report.output);
  CHECK(report.exit_code == 0);
  CHECK_THAT(report.output, Catch::Contains("gaussian"));
  CHECK(bytes_of(store) == before);
  CHECK_FALSE(has_side_files(store));
  // Writable by root: still read-only, and no -wal or -shm file appears.
  fs::permissions(shelf, fs::perms::owner_all, fs::perm_options::add);
  CHECK(rkhs_study("store check --store " + store.string()).exit_code == 0);
  CHECK(rkhs_study("store export --format json --store " + store.string()).exit_code == 0);
  CHECK(bytes_of(store) == before);
  CHECK_FALSE(has_side_files(store));
}

// `rkhs-study ARGS` with `folder` mounted read-only (a bind mount of its own, remounted ro, in a
// mount namespace of the command's own: nothing outside it sees the mount); nullopt where
// this user cannot make mount namespaces (not root, or a container without CAP_SYS_ADMIN).
std::optional<rkhs::test::CommandOutcome> on_read_only_mount(const fs::path& folder,
                                                             const std::string& arguments) {
  const std::string mount = "mount --bind '" + folder.string() + "' '" + folder.string() +
                            "' && mount -o remount,ro,bind '" + folder.string() + "'";
  if (geteuid() != 0 ||
      std::system(("unshare -m sh -c \"" + mount + "\" >/dev/null 2>&1").c_str()) != 0)
    return std::nullopt;
  return rkhs::test::run_command("unshare -m sh -c \"" + mount + " && exec " +
                                 RKHS_STUDY_EXECUTABLE + " " + arguments + "\"");
}

TEST_CASE("a store on a read-only mount serves the runs that only read it and is named read-only",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_read_only_mount");
  const auto made = make_store(dir);
  const auto shelf = dir / "shelf";
  fs::create_directories(shelf);
  const auto store = shelf / "store.sqlite";
  fs::rename(made, store);
  const auto before = bytes_of(store);
  const auto study = (dir / "study.toml").string();
  // The same study with two more n: two trials the store lacks.
  std::string more = proof_study;
  more.replace(more.find("128]"), 4, "128, 256]");
  more.replace(more.find("= 256"), 5, "= 1024");
  std::ofstream(dir / "more.toml") << more;
  fs::copy_file(store, dir / "copy.sqlite");
  const auto probe = on_read_only_mount(shelf, "--version");
  if (!probe) {
    WARN("no mount namespace for this user: the read-only mount is not tested here");
    return;
  }
  REQUIRE(probe->exit_code == 0);
  const auto s = " --store " + store.string();

  // Commands that only read: they work.
  const auto check = *on_read_only_mount(shelf, "store check" + s);
  INFO(check.output);
  CHECK(check.exit_code == 0);
  CHECK_THAT(check.output, Catch::Contains("10 records, 10 verified"));
  CHECK(on_read_only_mount(shelf, "store export" + s)->exit_code == 0);
  // A run whose every trial is stored reads the store: the outputs are those of the run that
  // stored them.
  const auto run = *on_read_only_mount(
      shelf, "run " + study + " --no-plots" + s + " --out " + (dir / "again").string());
  INFO(run.output);
  CHECK(run.exit_code == 0);
  CHECK_THAT(run.output,
             Catch::Contains("10 trials reused from " + store.string() + ", 0 run now"));
  CHECK(read_text(dir / "again" / "trials.csv") == read_text(dir / "out" / "trials.csv"));
  const auto checked = *on_read_only_mount(shelf, "check " + study + " --no-plots" + s);
  INFO(checked.output);
  // The study has no [[expect]]: nothing verified is exit 5, after reading every trial.
  CHECK(checked.exit_code == 5);
  CHECK_THAT(checked.output,
             Catch::Contains("10 trials reused from " + store.string() + ", 0 run now"));

  // Commands that must write: refused, naming the store and why, with nothing written.
  const std::string read_only =
      store.string() + ": the result store is read-only (the file is on a read-only file system)";
  for (const auto& command :
       {"run " + study + " --fresh --quiet --no-plots" + s + " --out " + (dir / "fresh").string(),
        "run " + (dir / "more.toml").string() + " --quiet --no-plots" + s + " --out " +
            (dir / "more").string(),
        "check " + (dir / "more.toml").string() + " --quiet --no-plots" + s + " --out " +
            (dir / "more").string(),
        "store vacuum" + s, "merge " + store.string() + " " + (dir / "copy.sqlite").string()}) {
    const auto refused = *on_read_only_mount(shelf, command);
    INFO(command << "\n" << refused.output);
    CHECK(refused.exit_code == 2);
    CHECK_THAT(refused.output, Catch::Contains(read_only));
    CHECK_THAT(refused.output, !Catch::Contains("not an rkhs-study result store"));
  }
  const auto lacking =
      *on_read_only_mount(shelf, "run " + (dir / "more.toml").string() + " --quiet --no-plots" + s);
  CHECK_THAT(lacking.output, Catch::Contains("2 of the 12 trials are not stored in it"));
  CHECK_FALSE(fs::exists(dir / "fresh"));
  CHECK_FALSE(fs::exists(dir / "more"));
  // A new store in the read-only folder: it cannot be created.
  const auto created =
      *on_read_only_mount(shelf, "merge " + (shelf / "new.sqlite").string() + " " + store.string());
  INFO(created.output);
  CHECK(created.exit_code == 2);
  CHECK_THAT(created.output, Catch::Contains((shelf / "new.sqlite").string() +
                                             ": cannot create the result store: its folder " +
                                             shelf.string() + " is on a read-only file system"));
  CHECK(bytes_of(store) == before);
  CHECK_FALSE(has_side_files(store));
}

TEST_CASE("a run refused because of its store leaves no file in the output folder",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_refused_store_outputs");
  const auto good = make_store(dir);
  const auto study = (dir / "study.toml").string();
  fs::create_directories(dir / "folder.sqlite");
  const auto whole = bytes_of(good);
  std::ofstream(dir / "cut.sqlite", std::ios::binary) << whole.substr(0, whole.size() / 2);
  // An output folder that exists, with a file of an earlier run in it, and one that does not.
  fs::create_directories(dir / "kept");
  std::ofstream(dir / "kept" / "notes.txt") << "mine\n";
  for (const auto& bad : {dir / "study.toml", dir / "folder.sqlite", dir / "cut.sqlite"}) {
    for (const auto& command : {std::string("run"), std::string("check")}) {
      for (const auto& out : {dir / "kept", dir / "new"}) {
        const auto refused = rkhs_study(command + " " + study + " --quiet --store " + bad.string() +
                                        " --out " + out.string());
        INFO(command << " --store " << bad << " --out " << out << "\n" << refused.output);
        CHECK((refused.exit_code == 1 || refused.exit_code == 2));
        CHECK_THAT(refused.output, Catch::Contains(bad.string() + ": "));
        CHECK_FALSE(fs::exists(dir / "new"));
        std::vector<std::string> files;
        for (const auto& entry : fs::directory_iterator(dir / "kept"))
          files.push_back(entry.path().filename().string());
        CHECK(files == std::vector<std::string>{"notes.txt"});
      }
    }
  }
  // An output folder that cannot be written: a store this run would have created is not left.
  std::ofstream(dir / "file") << "a file, not a folder\n";
  const auto no_out =
      rkhs_study("run " + study + " --quiet --store " + (dir / "new.sqlite").string() + " --out " +
                 (dir / "file" / "out").string());
  INFO(no_out.output);
  CHECK(no_out.exit_code == 2);
  CHECK_THAT(no_out.output, Catch::Contains("cannot write the output folder"));
  CHECK_FALSE(fs::exists(dir / "new.sqlite"));
  CHECK_FALSE(has_side_files(dir / "new.sqlite"));
}

TEST_CASE("a database that is not a result store is refused by name and left byte-identical",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_foreign");
  std::ofstream(dir / "study.toml") << proof_study;
  const auto foreign = dir / "notes.db";
  execute(foreign,
          "CREATE TABLE notes (id INTEGER PRIMARY KEY, text TEXT); "
          "INSERT INTO notes (text) VALUES ('keep me')");
  const auto before = bytes_of(foreign);
  const auto good = make_store(dir, "good.sqlite");
  for (const auto& command :
       {"store check --store " + foreign.string(), "store export --store " + foreign.string(),
        "store vacuum --store " + foreign.string(),
        "run " + (dir / "study.toml").string() + " --quiet --no-plots --store " + foreign.string() +
            " --out " + (dir / "run").string(),
        "merge " + foreign.string() + " " + good.string(),
        "merge " + good.string() + " " + foreign.string()}) {
    const auto outcome = rkhs_study(command);
    INFO(command << "\n" << outcome.output);
    CHECK(outcome.exit_code == 2);
    CHECK_THAT(outcome.output,
               Catch::Contains(foreign.string() + ": not an rkhs-study result store"));
    CHECK(bytes_of(foreign) == before);
    CHECK_FALSE(has_side_files(foreign));
  }
  CHECK(rows(foreign, "SELECT name FROM sqlite_master WHERE name = 'trials'").empty());
}

TEST_CASE("a full disk under the store ends the run with exit 2, and what was stored is kept",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_full_disk");
  std::ofstream(dir / "study.toml") << R"([study]
name = "full_disk"
evaluation_points = 64
[domain]
radius = 4
[grid]
n = { from = 4, to = 60, step = 1 }
[[kernel]]
name = "gaussian"
sigma = [0.5, 1.0]
)";
  const auto store = dir / "store.sqlite";
  // Files of at most 160 KiB (ulimit -f counts 512-byte blocks in sh): enough for the
  // store's -shm file (32 KiB), too little for the WAL of 114 trials, one commit each. SIGXFSZ
  // ignored: a write past the limit fails with EFBIG, as one on a full disk with ENOSPC.
  const auto outcome = rkhs::test::run_command(
      "trap '' XFSZ; ulimit -f 320; exec " + std::string(RKHS_STUDY_EXECUTABLE) + " run " +
      (dir / "study.toml").string() + " --threads 1 --quiet --no-plots --store " + store.string() +
      " --out " + (dir / "out").string());
  INFO(outcome.output);
  CHECK(outcome.exit_code == 2);
  CHECK_THAT(outcome.output, Catch::Contains(store.string()));
  CHECK_THAT(outcome.output, Catch::Contains("cannot store the trial"));
  CHECK_THAT(outcome.output, !Catch::Contains("terminate called"));
  // What was committed is kept and verifies; a run without the limit completes it.
  const auto check = rkhs_study("store check --store " + store.string());
  INFO(check.output);
  CHECK(check.exit_code == 0);
  const auto stored = rows(store, "SELECT COUNT(*) FROM trials")[0][0];
  CHECK(std::stoul(stored) > 0);
  CHECK(std::stoul(stored) < 114);
  const auto resumed =
      rkhs_study("run " + (dir / "study.toml").string() + " --quiet --no-plots --store " +
                 store.string() + " --out " + (dir / "out").string());
  INFO(resumed.output);
  CHECK(resumed.exit_code == 0);
  CHECK(rows(store, "SELECT COUNT(*) FROM trials")[0][0] == "114");
}

TEST_CASE("a store from before the schema marks and its records of format 2 still verify",
          "[cli][store][proof]") {
  const auto dir = rkhs::test::scratch_directory("proof_old_store");
  const auto store = make_store(dir);
  // As rkhs-study wrote it before: no marks, and records of format 2 (their checksum over the
  // hash and the record, not the key and study).
  const auto all = rows(store, "SELECT hash, result FROM trials ORDER BY key");
  REQUIRE(all.size() == 10);
  auto format_2 = [&](const std::string& hash, std::string record) {
    auto body = record.substr(0, record.rfind("checksum "));
    body.replace(0, std::string("rkhs-record 3").size(), "rkhs-record 2");
    return body + "checksum " + rkhs::sha256_hex(hash + "\n" + body) + "\n";
  };
  std::string sql = "PRAGMA application_id = 0; PRAGMA user_version = 0; ";
  for (std::size_t i = 0; i < 3; ++i)
    sql += "UPDATE trials SET result = '" + format_2(all[i][0], all[i][1]) + "' WHERE hash = '" +
           all[i][0] + "'; ";
  execute(store, sql);
  const auto check = rkhs_study("store check --store " + store.string());
  INFO(check.output);
  CHECK(check.exit_code == 0);
  CHECK_THAT(check.output, Catch::Contains("10 records, 10 verified, 0 bad"));
  CHECK_THAT(check.output, Catch::Contains("3 of the verified in record format 2"));
  CHECK(rows(store, "PRAGMA application_id")[0][0] == "0");  // read-only: not marked
  const auto again = rkhs_study("run " + (dir / "study.toml").string() + " --no-plots --store " +
                                store.string() + " --out " + (dir / "again").string());
  INFO(again.output);
  CHECK(again.exit_code == 0);
  CHECK_THAT(again.output, Catch::Contains("10 trials reused"));
  CHECK(rows(store, "PRAGMA application_id")[0][0] == std::to_string(0x726b6873));
  CHECK(rows(store, "PRAGMA user_version")[0][0] == "2");
  // A record of format 2 edited is not accepted; one moved to another key is not either (its
  // checksum covers the hash).
  execute(store,
          "UPDATE trials SET result = replace(result, 'metrics ', 'metrics 1') WHERE "
          "hash = '" +
              all[0][0] + "'");
  const auto edited = rkhs_study("store check --store " + store.string());
  INFO(edited.output);
  CHECK(edited.exit_code == 1);
  CHECK_THAT(edited.output, Catch::Contains("10 records, 9 verified, 1 bad"));
}
