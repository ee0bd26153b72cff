// rkhs_study._core: the library as the command line uses it, for the Python package
// (python/rkhs_study/__init__.py, docs/python.md). Thin bindings: a study is read by
// load_study / parse_study, run through the study pipeline (rkhs/pipeline/study_pipeline.hpp)
// and written by the output writers (rkhs/report/output.hpp), and its expectations are judged
// by verify_expectations, as `rkhs-study run` and `rkhs-study check` do. The tables come back
// as the CSV text the command writes; the Python side turns them into pandas DataFrames.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "rkhs/pipeline/executor.hpp"
#include "rkhs/pipeline/study_pipeline.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/run_folder.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/tiers.hpp"
#include "rkhs/study/trial_grid.hpp"
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

// One judged expectation as a dict (the fields of summary.json's "expectations").
py::dict outcome_dict(const StudyDefinition& study, const rkhs::ExpectationOutcome& outcome) {
  py::dict d;
  d["study"] = study.name;
  d["name"] = outcome.name;
  d["outcome"] = std::string(rkhs::case_outcome_id(rkhs::case_outcome(outcome)));
  d["verdict"] = std::string(rkhs::verdict_name(outcome.verdict));
  d["metric"] = outcome.expectation->metric;
  d["location"] = outcome.expectation->location;
  d["group"] = outcome.group;
  d["group_label"] = outcome.group_label;
  d["expected"] = outcome.expected;
  d["found"] = outcome.found;
  d["reason"] = outcome.reason;
  d["advice"] = outcome.advice;
  d["xfail"] = outcome.expectation->xfail;
  d["summary"] = rkhs::verdict_numbers(outcome);
  d["rate"] = outcome.rate;
  d["ci_low"] = outcome.ci_low;
  d["ci_high"] = outcome.ci_high;
  d["accepted_low"] = outcome.accepted_low;
  d["accepted_high"] = outcome.accepted_high;
  d["effectivity_min"] = outcome.effectivity_min;
  d["effectivity_max"] = outcome.effectivity_max;
  d["seconds"] = outcome.seconds;
  return d;
}

// What a run of one study leaves for Python: the counts, and the outcomes converted while the
// study (which they point into) is alive.
struct RunSummary {
  std::size_t trials = 0, failed = 0, reused = 0, ran = 0;
  double seconds = 0;
  std::string started;
  std::vector<rkhs::ExpectationOutcome> outcomes;
  std::string verification;  // format_verification
  int exit_code = 0;         // check_exit_code of the outcomes
};

// Runs every trial of `study` through the store, as `rkhs-study run --out DIR --no-plots` does:
// writes trials.csv, rates.csv, summary.json (with the verdicts), rates.md, rates.tex (and the
// adaptive files) and report.html into `out_dir`. No journal, no plots, no signal handlers
// (the Python process owns those). Called without the GIL.
RunSummary run_study_into(const StudyDefinition& study, const std::string& out_dir, int threads,
                          const rkhs::pipeline::StoreOptions& store) {
  namespace pipeline = rkhs::pipeline;
  pipeline::LocalExecutor executor;
  const auto trials = study.trials();
  auto opened = pipeline::open_store(executor, study, trials, store);
  rkhs::prepare_output_directory(out_dir);
  rkhs::RunOptions options;
  options.threads = threads;
  const auto outcome =
      pipeline::run_study(executor, study, trials, options, store, std::move(opened));
  if (outcome.interrupted) throw std::runtime_error(study.name + ": the run was interrupted");
  const auto& run = *outcome.completed;
  RunSummary summary;
  summary.outcomes = rkhs::verify_expectations(study, trials, run.stored.results, run.rates);
  auto record = run.record();
  record.verdicts = &summary.outcomes;
  rkhs::write_run_folder(record, out_dir, false);
  summary.trials = trials.size();
  summary.failed = run.failed;
  summary.reused = run.stored.reused;
  summary.ran = run.stored.ran;
  summary.seconds = run.seconds;
  summary.started = run.started;
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
  d["seconds"] = summary.seconds;
  d["started"] = summary.started;
  d["verification"] = summary.verification;
  d["warnings"] = study.warnings;
  py::list outcomes;
  for (const auto& o : summary.outcomes) outcomes.append(outcome_dict(study, o));
  d["outcomes"] = outcomes;
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "rkhs-study's library: studies loaded, run and judged as the rkhs-study command does";

  // "file:line:column: key: what was found; what is allowed", the text `rkhs-study` prints.
  py::register_exception<rkhs::StudyError>(m, "StudyError", PyExc_ValueError);

  prepare_registries();
  rkhs::python::bind_plugins(m);

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
         std::optional<std::string> store, bool fresh) {
        const auto options = store_options(store, fresh);
        RunSummary summary;
        {
          py::gil_scoped_release release;
          summary = run_study_into(study, out_dir, threads, options);
        }
        return summary_dict(study, summary);
      },
      py::arg("study"), py::arg("out_dir"), py::arg("threads") = 0, py::arg("store") = py::none(),
      py::arg("fresh") = false,
      "Runs every trial and writes what `rkhs-study run --out OUT_DIR --no-plots` writes; "
      "store None: no result store (--no-store)");

  m.def(
      "check",
      [](const std::vector<std::string>& files, int threads, std::optional<std::string> store,
         bool fresh, const std::string& tier, bool strict, bool allow_inconclusive) {
        rkhs::CheckPolicy policy;
        policy.strict = strict;
        policy.allow_inconclusive = allow_inconclusive && !strict;
        const auto options = store_options(store, fresh);
        py::list studies;
        rkhs::VerdictCounts total;
        std::string report;
        for (const auto& file : files) {
          auto study = rkhs::load_study(file);
          if (!tier.empty()) study = rkhs::restrict_to_tier(std::move(study), tier);
          RunSummary summary;
          {
            py::gil_scoped_release release;
            namespace pipeline = rkhs::pipeline;
            pipeline::LocalExecutor executor;
            const auto trials = study.trials();
            rkhs::RunOptions run_options;
            run_options.threads = threads;
            auto outcome = pipeline::run_study(executor, study, trials, run_options, options);
            if (outcome.interrupted)
              throw std::runtime_error(study.name + ": the run was interrupted");
            const auto& run = *outcome.completed;
            summary.outcomes =
                rkhs::verify_expectations(study, trials, run.stored.results, run.rates);
            summary.trials = trials.size();
            summary.failed = run.failed;
            summary.reused = run.stored.reused;
            summary.ran = run.stored.ran;
            summary.seconds = run.seconds;
            summary.started = run.started;
            summary.verification = rkhs::format_verification(summary.outcomes, policy);
          }
          total += rkhs::count_verdicts(summary.outcomes);
          report += summary.verification;
          studies.append(summary_dict(study, summary));
        }
        py::dict d;
        d["exit_code"] = rkhs::check_exit_code(total, policy);
        d["studies"] = studies;
        d["counts"] = rkhs::format_counts(total, policy);
        d["report"] = report;
        return d;
      },
      py::arg("files"), py::arg("threads") = 0, py::arg("store") = py::none(),
      py::arg("fresh") = false, py::arg("tier") = "", py::arg("strict") = false,
      py::arg("allow_inconclusive") = false,
      "Runs each study and judges its [[expect]] tables as `rkhs-study check` does; exit_code "
      "is the command's (0 all pass, 1 a failure, 3 inconclusive, 5 nothing judged)");
}
