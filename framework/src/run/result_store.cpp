#include "rkhs/run/result_store.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sqlite3.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <set>
#include <stdexcept>
#include <thread>

#include "rkhs/core/input_file.hpp"

namespace rkhs {

namespace {

// SQLite returns SQLITE_BUSY without calling the busy handler in two cases a study meets: while
// the last connection to close cleans up the WAL and shared-memory files, and while the first
// connection after a crashed one (a SIGKILLed rank) recovers the WAL (sqlite.org/wal.html,
// "Sometimes queries return SQLITE_BUSY in WAL mode"). Both end within milliseconds, so a
// statement that meets SQLITE_BUSY is tried again for up to the busy timeout before it fails.
constexpr int busy_timeout_ms = 10000;

template <class Attempt>
int retry_while_busy(Attempt attempt) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(busy_timeout_ms);
  int status = attempt();
  while ((status & 0xff) == SQLITE_BUSY && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    status = attempt();
  }
  return status;
}

// sqlite3_step, tried again (after a reset) while the database is busy.
int step(sqlite3_stmt* statement) {
  return retry_while_busy([&] {
    const int status = sqlite3_step(statement);
    if ((status & 0xff) == SQLITE_BUSY) sqlite3_reset(statement);
    return status;
  });
}

}  // namespace

namespace {

struct Statement {
  sqlite3_stmt* handle = nullptr;
  Statement(sqlite3* db, const char* sql, const std::filesystem::path& file) {
    if (sqlite3_prepare_v2(db, sql, -1, &handle, nullptr) != SQLITE_OK)
      throw std::runtime_error(
          fmt::format("{}: result store: {}", file.string(), sqlite3_errmsg(db)));
  }
  ~Statement() { sqlite3_finalize(handle); }
};

// The store's marks in the database header: PRAGMA application_id ("rkhs") and PRAGMA
// user_version, the store's schema (1: a store from before the marks, 2: records of format 3).
constexpr int store_application_id = 0x726b6873;
constexpr int store_schema = 2;

// `file` as an SQLite URI (sqlite.org/uri.html): every byte but the unreserved ones and '/'
// percent-encoded.
std::string file_uri(const std::filesystem::path& file, const char* parameters) {
  std::string out = "file:";
  for (unsigned char c : std::filesystem::absolute(file).string()) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '.' || c == '_' || c == '~')
      out += static_cast<char>(c);
    else
      out += fmt::format("%{:02X}", c);
  }
  return out + parameters;
}

std::filesystem::path wal_of(const std::filesystem::path& file) {
  return file.string() + "-wal";
}

// One integer of a PRAGMA (application_id, user_version), or nothing on an error.
std::optional<int> pragma_int(sqlite3* db, const char* sql) {
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &statement, nullptr) != SQLITE_OK) return std::nullopt;
  std::optional<int> value;
  if (step(statement) == SQLITE_ROW) value = sqlite3_column_int(statement, 0);
  sqlite3_finalize(statement);
  return value;
}

// A store path that exists and is not a regular file (a directory, a FIFO, a device, after
// links) is refused by its type before SQLite opens it (opening a FIFO waits for a writer).
void refuse_by_type(const std::filesystem::path& file) {
  const auto kind = not_regular_file_kind(file);
  if (kind.empty()) return;
  throw std::runtime_error(fmt::format(
      "{}: is {}, not a result store (an SQLite database file{})", file.string(), kind,
      kind == "a directory"
          ? fmt::format("; a store in a folder is a file in it, e.g. {}",
                        (file / "rkhs-study.sqlite").string())
          : std::string()));
}

