#pragma once
// JUnit XML for CI systems (GitLab, Jenkins, GitHub test reporters): `rkhs-study check --junit`.
//
//   <testsuites> with one <testsuite> per study (time: the run's wall time; timestamp: when it
//   started), one <testcase> per expectation and group: classname "<study>.<metric>", name the
//   case's stable name (ExpectationCase::name: the expectation's `name`, or its metric and
//   selectors, and the group), file and line of the [[expect]] table, time the seconds of the
//   group's trials plus the judging (ExpectationOutcome::seconds).
//
//   FAIL          <failure type="fail">
//   INCONCLUSIVE  <skipped type="inconclusive">; <failure type="inconclusive"> with --strict
//   XFAIL         <skipped type="xfail"> whose message starts with the xfail reason
//   XPASS         a passing test case; <failure type="xpass"> with --strict
//
//   Every test case carries the expected, found and verdict lines (fitted rate, CI, window) in
//   <system-out>, failures and skips also in their message. Cases that `-k` deselected are
//   not listed (the suite's "deselected" property counts them).

#include <string>
#include <string_view>
#include <vector>

#include "rkhs/study/study.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

/// One study's suite. The pointers must outlive junit_xml().
struct JUnitSuite {
  const StudyDefinition* study = nullptr;
  const std::vector<ExpectationOutcome>* outcomes = nullptr;  ///< the selected cases
  double seconds = 0;         ///< wall time of the study's run (0: not run)
  std::string tier;           ///< "" when all tiers ran
  std::string timestamp;      ///< ISO 8601, "" to omit
  std::size_t deselected = 0;  ///< cases `-k` left out
};

struct JUnitReport {
  std::vector<JUnitSuite> suites;
  CheckPolicy policy;
  std::string keyword_expression;  ///< `-k`, "" when not given
};

/// The XML document (UTF-8, escaped; never throws except std::bad_alloc).
std::string junit_xml(const JUnitReport& report);

/// `text` escaped for XML attribute values (&, <, >, ", ', and line breaks and tabs as character
/// references) or, with `attribute` false, for character data (line breaks kept). Other control
/// characters are dropped: XML 1.0 does not allow them.
std::string xml_escape(std::string_view text, bool attribute = true);

}  // namespace rkhs
