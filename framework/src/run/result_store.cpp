#include "rkhs/run/result_store.hpp"

#include "rkhs/run/trial_identity.hpp"

#include <fmt/format.h>
#include <sqlite3.h>

#include <charconv>
#include <cmath>
#include <ctime>
#include <map>
#include <sstream>
#include <stdexcept>

#include "rkhs/core/build_info.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/approx/target.hpp"

namespace rkhs {

namespace {

std::string join_reals(const std::vector<double>& values) {
  std::string out;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) out += ' ';
    out += format_real(values[i]);
  }
  return out;
}

// from_chars, not stod: stod rejects subnormal numbers, which a metric can be.
double parse_real(const std::string& token) {
  if (token == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (token == "inf") return std::numeric_limits<double>::infinity();
  if (token == "-inf") return -std::numeric_limits<double>::infinity();
  double value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size())
    throw std::invalid_argument("stored value '" + token + "' is not a number");
  return value;
}

std::vector<double> split_reals(std::string_view text) {
  std::vector<double> out;
  std::istringstream in{std::string(text)};
  std::string token;
  while (in >> token) out.push_back(parse_real(token));
  return out;
}

// One line per field: strings have '\\' and line breaks escaped.
std::string escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '\\') out += "\\\\";
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

std::string unescape(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\\' && i + 1 < text.size()) {
      out += text[i + 1] == 'n' ? '\n' : text[i + 1];
      ++i;
    } else {
      out += text[i];
    }
  }
  return out;
}

}  // namespace

StoredRun run_with_store(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                         const RunOptions& options, ResultStore* store, bool fresh,
                         const TrialExecutor& execute,
                         const std::vector<std::string>& known_hashes) {
  StoredRun out;
  out.results.resize(trials.size());
  if (!known_hashes.empty() && known_hashes.size() != trials.size())
    throw std::invalid_argument("run_with_store: one known hash per trial expected");
  const auto hashes = !store                 ? std::vector<std::string>()
                      : known_hashes.empty() ? trial_hashes(study, trials)
                                             : known_hashes;
  std::vector<TrialSpec> pending;
  std::vector<std::size_t> position;  // index into `trials` of each pending trial
  for (std::size_t i = 0; i < trials.size(); ++i) {
    if (store && !fresh)
      if (auto found = store->find(hashes[i])) {
        out.results[i] = std::move(*found);
        ++out.reused;
        continue;
      }
    pending.push_back(trials[i]);
    position.push_back(i);
  }
  std::map<std::size_t, std::size_t> slot;  // trial index -> position in `trials`
  for (std::size_t k = 0; k < pending.size(); ++k) slot[pending[k].index] = position[k];
  RunOptions storing = options;
  storing.on_trial_finished = [&](const TrialSpec& trial, const TrialResult& result) {
    if (store) store->put(hashes[slot.at(trial.index)], study.name, trial.key, result);
    if (options.on_trial_finished) options.on_trial_finished(trial, result);
  };
  auto ran = execute(study, pending, storing);
  for (std::size_t k = 0; k < pending.size(); ++k) {
    if (ran[k].skipped) {
      ++out.skipped;
      if (ran[k].stopped_while_running) ++out.stopped;
    } else {
      ++out.ran;
    }
    out.results[position[k]] = std::move(ran[k]);
  }
  return out;
}

std::string serialize_result(const TrialResult& r) {
  std::string out = "rkhs-trial 1\n";
  out += fmt::format("ok {}\n", r.ok ? 1 : 0);
  out += "reason " + escape(r.reason) + "\n";
  out += "solve " + escape(r.solve_method) + "\n";
  if (!r.engine.empty()) out += "engine " + escape(r.engine) + "\n";
  std::string flags;
  for (std::size_t i = 0; i < r.flags.size(); ++i) flags += (i ? ";" : "") + r.flags[i];
  out += "flags " + escape(flags) + "\n";
  out += "seconds " + format_real(r.seconds) + "\n";
  out += "data " + escape(r.data_provenance) + "\n";
  out += "metrics " + join_reals(r.metrics) + "\n";
  std::vector<double> samples;
  for (const auto& s : r.samples) samples.insert(samples.end(), {s.t, s.state_error, s.lyapunov});
  out += "samples " + join_reals(samples) + "\n";
  out += "road " + join_reals(r.road) + "\n";
  for (const auto& snapshot : r.snapshots)
    out += "snapshot " + format_real(snapshot.lap) + " " + join_reals(snapshot.estimate) + "\n";
  return out;
}

