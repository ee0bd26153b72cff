#pragma once
// The result store: every finished trial is committed to an SQLite database as soon as it
// finishes, keyed by a content hash of everything that determines it. A re-run reuses stored
// trials and runs only what is missing or changed; a run killed at any moment (SIGINT,
// SIGTERM, kill -9) loses only the trials in flight. Several studies can share one store.
//
// Durability: the database is in WAL mode and each trial is its own transaction, so a
// committed trial survives the death of the process (not necessarily a power failure:
// synchronous = NORMAL). checkpoint() moves the WAL into the database file, so that the file
// alone holds every trial (run_study calls it at the end of a run).
//
// Trust: a record is reused only when it verifies (read_record): its format version, the
// checksum over its trial hash and text, one value per metric name it holds, and those names
// equal to the study's. Anything else is reported (store, trial key, what is wrong) and the
// trial runs again; records of format 1 (no checksum) are "old format", re-run the same way.
// SQLite errors are errors (std::runtime_error naming the store), never "not stored".
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/run/run.hpp"
#include "rkhs/run/trial_identity.hpp"  // trial_hashes
#include "rkhs/study/study.hpp"

struct sqlite3;

namespace rkhs {

/// A TrialResult as text (round-trip exact: reals are written in their shortest exact form)
/// and back. Throws std::invalid_argument for text that is not such a record (a field that is
/// not one, a value that does not parse, a field other than `snapshot` given twice). This is also the
/// payload MPI ranks send; the store wraps it in a verified record (store_record). The line
/// `work name=count ...` (TrialResult::work) is written when the result has work counters and
/// is optional on reading: a record stored without it reads back with no work counters.
std::string serialize_result(const TrialResult& result);
TrialResult deserialize_result(std::string_view text);

/// The version of the records store_record writes.
inline constexpr int record_format = 2;

/// A stored record of format 2: the line "rkhs-record 2", the line "metric_names" followed by
/// `metric_names` (the names of result.metrics, in order), serialize_result(result), and the
/// line "checksum " + SHA-256 (hex) of `hash`, a newline, and every line before this one.
std::string store_record(const std::string& hash, const TrialResult& result,
                         const std::vector<std::string>& metric_names);

/// What read_record found in one stored record.
struct RecordCheck {
  std::optional<TrialResult> result;      ///< the result, when the record verifies
  std::string problem;                    ///< why it does not ("" when it does)
  bool old_format = false;                ///< a record of format 1 (no checksum, never reused)
  std::vector<std::string> metric_names;  ///< the metric names it holds (format 2)
  bool sound() const { return result.has_value(); }
};

/// Verifies a stored record of the trial `hash`: format 2, checksum, that it parses, one value
/// per metric name, and, when `expected_metrics` is given, those names equal to it. Never
/// throws for bad text: what is wrong is RecordCheck::problem.
RecordCheck read_record(const std::string& hash, std::string_view text,
                        const std::vector<std::string>* expected_metrics = nullptr);

class ResultStore;

struct StoredRun {
  std::vector<TrialResult> results;  ///< in the order of the trials
  std::size_t reused = 0;            ///< trials taken from the store
  std::size_t ran = 0;               ///< trials run (and stored) now
  std::size_t skipped = 0;           ///< trials not run because the run was interrupted
  std::size_t stopped = 0;           ///< of those, trials stopped while they ran (not stored)
  /// What was wrong with the stored records that were not reused (their trials ran again),
  /// one line each: "STORE: trial KEY: what is wrong; run again", and one line for all
  /// records of the old format ("STORE: N stored trials in the old record format ...").
  std::vector<std::string> store_problems;
};

/// What runs the trials the store does not hold: run_trials by default, the MPI coordinator in
/// a distributed run. Same contract as run_trials (results in the order of its `trials`).
using TrialExecutor = std::function<std::vector<TrialResult>(
    const StudyDefinition&, const std::vector<TrialSpec>&, const RunOptions&)>;

/// Runs the trials that `store` does not hold yet (all of them when `fresh` or when `store` is
/// null) with `execute`, committing each to the store as it finishes, and returns every result.
/// `options`' own callback is called for the trials run now. `known_hashes`: trial_hashes() of
/// `trials` when the caller has them already (empty: computed here when there is a store).
StoredRun run_with_store(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                         const RunOptions& options, ResultStore* store, bool fresh,
                         const TrialExecutor& execute = run_trials,
                         const std::vector<std::string>& known_hashes = {});

class ResultStore {
 public:
  /// Opens or creates the store at `file` (parent directories created). Throws
  /// std::runtime_error naming the file when it cannot be opened or is not a store.
  explicit ResultStore(const std::filesystem::path& file);
  ~ResultStore();
  ResultStore(const ResultStore&) = delete;
  ResultStore& operator=(const ResultStore&) = delete;

  /// The stored record of the trial with this hash, verified by read_record against
  /// `metric_names` (nullptr: only against itself); an empty RecordCheck when none is stored.
  /// Throws std::runtime_error naming the store on any SQLite error.
  RecordCheck lookup(const std::string& hash,
                     const std::vector<std::string>* metric_names = nullptr) const;
  /// The stored result of the trial with this hash, if one is stored and verifies.
  std::optional<TrialResult> find(const std::string& hash) const;
  /// Stores (or replaces) a result as a record of format 2 (store_record) and commits it
  /// before returning. `metric_names`: the names of result.metrics.
  void put(const std::string& hash, const std::string& study, const std::string& key,
           const TrialResult& result, const std::vector<std::string>& metric_names);
  /// Copies every trial of the store at `other` into this one (a later copy of the same hash
  /// replaces an earlier one: results of the same hash are identical). Returns how many trials
  /// `other` holds. Throws std::runtime_error naming a file that is not a store.
  std::size_t merge_from(const std::filesystem::path& other);
  /// Number of stored trials (of all studies).
  std::size_t size() const;

  /// One stored row and what read_record (without expected metric names) found in it.
  struct Entry {
    std::string hash, study, key, stored;  ///< stored: the UTC time it was committed
    RecordCheck check;
  };
  /// Calls `visit` for every stored row, in the order of their keys.
  void for_each(const std::function<void(const Entry&)>& visit) const;
  /// Removes the rows of these hashes; returns how many there were.
  std::size_t remove(const std::vector<std::string>& hashes);
  /// Rebuilds the database file without free pages (SQLite VACUUM).
  void vacuum();
  /// Copies the WAL into the database file and truncates it (PRAGMA wal_checkpoint(TRUNCATE)),
  /// so that the database file alone holds every committed trial. Returns false when another
  /// connection kept it from completing (the WAL then still holds the rest; nothing is lost).
  bool checkpoint();

  const std::filesystem::path& file() const noexcept { return file_; }

 private:
  void exec(const char* sql) const;
  /// Throws std::runtime_error "STORE: result store: WHAT: SQLite's message".
  [[noreturn]] void fail(const std::string& what) const;
  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
};

}  // namespace rkhs
