// rkhs_study._core: the library as the command line uses it, for the Python package
// (python/rkhs_study/__init__.py, docs/python.md). Thin bindings: a study is read by
// load_study / parse_study, run and judged by run_and_judge (rkhs/pipeline/study_pipeline.hpp)
// and written by the output writers (rkhs/report/output.hpp), as `rkhs-study run` and
// `rkhs-study check` do; the plots are rendered by write_plots (rkhs/report/plots.hpp) and the
// progress shown by the command's Progress display (rkhs/pipeline/progress.hpp). The tables come
// back as the CSV text the command writes; the Python side turns them into pandas DataFrames.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <streambuf>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "rkhs/core/printable.hpp"
#include "rkhs/pipeline/executor.hpp"
#include "rkhs/pipeline/progress.hpp"
#include "rkhs/pipeline/study_pipeline.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/plots.hpp"
#include "rkhs/report/run_folder.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/tiers.hpp"
#include "rkhs/study/trial_grid.hpp"
#include "rkhs/verify/expectation_cases.hpp"
#include "rkhs/verify/junit.hpp"
#include "rkhs/verify/keyword_expression.hpp"
#include "rkhs/verify/verification.hpp"

namespace py = pybind11;

namespace rkhs::python {
// Kernels, targets and centre placements written in Python (plugins.cpp).
void bind_plugins(py::module_& m);
}  // namespace rkhs::python

namespace {

using rkhs::StudyDefinition;

// What `rkhs-study` checks before any command (cli/commands/session.cpp): the registries hold
// no registration error and every built-in plugin; then the plugin modules of
// RKHS_STUDY_PLUGIN_PATH are loaded, once per process.
void prepare_registries() {
  static std::once_flag once;
  std::call_once(once, [] {
    std::string problems;
    for (const auto& e : rkhs::registration_errors())
      problems += "plugin registration error: " + e + "\n";
    for (const auto& m : rkhs::missing_builtin_plugins())
      problems += "built-in plugin missing: " + m + "\n";
    if (!problems.empty()) throw std::runtime_error("rkhs_study: " + problems);
    rkhs::load_plugins_from_environment();
  });
}

// The grid of trials without running them: the axis columns of trials.csv and n, as CSV text
// written as trials.csv writes those columns.
std::string grid_csv(const StudyDefinition& study) {
  const auto trials = study.trials();
  auto columns = rkhs::axis_columns(trials);
  std::string out;
  const auto row = [&](const std::vector<std::string>& fields) {
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (i) out += ',';
      out += rkhs::csv_field(fields[i]);
    }
    out += '\n';
  };
  auto header = columns;
  header.push_back("n");
  row(header);
  for (const auto& trial : trials) {
    auto values = rkhs::axis_values(columns, trial);
    values.push_back(std::to_string(trial.n));
    row(values);
  }
  return out;
}

rkhs::pipeline::StoreOptions store_options(const std::optional<std::string>& store, bool fresh) {
  rkhs::pipeline::StoreOptions options;
  options.disabled = !store.has_value();
  if (store) options.file = *store;
  options.fresh = fresh;
  return options;
}

// One judged expectation as a dict: its study's name, then the fields of the outcome table
// (rkhs::outcome_fields) that appear in Python, in summary.json's order.
py::dict outcome_dict(const StudyDefinition& study, const rkhs::ExpectationOutcome& outcome) {
  using rkhs::OutcomeFieldType;
  py::dict d;
  d["study"] = study.name;
  for (const auto& field : rkhs::outcome_fields) {
    if (!field.in(rkhs::OutcomeField::in_python)) continue;
    const py::str key(field.key.data(), field.key.size());
    switch (field.type) {
      case OutcomeFieldType::text:
      case OutcomeFieldType::optional_text:  // "" when absent
        d[key] = field.text(outcome);
        break;
      case OutcomeFieldType::number:
      case OutcomeFieldType::seconds:
        d[key] = outcome.*field.number;
        break;
      case OutcomeFieldType::verdict:
        d[key] = std::string(rkhs::verdict_name(outcome.verdict));
        break;
      case OutcomeFieldType::kind:
        d[key] = std::string(rkhs::expectation_kind_name(outcome.expectation->kind));
        break;
      case OutcomeFieldType::window: {
        py::dict window;
        window["from"] = outcome.window_from;
        window["to"] = outcome.window_to;
        window["points"] = outcome.window_points;
        d[key] = window;
        break;
      }
      case OutcomeFieldType::outcome:
        d[key] = std::string(rkhs::case_outcome_id(rkhs::case_outcome(outcome)));
        break;
      case OutcomeFieldType::summary:
        d[key] = rkhs::verdict_numbers(outcome);
        break;
    }
  }
  return d;
}