// An SQLite file shorter than its header says: "truncated: N bytes of the M its header gives
// (P pages of S bytes)"; nothing for a file that is not SQLite's or is whole. Not judged while
// a -wal file is beside it: a writer's checkpoint may then be extending the file (SQLite reads
// it consistently through the WAL), and the header's page count is trusted only when its
// version-valid-for number equals its change counter (SQLite's own rule).
std::optional<std::string> truncation(const std::filesystem::path& file) {
  if (std::filesystem::exists(wal_of(file))) return std::nullopt;
  std::error_code error;
  const auto size = std::filesystem::file_size(file, error);
  if (error || size == 0) return std::nullopt;
  std::array<unsigned char, 100> header{};
  std::FILE* in = std::fopen(file.c_str(), "rb");
  if (!in) return std::nullopt;
  const auto got = std::fread(header.data(), 1, header.size(), in);
  std::fclose(in);
  static constexpr char magic[] = "SQLite format 3";  // with its NUL: 16 bytes
  if (got < sizeof magic || std::memcmp(header.data(), magic, sizeof magic) != 0)
    return std::nullopt;
  if (got < header.size())
    return fmt::format("truncated: {} bytes, shorter than SQLite's 100-byte header", size);
  const std::uint64_t page_size =
      header[16] == 0 && header[17] == 1 ? 65536 : (std::uint64_t{header[16]} << 8 | header[17]);
  const std::uint64_t pages = std::uint64_t{header[28]} << 24 | std::uint64_t{header[29]} << 16 |
                              std::uint64_t{header[30]} << 8 | header[31];
  const bool count_valid = std::memcmp(header.data() + 24, header.data() + 92, 4) == 0;
  if (!count_valid || page_size < 512 || pages == 0 || size >= page_size * pages)
    return std::nullopt;
  return fmt::format("truncated: {} bytes of the {} its header gives ({} pages of {} bytes)", size,
                     page_size * pages, pages, page_size);
}

// Why the store `file` cannot be written where it lies, if it cannot: the file itself, or the
// folder SQLite creates the -wal and -shm files in (or, for a new store, the file in). Asked of
// the system (access(2)), which knows a read-only file system also for root.
std::optional<std::string> unwritable(const std::filesystem::path& file) {
  const auto reason = [](int error, const std::string& what) {
    return error == EROFS
               ? fmt::format("{} is on a read-only file system", what)
               : fmt::format("{} cannot be written by this user: {}", what, std::strerror(error));
  };
  std::error_code ignored;
  const bool exists = std::filesystem::exists(file, ignored);
  if (exists && ::access(file.c_str(), W_OK) != 0) return reason(errno, "the file");
  // The nearest folder that exists: the store's own, or the one its folders are created in.
  auto folder = file.parent_path();
  while (!folder.empty() && !std::filesystem::exists(folder, ignored))
    folder = folder.parent_path();
  if (folder.empty()) folder = ".";
  const bool side_files = std::filesystem::exists(wal_of(file), ignored) &&
                          std::filesystem::exists(file.string() + "-shm", ignored);
  if ((!exists || !side_files) && ::access(folder.c_str(), W_OK | X_OK) != 0)
    return reason(errno, fmt::format("its folder {}", folder.string())) +
           (exists ? " (SQLite creates the -wal and -shm files beside the store)" : "");
  return std::nullopt;
}

}  // namespace

