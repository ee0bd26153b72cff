// `rkhs-study store check|vacuum|export`: the result store's records verified one by one
// (read_record, rkhs/run/result_store.hpp), the ones that do not verify removed, or every
// record written out as CSV or JSON.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/run/result_store.hpp"

namespace rkhs::cli {

namespace {

// An existing store: `store` commands never create one; check and export open it read-only.
ResultStore open_existing(const std::string& file, StoreAccess access) {
  if (!std::filesystem::exists(file))
    throw std::runtime_error(fmt::format("{}: no such result store", file));
  return ResultStore(file, access);
}

// "STORE: trial KEY (study S, hash 1a2b3c4d5e6f): what is wrong".
std::string bad_record_line(const std::string& file, const ResultStore::Entry& entry) {
  return fmt::format("{}: trial {} (study {}, hash {}): {}", file, entry.key, entry.study,
                     entry.hash.substr(0, 12), entry.check.problem);
}

// What `store check` finds in a store.
struct Findings {
  std::vector<std::string> integrity;  // SQLite's integrity check (empty: ok)
  std::vector<std::string> bad_lines;  // one per record that does not verify
  std::size_t total = 0, bad = 0, old_format = 0, format_2 = 0;
};

Findings find_problems(const std::string& file, const ResultStore& store) {
  Findings found;
  // SQLite's own check first: a damaged index finds rows it should not (or misses some), so
  // the records' checksums alone do not prove the file.
  found.integrity = store.integrity_problems();
  if (!found.integrity.empty()) return found;
  store.for_each([&](const ResultStore::Entry& entry) {
    ++found.total;
    if (entry.check.sound()) {
      found.format_2 += entry.check.key_and_study_proven() ? 0 : 1;
      return;
    }
    if (entry.check.old_format) {
      ++found.old_format;
      return;
    }
    ++found.bad;
    found.bad_lines.push_back(bad_record_line(file, entry));
  });
  return found;
}

// `read` of the store opened read-only; once more (through the WAL) when a run started writing
// it while it was read as an immutable file.
template <class Read>
auto read_store(const std::string& file, Read read) {
  for (int attempt = 0;; ++attempt) {
    const auto store = open_existing(file, StoreAccess::read_only);
    auto found = read(store);
    if (attempt > 0 || !store.written_meanwhile()) return found;
  }
}

int store_check(const std::string& file) {
  const auto found =
      read_store(file, [&](const ResultStore& store) { return find_problems(file, store); });
  if (!found.integrity.empty()) {
    for (std::size_t i = 0; i < found.integrity.size() && i < 20; ++i)
      std::cout << fmt::format("{}: {}\n", file, found.integrity[i]);
    std::cout << fmt::format(
        "{}: SQLite's integrity check failed ({}): the database file is damaged and its "
        "records are not checked (a damaged index finds a stored trial under no hash, or two); "
        "restore the store from a copy, or, when only an index is damaged, rebuild it with "
        "`sqlite3 {} REINDEX` and check again\n",
        file, counted(found.integrity.size(), "problem", "problems"), file);
    return exit_failed_trials;
  }
  for (const auto& line : found.bad_lines) std::cout << line << "\n";
  const auto [total, bad, old_format, format_2] =
      std::tuple(found.total, found.bad, found.old_format, found.format_2);
  std::cout << fmt::format("{}: {}, {} verified, {} bad, {} in the old record format (no checksum)",
                           file, counted(total, "record", "records"), total - bad - old_format, bad,
                           old_format);
  if (format_2)
    std::cout << fmt::format(
        "; {} of the verified in record format 2 (its checksum does not cover the key and study "
        "columns)",
        format_2);
  std::cout << (bad + old_format ? "; `rkhs-study store vacuum` removes them (their trials run "
                                   "again when a study needs them)\n"
                                 : "\n");
  return bad + old_format ? exit_failed_trials : exit_ok;
}

int store_vacuum(const std::string& file) {
  auto store = open_existing(file, StoreAccess::read_write);
  std::vector<std::string> doomed;
  std::size_t bad = 0, old_format = 0;
  store.for_each([&](const ResultStore::Entry& entry) {
    if (entry.check.sound()) return;
    doomed.push_back(entry.hash);
    if (entry.check.old_format) {
      ++old_format;
    } else {
      ++bad;
      std::cout << "removed " << bad_record_line(file, entry) << "\n";
    }
  });
  store.remove(doomed);
  store.vacuum();
  store.checkpoint();
  std::cout << fmt::format("{}: removed {} bad and {} old-format records; it holds {}\n", file, bad,
                           old_format, counted(store.size(), "trial", "trials"));
  return exit_ok;
}

// The metric names of every record that verifies, in the order they first appear.
std::vector<std::string> metric_columns(const std::vector<ResultStore::Entry>& entries) {
  std::vector<std::string> columns;
  for (const auto& entry : entries)
    for (const auto& name : entry.check.metric_names)
      if (std::find(columns.begin(), columns.end(), name) == columns.end()) columns.push_back(name);
  return columns;
}

// The `check` column of an export: "ok", what is wrong, or that a record of format 2 proves its
// result but not its key and study columns.
std::string check_text(const ResultStore::Entry& entry) {
  if (!entry.check.sound()) return entry.check.problem;
  return entry.check.key_and_study_proven()
             ? "ok"
             : "ok (record format 2: its checksum does not cover key and study)";
}

std::string flags_text(const TrialResult& result) {
  return fmt::format("{}", fmt::join(result.flags, ";"));
}

std::string export_csv(const std::vector<ResultStore::Entry>& entries) {
  const auto metrics = metric_columns(entries);
  std::vector<std::string> header{"hash",   "study", "key",    "stored", "check",   "status",
                                  "reason", "solve", "engine", "flags",  "seconds", "data"};
  header.insert(header.end(), metrics.begin(), metrics.end());
  auto row = [](const std::vector<std::string>& fields) {
    std::string line;
    for (std::size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + csv_field(fields[i]);
    return line + "\n";
  };
  std::string out = row(header);
  for (const auto& entry : entries) {
    std::vector<std::string> fields{entry.hash, entry.study, entry.key, entry.stored,
                                    check_text(entry)};
    if (const auto& r = entry.check.result) {
      fields.insert(fields.end(), {r->ok ? "ok" : "failed", r->reason, r->solve_method,
                                   std::string(engine_text(*r)), flags_text(*r),
                                   csv_number(r->seconds), r->data_provenance});
      for (const auto& metric : metrics) {
        const auto& names = entry.check.metric_names;
        const auto at = std::find(names.begin(), names.end(), metric);
        fields.push_back(at == names.end() ? "" : csv_number(r->metrics[at - names.begin()]));
      }
    } else {
      fields.resize(header.size());
    }
    out += row(fields);
  }
  return out;
}

std::string json_reals(const std::vector<double>& values) {
  std::vector<std::string> items;
  for (double v : values) items.push_back(json_number(v));
  return fmt::format("[{}]", fmt::join(items, ", "));
}

// A record's work counters (docs/results.md "Work counters"), null when it holds none; the
// allocation counts null when the build that stored it did not count them.
std::string work_json(const std::optional<WorkCounts>& work) {
  if (!work) return "null";
  return "{" + work_counts_json(*work) + "}";
}

std::string export_json(const std::vector<ResultStore::Entry>& entries) {
  std::vector<std::string> records;
  for (const auto& entry : entries) {
    std::string record =
        fmt::format("  {{\"hash\": {}, \"study\": {}, \"key\": {}, \"stored\": {}, \"check\": {}",
                    json_string(entry.hash), json_string(entry.study), json_string(entry.key),
                    json_string(entry.stored), json_string(check_text(entry)));
    if (const auto& r = entry.check.result) {
      std::vector<std::string> metrics, samples, snapshots;
      for (std::size_t i = 0; i < r->metrics.size(); ++i)
        metrics.push_back(fmt::format("{}: {}", json_string(entry.check.metric_names[i]),
                                      json_number(r->metrics[i])));
      for (const auto& s : r->samples)
        samples.push_back(json_reals({s.t, s.state_error, s.lyapunov}));
      for (const auto& s : r->snapshots)
        snapshots.push_back(fmt::format("{{\"lap\": {}, \"estimate\": {}}}", json_number(s.lap),
                                        json_reals(s.estimate)));
      record += fmt::format(
          ", \"status\": {}, \"reason\": {}, \"solve\": {}, \"engine\": {}, \"flags\": {}, "
          "\"seconds\": {}, \"data\": {}, \"metrics\": {{{}}}, \"samples\": [{}], \"road\": {}, "
          "\"snapshots\": [{}], \"work\": {}",
          json_string(r->ok ? "ok" : "failed"), json_string(r->reason),
          json_string(r->solve_method), json_string(engine_text(*r)), json_string(flags_text(*r)),
          json_number(r->seconds), json_string(r->data_provenance), fmt::join(metrics, ", "),
          fmt::join(samples, ", "), json_reals(r->road), fmt::join(snapshots, ", "),
          work_json(r->work));
    }
    records.push_back(record + "}");
  }
  return records.empty() ? "[]\n" : fmt::format("[\n{}\n]\n", fmt::join(records, ",\n"));
}

int store_export(const std::string& file, const std::string& format, const std::string& out) {
  // The store itself, or its -wal, -shm or -journal file, by any path or link: the export
  // would replace the store with its own records as text. Refused before anything is read.
  if (!out.empty() && out != "-")
    for (const char* suffix : {"", "-wal", "-shm", "-journal"})
      refuse_output_onto_input("--out", out, suffix[0] ? "a file of the store," : "the store",
                               file + suffix);
  const auto entries = read_store(file, [](const ResultStore& store) {
    std::vector<ResultStore::Entry> all;
    store.for_each([&](const ResultStore::Entry& entry) { all.push_back(entry); });
    return all;
  });
  const auto text = format == "json" ? export_json(entries) : export_csv(entries);
  if (out.empty() || out == "-") {
    std::cout << text;
  } else {
    write_file_atomically(out, text);
    std::cerr << fmt::format("wrote {} of {} to {}\n", counted(entries.size(), "record", "records"),
                             file, out);
  }
  return exit_ok;
}

}  // namespace

int command_store(const StoreCommand& arguments) {
  if (arguments.action == "check") return store_check(arguments.store_file);
  if (arguments.action == "vacuum") return store_vacuum(arguments.store_file);
  if (arguments.action == "export")
    return store_export(arguments.store_file, arguments.format, arguments.out_file);
  throw std::invalid_argument(fmt::format("unknown store action '{}'", arguments.action));
}

Command add_store_command(CLI::App& app) {
  auto arguments = std::make_shared<StoreCommand>();
  auto* store = app.add_subcommand(
      "store",
      "the result store: check (verify every record), vacuum (remove the records that "
      "do not verify), export (records as CSV or JSON)");
  store->add_option("action", arguments->action, "check, vacuum or export")
      ->required()
      ->check(CLI::IsMember({"check", "vacuum", "export"}));
  store->add_option("--store", arguments->store_file,
                    "result store (default: results/rkhs-study.sqlite)");
  store->add_option("--format", arguments->format, "export: csv (default) or json")
      ->check(CLI::IsMember({"csv", "json"}));
  store->add_option("--out", arguments->out_file, "export: write to FILE (default: stdout)");
  return {store, {}, [arguments](pipeline::Executor&) { return command_store(*arguments); }};
}

}  // namespace rkhs::cli