// A finished run kept for Results.report: the study (a copy, which the trials and verdicts
// point into), its trials, the completed run and its verdicts, so that the output folder can be
// written again from the very record the run wrote (write_run_folder), anywhere, later. Never
// moved once made (the members refer to each other): held by a shared_ptr.
struct FinishedRun {
  StudyDefinition study;
  std::vector<rkhs::TrialSpec> trials;
  std::optional<rkhs::pipeline::CompletedRun> completed;  // refers to study and trials
  std::vector<rkhs::ExpectationOutcome> verdicts;         // point into study

  explicit FinishedRun(const StudyDefinition& definition)
      : study(definition), trials(study.trials()) {}
  FinishedRun(const FinishedRun&) = delete;
  FinishedRun& operator=(const FinishedRun&) = delete;

  // The record `rkhs-study run` writes its folder from: the run's, with its verdicts.
  rkhs::RunRecord record() const {
    auto record = completed->record();
    record.verdicts = &verdicts;
    return record;
  }
};

// What write_plots rendered into <out>/plots (rendered stems, notes on plots left out, plots
// that failed), and whether Ctrl-C stopped it.
struct PlotSummary {
  std::vector<std::string> rendered, notes, failures;
  bool interrupted = false;
};

// Writes the output folder of `record` into `out_dir` as `rkhs-study run --out OUT_DIR` does
// (write_run_folder), with the plots rendered by write_plots between the tables and report.html
// when `plots` (gnuplot killed once `stop` is set). Called without the GIL.
PlotSummary write_folder(const rkhs::RunRecord& record, const std::string& out_dir, bool plots,
                         const std::atomic<bool>& stop) {
  PlotSummary summary;
  rkhs::write_run_folder(record, out_dir, plots, [&] {
    if (!plots) return;
    try {
      auto outcome =
          rkhs::write_plots(record, out_dir, rkhs::plot_options([&stop] { return stop.load(); }));
      summary.rendered = std::move(outcome.rendered);
      summary.notes = std::move(outcome.notes);
      summary.failures = std::move(outcome.failures);
      summary.interrupted = outcome.interrupted;
    } catch (const std::exception& e) {  // the plots folder cannot be written: as the command
      summary.failures.push_back(std::string("no plots: ") + rkhs::printable(e.what(), true));
    }
  });
  return summary;
}

py::dict plot_dict(const PlotSummary& plots) {
  py::dict d;
  d["rendered"] = plots.rendered;
  d["notes"] = plots.notes;
  d["failures"] = plots.failures;
  return d;
}

// The progress display of `rkhs-study run` (Progress) writing into a buffer instead of a
// terminal: its display thread writes there, and the calling Python thread takes the text every
// 100 ms (run_interruptibly's poll, with the GIL) and writes it to sys.stderr.
class ProgressText final : public std::streambuf {
 public:
  explicit ProgressText(bool redraw) : stream_(this), progress_(stream_, redraw) {}
  rkhs::pipeline::Progress& progress() { return progress_; }

  // The text written since the last call.
  std::string take() {
    std::lock_guard lock(mutex_);
    std::string text;
    text.swap(text_);
    return text;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      std::lock_guard lock(mutex_);
      text_ += traits_type::to_char_type(c);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    std::lock_guard lock(mutex_);
    text_.append(s, static_cast<std::size_t>(n));
    return n;
  }

