// A trial's result as text and the verified record the store keeps of it (result_store.hpp):
// serialize_result, deserialize_result, store_record, read_record. The SQLite store is
// result_store.cpp; run_with_store is run_with_store.cpp.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "rkhs/core/printable.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/run/result_store.hpp"

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
  // Only what format_real writes: "nan(0x123)", "NaN", "infinity" or "INF" are read by
  // from_chars, but a record that holds them was not written by rkhs-study.
  if (ec != std::errc() || end != token.data() + token.size() || !std::isfinite(value))
    throw std::invalid_argument("stored value '" + printable(token) + "' is not a number");
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
// "kernel_evaluations=12 kernel_derivative_evaluations=0 factorisations=1 ... [allocations=...]":
// the fields of work_count_fields in order, the allocation fields only when tracked.
std::string work_line(const WorkCounts& work) {
  std::string out;
  for (const auto& field : work_count_fields)
    if (!field.allocation || work.allocations_tracked)
      out += fmt::format("{}{}={}", out.empty() ? "" : " ", field.name, work.*field.member);
  return out;
}

WorkCounts parse_work_line(std::string_view text) {
  std::map<std::string, std::uint64_t, std::less<>> values;
  std::istringstream in{std::string(text)};
  for (std::string item; in >> item;) {
    const auto equals = item.find('=');
    std::uint64_t value = 0;
    const char* first = item.data() + (equals == std::string::npos ? item.size() : equals + 1);
    const char* last = item.data() + item.size();
    const auto [end, error] = std::from_chars(first, last, value);
    if (equals == std::string::npos || first == last || error != std::errc() || end != last)
      throw std::invalid_argument("stored work counter '" + item + "' is not name=count");
    if (!values.emplace(item.substr(0, equals), value).second)
      throw std::invalid_argument("stored work counter '" + item.substr(0, equals) + "' twice");
  }
  WorkCounts work;
  work.allocations_tracked = values.contains("allocations");
  for (const auto& field : work_count_fields) {
    if (field.allocation && !work.allocations_tracked) continue;
    const auto found = values.find(field.name);
    if (found == values.end())
      throw std::invalid_argument("stored work counters lack " + std::string(field.name));
    work.*field.member = found->second;
    values.erase(found);
  }
  if (!values.empty())
    throw std::invalid_argument("unknown stored work counter '" + values.begin()->first + "'");
  return work;
}

std::string escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '\\')
      out += "\\\\";
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
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

std::string serialize_result(const TrialResult& r) {
  std::string out = "rkhs-trial 1\n";
  out += fmt::format("ok {}\n", r.ok ? 1 : 0);
  out += "reason " + escape(r.reason) + "\n";
  out += "solve " + escape(r.solve_method) + "\n";
  if (r.engine) out += "engine " + escape(std::string(adaptive_engine_name(*r.engine))) + "\n";
  std::string flags;
  for (std::size_t i = 0; i < r.flags.size(); ++i) flags += (i ? ";" : "") + r.flags[i];
  out += "flags " + escape(flags) + "\n";
  out += "seconds " + format_real(r.seconds) + "\n";
  out += "data " + escape(r.data_provenance) + "\n";
  out += "metrics " + join_reals(r.metrics) + "\n";
  if (!r.floors.empty()) out += "floors " + join_reals(r.floors) + "\n";
  if (r.work) out += "work " + work_line(*r.work) + "\n";
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
  std::set<std::string> seen;  // each field once, but snapshot (one line per snapshot)
  while (std::getline(in, line)) {
    const auto space = line.find(' ');
    const std::string field = line.substr(0, space);
    const std::string value = space == std::string::npos ? "" : line.substr(space + 1);
    if (field != "snapshot" && !seen.insert(field).second)
      throw std::invalid_argument("field '" + field + "' twice in a stored trial");
    if (field == "ok")
      r.ok = value == "1";
    else if (field == "reason")
      r.reason = unescape(value);
    else if (field == "solve")
      r.solve_method = unescape(value);
    else if (field == "engine") {
      r.engine = adaptive_engine_from_name(unescape(value));
      if (!r.engine)
        throw std::invalid_argument("unknown engine '" + value + "' in a stored trial");
    } else if (field == "flags") {
      // Names separated by ';'; an empty name ("a;;b", a trailing ';') is no flag.
      const auto flags = unescape(value);
      std::size_t start = 0;
      while (start < flags.size()) {
        const auto stop = std::min(flags.find(';', start), flags.size());
        if (stop > start) r.flags.push_back(flags.substr(start, stop - start));
        start = stop + 1;
      }
    } else if (field == "seconds")
      r.seconds = parse_real(value);
    else if (field == "data")
      r.data_provenance = unescape(value);
    else if (field == "metrics")
      r.metrics = split_reals(value);
    else if (field == "floors")
      r.floors = split_reals(value);
    else if (field == "work")
      r.work = parse_work_line(value);
    else if (field == "samples") {
      const auto v = split_reals(value);
      if (v.size() % 3) throw std::invalid_argument("stored samples are not triples");
      for (std::size_t i = 0; i < v.size(); i += 3) r.samples.push_back({v[i], v[i + 1], v[i + 2]});
    } else if (field == "road")
      r.road = split_reals(value);
    else if (field == "snapshot") {
      auto v = split_reals(value);
      if (v.empty()) throw std::invalid_argument("empty stored snapshot");
      r.snapshots.push_back({v.front(), std::vector<double>(v.begin() + 1, v.end())});
    } else
      throw std::invalid_argument("unknown field '" + field + "' in a stored trial");
  }
  return r;
}

