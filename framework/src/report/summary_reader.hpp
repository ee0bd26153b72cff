#pragma once
// Internal to the report layer: reading typed values out of summary.json (run_summary.cpp,
// summary_verdicts.cpp), every refusal naming the file and the key's JSON path.

#include <fmt/format.h>

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "rkhs/report/run_summary.hpp"

namespace rkhs::report_detail {

using Json = nlohmann::ordered_json;

// The text of a JSON value's type, for messages.
inline std::string type_text(const Json& value) {
  if (value.is_null()) return "null";
  if (value.is_boolean()) return "a boolean";
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_array()) return "an array";
  return "an object";
}

// Reads typed values out of summary.json, naming the file and the key's JSON path in every
// refusal.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw std::runtime_error(fmt::format("{}: {}: {}", file_, path, what));
  }

  const Json& member(const Json& object, const std::string& path, const char* key) const {
    if (!object.is_object()) fail(path, "expected an object; found " + type_text(object));
    const auto found = object.find(key);
    if (found == object.end())
      fail(path.empty() ? key : path + "." + key, "missing (not a summary.json of this version?)");
    return *found;
  }

  std::string text(const Json& value, const std::string& path) const {
    if (!value.is_string()) fail(path, "expected a string; found " + type_text(value));
    return value.get<std::string>();
  }
  std::string text(const Json& object, const std::string& path, const char* key) const {
    return text(member(object, path, key), join(path, key));
  }
  // A string or null ("" for null).
  std::string optional_text(const Json& object, const std::string& path, const char* key) const {
    if (!object.is_object() || !object.contains(key) || object[key].is_null()) return {};
    return text(object[key], join(path, key));
  }

  // A number as json_number writes it: a number, "inf", "-inf", or null for NaN.
  double number(const Json& value, const std::string& path) const {
    if (value.is_number()) return value.get<double>();
    if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (value.is_string()) {
      const auto& s = value.get_ref<const std::string&>();
      if (s == "inf") return std::numeric_limits<double>::infinity();
      if (s == "-inf") return -std::numeric_limits<double>::infinity();
    }
    fail(path, "expected a number, \"inf\", \"-inf\" or null; found " + type_text(value));
  }
  double number(const Json& object, const std::string& path, const char* key) const {
    return number(member(object, path, key), join(path, key));
  }

  std::size_t count(const Json& value, const std::string& path,
                    std::size_t most = std::numeric_limits<std::uint32_t>::max()) const {
    if (!value.is_number_unsigned() || value.get<std::uint64_t>() > most)
      fail(path, fmt::format("expected an integer in [0, {}]; found {}", most,
                             value.is_number() ? value.dump() : type_text(value)));
    return static_cast<std::size_t>(value.get<std::uint64_t>());
  }
  std::size_t count(const Json& object, const std::string& path, const char* key) const {
    return count(member(object, path, key), join(path, key));
  }

  const Json& array(const Json& value, const std::string& path) const {
    if (!value.is_array()) fail(path, "expected an array; found " + type_text(value));
    return value;
  }
  const Json& array(const Json& object, const std::string& path, const char* key) const {
    return array(member(object, path, key), join(path, key));
  }

  static std::string join(const std::string& path, const char* key) {
    return path.empty() ? std::string(key) : path + "." + key;
  }
  static std::string at(const std::string& path, std::size_t index) {
    return fmt::format("{}[{}]", path, index);
  }

 private:
  std::string file_;
};

/// The verdicts of summary.json's "expectations" (when it has them) into `folder`, each with an
/// Expectation of its own location in folder.study.expectations (summary_verdicts.cpp).
void read_summary_verdicts(const Reader& reader, const Json& json, ResultsFolder& folder);

}  // namespace rkhs::report_detail