 private:
  std::mutex mutex_;
  std::string text_;
  std::ostream stream_;
  rkhs::pipeline::Progress progress_;  // last: stopped (its thread joined) before the rest goes
};

// Writes `text` to sys.stderr and flushes it (nothing when there is no sys.stderr). Called with
// the GIL.
void write_to_stderr(const std::string& text) {
  if (text.empty()) return;
  py::object err = py::module_::import("sys").attr("stderr");
  if (err.is_none()) return;
  err.attr("write")(py::str(text));
  if (py::hasattr(err, "flush")) err.attr("flush")();
}

// Sets the command's progress callbacks (run.cpp) on `options`: the trials to run, each trial's
// start and end, a line per failed trial.
void show_progress(rkhs::RunOptions& options, rkhs::pipeline::Progress& progress) {
  options.on_start = [&progress](std::size_t count) { progress.start(count); };
  options.on_trial_started = [&progress](const rkhs::TrialSpec& trial) {
    progress.trial_started(trial.index);
  };
  options.on_trial_finished = [&progress](const rkhs::TrialSpec& trial,
                                          const rkhs::TrialResult& result) {
    if (!result.ok)
      progress.message("  trial failed: " + rkhs::printable(trial.key) + ": " +
                       rkhs::printable(result.reason));
    progress.trial_finished(trial.index, result.ok);
  };
}

// What a run of one study leaves for Python: the counts, and the outcomes converted while the
// study (which they point into) is alive.
struct RunSummary {
  std::size_t trials = 0, failed = 0, reused = 0, ran = 0;
  std::size_t deselected = 0;  // test cases `check -k` left out
  double seconds = 0;
  std::string started;
  std::vector<rkhs::ExpectationOutcome> outcomes;
  std::string verification;  // format_verification
  int exit_code = 0;         // check_exit_code of the outcomes
  // The run was stopped (Ctrl-C): what finished (and was stored) and what did not; nothing
  // else above is set then.
  std::optional<rkhs::StoredRun> interrupted;
  PlotSummary plots;                      // Study.run(plots=True)
  std::shared_ptr<FinishedRun> finished;  // for Results.report (`run` only)

  // The counts and times of a completed run of `trial_count` trials.
  void record_run(const rkhs::pipeline::CompletedRun& run, std::size_t trial_count) {
    trials = trial_count;
    failed = run.failed;
    reused = run.stored.reused;
    ran = run.stored.ran;
    seconds = run.seconds;
    started = run.started;
  }
};

// rkhs_study.RunInterrupted, a KeyboardInterrupt (set at import).
PyObject* run_interrupted_type = nullptr;

// The Python error that Ctrl-C raised while `study` ran (a KeyboardInterrupt, with the default
// SIGINT handler) replaced by a RunInterrupted that says what finished: the store keeps it, and
// the same call again reuses it. Another error a signal handler raised is raised as it is.
[[noreturn]] void raise_interrupted(py::error_already_set signal, const StudyDefinition& study,
                                    const rkhs::StoredRun& run, bool stored,
                                    const std::string& plots_out = {}) {
  if (!signal.matches(PyExc_KeyboardInterrupt)) throw std::move(signal);
  const std::size_t stopped = run.stopped, not_started = run.skipped - run.stopped;
  // Stopped while gnuplot ran (`plots_out` the folder): every trial and table is there.
  const std::string message =
      !plots_out.empty()
          ? study.name + ": interrupted while rendering plots; every other output in " +
                plots_out + " is complete (" + std::to_string(run.ran) + " trials run" +
                (stored ? " and stored)" : ")")
          : study.name + ": interrupted: " + std::to_string(run.ran) + " trials finished" +
                (stored ? " and stored" : "") + ", " + std::to_string(stopped) +
                " stopped while running and " + std::to_string(not_started) + " not started" +
                (stored ? " (not stored); the same call again reuses the stored trials"
                        : "; nothing was stored (no store)");
  py::object error = py::reinterpret_borrow<py::object>(run_interrupted_type)(message);
  error.attr("study") = study.name;
  error.attr("finished") = run.ran;
  error.attr("stored") = stored ? run.ran : std::size_t{0};
  error.attr("reused") = run.reused;
  error.attr("stopped") = stopped;
  error.attr("not_started") = not_started;
  PyErr_SetObject(run_interrupted_type, error.ptr());
  throw py::error_already_set();
}