TrialResult deserialize_result(std::string_view text) {
  std::istringstream in{std::string(text)};
  std::string line;
  if (!std::getline(in, line) || line != "rkhs-trial 1")
    throw std::invalid_argument("not a stored trial record (version line missing)");
  TrialResult r;
  while (std::getline(in, line)) {
    const auto space = line.find(' ');
    const std::string field = line.substr(0, space);
    const std::string value = space == std::string::npos ? "" : line.substr(space + 1);
    if (field == "ok") r.ok = value == "1";
    else if (field == "reason") r.reason = unescape(value);
    else if (field == "solve") r.solve_method = unescape(value);
    else if (field == "engine") r.engine = unescape(value);
    else if (field == "flags") {
      const auto flags = unescape(value);
      std::size_t start = 0;
      while (start < flags.size()) {
        const auto stop = std::min(flags.find(';', start), flags.size());
        r.flags.push_back(flags.substr(start, stop - start));
        start = stop + 1;
      }
    } else if (field == "seconds") r.seconds = parse_real(value);
    else if (field == "data") r.data_provenance = unescape(value);
    else if (field == "metrics") r.metrics = split_reals(value);
    else if (field == "samples") {
      const auto v = split_reals(value);
      if (v.size() % 3) throw std::invalid_argument("stored samples are not triples");
      for (std::size_t i = 0; i < v.size(); i += 3) r.samples.push_back({v[i], v[i + 1], v[i + 2]});
    } else if (field == "road") r.road = split_reals(value);
    else if (field == "snapshot") {
      auto v = split_reals(value);
      if (v.empty()) throw std::invalid_argument("empty stored snapshot");
      r.snapshots.push_back({v.front(), std::vector<double>(v.begin() + 1, v.end())});
    } else throw std::invalid_argument("unknown field '" + field + "' in a stored trial");
  }
  return r;
}

ResultStore::ResultStore(const std::filesystem::path& file) : file_(file) {
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(fmt::format("{}: cannot open the result store: {}", file.string(), why));
  }
  sqlite3_busy_timeout(db_, 10000);
  try {
    exec("PRAGMA journal_mode=WAL");
    exec("PRAGMA synchronous=NORMAL");
    exec("CREATE TABLE IF NOT EXISTS trials (hash TEXT PRIMARY KEY, study TEXT NOT NULL, "
         "key TEXT NOT NULL, result TEXT NOT NULL, stored TEXT NOT NULL)");
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

ResultStore::~ResultStore() { sqlite3_close(db_); }

void ResultStore::exec(const char* sql) const {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string why = message ? message : "unknown error";
    sqlite3_free(message);
    throw std::runtime_error(fmt::format("{}: result store: {}", file_.string(), why));
  }
}

namespace {
struct Statement {
  sqlite3_stmt* handle = nullptr;
  Statement(sqlite3* db, const char* sql, const std::filesystem::path& file) {
    if (sqlite3_prepare_v2(db, sql, -1, &handle, nullptr) != SQLITE_OK)
      throw std::runtime_error(fmt::format("{}: result store: {}", file.string(), sqlite3_errmsg(db)));
  }
  ~Statement() { sqlite3_finalize(handle); }
};
}  // namespace

std::optional<TrialResult> ResultStore::find(const std::string& hash) const {
  Statement statement(db_, "SELECT result FROM trials WHERE hash = ?1", file_);
  sqlite3_bind_text(statement.handle, 1, hash.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(statement.handle) != SQLITE_ROW) return std::nullopt;
  const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement.handle, 0));
  return deserialize_result(text ? text : "");
}

void ResultStore::put(const std::string& hash, const std::string& study, const std::string& key,
                      const TrialResult& result) {
  Statement statement(db_,
                      "INSERT OR REPLACE INTO trials (hash, study, key, result, stored) "
                      "VALUES (?1, ?2, ?3, ?4, datetime('now'))",
                      file_);
  const auto record = serialize_result(result);
  sqlite3_bind_text(statement.handle, 1, hash.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement.handle, 2, study.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement.handle, 3, key.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(statement.handle, 4, record.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(statement.handle) != SQLITE_DONE)
    throw std::runtime_error(fmt::format("{}: result store: {}", file_.string(), sqlite3_errmsg(db_)));
}

std::size_t ResultStore::merge_from(const std::filesystem::path& other) {
  if (!std::filesystem::exists(other))
    throw std::runtime_error(fmt::format("{}: no such result store", other.string()));
  const std::size_t count = ResultStore(other).size();  // also checks that it is a store
  Statement attach(db_, "ATTACH DATABASE ?1 AS other", file_);
  sqlite3_bind_text(attach.handle, 1, other.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(attach.handle) != SQLITE_DONE)
    throw std::runtime_error(fmt::format("{}: cannot attach {}: {}", file_.string(), other.string(),
                                         sqlite3_errmsg(db_)));
  try {
    exec("INSERT OR REPLACE INTO trials SELECT hash, study, key, result, stored FROM other.trials");
  } catch (...) {
    exec("DETACH DATABASE other");
    throw;
  }
  exec("DETACH DATABASE other");
  return count;
}

std::size_t ResultStore::size() const {
  Statement statement(db_, "SELECT COUNT(*) FROM trials", file_);
  if (sqlite3_step(statement.handle) != SQLITE_ROW) return 0;
  return static_cast<std::size_t>(sqlite3_column_int64(statement.handle, 0));
}

}  // namespace rkhs
