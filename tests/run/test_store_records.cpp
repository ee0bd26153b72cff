// Verified store records: a record is reused only when its format, checksum, shape and metric
// names check out; anything else says what is wrong. SQLite errors are errors.
#include <sqlite3.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "rkhs/core/sha256.hpp"
#include "rkhs/run/result_store.hpp"

using namespace rkhs;

namespace {

const std::vector<std::string> names{"a", "b", "c"};
const std::string hash = "0123abcd";
const std::string study = "records", key = "kernel=gaussian sigma=0.5 | n=8";

TrialResult result() {
  TrialResult r;
  r.ok = true;
  r.solve_method = "cholesky";
  r.metrics = {0.5, 1.0 / 3.0, 2e-300};
  return r;
}

// The record's text before its checksum line, and the record sealed again for `for_hash` (as
// docs/results.md describes format 3: SHA-256 of the hash, the study and the key, each followed
// by a newline, and the lines before).
std::string body_of(const std::string& record) {
  return record.substr(0, record.rfind("checksum "));
}
std::string sealed(const std::string& body, const std::string& for_hash = hash) {
  return body + "checksum " + sha256_hex(for_hash + "\n" + study + "\n" + key + "\n" + body) + "\n";
}
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("a stored record verifies and reads back: its format is the documented one", "[store]") {
  const auto record = store_record(hash, study, key, result(), names);
  CHECK(record.rfind("rkhs-record 3\nmetric_names a b c\nrkhs-trial 1\n", 0) == 0);
  CHECK(sealed(body_of(record)) == record);
  const auto check = read_record(hash, study, key, record, &names);
  REQUIRE(check.sound());
  CHECK(check.problem.empty());
  CHECK(check.metric_names == names);
  CHECK(check.result->metrics == result().metrics);
}

TEST_CASE("a record that does not verify says what is wrong", "[store]") {
  const auto record = store_record(hash, study, key, result(), names);
  auto problem = [&](const std::string& text, const std::vector<std::string>* expected = &names) {
    const auto check = read_record(hash, study, key, text, expected);
    CHECK_FALSE(check.sound());
    return check.problem;
  };
  // One metric too many (resealed, so that the shape is what is caught).
  CHECK(problem(sealed(replaced(body_of(record), "\nmetrics ", "\nmetrics 0.25 "))) ==
        "4 metric values for 3 metric names");
  // The metric names are not the study's.
  const std::vector<std::string> other{"a", "b", "d"};
  CHECK(problem(record, &other) == "it holds the metrics a, b, c, the study measures a, b, d");
  CHECK(read_record(hash, study, key, record).sound());  // without expectations: sound in itself
  // A flipped digit of the checksum, an edited value, a record under another hash.
  auto flipped = record;
  flipped[flipped.rfind("checksum ") + 9] ^= 1;
  CHECK_THAT(problem(flipped), Catch::StartsWith("checksum mismatch (stored "));
  CHECK_THAT(problem(replaced(record, "metrics 0.5", "metrics 0.6")),
             Catch::StartsWith("checksum mismatch"));
  CHECK_THAT(read_record("another", study, key, record, &names).problem,
             Catch::StartsWith("checksum mismatch"));
  // Garbage where a number belongs, resealed: the parser's reason.
  CHECK(problem(sealed(replaced(body_of(record), "metrics 0.5", "metrics x"))) ==
        "stored value 'x' is not a number");
  // A field given twice, resealed: the second flags line was appended to the first and the
  // second metrics line replaced it (found by fuzz_store_record: such a result did not read back
  // as it was written). Snapshots are one line each.
  CHECK(problem(sealed(replaced(body_of(record), "\nflags ", "\nflags a\nflags "))) ==
        "field 'flags' twice in a stored trial");
  CHECK(problem(sealed(body_of(record) + "metrics 1 2 3\n")) ==
        "field 'metrics' twice in a stored trial");
  CHECK(read_record(hash, study, key, sealed(body_of(record) + "snapshot 1 0.5\nsnapshot 2 0.25\n"),
                    &names)
            .result->snapshots.size() == 2);
  // Empty flags are none: "a;;" read as ["a", ""] was written back as "a;", which read as ["a"]
  // (found by fuzz_store_record: a result that did not read back as it was written).
  const auto flagged =
      deserialize_result("rkhs-trial 1\nok 1\nflags ;gram_singular;;l2_error_at_floor;;\n");
  CHECK(flagged.flags == std::vector<std::string>{"gram_singular", "l2_error_at_floor"});
  CHECK(deserialize_result(serialize_result(flagged)).flags == flagged.flags);
  // No checksum, not a record, the old format.
  CHECK(problem(body_of(record)) == "no checksum line");
  CHECK(problem("") == "not a stored record: first line '', expected 'rkhs-record 3'");
  const auto old = read_record(hash, study, key, serialize_result(result()), &names);
  CHECK_FALSE(old.sound());
  CHECK(old.old_format);
  CHECK(old.problem == "old record format (no checksum)");
}

TEST_CASE("run_with_store reruns records that do not verify and says which", "[store]") {
  const auto dir = std::filesystem::temp_directory_path() / "rkhs_store_records";
  std::filesystem::remove_all(dir);
  const auto study = parse_study(R"([study]
name = "records"
evaluation_points = 128
metrics = ["gram_condition_number", "power_function_sup"]
[domain]
radius = 4
[grid]
n = [8, 16]
[[kernel]]
name = "gaussian"
sigma = 0.5
)",
                                 "records.toml");
  const auto trials = study.trials();
  const auto hashes = trial_hashes(study, trials);
  RunOptions options;
  options.threads = 1;
  ResultStore store(dir / "store.sqlite");
  const auto first = run_with_store(study, trials, options, &store, false);
  REQUIRE(first.ran == 2);
  // The first record under the second trial's hash: its checksum does not hold there.
  {
    sqlite3* db = nullptr;
    REQUIRE(sqlite3_open((dir / "store.sqlite").c_str(), &db) == SQLITE_OK);
    const auto sql = "UPDATE trials SET result = (SELECT result FROM trials WHERE hash = '" +
                     hashes[0] + "') WHERE hash = '" + hashes[1] + "'";
    REQUIRE(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) == SQLITE_OK);
    sqlite3_close(db);
  }
  const auto second = run_with_store(study, trials, options, &store, false);
  CHECK(second.reused == 1);
  CHECK(second.ran == 1);
  REQUIRE(second.store_problems.size() == 1);
  CHECK_THAT(second.store_problems[0],
             Catch::StartsWith((dir / "store.sqlite").string() + ": trial " + trials[1].key +
                               ": checksum mismatch"));
  CHECK_THAT(second.store_problems[0], Catch::EndsWith("; run again"));
  // Bit for bit, NaN (a metric the study does not compute) equal to NaN.
  CHECK(std::equal(second.results[1].metrics.begin(), second.results[1].metrics.end(),
                   first.results[1].metrics.begin(), first.results[1].metrics.end(),
                   [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); }));
  CHECK(run_with_store(study, trials, options, &store, false).store_problems.empty());
}

