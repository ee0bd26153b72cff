#pragma once
// Study kinds as table entries. A study kind (approximation, adaptive) is one descriptor: its
// name, its metric catalogue (one MetricInfo per metric, rkhs/approx/metrics.hpp), which of
// them a study's trials compute, the sections of a study file it owns and the extra outputs its
// trials give. Everything in the framework that depends on the kind reads the descriptor; the
// table of descriptors (study_kind_table) is the only list of kinds, and messages, `rkhs-study
// list` and the parser's "known:" lists come from it. The run layer's part of a kind (running
// and costing one of its trials) is its own table, rkhs/run/trial_kinds.hpp.

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/approx/metrics.hpp"

namespace rkhs {

struct StudyDefinition;
namespace detail {
class StudyFileSections;  // the study file reader's part of a kind (internal to the study layer)
}

/// What the trials of a study do: approximate a target by kernel interpolation at n centres,
/// or learn it with an adaptive estimator driven along the track (docs/model.md). The
/// identifier of a table entry; what a kind means is its descriptor.
enum class StudyKind { approximation, adaptive };

/// What a study kind's trials write beyond trials.csv, rates.csv and summary.json's common
/// fields; the report layer writes what is declared here, by name.
struct StudyKindOutputs {
  /// Files beside trials.csv ("estimates.csv", "timeseries.csv").
  std::vector<std::string_view> files;
  /// trials.csv columns after "flags" ("engine").
  std::vector<std::string_view> trial_columns;
  /// Metrics summary.json repeats among a trial's work counters and sums over the run
  /// ("steps", "rhs_evaluations").
  std::vector<std::string_view> work_metrics;
  /// Whether the plots include the estimates at snapshot laps and the states against time.
  bool time_series_plots = false;
};

class StudyKindDescriptor {
 public:
  virtual ~StudyKindDescriptor() = default;

  virtual StudyKind kind() const noexcept = 0;
  /// "approximation", "adaptive": the name study files (`kind = ...`), summary.json and
  /// report.html use.
  virtual std::string_view name() const noexcept = 0;
  /// Every metric a trial of this kind measures, in output order (TrialResult::metrics is
  /// aligned with it).
  virtual const std::vector<MetricInfo>& metrics() const = 0;
  /// The sections of a study file only this kind may have ("adaptive", "plant", ...).
  virtual std::span<const std::string_view> own_sections() const noexcept = 0;
  virtual const StudyKindOutputs& outputs() const = 0;
  /// How the study file reader reads the kind's own sections and plugin axes.
  virtual const detail::StudyFileSections& file_sections() const = 0;

  /// The metrics a trial of `study` computes, by position in metrics(); see
  /// StudyDefinition::computed_metrics.
  virtual MetricSelection computed_metrics(const StudyDefinition& study) const = 0;
  /// Why each metric computed beyond study.metrics is computed, each reason once.
  virtual std::vector<std::string> computed_metric_reasons(const StudyDefinition& study) const = 0;

  /// The names of metrics(), in output order.
  const std::vector<std::string>& metric_names() const;
  /// The catalogue's row for `metric`; nullptr for a metric this kind does not have.
  const MetricInfo* find_metric(std::string_view metric) const noexcept;
  /// Whether theory predicts a rate for some metric of the kind (TheoryLaw), so that a study
  /// of this kind may have `theory = true` expectations.
  bool has_theory() const noexcept;
};

/// Every study kind, in the order `rkhs-study list metrics` prints them.
std::span<const StudyKindDescriptor* const> study_kind_table() noexcept;

/// The descriptor of `kind`.
const StudyKindDescriptor& describe(StudyKind kind) noexcept;

/// The kind `name` stands for; nullptr for an unknown name.
const StudyKindDescriptor* find_study_kind(std::string_view name) noexcept;

/// "approximation, adaptive": the kinds' names, for messages.
std::string study_kind_names();

/// The descriptors of the kinds this framework has (study/approximation_kind.cpp,
/// study/adaptive_kind.cpp); study_kind_table() lists them.
const StudyKindDescriptor& approximation_study_kind() noexcept;
const StudyKindDescriptor& adaptive_study_kind() noexcept;

}  // namespace rkhs
