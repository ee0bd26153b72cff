#include "rkhs/verify/junit.hpp"

#include <fmt/format.h>

namespace rkhs {

std::string xml_escape(std::string_view text, bool attribute) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      case '\n': out += attribute ? "&#10;" : "\n"; break;
      case '\t': out += attribute ? "&#9;" : "\t"; break;
      default:
        if (static_cast<unsigned char>(c) >= 0x20) out += c;
    }
  }
  return out;
}

namespace {

// "file:line:column" -> line (0 when it cannot be read).
std::string line_of(const std::string& location) {
  const auto last = location.rfind(':');
  if (last == std::string::npos || last == 0) return "0";
  const auto before = location.rfind(':', last - 1);
  if (before == std::string::npos) return "0";
  return location.substr(before + 1, last - before - 1);
}

}  // namespace

std::string junit_xml(const JUnitReport& report) {
  const bool strict = report.policy.strict;
  struct Totals {
    std::size_t tests = 0, failures = 0, skipped = 0;
  };
  const auto totals_of = [&](const std::vector<ExpectationOutcome>& outcomes) {
    const auto counts = count_verdicts(outcomes);
    return Totals{outcomes.size(),
                  counts.failed + (strict ? counts.inconclusive + counts.xpassed : 0),
                  counts.xfailed + (strict ? 0 : counts.inconclusive)};
  };
  Totals all;
  double seconds = 0;
  for (const auto& suite : report.suites) {
    const auto totals = totals_of(*suite.outcomes);
    all.tests += totals.tests;
    all.failures += totals.failures;
    all.skipped += totals.skipped;
    seconds += suite.seconds;
  }
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += fmt::format(
      "<testsuites name=\"rkhs-study check\" tests=\"{}\" failures=\"{}\" errors=\"0\" "
      "skipped=\"{}\" time=\"{:.3f}\">\n",
      all.tests, all.failures, all.skipped, seconds);
  for (const auto& suite : report.suites) {
    const auto& study = *suite.study;
    const auto totals = totals_of(*suite.outcomes);
    out += fmt::format(
        "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"{}\" "
        "time=\"{:.3f}\"{} file=\"{}\">\n",
        xml_escape(study.name), totals.tests, totals.failures, totals.skipped, suite.seconds,
        suite.timestamp.empty() ? std::string()
                                : fmt::format(" timestamp=\"{}\"", xml_escape(suite.timestamp)),
        xml_escape(study.source));
    out += "    <properties>\n";
    const auto property = [&out](std::string_view name, std::string_view value) {
      out += fmt::format("      <property name=\"{}\" value=\"{}\"/>\n", name, xml_escape(value));
    };
    property("study", study.source);
    property("tier", suite.tier.empty() ? "all" : suite.tier);
    property("strict", strict ? "true" : "false");
    if (report.policy.allow_inconclusive) property("allow", "inconclusive");
    if (!report.keyword_expression.empty()) {
      property("keyword_expression", report.keyword_expression);
      property("deselected", std::to_string(suite.deselected));
    }
    out += "    </properties>\n";
    for (const auto& o : *suite.outcomes) {
      const auto& e = *o.expectation;
      const auto outcome = case_outcome(o);
      out += fmt::format(
          "    <testcase classname=\"{}.{}\" name=\"{}\" file=\"{}\" line=\"{}\" "
          "time=\"{:.3f}\">\n",
          xml_escape(study.name), xml_escape(e.metric), xml_escape(o.name),
          xml_escape(study.source), line_of(e.location), o.seconds);
      const auto xfail = e.xfail.empty() ? std::string() : fmt::format("\nxfail: {}", e.xfail);
      const auto body =
          fmt::format("expected: {}\nfound: {}\nverdict: {}: {}{}\noutcome: {}\ngroup: {}\nat: {}",
                      o.expected, o.found, verdict_name(o.verdict), o.reason, xfail,
                      case_outcome_name(outcome), o.group, e.location);
      const auto message = fmt::format("{}: {}. Expected {}. Found {}", verdict_name(o.verdict),
                                       o.reason, o.expected, o.found);
      const auto failure = [&](std::string_view type, const std::string& text) {
        out += fmt::format("      <failure type=\"{}\" message=\"{}\">{}</failure>\n", type,
                           xml_escape(text), xml_escape(body, false));
      };
      const auto skipped = [&](std::string_view type, const std::string& text) {
        out += fmt::format("      <skipped type=\"{}\" message=\"{}\"/>\n", type, xml_escape(text));
      };
      switch (outcome) {
        case CaseOutcome::passed:
          break;
        case CaseOutcome::failed:
          failure("fail", message);
          break;
        case CaseOutcome::inconclusive:
          if (strict)
            failure("inconclusive", message);
          else
            skipped("inconclusive", message);
          break;
        case CaseOutcome::xfailed:
          skipped("xfail", fmt::format("XFAIL: {}. {}", e.xfail, message));
          break;
        case CaseOutcome::xpassed:
          if (strict) failure("xpass", fmt::format("XPASS(strict): {}. {}", e.xfail, message));
          break;
      }
      out += fmt::format("      <system-out>{}</system-out>\n", xml_escape(body, false));
      out += "    </testcase>\n";
    }
    out += "  </testsuite>\n";
  }
  out += "</testsuites>\n";
  return out;
}

}  // namespace rkhs