// After run_interruptibly: raises what a signal handler raised while the run went on (Ctrl-C:
// a RunInterrupted saying what finished, also when the run ended before it saw the stop).
// `out_dir`: where the plots were being rendered (run with plots), to say so when the stop came
// while gnuplot ran.
void raise_if_interrupted(std::optional<py::error_already_set> signal, const StudyDefinition& study,
                          const RunSummary& summary, bool stored, const std::string& out_dir = {}) {
  if (!signal) return;
  rkhs::StoredRun finished;
  finished.ran = summary.ran;
  finished.reused = summary.reused;
  raise_interrupted(std::move(*signal), study,
                    summary.interrupted ? *summary.interrupted : finished, stored,
                    summary.plots.interrupted ? out_dir : std::string());
}

// Runs `work` (a study run, without Python) on a thread of its own while the calling thread,
// without the GIL, waits for it in steps of 100 ms and between them takes the GIL to run
// Python's signal handlers (PyErr_CheckSignals). When a handler raises (Ctrl-C: a
// KeyboardInterrupt) `stop` is set, which stops the run as SIGINT stops `rkhs-study run`
// (trials in flight are cancelled, finished ones are in the store), and the error is returned
// beside the result once the work has ended. An exception `work` throws is rethrown here, on
// the calling thread, for pybind11 to translate (a StudyError stays a StudyError). `poll`
// (may be empty) runs with the GIL at every step and once after the work has ended: it writes
// the progress text to sys.stderr; an error it raises is dropped (a broken sys.stderr does not
// stop the run), a KeyboardInterrupt stops the run as Ctrl-C does. Called with the GIL.
template <class Work>
std::pair<std::invoke_result_t<Work&>, std::optional<py::error_already_set>> run_interruptibly(
    Work& work, std::atomic<bool>& stop, const std::function<void()>& poll = {}) {
  using Result = std::invoke_result_t<Work&>;
  std::promise<Result> promise;
  auto future = promise.get_future();
  std::optional<py::error_already_set> signal;
  const auto poll_once = [&] {  // with the GIL
    if (!poll) return;
    try {
      poll();
    } catch (py::error_already_set& error) {
      if (!signal && error.matches(PyExc_KeyboardInterrupt)) {
        signal.emplace(std::move(error));
        stop = true;
      }
    }
  };
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        promise.set_value(work());
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
    });
    while (future.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
      if (signal && !poll) continue;  // stopping: wait for the worker
      py::gil_scoped_acquire acquire;
      poll_once();
      if (!signal && PyErr_CheckSignals() != 0) {
        signal.emplace();  // takes the raised error
        stop = true;
      }
    }
    worker.join();
  }
  poll_once();
  return {future.get(), std::move(signal)};
}