ResultStore::ResultStore(const std::filesystem::path& file, StoreAccess access)
    : file_(file), access_(access) {
  refuse_by_type(file);
  if (const auto why = truncation(file))
    throw DamagedStore(
        fmt::format("{}: damaged result store: {}; restore it from a copy or "
                    "remove it (its trials then run again)",
                    file.string(), *why));
  if (access == StoreAccess::read_only) {
    if (!std::filesystem::is_regular_file(file))
      throw std::runtime_error(fmt::format("{}: no such result store", file.string()));
    // Without a -wal file the database file holds every committed trial: it is read as an
    // immutable file, so that SQLite creates no -wal and -shm files beside it (which it does
    // for a read-only connection to a WAL database, and cannot on a read-only mount).
    open(!std::filesystem::exists(wal_of(file)));
  } else {
    if (const auto why = unwritable(file))
      throw ReadOnlyStore(
          std::filesystem::exists(file)
              ? fmt::format("{}: the result store is read-only ({})", file.string(), *why)
              : fmt::format("{}: cannot create the result store: {}", file.string(), *why));
    if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
    open(false);
  }
  try {
    adopt_schema();
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

void ResultStore::open(bool immutable) {
  const bool read_only = access_ == StoreAccess::read_only;
  const auto name =
      read_only ? file_uri(file_, immutable ? "?mode=ro&immutable=1" : "?mode=ro") : file_.string();
  const int flags = read_only ? SQLITE_OPEN_READONLY | SQLITE_OPEN_URI | SQLITE_OPEN_FULLMUTEX
                              : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX;
  immutable_ = read_only && immutable;
  if (sqlite3_open_v2(name.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(
        fmt::format("{}: cannot open the result store: {}", file_.string(), why));
  }
  sqlite3_busy_timeout(db_, busy_timeout_ms);
}

// Everything is read before anything is written: a database that is not a store is left as it
// was (no WAL switch, no table).
void ResultStore::adopt_schema() {
  auto not_a_store = [&](const std::string& why) {
    // SQLite's own verdict on pages it could not read: a damaged store, not another file.
    if (sqlite3_errcode(db_) == SQLITE_CORRUPT)
      throw DamagedStore(
          fmt::format("{}: damaged result store: {}; restore it from a copy or "
                      "remove it (its trials then run again)",
                      file_.string(), why));
    // A file SQLite could not open or write (its -wal or -shm file) is not judged.
    const int code = sqlite3_errcode(db_);
    if (code == SQLITE_CANTOPEN || code == SQLITE_READONLY || code == SQLITE_PERM)
      throw std::runtime_error(
          fmt::format("{}: cannot open the result store: {}", file_.string(), why));
    throw std::runtime_error(
        fmt::format("{}: not an rkhs-study result store: {}", file_.string(), why));
  };
  const auto application_id = pragma_int(db_, "PRAGMA application_id");
  const auto schema = pragma_int(db_, "PRAGMA user_version");
  if (!application_id || !schema) not_a_store(sqlite3_errmsg(db_));
  // The tables and their columns.
  std::vector<std::string> objects, columns;
  auto names = [&](const char* sql, std::vector<std::string>& out) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &statement, nullptr) != SQLITE_OK)
      not_a_store(sqlite3_errmsg(db_));
    int status = step(statement);
    for (; status == SQLITE_ROW; status = sqlite3_step(statement)) {
      const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
      out.emplace_back(text ? text : "");
    }
    sqlite3_finalize(statement);
    if (status != SQLITE_DONE) not_a_store(sqlite3_errmsg(db_));
  };
  names("SELECT name FROM sqlite_master WHERE type = 'table'", objects);
  const bool has_trials = std::find(objects.begin(), objects.end(), "trials") != objects.end();
  if (has_trials) names("SELECT name FROM pragma_table_info('trials') ORDER BY cid", columns);
  const std::vector<std::string> store_columns{"hash", "study", "key", "result", "stored"};
  const bool empty = objects.empty() && *application_id == 0 && *schema == 0;
  if (*application_id != 0 && *application_id != store_application_id)
    not_a_store(fmt::format("its application id is {:#x}, a store's {:#x}", *application_id,
                            store_application_id));
  if (*schema > store_schema)
    not_a_store(
        fmt::format("its schema is {}, newer than this rkhs-study's {} (a newer "
                    "rkhs-study wrote it)",
                    *schema, store_schema));
  if (empty && access_ == StoreAccess::read_only) not_a_store("an empty database");
  if (!empty && !has_trials)
    not_a_store(objects.empty() ? std::string("it has no trials table")
                                : fmt::format("it has no trials table (its tables: {})",
                                              fmt::join(objects, ", ")));
  if (has_trials && columns != store_columns)
    not_a_store(fmt::format("its trials table has the columns {}, a store's {}",
                            fmt::join(columns, ", "), fmt::join(store_columns, ", ")));
  if (access_ == StoreAccess::read_only) return;
  exec("PRAGMA journal_mode=WAL");
  exec("PRAGMA synchronous=NORMAL");
  if (*application_id == store_application_id && *schema == store_schema) return;
  // A new store, or one from before the marks: created and marked in one transaction.
  exec("BEGIN IMMEDIATE");
  try {
    exec(
        "CREATE TABLE IF NOT EXISTS trials (hash TEXT PRIMARY KEY, study TEXT NOT NULL, "
        "key TEXT NOT NULL, result TEXT NOT NULL, stored TEXT NOT NULL)");
    exec(fmt::format("PRAGMA application_id = {}", store_application_id).c_str());
    exec(fmt::format("PRAGMA user_version = {}", store_schema).c_str());
    exec("COMMIT");
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

ResultStore::~ResultStore() {
  sqlite3_close(db_);
}

bool ResultStore::written_meanwhile() const {
  return immutable_ && std::filesystem::exists(wal_of(file_));
}

void ResultStore::exec(const char* sql) const {
  char* message = nullptr;
  const int status = retry_while_busy([&] {
    sqlite3_free(message);
    message = nullptr;
    return sqlite3_exec(db_, sql, nullptr, nullptr, &message);
  });
  if (status != SQLITE_OK) {
    const std::string why = message ? message : "unknown error";
    sqlite3_free(message);
    throw std::runtime_error(fmt::format("{}: result store: {}", file_.string(), why));
  }
}

[[noreturn]] void ResultStore::fail(const std::string& what) const {
  throw std::runtime_error(
      fmt::format("{}: result store: {}: {}", file_.string(), what, sqlite3_errmsg(db_)));
}

RecordCheck ResultStore::lookup(const std::string& hash,
                                const std::vector<std::string>* metric_names) const {
  Statement statement(db_, "SELECT study, key, result FROM trials WHERE hash = ?1", file_);
  sqlite3_bind_text(statement.handle, 1, hash.c_str(), -1, SQLITE_TRANSIENT);
  const int status = step(statement.handle);
  if (status == SQLITE_DONE) return {};
  if (status != SQLITE_ROW) fail("cannot read the trial " + hash);
  auto column = [&](int i) {
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement.handle, i));
    return std::string(text ? text : "");
  };
  return read_record(hash, column(0), column(1), column(2), metric_names);
}

