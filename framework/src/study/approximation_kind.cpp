// The approximation study kind: a trial places n centres and measures the projection Pi_n of
// the target (docs/metrics.md); it computes only what its study asks for.
#include <algorithm>
#include <type_traits>
#include <variant>

#include "rkhs/study/study.hpp"
#include "rkhs/study/study_kind.hpp"
#include "study_file_parts.hpp"

namespace rkhs {
namespace {

// The kind's own part of a study and of a trial is the alternative of its enumerator's index.
static_assert(std::is_same_v<std::variant_alternative_t<
                                 static_cast<std::size_t>(StudyKind::approximation), StudyKindAxes>,
                             ApproximationStudyAxes>);
static_assert(std::is_same_v<std::variant_alternative_t<
                                 static_cast<std::size_t>(StudyKind::approximation), TrialKindAxes>,
                             ApproximationTrialAxes>);

// The rules of computed_metrics(), once: calls need(metric, reason) for every metric an
// approximation study's trials compute, reason "" for those of study.metrics.
template <class Need>
void for_each_needed_metric(const StudyDefinition& study, Need&& need) {
  for (const auto& metric : study.metrics) need(metric, "");
  if (study.abscissa == Abscissa::fill_distance) need("fill_distance", "abscissa = \"h\"");
  for (const auto& expectation : study.expectations)
    if (expectation.kind == ExpectationKind::theory) {
      need("fill_distance", "theory expectations (quasi-uniformity)");
      need("separation_distance", "theory expectations (quasi-uniformity)");
    }
}

class ApproximationKind final : public StudyKindDescriptor {
 public:
  StudyKind kind() const noexcept override { return StudyKind::approximation; }
  std::string_view name() const noexcept override { return "approximation"; }
  const std::vector<MetricInfo>& metrics() const override { return metrics_; }
  std::span<const std::string_view> own_sections() const noexcept override { return {}; }
  const StudyKindOutputs& outputs() const override { return outputs_; }
  const detail::StudyFileSections& file_sections() const override {
    return detail::no_file_sections();
  }

  MetricSelection computed_metrics(const StudyDefinition& study) const override {
    const auto& names = metric_names();
    MetricSelection computed(names.size(), false);
    for_each_needed_metric(study, [&](std::string_view metric, std::string_view) {
      const auto it = std::find(names.begin(), names.end(), metric);
      if (it != names.end()) computed[static_cast<std::size_t>(it - names.begin())] = true;
    });
    return computed;
  }

  std::vector<std::string> computed_metric_reasons(const StudyDefinition& study) const override {
    std::vector<std::string> reasons;
    for_each_needed_metric(study, [&](std::string_view metric, std::string_view reason) {
      const bool asked =
          std::find(study.metrics.begin(), study.metrics.end(), metric) != study.metrics.end();
      if (!asked && !reason.empty() &&
          std::find(reasons.begin(), reasons.end(), reason) == reasons.end())
        reasons.emplace_back(reason);
    });
    return reasons;
  }

 private:
  std::vector<MetricInfo> metrics_ = metric_infos<ApproximationMetric>();
  StudyKindOutputs outputs_;
};

}  // namespace

namespace detail {
namespace {
class NoFileSections final : public StudyFileSections {
 public:
  void add_grid_factors(const toml::table&, std::vector<GridFactor>&) const override {}
  void read(const Reporter&, const toml::table&, StudyDefinition&,
            std::vector<PluginAxis>&) const override {}
  std::vector<std::vector<PluginChoice>*> axis_members(StudyDefinition&) const override {
    return {};
  }
  void check(const Reporter&, const toml::table&, StudyDefinition&,
             const std::vector<PluginAxis>&) const override {}
};
}  // namespace

const StudyFileSections& no_file_sections() {
  static const NoFileSections sections;
  return sections;
}
}  // namespace detail

const StudyKindDescriptor& approximation_study_kind() noexcept {
  static const ApproximationKind kind;
  return kind;
}

}  // namespace rkhs
