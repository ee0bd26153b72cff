// libFuzzer harness: the `csv` road target (plugins/targets/csv_road.cpp) built from arbitrary
// bytes as the text of its CSV file (rkhs::csv_road_from_text, which the target uses for its
// file). Refusals are std::invalid_argument (ParameterError for a parameter), the exception the
// target documents; anything else is a bug. A road that is built is evaluated, with its
// derivative, inside, at the ends of and beyond its section, and at its kinks.
//
// An input may start with a line of options, a CSV comment for the parser:
//   #! header=false delimiter=; arc_length_column=3 detrend=linear length=12.5 periodic=true
// `length` and `periodic` set the domain (default: an interval of 10 m); any other key=value is
// a parameter of the target, converted to the type it declares (a wrong value is a refusal).
// Without the line, the target's defaults: the shipped profiles (studies/data/) are seeds as
// they are.
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/targets/csv_road.hpp"

namespace {

using rkhs::ParameterValue;

std::optional<double> real_of(std::string_view text) {
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

// `value` as the parameter `key` of the target declares it; a string when it cannot be (the
// target then refuses it).
ParameterValue typed(const std::vector<rkhs::ParameterSpec>& specs, const std::string& key,
                     const std::string& value) {
  for (const auto& spec : specs) {
    if (spec.name != key) continue;
    if (spec.type == rkhs::ParameterType::real)
      if (const auto real = real_of(value)) return *real;
    if (spec.type == rkhs::ParameterType::boolean && (value == "true" || value == "false"))
      return value == "true";
  }
  return value;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  static const auto& specs = rkhs::target_registry().find("csv")->info.parameters;
  std::map<std::string, ParameterValue> given{{"file", std::string("fuzz.csv")}};
  rkhs::Domain domain{10.0, false};
  if (text.starts_with("#!")) {
    std::string_view options = text.substr(2, text.find('\n') - 2);
    while (!options.empty()) {
      const auto space = options.find(' ');
      const auto token = options.substr(0, space);
      options.remove_prefix(space == std::string_view::npos ? options.size() : space + 1);
      const auto equals = token.find('=');
      if (equals == std::string_view::npos) continue;
      const std::string key(token.substr(0, equals)), value(token.substr(equals + 1));
      if (key == "length") {
        if (const auto length = real_of(value); length && *length > 0 && std::isfinite(*length))
          domain.length = *length;
      } else if (key == "periodic") {
        domain.periodic = value == "true";
      } else {
        given[key] = typed(specs, key, value);
      }
    }
  }
  try {
    const auto parameters = rkhs::ParameterSet::resolve(specs, given);
    const auto road = rkhs::csv_road_from_text(parameters, domain, text, "fuzz.csv");
    const double length = domain.length;
    std::vector<double> points{0, length / 3, length / 2, length, -length / 4, 1.25 * length};
    const auto kinks = road->kink_points();
    for (std::size_t k = 0; k < kinks.size() && k < 16; ++k) points.push_back(kinks[k]);
    std::vector<double> values(points.size()), slopes(points.size());
    road->evaluate(points, values);
    road->derivative(points, slopes);
    (void)road->data_provenance();
    (void)road->notes();
  } catch (const std::invalid_argument&) {
    // A refusal is a correct answer to a malformed file or parameter.
  } catch (const std::exception& e) {
    rkhs::fuzz::unexpected_exception(e);
  }
  return 0;
}