// Runs every trial of `study` through the store and judges its expectations (run_and_judge, as
// `rkhs-study run` and `check` do), as `rkhs-study run --out DIR` does (with --no-plots unless
// `plots`): writes trials.csv, rates.csv, summary.json (with the verdicts), rates.md, rates.tex
// (and the adaptive files), the plots and report.html into `out_dir` (write_folder). No
// journal, no signal handlers (the Python process owns those). `progress`: the command's
// progress display (null: none). The run is kept (RunSummary::finished) for Results.report.
// Called without the GIL.
RunSummary run_study_into(const StudyDefinition& definition, const std::string& out_dir,
                          int threads, const rkhs::pipeline::StoreOptions& store, bool plots,
                          rkhs::pipeline::Progress* progress, const std::atomic<bool>& stop) {
  namespace pipeline = rkhs::pipeline;
  pipeline::LocalExecutor executor;
  auto finished = std::make_shared<FinishedRun>(definition);
  const auto& study = finished->study;
  const auto& trials = finished->trials;
  auto opened = pipeline::open_store(executor, study, trials, store);
  rkhs::prepare_output_directory(out_dir);
  if (plots) rkhs::prepare_output_directory(std::filesystem::path(out_dir) / "plots");
  rkhs::RunOptions options;
  options.threads = threads;
  options.stop_requested = [&stop] { return stop.load(); };
  if (progress) show_progress(options, *progress);
  auto judged = pipeline::run_and_judge(executor, study, trials, options, store, std::move(opened));
  if (progress) progress->stop();
  RunSummary summary;
  if (judged.outcome.interrupted) {
    summary.interrupted = *judged.outcome.interrupted;
    return summary;
  }
  finished->completed.emplace(std::move(*judged.outcome.completed));
  finished->verdicts = std::move(judged.verdicts);
  const auto& run = *finished->completed;
  summary.outcomes = finished->verdicts;
  summary.plots = write_folder(finished->record(), out_dir, plots, stop);
  summary.finished = finished;
  summary.record_run(run, trials.size());
  summary.verification = rkhs::format_verification(summary.outcomes);
  summary.exit_code = rkhs::check_exit_code(rkhs::count_verdicts(summary.outcomes));
  return summary;
}