namespace {

// A line of a record for a message: at most 60 characters.
std::string quoted_excerpt(std::string_view text) {
  return text.size() <= 60 ? fmt::format("'{}'", text) : fmt::format("'{}...'", text.substr(0, 57));
}

constexpr std::string_view record_header = "rkhs-record 3\n";
constexpr std::string_view record_header_2 = "rkhs-record 2\n";
constexpr std::string_view names_field = "metric_names";
constexpr std::string_view checksum_field = "\nchecksum ";

// Format 3: the hash, the study and the key (escaped: one line each) and the body. Format 2:
// the hash and the body (the study and the key not covered).
std::string record_checksum(int format, const std::string& hash, const std::string& study,
                            const std::string& key, std::string_view body) {
  Sha256 sum;
  sum.update(hash);
  sum.update("\n");
  if (format >= 3) {
    sum.update(escape(study));
    sum.update("\n");
    sum.update(escape(key));
    sum.update("\n");
  }
  sum.update(body);
  return sum.hex_digest();
}

}  // namespace

std::string store_record(const std::string& hash, const std::string& study, const std::string& key,
                         const TrialResult& result, const std::vector<std::string>& metric_names) {
  std::string body(record_header);
  body += names_field;
  for (const auto& name : metric_names) body += " " + name;
  body += "\n" + serialize_result(result);
  return body + "checksum " + record_checksum(record_format, hash, study, key, body) + "\n";
}

RecordCheck read_record(const std::string& hash, const std::string& study, const std::string& key,
                        std::string_view text, const std::vector<std::string>* expected_metrics) {
  RecordCheck check;
  const auto first_line = text.substr(0, text.find('\n'));
  if (first_line == "rkhs-trial 1") {
    check.old_format = true;
    check.format = 1;
    check.problem = "old record format (no checksum)";
    return check;
  }
  const bool format_2 = text.starts_with(record_header_2);
  if (!text.starts_with(record_header) && !format_2) {
    check.problem = fmt::format("not a stored record: first line {}, expected 'rkhs-record {}'",
                                quoted_excerpt(first_line), record_format);
    return check;
  }
  check.format = format_2 ? 2 : 3;
  const auto at_checksum = text.rfind(checksum_field);
  if (at_checksum == std::string_view::npos) {
    check.problem = "no checksum line";
    return check;
  }
  const auto body = text.substr(0, at_checksum + 1);
  auto stored = text.substr(at_checksum + checksum_field.size());
  if (stored.ends_with('\n')) stored.remove_suffix(1);
  if (const auto computed = record_checksum(check.format, hash, study, key, body);
      stored != computed) {
    // Their first 16 digits: enough to tell them apart, short enough to read.
    check.problem = fmt::format("checksum mismatch (stored {}..., computed {}...)",
                                stored.substr(0, 16), computed.substr(0, 16));
    return check;
  }
  auto rest = body.substr(record_header.size());
  const auto names_line = rest.substr(0, rest.find('\n'));
  if (!names_line.starts_with(names_field) ||
      (names_line.size() > names_field.size() && names_line[names_field.size()] != ' ')) {
    check.problem =
        fmt::format("second line {}, expected 'metric_names ...'", quoted_excerpt(names_line));
    return check;
  }
  std::istringstream names{std::string(names_line.substr(names_field.size()))};
  for (std::string name; names >> name;) check.metric_names.push_back(name);
  TrialResult result;
  try {
    result = deserialize_result(rest.substr(std::min(rest.size(), names_line.size() + 1)));
  } catch (const std::exception& e) {
    check.problem = e.what();
    return check;
  }
  if (result.metrics.size() != check.metric_names.size()) {
    check.problem = fmt::format("{} metric values for {} metric names", result.metrics.size(),
                                check.metric_names.size());
    return check;
  }
  if (!result.floors.empty() && result.floors.size() != result.metrics.size()) {
    check.problem =
        fmt::format("{} floors for {} metric values", result.floors.size(), result.metrics.size());
    return check;
  }
  if (expected_metrics && check.metric_names != *expected_metrics) {
    check.problem =
        fmt::format("it holds the metrics {}, the study measures {}",
                    fmt::join(check.metric_names, ", "), fmt::join(*expected_metrics, ", "));
    return check;
  }
  check.result = std::move(result);
  return check;
}
}  // namespace rkhs
