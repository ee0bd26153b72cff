#pragma once
// The test cases of `rkhs-study check`: each expectation on each group it selects, with a name
// that does not depend on the table's position in the file (JUnit test names, summary.json, the
// console), and the keywords `-k` matches (keyword_expression.hpp). Both are
// known before any trial runs, so `-k` can leave a study out without running it.

#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "rkhs/study/expectation.hpp"
#include "rkhs/study/study.hpp"
#include "rkhs/verify/keyword_expression.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

/// One expectation on one group it selects.
struct ExpectationCase {
  const Expectation* expectation = nullptr;  ///< points into StudyDefinition::expectations
  std::string group;                         ///< the group's key (every axis but n)
  std::string group_label;                   ///< the axes that tell it from the study's others
  /// Unique within the study: "<expectation.id()> [<group_label>]". Where two cases would
  /// share it, both add what they expect and the points they judge, as written in the file
  /// ("power_function_sup (theory = true) [kernel=bspline]", "... (rate = -1, last = 4) [...]");
  /// where even that is shared, " #1", " #2", ... follow in file order.
  std::string name;
  /// What `-k` matches: the name, the metric, the expectation's `name`, the study's name and
  /// its file's stem, the kind (theory, rate, model, bound), its tiers, and "xfail" when marked.
  std::vector<std::string> keywords;
};

/// Every case of `study` on `trials` (study.trials(), of the whole study or of a tier): the
/// expectations in file order, each on the groups it selects in the order of `trials`.
std::vector<ExpectationCase> expectation_cases(const StudyDefinition& study,
                                               const std::vector<TrialSpec>& trials);

/// The test cases of one study that `check -k` judges, known before any trial runs.
struct CaseSelection {
  std::set<std::pair<std::size_t, std::string>> selected;  ///< (expectation number, group)
  std::size_t deselected = 0;                              ///< cases the expression left out
};

/// The cases of expectation_cases(study, trials) that `expression` selects (null: every case).
CaseSelection select_cases(const StudyDefinition& study, const std::vector<TrialSpec>& trials,
                           const KeywordExpression* expression);

/// Removes from `outcomes` (verify_expectations of the study) those of cases `selection` left
/// out.
void keep_selected(std::vector<ExpectationOutcome>& outcomes, const CaseSelection& selection);

/// Each group key of `trials` with its label: "column=value" for each axis column whose value
/// differs between the groups (kernel always), in column order: "kernel=bspline degree=1 r=1".
std::map<std::string, std::string> group_labels(const std::vector<TrialSpec>& trials);

}  // namespace rkhs