std::optional<TrialResult> ResultStore::find(const std::string& hash) const {
  return lookup(hash).result;
}

void ResultStore::put(const std::string& hash, const std::string& study, const std::string& key,
                      const TrialResult& result, const std::vector<std::string>& metric_names) {
  if (access_ == StoreAccess::read_only)
    throw std::logic_error(file_.string() + ": result store opened read-only");
  Statement statement(db_,
                      "INSERT OR REPLACE INTO trials (hash, study, key, result, stored) "
                      "VALUES (?1, ?2, ?3, ?4, datetime('now'))",
                      file_);
  const auto record = store_record(hash, study, key, result, metric_names);
  sqlite3_bind_text(statement.handle, 1, hash.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement.handle, 2, study.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement.handle, 3, key.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement.handle, 4, record.c_str(), -1, SQLITE_TRANSIENT);
  if (step(statement.handle) != SQLITE_DONE) fail("cannot store the trial " + key);
}

std::set<std::string> ResultStore::keys_of_study(const std::string& study) const {
  Statement statement(db_, "SELECT key FROM trials WHERE study = ?1", file_);
  sqlite3_bind_text(statement.handle, 1, study.c_str(), -1, SQLITE_TRANSIENT);
  std::set<std::string> keys;
  for (bool first = true;; first = false) {
    const int status = first ? step(statement.handle) : sqlite3_step(statement.handle);
    if (status == SQLITE_DONE) return keys;
    if (status != SQLITE_ROW) fail("cannot read the stored trials");
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement.handle, 0));
    keys.emplace(text ? text : "");
  }
}

void ResultStore::for_each(const std::function<void(const Entry&)>& visit) const {
  Statement statement(db_, "SELECT hash, study, key, result, stored FROM trials ORDER BY key, hash",
                      file_);
  auto column = [&](int i) {
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement.handle, i));
    return std::string(text ? text : "");
  };
  // Only the first step may meet a busy database (and start again): the later ones read within
  // the read transaction it opened.
  for (bool first = true;; first = false) {
    const int status = first ? step(statement.handle) : sqlite3_step(statement.handle);
    if (status == SQLITE_DONE) return;
    if (status != SQLITE_ROW) fail("cannot read the stored trials");
    Entry entry{column(0), column(1), column(2), column(4), {}, column(3)};
    entry.check = read_record(entry.hash, entry.study, entry.key, entry.record);
    visit(entry);
  }
}

