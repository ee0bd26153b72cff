// The adaptive study kind: a trial drives a plant along the track (or a state-dependent plant
// through time) and learns the target with an estimator and a learning law (docs/adaptive.md);
// it computes every metric of its catalogue.
#include <type_traits>
#include <variant>

#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/study/study_kind.hpp"
#include "study_file_parts.hpp"

namespace rkhs {
namespace {

// The kind's own part of a study and of a trial is the alternative of its enumerator's index.
static_assert(
    std::is_same_v<
        std::variant_alternative_t<static_cast<std::size_t>(StudyKind::adaptive), StudyKindAxes>,
        AdaptiveStudyAxes>);
static_assert(
    std::is_same_v<
        std::variant_alternative_t<static_cast<std::size_t>(StudyKind::adaptive), TrialKindAxes>,
        AdaptiveTrialAxes>);

class AdaptiveKind final : public StudyKindDescriptor {
 public:
  StudyKind kind() const noexcept override { return StudyKind::adaptive; }
  std::string_view name() const noexcept override { return "adaptive"; }
  const std::vector<MetricInfo>& metrics() const override { return metrics_; }
  std::span<const std::string_view> own_sections() const noexcept override { return sections; }
  const StudyKindOutputs& outputs() const override { return outputs_; }
  const detail::StudyFileSections& file_sections() const override {
    return detail::adaptive_file_sections();
  }

  MetricSelection computed_metrics(const StudyDefinition&) const override {
    return MetricSelection(metrics_.size(), true);
  }
  std::vector<std::string> computed_metric_reasons(const StudyDefinition&) const override {
    return {};
  }

 private:
  static constexpr std::string_view sections[] = {"adaptive", "plant", "law", "integrator"};
  std::vector<MetricInfo> metrics_ = metric_infos<AdaptiveMetric>();
  StudyKindOutputs outputs_{
      {"estimates.csv", "timeseries.csv"}, {"engine"}, {"steps", "rhs_evaluations"}, true};
};

}  // namespace

const StudyKindDescriptor& adaptive_study_kind() noexcept {
  static const AdaptiveKind kind;
  return kind;
}

}  // namespace rkhs
