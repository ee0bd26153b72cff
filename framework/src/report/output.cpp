#include "rkhs/report/output.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>

#include "output_fields.hpp"
#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs {

using report_detail::abscissa_name;
using report_detail::model_id;
using report_detail::reported_flags;

namespace {

std::string csv_row(const std::vector<std::string>& fields) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) out += ',';
    out += csv_field(fields[i]);
  }
  out += '\n';
  return out;
}

}  // namespace

// Minimal JSON writing: strings escaped, non-finite numbers as null (with the value kept as
// a string beside it where it matters, e.g. an infinite condition number).
std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20)
          out += fmt::format("\\u{:04x}", static_cast<int>(c));
        else
          out += c;
    }
  }
  return out + "\"";
}

std::string json_number(double value) {
  if (std::isfinite(value)) return format_real(value);
  if (std::isnan(value)) return "null";
  return value > 0 ? "\"inf\"" : "\"-inf\"";
}

std::string csv_field(const std::string& raw) {
  // Control bytes (ESC, BEL, CR, ...) and bytes that are not UTF-8 as \xNN: text from a study,
  // a data file or a stored record cannot carry terminal escapes into a file that is shown on
  // a terminal. Line breaks and tabs stay, inside quotes.
  const auto value = printable(raw, true);
  if (value.find_first_of(",\"\n\r") == std::string::npos) return value;
  std::string out = "\"";
  for (char c : value) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string csv_number(double value) {
  return std::isnan(value) ? "" : format_real(value);
}

// The value of a trials.csv column a study kind declares (StudyKindOutputs::trial_columns).
std::string kind_column_value(std::string_view column, const TrialResult& result) {
  static const std::map<std::string_view, std::string (*)(const TrialResult&)> columns{
      {"engine", [](const TrialResult& r) { return std::string(engine_text(r)); }},
  };
  const auto it = columns.find(column);
  if (it == columns.end())
    throw std::logic_error(fmt::format("no writer for the trials.csv column '{}'", column));
  return it->second(result);
}

std::string trials_csv(const RunRecord& run) {
  const auto columns = axis_columns(run.trials);
  std::vector<std::string> header = columns;
  header.push_back("n");
  header.insert(header.end(), run.study.metrics.begin(), run.study.metrics.end());
  for (const char* extra : {"status", "reason", "solve", "flags"}) header.push_back(extra);
  const auto& kind_columns = run.study.kind_descriptor().outputs().trial_columns;
  header.insert(header.end(), kind_columns.begin(), kind_columns.end());
  // The floors of the metrics that have one (MetricInfo::floor), after the other columns.
  std::vector<std::string> floored;
  for (const auto& metric : run.study.metrics)
    if (metric_floor_rule(run.study.kind(), metric) != FloorRule::exact) {
      floored.push_back(metric);
      header.push_back(metric + "_floor");
    }
  std::string out = csv_row(header);
  for (const auto& trial : run.trials) {
    const auto& result = run.results[trial.index];
    auto row = axis_values(columns, trial);
    row.push_back(std::to_string(trial.n));
    for (const auto& metric : run.study.metrics)
      row.push_back(csv_number(result.metrics[run.study.metric_index(metric)]));
    row.push_back(result.ok ? "ok" : "failed");
    row.push_back(result.reason);
    row.push_back(result.solve_method);
    row.push_back(fmt::format("{}", fmt::join(reported_flags(run.study, result.flags), ";")));
    for (const auto column : kind_columns) row.push_back(kind_column_value(column, result));
    for (const auto& metric : floored) {
      const auto position = run.study.metric_index(metric);
      row.push_back(position < result.floors.size() ? csv_number(result.floors[position]) : "");
    }
    out += csv_row(row);
  }
  return out;
}

namespace {

// The floor of the pairwise rate between points k and k + 1 of the reported model: their
// relative floors over the step in its abscissa (ln x, or n).
double pairwise_rate_floor(const MetricSeries& series, std::size_t k) {
  const auto relative = [&](std::size_t i) {
    const double floor = i < series.floors.size() && series.floors[i] > 0 ? series.floors[i] : 0.0;
    return floor / std::abs(series.values[i]);
  };
  const bool power_law = series.analysis.reported == RateModel::power_law;
  const double step = power_law ? std::log(series.abscissa[k + 1] / series.abscissa[k])
                                : series.n[k + 1] - series.n[k];
  const double value = (relative(k) + relative(k + 1)) / std::abs(step);
  return std::isfinite(series.pairwise[k]) ? value : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

std::string rates_csv(const RunRecord& run) {
  const auto columns = axis_columns(run.trials);
  std::vector<std::string> header = columns;
  for (const char* extra :
       {"metric", "abscissa", "kind", "model", "n_from", "n_to", "points", "rate", "std_error",
        "ci_low", "ci_high", "r_squared", "delta_aic", "note", "rate_floor", "r_squared_floor",
        "delta_aic_floor", "value", "band", "value_floor"})
    header.push_back(extra);
  std::string out = csv_row(header);
  for (const auto& series : run.rates) {
    if (series.trials.empty()) continue;
    const auto axes = axis_values(columns, run.trials[series.trials.front()]);
    auto row_start = [&](const char* kind, RateModel model, std::size_t from, std::size_t to) {
      auto row = axes;
      row.push_back(series.metric);
      row.push_back(model == RateModel::exponential ? std::string("n") : abscissa_name(run.study));
      row.push_back(kind);
      row.push_back(model_id(model));
      row.push_back(std::to_string(from));
      row.push_back(std::to_string(to));
      return row;
    };
    const auto& n_of = [&](std::size_t k) { return run.trials[series.trials[k]].n; };
    // A constant series: its value and band are what is reported ("fit", model "constant"); both
    // models' fits follow as alternatives, for reference.
    const auto& constant = series.analysis.constant;
    if (constant) {
      auto row = axes;
      for (const std::string& cell :
           {series.metric, std::string(abscissa_name(run.study)), std::string("fit"),
            std::string("constant"), std::to_string(n_of(constant->points.front())),
            std::to_string(n_of(constant->points.back())), std::to_string(constant->points.size())})
        row.push_back(cell);
      for (int i = 0; i < 6; ++i) row.push_back("");
      row.push_back(series.note.empty() ? series.no_fit_reason
                                        : series.no_fit_reason + "; " + series.note);
      for (int i = 0; i < 3; ++i) row.push_back("");
      row.push_back(csv_number(constant->value));
      row.push_back(csv_number(constant->band));
      row.push_back(csv_number(constant->floor));
      out += csv_row(row);
    }
    // The reported fit ("fit") and the other model's ("alternative_fit"), each on its window.
    const auto reported = series.analysis.reported;
    const auto other =
        reported == RateModel::power_law ? RateModel::exponential : RateModel::power_law;
    for (const auto model : {reported, other}) {
      const auto& analysis = series.analysis.analysis(model);
      const auto& fit = analysis.fit;
      std::size_t from = n_of(0), to = n_of(series.trials.size() - 1);
      if (fit && !fit->used.empty()) {
        from = n_of(fit->used.front());
        to = n_of(fit->used.back());
      }
      auto row =
          row_start(model == reported && !constant ? "fit" : "alternative_fit", model, from, to);
      const double nan = std::numeric_limits<double>::quiet_NaN();
      row.push_back(std::to_string(fit ? fit->points : 0));
      for (double v : {fit ? fit->rate : nan, fit ? fit->std_error : nan, fit ? fit->ci_low : nan,
                       fit ? fit->ci_high : nan, fit ? fit->r_squared : nan, analysis.advantage})
        row.push_back(csv_number(v));
      std::vector<std::string> notes;
      if (model == reported && !constant) {
        if (!series.note.empty()) notes.push_back(series.note);
        if (!series.analysis.note.empty()) notes.push_back(series.analysis.note);
      } else {
        if (!analysis.window.note.empty()) notes.push_back(analysis.window.note);
        if (fit && !fit->note.empty()) notes.push_back(fit->note);
      }
      row.push_back(fmt::format("{}", fmt::join(notes, "; ")));
      for (double v : {fit ? analysis.floors.rate : nan, fit ? analysis.floors.r_squared : nan,
                       analysis.advantage_floor})
        row.push_back(csv_number(v));
      for (int i = 0; i < 3; ++i) row.push_back("");  // value, band, value_floor
      out += csv_row(row);
    }
    // The power law with a pre-asymptotic term, where the pairwise rates bend (asymptotic.hpp).
    if (const auto& corrected = series.analysis.corrected) {
      const auto& fit = corrected->fit;
      auto row = row_start("corrected_fit", RateModel::power_law, n_of(fit.used.front()),
                           n_of(fit.used.back()));
      row.push_back(std::to_string(fit.points));
      for (double v :
           {fit.rate, fit.std_error, fit.ci_low, fit.ci_high, fit.r_squared, corrected->advantage})
        row.push_back(csv_number(v));
      row.push_back(fmt::format(
          "C x^p (1 + D t^-q) with q = {:.3g}, D = {:.3g} at n = {}; {}", corrected->order,
          corrected->correction, n_of(fit.used.back()),
          series.analysis.bends() ? "judged by power-law rate verdicts"
          : series.analysis.reported != RateModel::power_law
              ? "not judged: the exponential model is reported"
              : "not judged: the correction does not earn its two parameters (ΔAICc < 2)"));
      const auto& floors = series.analysis.corrected_floors;
      for (double v : {floors.rate, floors.r_squared, floors.log_sse}) row.push_back(csv_number(v));
      for (int i = 0; i < 3; ++i) row.push_back("");  // value, band, value_floor
      out += csv_row(row);
    }
    const auto& window = series.analysis.reported_analysis().window;
    auto outside = [&](std::size_t k) {
      auto in = [k](const std::vector<std::size_t>& v) {
        return std::find(v.begin(), v.end(), k) != v.end();
      };
      if (constant) return in(constant->head);  // a constant keeps every point after its head
      return in(window.head) || in(window.floor);
    };
    for (std::size_t k = 0; k < series.pairwise.size(); ++k) {
      auto row = row_start("pairwise", reported, n_of(k), n_of(k + 1));
      row.push_back("2");
      row.push_back(csv_number(series.pairwise[k]));
      for (int i = 0; i < 5; ++i) row.push_back("");
      const bool doubtful = series.flagged[k] || series.flagged[k + 1];
      row.push_back(doubtful ? "flagged value (not used in the fit)"
                    : outside(k) || outside(k + 1)
                        ? "outside the asymptotic window (not used in the fit)"
                        : "");
      row.push_back(csv_number(pairwise_rate_floor(series, k)));
      for (int i = 0; i < 5; ++i) row.push_back("");  // ..., value, band, value_floor
      out += csv_row(row);
    }
  }
  return out;
}

std::string estimates_csv(const RunRecord& run) {
  const auto columns = axis_columns(run.trials);
  std::vector<std::string> header = columns;
  for (const char* extra : {"n", "lap", "s", "road", "estimate"}) header.push_back(extra);
  std::string out = csv_row(header);
  const auto grid =
      run.study.domain.uniform_points(run.study.adaptive_axes().settings.snapshot_points);
  for (const auto& trial : run.trials) {
    const auto& result = run.results[trial.index];
    if (!result.ok) continue;
    const auto axes = axis_values(columns, trial);
    for (const auto& snapshot : result.snapshots) {
      for (std::size_t m = 0; m < snapshot.estimate.size() && m < grid.size(); ++m) {
        auto row = axes;
        row.push_back(std::to_string(trial.n));
        row.push_back(format_real(snapshot.lap));
        row.push_back(format_real(grid[m]));
        row.push_back(csv_number(result.road[m]));
        row.push_back(csv_number(snapshot.estimate[m]));
        out += csv_row(row);
      }
    }
  }
  return out;
}

std::string timeseries_csv(const RunRecord& run) {
  const auto columns = axis_columns(run.trials);
  std::vector<std::string> header = columns;
  for (const char* extra : {"n", "t", "lap", "state_error", "lyapunov"}) header.push_back(extra);
  std::string out = csv_row(header);
  const double lap_time = run.study.adaptive_axes().settings.lap_time(run.study.domain.length);
  for (const auto& trial : run.trials) {
    const auto& result = run.results[trial.index];
    const auto axes = axis_values(columns, trial);
    for (const auto& sample : result.samples) {
      auto row = axes;
      row.push_back(std::to_string(trial.n));
      row.push_back(format_real(sample.t));
      row.push_back(format_real(sample.t / lap_time));
      row.push_back(csv_number(sample.state_error));
      row.push_back(csv_number(sample.lyapunov));
      out += csv_row(row);
    }
  }
  return out;
}

namespace {

// Writes all of `content` to `fd`; false (errno set) when the system refuses.
bool write_all(int fd, std::string_view content) {
  while (!content.empty()) {
    const auto written = ::write(fd, content.data(), content.size());
    if (written < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    content.remove_prefix(static_cast<std::size_t>(written));
  }
  return true;
}

// Makes a rename in `directory` durable.
void sync_directory(const std::filesystem::path& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // nothing to sync through (the rename itself succeeded)
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void write_file_atomically(const std::filesystem::path& file, const std::string& content) {
  static std::atomic<unsigned long> counter{0};
  const auto temporary = std::filesystem::path(
      fmt::format("{}.tmp.{}.{}", file.string(), static_cast<long>(::getpid()), counter++));
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0)
    throw std::runtime_error(
        fmt::format("cannot write {}: {}", file.string(), std::strerror(errno)));
  const auto fail = [&](const char* step, int error, bool open) {
    if (open) ::close(fd);
    ::unlink(temporary.c_str());
    throw std::runtime_error(
        fmt::format("cannot write {} ({}): {}", file.string(), step, std::strerror(error)));
  };
  if (!write_all(fd, content)) fail("write", errno, true);
  if (::fsync(fd) != 0) fail("fsync", errno, true);
  if (::close(fd) != 0) fail("close", errno, false);
  if (::rename(temporary.c_str(), file.c_str()) != 0) fail("rename", errno, false);
  sync_directory(file.has_parent_path() ? file.parent_path() : std::filesystem::path("."));
}

void prepare_output_directory(const std::filesystem::path& directory) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(
        fmt::format("cannot write the output folder {}: {} (choose another with --out DIR)",
                    printable(directory.string()), why));
  };
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) fail("cannot create it: " + error.message());
  if (!std::filesystem::is_directory(directory, error)) fail("it is not a folder");
  // Writable: a probe file created, written and removed (permissions alone do not say: a
  // read-only file system, an ACL, root on a file system that maps it to nobody).
  const auto probe = directory / fmt::format(".rkhs-study-probe.{}", static_cast<long>(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) fail(fmt::format("cannot create a file in it: {}", std::strerror(errno)));
  const bool written = ::write(fd, "x", 1) == 1;
  const int saved = errno;
  ::close(fd);
  ::unlink(probe.c_str());
  if (!written) fail(fmt::format("cannot write a file in it: {}", std::strerror(saved)));
}

std::vector<std::string> output_file_names(const RunRecord& run, bool with_report,
                                           bool with_plots) {
  std::vector<std::string> names{"trials.csv", "rates.csv", "summary.json", "rates.md",
                                 "rates.tex"};
  for (const auto file : run.study.kind_descriptor().outputs().files) names.emplace_back(file);
  if (with_plots) names.push_back("plots/");
  if (with_report) names.push_back("report.html");
  return names;
}

void mark_outputs_incomplete(const RunRecord& run, const std::filesystem::path& directory,
                             const std::vector<std::string>& files) {
  std::string text = fmt::format(
      "INCOMPLETE: the outputs in this folder are not those of one run.\n"
      "The run of study '{}' started {} was writing them and stopped before it had written all\n"
      "(a failed write: a full disk, a quota, an I/O error; or the process was killed). Of the\n"
      "files below, some may be this run's and some an earlier run's. Run the study again into\n"
      "this folder (stored trials are reused): the run that writes them all removes this file.\n"
      "\nfiles that may be stale:\n",
      printable(run.study.name), run.started);
  for (const auto& file : files) text += "  " + file + "\n";
  write_file_atomically(directory / incomplete_marker, text);
}

void mark_outputs_complete(const std::filesystem::path& directory) {
  std::error_code error;
  std::filesystem::remove(directory / incomplete_marker, error);
  if (error)
    throw std::runtime_error(fmt::format(
        "cannot remove {}: {}", (directory / incomplete_marker).string(), error.message()));
}

void write_outputs(const RunRecord& run, const std::filesystem::path& directory) {
  std::filesystem::create_directories(directory);
  write_file_atomically(directory / "trials.csv", trials_csv(run));
  write_file_atomically(directory / "rates.csv", rates_csv(run));
  write_file_atomically(directory / "summary.json", summary_json(run));
  write_file_atomically(directory / "rates.md", markdown_tables(run));
  write_file_atomically(directory / "rates.tex", latex_tables(run));
  // The files a study kind declares (StudyKindOutputs::files), each by its writer.
  static const std::map<std::string_view, std::string (*)(const RunRecord&)> kind_files{
      {"estimates.csv", estimates_csv},
      {"timeseries.csv", timeseries_csv},
  };
  for (const auto file : run.study.kind_descriptor().outputs().files) {
    const auto writer = kind_files.find(file);
    if (writer == kind_files.end())
      throw std::logic_error(fmt::format("no writer for the output file '{}'", file));
    write_file_atomically(directory / file, writer->second(run));
  }
}

}  // namespace rkhs
