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
// checksum over its trial hash, key, study and text, one value per metric name it holds, and
// those names equal to the study's. Anything else is reported (store, trial key, what is wrong) and
// the trial runs again; records of format 1 (no checksum) are "old format", re-run the same way.
// SQLite errors are errors (std::runtime_error naming the store), never "not stored"; a write
// that fails (a full disk) ends the run with that error after the trials in flight, the trials
// committed before it kept.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
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
/// not one, a value that does not parse, a field other than `snapshot` given twice). This is also
/// the payload MPI ranks send; the store wraps it in a verified record (store_record). The line
/// `work name=count ...` (TrialResult::work) is written when the result has work counters and
/// is optional on reading: a record stored without it reads back with no work counters.
std::string serialize_result(const TrialResult& result);
TrialResult deserialize_result(std::string_view text);

/// The version of the records store_record writes.
inline constexpr int record_format = 3;

/// A stored record of format 3: the line "rkhs-record 3", the line "metric_names" followed by
/// `metric_names` (the names of result.metrics, in order), serialize_result(result), and the
/// line "checksum " + SHA-256 (hex) of `hash`, `study` and `key` (each followed by a newline,
/// line breaks and backslashes in them escaped as in a record) and every line before this one:
/// the record proves the row's key and study columns as well as its result.
std::string store_record(const std::string& hash, const std::string& study, const std::string& key,
                         const TrialResult& result, const std::vector<std::string>& metric_names);

/// What read_record found in one stored record.
struct RecordCheck {
  std::optional<TrialResult> result;      ///< the result, when the record verifies
  std::string problem;                    ///< why it does not ("" when it does)
  bool old_format = false;                ///< a record of format 1 (no checksum, never reused)
  int format = 0;                         ///< its format (1, 2, 3; 0 when not a record)
  std::vector<std::string> metric_names;  ///< the metric names it holds (formats 2 and 3)
  bool sound() const { return result.has_value(); }
  /// A record of format 2 verifies by the rule of its time: its checksum covers the hash and
  /// the result, not the key and study columns (docs/results.md).
  bool key_and_study_proven() const { return sound() && format >= 3; }
};

/// Verifies a stored record of the trial `hash` in a row of `study` and `key`: format 3 (or 2,
/// by its own rule), checksum, that it parses, one value per metric name, and, when
/// `expected_metrics` is given, those names equal to it. Never throws for bad text: what is
/// wrong is RecordCheck::problem.
RecordCheck read_record(const std::string& hash, const std::string& study, const std::string& key,
                        std::string_view text,
                        const std::vector<std::string>* expected_metrics = nullptr);

class ResultStore;

