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
  const auto counts = count_verdicts(report.outcomes);
  const std::size_t failures = counts.failed + (report.strict ? counts.inconclusive : 0);
  const std::size_t skipped = report.strict ? 0 : counts.inconclusive;
  const auto time = fmt::format("{:.3f}", report.seconds);
  const auto& study = report.study;
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += fmt::format(
      "<testsuites name=\"rkhs-study check\" tests=\"{}\" failures=\"{}\" errors=\"0\" "
      "skipped=\"{}\" time=\"{}\">\n",
      report.outcomes.size(), failures, skipped, time);
  out += fmt::format(
      "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"{}\" "
      "time=\"{}\"{} file=\"{}\">\n",
      xml_escape(study.name), report.outcomes.size(), failures, skipped, time,
      report.timestamp.empty() ? std::string() : fmt::format(" timestamp=\"{}\"", xml_escape(report.timestamp)),
      xml_escape(study.source));
  out += "    <properties>\n";
  out += fmt::format("      <property name=\"study\" value=\"{}\"/>\n", xml_escape(study.source));
  out += fmt::format("      <property name=\"tier\" value=\"{}\"/>\n",
                     xml_escape(report.tier.empty() ? "all" : report.tier));
  out += fmt::format("      <property name=\"strict\" value=\"{}\"/>\n", report.strict ? "true" : "false");
  out += "    </properties>\n";
  for (const auto& o : report.outcomes) {
    const auto& e = *o.expectation;
    const auto name = fmt::format("#{} {}{}", e.number, e.name.empty() ? "" : e.name + ": ", o.group_label);
    out += fmt::format(
        "    <testcase classname=\"{}.{}\" name=\"{}\" file=\"{}\" line=\"{}\" time=\"0\">\n",
        xml_escape(study.name), xml_escape(e.metric), xml_escape(name), xml_escape(study.source),
        line_of(e.location));
    const auto body = fmt::format("expected: {}\nfound: {}\nverdict: {}: {}\ngroup: {}\nat: {}",
                                  o.expected, o.found, verdict_name(o.verdict), o.reason, o.group,
                                  e.location);
    const auto message = fmt::format("{}: {}. Expected {}. Found {}", verdict_name(o.verdict),
                                     o.reason, o.expected, o.found);
    if (o.verdict == Verdict::fail || (report.strict && o.verdict == Verdict::inconclusive))
      out += fmt::format("      <failure type=\"{}\" message=\"{}\">{}</failure>\n",
                         o.verdict == Verdict::fail ? "fail" : "inconclusive", xml_escape(message),
                         xml_escape(body, false));
    else if (o.verdict == Verdict::inconclusive)
      out += fmt::format("      <skipped message=\"{}\"/>\n", xml_escape(message));
    out += fmt::format("      <system-out>{}</system-out>\n", xml_escape(body, false));
    out += "    </testcase>\n";
  }
  out += "  </testsuite>\n</testsuites>\n";
  return out;
}

}  // namespace rkhs