py::dict summary_dict(const StudyDefinition& study, const RunSummary& summary) {
  py::dict d;
  d["study"] = study.name;
  d["trials"] = summary.trials;
  d["failed"] = summary.failed;
  d["reused"] = summary.reused;
  d["ran"] = summary.ran;
  d["deselected"] = summary.deselected;
  d["seconds"] = summary.seconds;
  d["started"] = summary.started;
  d["verification"] = summary.verification;
  d["warnings"] = study.warnings;
  py::list outcomes;
  for (const auto& o : summary.outcomes) outcomes.append(outcome_dict(study, o));
  d["outcomes"] = outcomes;
  d["plots"] = plot_dict(summary.plots);
  d["finished"] = summary.finished ? py::cast(summary.finished) : py::none();
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "rkhs-study's library: studies loaded, run and judged as the rkhs-study command does";

  // "file:line:column: key: what was found; what is allowed", the text `rkhs-study` prints.
  py::register_exception<rkhs::StudyError>(m, "StudyError", PyExc_ValueError);
  // Ctrl-C during run or check: a KeyboardInterrupt that says what finished (raise_interrupted).
  run_interrupted_type = PyErr_NewExceptionWithDoc(
      "rkhs_study._core.RunInterrupted",
      "A run stopped by Ctrl-C (a KeyboardInterrupt): study, finished, stored, reused, stopped "
      "and not_started count its trials; the stored ones are reused by the same call again",
      PyExc_KeyboardInterrupt, nullptr);
  if (!run_interrupted_type) throw py::error_already_set();
  m.add_object("RunInterrupted", py::reinterpret_borrow<py::object>(run_interrupted_type));

  prepare_registries();
  rkhs::python::bind_plugins(m);

  py::class_<FinishedRun, std::shared_ptr<FinishedRun>>(
      m, "FinishedRun",
      "A finished run as `rkhs-study run` wrote it (study, trials, results, rates, verdicts), "
      "kept for Results.report");

  py::class_<StudyDefinition>(m, "StudyDefinition")
      .def_property_readonly("name", [](const StudyDefinition& s) { return s.name; })
      .def_property_readonly("description", [](const StudyDefinition& s) { return s.description; })
      .def_property_readonly("source", [](const StudyDefinition& s) { return s.source; })
      .def_property_readonly(
          "kind",
          [](const StudyDefinition& s) { return std::string(rkhs::study_kind_name(s.kind())); })
      .def_property_readonly("warnings", [](const StudyDefinition& s) { return s.warnings; })
      .def_property_readonly("metrics", [](const StudyDefinition& s) { return s.metrics; })
      .def_property_readonly("computed_metrics",
                             [](const StudyDefinition& s) { return s.computed_metric_names(); })
      .def_property_readonly("n_values", [](const StudyDefinition& s) { return s.n_values; })
      .def_property_readonly("tiers", [](const StudyDefinition& s) { return rkhs::study_tiers(s); })
      .def_property_readonly("expectation_count",
                             [](const StudyDefinition& s) { return s.expectations.size(); })
      .def(
          "grid_axes",
          [](const StudyDefinition& s) {
            std::vector<std::tuple<std::string, std::string, std::size_t>> axes;
            for (const auto& a : s.grid_axes()) axes.emplace_back(a.singular, a.plural, a.count);
            return axes;
          },
          "(singular, plural, count) of each axis of the trial grid, in the order trials nest "
          "them (n last)")
      .def("grid_csv", &grid_csv,
           "The trial grid as CSV text: the axis columns of trials.csv and n, one row per trial")
      .def("restrict_to_tier", &rkhs::restrict_to_tier, py::arg("tier"),
           "The study restricted to one tier's entries and expectations (`check --tier`)");

  m.def(
      "load_study", [](const std::filesystem::path& file) { return rkhs::load_study(file); },
      py::arg("file"),
      "Reads and validates a study file; raises StudyError (file:line:column: ...)");
  m.def("parse_study", &rkhs::parse_study, py::arg("text"), py::arg("source_name"),
        "Reads and validates a study from TOML text; messages name `source_name`");

  m.def(
      "run",
      [](const StudyDefinition& study, const std::string& out_dir, int threads,
         std::optional<std::string> store, bool fresh, bool plots, int progress) {
        const auto options = store_options(store, fresh);
        std::atomic<bool> stop{false};
        std::optional<ProgressText> text;
        if (progress) text.emplace(progress == 2);
        auto work = [&] {
          return run_study_into(study, out_dir, threads, options, plots,
                                text ? &text->progress() : nullptr, stop);
        };
        std::function<void()> poll;
        if (text) poll = [&] { write_to_stderr(text->take()); };
        auto [summary, signal] = run_interruptibly(work, stop, poll);
        raise_if_interrupted(std::move(signal), study, summary, !options.disabled, out_dir);
        return summary_dict(study, summary);
      },
      py::arg("study"), py::arg("out_dir"), py::arg("threads") = 0, py::arg("store") = py::none(),
      py::arg("fresh") = false, py::arg("plots") = false, py::arg("progress") = 0,
      "Runs every trial and writes what `rkhs-study run --out OUT_DIR` writes (plots False: "
      "--no-plots); store None: no result store (--no-store); progress 1: the command's progress "
      "lines on sys.stderr, 2: its line redrawn in place, 0: none");

  m.def(
      "report",
      [](const std::shared_ptr<FinishedRun>& finished, const std::string& out_dir, bool plots) {
        std::atomic<bool> stop{false};
        auto work = [&] {
          rkhs::prepare_output_directory(out_dir);
          if (plots) rkhs::prepare_output_directory(std::filesystem::path(out_dir) / "plots");
          return write_folder(finished->record(), out_dir, plots, stop);
        };
        auto [written, signal] = run_interruptibly(work, stop);
        if (signal) throw std::move(*signal);  // Ctrl-C while gnuplot ran: a KeyboardInterrupt
        return plot_dict(written);
      },
      py::arg("finished"), py::arg("out_dir"), py::arg("plots") = true,
      "Writes the output folder of a finished run into OUT_DIR again, as `rkhs-study run --out "
      "OUT_DIR` wrote it (plots False: --no-plots), from the run's own record");

  m.def(
      "check",
      [](const std::vector<std::string>& files, int threads, std::optional<std::string> store,
         bool fresh, const std::string& tier, bool strict, bool allow_inconclusive,
         const std::string& keyword_expression, const std::string& junit_file) {
        rkhs::CheckPolicy policy;
        policy.strict = strict;
        policy.allow_inconclusive = allow_inconclusive && !strict;
        const auto options = store_options(store, fresh);
        // As the command: the expression and every study read, and the cases split by -k,
        // before any trial runs.
        std::optional<rkhs::KeywordExpression> selection;
        if (!keyword_expression.empty())
          selection = rkhs::KeywordExpression::parse(keyword_expression);
        struct Checked {
          StudyDefinition study;
          rkhs::CaseSelection cases;
          RunSummary summary;
        };
        std::deque<Checked> checked;  // a deque: outcomes point into each study, never moved
        for (const auto& file : files) {
          auto study = rkhs::load_study(file);
          if (!tier.empty()) study = rkhs::restrict_to_tier(std::move(study), tier);
          checked.push_back({std::move(study), {}, {}});
          auto& c = checked.back();
          c.cases =
              rkhs::select_cases(c.study, c.study.trials(), selection ? &*selection : nullptr);
        }
        py::list studies;
        rkhs::VerdictCounts total;
        std::string report;
        for (auto& c : checked) {
          const auto& study = c.study;
          if (!selection || !c.cases.selected.empty()) {  // else not run: -k selects none
            std::atomic<bool> stop{false};
            auto work = [&] {
              RunSummary summary;
              namespace pipeline = rkhs::pipeline;
              pipeline::LocalExecutor executor;
              const auto trials = study.trials();
              rkhs::RunOptions run_options;
              run_options.threads = threads;
              run_options.stop_requested = [&stop] { return stop.load(); };
              auto opened = pipeline::open_store(executor, study, trials, options);
              auto judged = pipeline::run_and_judge(executor, study, trials, run_options, options,
                                                    std::move(opened), &c.cases);
              if (judged.outcome.interrupted) {
                summary.interrupted = *judged.outcome.interrupted;
                return summary;
              }
              const auto& run = *judged.outcome.completed;
              summary.outcomes = std::move(judged.verdicts);
              summary.record_run(run, trials.size());
              summary.verification =
                  rkhs::format_verification(summary.outcomes, policy, c.cases.deselected);
              return summary;
            };
            auto [summary, signal] = run_interruptibly(work, stop);
            raise_if_interrupted(std::move(signal), study, summary, !options.disabled);
            c.summary = std::move(summary);
          }
          c.summary.deselected = c.cases.deselected;
          auto counts = rkhs::count_verdicts(c.summary.outcomes);
          counts.deselected = c.cases.deselected;
          total += counts;
          report += c.summary.verification;
          studies.append(summary_dict(study, c.summary));
        }
        if (!junit_file.empty()) {
          rkhs::JUnitReport junit{{}, policy, keyword_expression};
          for (const auto& c : checked)
            junit.suites.push_back({&c.study, &c.summary.outcomes, c.summary.seconds, tier,
                                    c.summary.started, c.cases.deselected});
          rkhs::write_file_atomically(junit_file, rkhs::junit_xml(junit));
        }
        py::dict d;
        // -k that selects nothing is pytest's "no tests collected" (5), as the command's.
        d["exit_code"] = selection && total.selected() == 0 ? rkhs::check_none_selected
                                                            : rkhs::check_exit_code(total, policy);
        d["studies"] = studies;
        d["counts"] = rkhs::format_counts(total, policy);
        d["report"] = report;
        return d;
      },
      py::arg("files"), py::arg("threads") = 0, py::arg("store") = py::none(),
      py::arg("fresh") = false, py::arg("tier") = "", py::arg("strict") = false,
      py::arg("allow_inconclusive") = false, py::arg("k") = "", py::arg("junit") = "",
      "Runs each study and judges its [[expect]] tables as `rkhs-study check` does; exit_code "
      "is the command's (0 all pass, 1 a failure, 3 inconclusive, 5 nothing judged); k: -k EXPR, "
      "junit: --junit FILE");
}