struct StoredRun {
  std::vector<TrialResult> results;  ///< in the order of the trials
  std::size_t reused = 0;            ///< trials taken from the store
  std::size_t ran = 0;               ///< trials run (and stored) now
  std::size_t skipped = 0;           ///< trials not run because the run was interrupted
  std::size_t stopped = 0;           ///< of those, trials stopped while they ran (not stored)
  /// Of the trials run now, those of which the store held a record of the same study and trial
  /// key under another identity (trial_hashes): a plugin module rebuilt, another rkhs-study
  /// build or other study settings; their stored records were not reused.
  std::size_t superseded = 0;
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

/// A result store whose file is an SQLite database that is damaged (truncated, or pages SQLite
/// finds malformed) rather than another kind of file: its records may be lost. Commands exit 1
/// for it ("damaged"), 2 for a file that is not a store at all.
class DamagedStore : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A result store that cannot be written where it lies (a read-only file system, a file or
/// folder this user may not write): "FILE: the result store is read-only (why)". A command that
/// only needs to read it may open it with StoreAccess::read_only instead.
class ReadOnlyStore : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A merge stopped because it was asked to (SIGINT, SIGTERM): its transaction was rolled back
/// and nothing was written.
class MergeInterrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How a ResultStore opens its database.
enum class StoreAccess {
  read_write,  ///< opened or created; WAL mode
  read_only,   ///< an existing store, SQLITE_OPEN_READONLY: nothing written, no -wal created
};

/// Which record a merge keeps when two records of one trial differ (in more than their wall
/// time): none (the merge is refused), the one already there (the destination's, or that of
/// the earlier source), or the one of the source merged later.
enum class MergePreference { refuse, destination, source };

/// What merge_from did with the trials of one source.
struct MergedSource {
  std::string file;
  std::size_t records = 0;   ///< trials it holds (every one verified)
  std::size_t added = 0;     ///< not held before
  std::size_t same = 0;      ///< held already with the same result (only the wall time differs)
  std::size_t replaced = 0;  ///< a different record replaced (--prefer source)
  std::size_t kept = 0;      ///< a different record kept (--prefer destination)
  std::size_t repaired = 0;  ///< replaced a record of the destination that did not verify
};

class ResultStore {
 public:
  /// Opens the store at `file`. read_write: creates it when the file does not exist or is an
  /// empty database (parent directories created). read_only: the file must exist; the database
  /// is opened with SQLITE_OPEN_READONLY (immutable when no -wal file is beside it, so that
  /// nothing is created beside it either). Either way a database that is not an rkhs-study
  /// store (no `trials` table of the store's columns, another application id, a newer schema)
  /// is refused before anything is written: std::runtime_error "FILE: not an rkhs-study result
  /// store: why". A `file` that exists and is not a regular file (a directory, a FIFO, a
  /// device) is refused by its type before it is opened: "FILE: is a FIFO, not a result store
  /// (an SQLite database file)". An SQLite file shorter than its header says (truncated) or one
  /// SQLite reports malformed throws DamagedStore "FILE: damaged result store: why". read_write
  /// on a store that cannot be written (on a read-only file system, not writable by this user,
  /// or in a folder where SQLite cannot create its -wal and -shm files) throws ReadOnlyStore
  /// before the database is opened; where no file is, one that cannot be created throws it too.
  explicit ResultStore(const std::filesystem::path& file,
                       StoreAccess access = StoreAccess::read_write);
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
  /// Copies every trial of the stores `sources` into this one, all or nothing: every source
  /// opened read-only and checked by SQLite (PRAGMA integrity_check), every record verified
  /// (read_record), a trial held with a different record resolved by `prefer`, and everything
  /// written in one transaction. A source that is not a store or is damaged, a record that does
  /// not verify (old format included) or a conflict under MergePreference::refuse throws
  /// std::runtime_error naming the source and the trials, and nothing is written.
  /// `stop_requested` is asked between batches of records (while the sources and the
  /// destination are read and while the records are written) and before the commit: once it
  /// returns true the transaction is rolled back and MergeInterrupted thrown.
  std::vector<MergedSource> merge_from(const std::vector<std::filesystem::path>& sources,
                                       MergePreference prefer = MergePreference::refuse,
                                       const std::function<bool()>& stop_requested = {});
  /// What SQLite's PRAGMA integrity_check finds wrong with the database file (its index and
  /// table b-trees, their pages and their agreement): empty when nothing.
  std::vector<std::string> integrity_problems() const;
  /// Number of stored trials (of all studies).
  std::size_t size() const;

  /// One stored row and what read_record (without expected metric names) found in it.
  struct Entry {
    std::string hash, study, key, stored;  ///< stored: the UTC time it was committed
    RecordCheck check;
    std::string record;  ///< the stored text of the record
  };
  /// The trial keys of the rows of `study` (one read of the table, not per trial): a trial of
  /// that study and key not found by its hash was stored under another identity.
  std::set<std::string> keys_of_study(const std::string& study) const;
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
  StoreAccess access() const noexcept { return access_; }
  /// True when the store was opened read-only as an immutable file (no -wal file beside it)
  /// and a -wal file has appeared since: a writer started while it was read, so what was read
  /// may be inconsistent; a new ResultStore reads it through the WAL.
  bool written_meanwhile() const;

 private:
  void open(bool immutable);
  void adopt_schema();
  void exec(const char* sql) const;
  /// Throws std::runtime_error "STORE: result store: WHAT: SQLite's message".
  [[noreturn]] void fail(const std::string& what) const;
  std::filesystem::path file_;
  StoreAccess access_ = StoreAccess::read_write;
  bool immutable_ = false;
  sqlite3* db_ = nullptr;
};

}  // namespace rkhs
