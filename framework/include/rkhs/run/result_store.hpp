#pragma once
// The result store: every finished trial is committed to an SQLite database as soon as it
// finishes, keyed by a content hash of everything that determines it. A re-run reuses stored
// trials and runs only what is missing or changed; a run killed at any moment (SIGINT,
// SIGTERM, kill -9) loses only the trials in flight. Several studies can share one store.
//
// Durability: the database is in WAL mode and each trial is its own transaction, so a
// committed trial survives the death of the process (not necessarily a power failure:
// synchronous = NORMAL).

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
/// and back. Throws std::invalid_argument for text that is not such a record.
std::string serialize_result(const TrialResult& result);
TrialResult deserialize_result(std::string_view text);

class ResultStore;

struct StoredRun {
  std::vector<TrialResult> results;  ///< in the order of the trials
  std::size_t reused = 0;            ///< trials taken from the store
  std::size_t ran = 0;               ///< trials run (and stored) now
  std::size_t skipped = 0;           ///< trials not run because the run was interrupted
  std::size_t stopped = 0;           ///< of those, trials stopped while they ran (not stored)
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

  /// The stored result of the trial with this hash, if any.
  std::optional<TrialResult> find(const std::string& hash) const;
  /// Stores (or replaces) a result and commits it before returning.
  void put(const std::string& hash, const std::string& study, const std::string& key,
           const TrialResult& result);
  /// Copies every trial of the store at `other` into this one (a later copy of the same hash
  /// replaces an earlier one: results of the same hash are identical). Returns how many trials
  /// `other` holds. Throws std::runtime_error naming a file that is not a store.
  std::size_t merge_from(const std::filesystem::path& other);
  /// Number of stored trials (of all studies).
  std::size_t size() const;
  const std::filesystem::path& file() const noexcept { return file_; }

 private:
  void exec(const char* sql) const;
  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
};

}  // namespace rkhs