std::vector<std::string> ResultStore::integrity_problems() const {
  Statement statement(db_, "PRAGMA integrity_check", file_);
  std::vector<std::string> problems;
  int status = step(statement.handle);
  for (; status == SQLITE_ROW; status = sqlite3_step(statement.handle)) {
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement.handle, 0));
    const std::string line = text ? text : "";
    if (line != "ok") problems.push_back(line);
  }
  // A database too damaged to be checked at all: that is what is wrong with it.
  if (status != SQLITE_DONE) problems.push_back(sqlite3_errmsg(db_));
  return problems;
}

std::size_t ResultStore::remove(const std::vector<std::string>& hashes) {
  exec("BEGIN IMMEDIATE");
  std::size_t removed = 0;
  try {
    Statement statement(db_, "DELETE FROM trials WHERE hash = ?1", file_);
    for (const auto& hash : hashes) {
      sqlite3_reset(statement.handle);
      sqlite3_bind_text(statement.handle, 1, hash.c_str(), -1, SQLITE_TRANSIENT);
      if (step(statement.handle) != SQLITE_DONE) fail("cannot remove the trial " + hash);
      removed += static_cast<std::size_t>(sqlite3_changes(db_));
    }
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  exec("COMMIT");
  return removed;
}

void ResultStore::vacuum() {
  exec("VACUUM");
}

bool ResultStore::checkpoint() {
  if (access_ == StoreAccess::read_only) return true;  // nothing written
  const int status =
      sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_TRUNCATE, nullptr, nullptr);
  if (status == SQLITE_BUSY) return false;
  if (status != SQLITE_OK) fail("cannot checkpoint the WAL");
  return true;
}

namespace {

// Two verified records hold the same result when they differ at most in the trial's wall time
// (which a trial run twice never repeats) and in the study that stored it (studies share
// trials).
bool same_result(const RecordCheck& a, const RecordCheck& b) {
  if (a.metric_names != b.metric_names) return false;
  auto timeless = [](TrialResult result) {
    result.seconds = 0;
    return serialize_result(result);
  };
  return timeless(*a.result) == timeless(*b.result);
}

std::string entry_line(const std::string& file, const ResultStore::Entry& entry) {
  return fmt::format("{}: trial {} (study {}, hash {})", file, entry.key, entry.study,
                     entry.hash.substr(0, 12));
}

// At most 10 of `lines`, and how many more there are.
std::string listed(const std::vector<std::string>& lines) {
  std::string out;
  for (std::size_t i = 0; i < lines.size() && i < 10; ++i) out += "\n  " + lines[i];
  if (lines.size() > 10) out += fmt::format("\n  ... and {} more", lines.size() - 10);
  return out;
}

}  // namespace

