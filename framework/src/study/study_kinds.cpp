// The table of study kinds and what every descriptor shares (rkhs/study/study_kind.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "rkhs/study/study.hpp"
#include "rkhs/study/study_kind.hpp"

namespace rkhs {

const std::vector<std::string>& StudyKindDescriptor::metric_names() const {
  // Built once for every kind, on first use; descriptors live for the whole program.
  struct Names {
    const StudyKindDescriptor* kind;
    std::vector<std::string> names;
  };
  static const std::vector<Names> all = [] {
    std::vector<Names> out;
    for (const auto* kind : study_kind_table()) {
      Names entry{kind, {}};
      for (const auto& metric : kind->metrics()) entry.names.emplace_back(metric.name);
      out.push_back(std::move(entry));
    }
    return out;
  }();
  for (const auto& entry : all)
    if (entry.kind == this) return entry.names;
  static const std::vector<std::string> none;
  return none;
}

const MetricInfo* StudyKindDescriptor::find_metric(std::string_view metric) const noexcept {
  for (const auto& row : metrics())
    if (row.name == metric) return &row;
  return nullptr;
}

bool StudyKindDescriptor::has_theory() const noexcept {
  return std::any_of(metrics().begin(), metrics().end(),
                     [](const MetricInfo& row) { return row.theory != TheoryLaw::none; });
}

std::span<const StudyKindDescriptor* const> study_kind_table() noexcept {
  static const std::array<const StudyKindDescriptor*, 2> table{&approximation_study_kind(),
                                                               &adaptive_study_kind()};
  return table;
}

const StudyKindDescriptor& describe(StudyKind kind) noexcept {
  for (const auto* descriptor : study_kind_table())
    if (descriptor->kind() == kind) return *descriptor;
  return *study_kind_table().front();
}

const StudyKindDescriptor* find_study_kind(std::string_view name) noexcept {
  for (const auto* descriptor : study_kind_table())
    if (descriptor->name() == name) return descriptor;
  return nullptr;
}

std::string study_kind_names() {
  std::string out;
  for (const auto* descriptor : study_kind_table())
    out += fmt::format("{}{}", out.empty() ? "" : ", ", descriptor->name());
  return out;
}

}  // namespace rkhs