TEST_CASE("a damaged database file is an error naming the store, not 'not stored'", "[store]") {
  const auto dir = std::filesystem::temp_directory_path() / "rkhs_store_damaged";
  std::filesystem::remove_all(dir);
  const auto file = dir / "store.sqlite";
  {
    ResultStore store(file);
    for (int i = 0; i < 200; ++i)
      store.put("hash" + std::to_string(i), "s", "key " + std::to_string(i), result(), names);
    CHECK(store.checkpoint());
  }
  REQUIRE(std::filesystem::file_size(file) > 3 * 4096);
  {  // garbage over the pages after the schema (the table's b-tree)
    std::fstream bytes(file, std::ios::in | std::ios::out | std::ios::binary);
    bytes.seekp(4096);
    const std::string garbage(2 * 4096, '\x5a');
    bytes.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
  ResultStore store(file);
  CHECK_THROWS_WITH(store.size(), Catch::StartsWith(file.string() + ": result store: "));
  CHECK_THROWS_WITH(store.lookup("hash7"), Catch::StartsWith(file.string() + ": result store: "));
}

TEST_CASE("a stored trial's engine is written by name and read back as the engine", "[store]") {
  TrialResult result;
  result.ok = true;
  result.engine = AdaptiveEngine::lap_map;
  const auto text = serialize_result(result);
  CHECK(text.find("engine lap_map\n") != std::string::npos);
  CHECK(deserialize_result(text).engine == AdaptiveEngine::lap_map);
  result.engine.reset();  // an approximation trial has none, and its record says nothing
  CHECK(serialize_result(result).find("engine") == std::string::npos);
  CHECK_FALSE(deserialize_result(serialize_result(result)).engine.has_value());
  std::string unknown = text;
  unknown.replace(unknown.find("lap_map"), 7, "warp");
  CHECK_THROWS_WITH(deserialize_result(unknown), Catch::Contains("unknown engine 'warp'"));
}