std::vector<MergedSource> ResultStore::merge_from(const std::vector<std::filesystem::path>& sources,
                                                  MergePreference prefer,
                                                  const std::function<bool()>& stop_requested) {
  if (access_ == StoreAccess::read_only)
    throw std::logic_error(file_.string() + ": result store opened read-only");
  // Asked once per batch of records: a stop throws, and the transaction (if begun) is rolled
  // back below.
  constexpr std::size_t batch = 1024;
  std::size_t visited = 0;
  auto stop_point = [&](bool now = false) {
    if ((now || ++visited % batch == 0) && stop_requested && stop_requested())
      throw MergeInterrupted(fmt::format("{}: merge interrupted, nothing merged", file_.string()));
  };
  stop_point(true);
  // Every source read and verified first: nothing is written unless all of them are sound.
  std::vector<MergedSource> merged;
  std::vector<std::vector<Entry>> entries(sources.size());
  std::vector<std::string> bad;
  for (std::size_t s = 0; s < sources.size(); ++s) {
    const auto& file = sources[s];
    merged.push_back({file.string()});
    const ResultStore source(file, StoreAccess::read_only);
    if (const auto problems = source.integrity_problems(); !problems.empty())
      throw std::runtime_error(fmt::format("{}: SQLite's integrity check failed, nothing merged:{}",
                                           file.string(), listed(problems)));
    source.for_each([&](const Entry& entry) {
      stop_point();
      if (!entry.check.sound())
        bad.push_back(entry_line(file.string(), entry) + ": " + entry.check.problem);
      entries[s].push_back(entry);
    });
    merged[s].records = entries[s].size();
  }
  if (!bad.empty())
    throw std::runtime_error(fmt::format(
        "{} not verify, nothing merged (`rkhs-study store vacuum --store SOURCE` removes "
        "them):{}",
        bad.size() == 1 ? "1 stored trial does" : fmt::format("{} stored trials do", bad.size()),
        listed(bad)));

  // What the destination holds, then each source's trials resolved against it in turn, all in
  // one write transaction.
  struct Candidate {
    Entry entry;
    std::size_t source;  // index into `sources`; sources.size(): the destination's own
  };
  exec("BEGIN IMMEDIATE");
  try {
    std::map<std::string, Candidate> held;
    std::set<std::string> changed;
    for_each([&](const Entry& entry) {
      stop_point();
      held.insert({entry.hash, {entry, sources.size()}});
    });
    std::vector<std::string> conflicts;
    for (std::size_t s = 0; s < sources.size(); ++s) {
      for (auto& entry : entries[s]) {
        const auto [at, added] = held.try_emplace(entry.hash, Candidate{entry, s});
        if (added) {
          ++merged[s].added;
          changed.insert(entry.hash);
          continue;
        }
        auto& there = at->second;
        if (!there.entry.check.sound()) {  // the destination's own record does not verify
          there = {entry, s};
          ++merged[s].repaired;
          changed.insert(entry.hash);
        } else if (same_result(there.entry.check, entry.check)) {
          ++merged[s].same;
        } else if (prefer == MergePreference::source) {
          there = {entry, s};
          ++merged[s].replaced;
          changed.insert(entry.hash);
        } else if (prefer == MergePreference::destination) {
          ++merged[s].kept;
        } else {
          conflicts.push_back(fmt::format(
              "{} holds another result than {}", entry_line(sources[s].string(), entry),
              there.source == sources.size() ? file_.string() : sources[there.source].string()));
        }
      }
    }
    if (!conflicts.empty())
      throw std::runtime_error(fmt::format(
          "{} stored with different results, nothing merged (--prefer destination keeps the "
          "record already there, --prefer source takes the one merged later):{}",
          conflicts.size() == 1 ? "1 trial" : fmt::format("{} trials", conflicts.size()),
          listed(conflicts)));
    Statement insert(db_,
                     "INSERT OR REPLACE INTO trials (hash, study, key, result, stored) "
                     "VALUES (?1, ?2, ?3, ?4, ?5)",
                     file_);
    for (const auto& hash : changed) {
      stop_point();
      const auto& entry = held.at(hash).entry;
      sqlite3_reset(insert.handle);
      sqlite3_bind_text(insert.handle, 1, entry.hash.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(insert.handle, 2, entry.study.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(insert.handle, 3, entry.key.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(insert.handle, 4, entry.record.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(insert.handle, 5, entry.stored.c_str(), -1, SQLITE_TRANSIENT);
      if (step(insert.handle) != SQLITE_DONE) fail("cannot store the trial " + entry.key);
    }
    stop_point(true);
    exec("COMMIT");
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  return merged;
}

std::size_t ResultStore::size() const {
  Statement statement(db_, "SELECT COUNT(*) FROM trials", file_);
  if (step(statement.handle) != SQLITE_ROW) fail("cannot count the stored trials");
  return static_cast<std::size_t>(sqlite3_column_int64(statement.handle, 0));
}

}  // namespace rkhs
