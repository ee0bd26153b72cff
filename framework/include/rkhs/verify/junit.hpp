#pragma once
// JUnit XML for CI systems (GitLab, Jenkins, GitHub test reporters): `rkhs-study check --junit`.
//
//   <testsuites> with one <testsuite> (the study), one <testcase> per expectation and group:
//   classname "<study>.<metric>", name "#k <group label>", file and line of the [[expect]]
//   table. A fail is a <failure>, an inconclusive verdict a <skipped> (a <failure> of type
//   "inconclusive" with --strict); every test case carries the expected, found and verdict
//   lines (fitted rate, CI, window) in <system-out>, and failures and skips in their message.

#include <string>
#include <string_view>
#include <vector>

#include "rkhs/study/study.hpp"
#include "rkhs/verify/verification.hpp"

namespace rkhs {

struct JUnitReport {
  const StudyDefinition& study;
  const std::vector<ExpectationOutcome>& outcomes;
  bool strict = false;
  double seconds = 0;         ///< wall time of the run, reported on the suite
  std::string tier;           ///< "" when all tiers ran
  std::string timestamp;      ///< ISO 8601, "" to omit
};

/// The XML document (UTF-8, escaped; never throws except std::bad_alloc).
std::string junit_xml(const JUnitReport& report);

/// `text` escaped for XML attribute values (&, <, >, ", ', and line breaks and tabs as character
/// references) or, with `attribute` false, for character data (line breaks kept). Other control
/// characters are dropped: XML 1.0 does not allow them.
std::string xml_escape(std::string_view text, bool attribute = true);

}  // namespace rkhs
