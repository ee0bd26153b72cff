#include "rkhs/core/parameters.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

namespace rkhs {

ParameterSpec real_parameter(std::string name, double default_value, std::string doc, double min,
                             double max) {
  ParameterSpec spec;
  spec.name = std::move(name);
  spec.type = ParameterType::real;
  spec.default_value = default_value;
  spec.doc = std::move(doc);
  spec.min = min;
  spec.max = max;
  return spec;
}

ParameterSpec positive_parameter(std::string name, double default_value, std::string doc) {
  auto spec = real_parameter(std::move(name), default_value, std::move(doc), 0.0);
  spec.min_exclusive = true;
  return spec;
}

ParameterSpec integer_parameter(std::string name, std::int64_t default_value, std::string doc,
                                std::int64_t min, std::int64_t max) {
  ParameterSpec spec;
  spec.name = std::move(name);
  spec.type = ParameterType::integer;
  spec.default_value = default_value;
  spec.doc = std::move(doc);
  spec.min = static_cast<double>(min);
  spec.max = static_cast<double>(max);
  return spec;
}

ParameterSpec choice_parameter(std::string name, std::string default_value, std::string doc,
                               std::vector<std::string> choices) {
  ParameterSpec spec;
  spec.name = std::move(name);
  spec.type = ParameterType::choice;
  spec.default_value = std::move(default_value);
  spec.doc = std::move(doc);
  spec.choices = std::move(choices);
  return spec;
}

ParameterSpec boolean_parameter(std::string name, bool default_value, std::string doc) {
  ParameterSpec spec;
  spec.name = std::move(name);
  spec.type = ParameterType::boolean;
  spec.default_value = default_value;
  spec.doc = std::move(doc);
  return spec;
}

ParameterSpec text_parameter(std::string name, std::string default_value, std::string doc) {
  ParameterSpec spec;
  spec.name = std::move(name);
  spec.type = ParameterType::text;
  spec.default_value = std::move(default_value);
  spec.doc = std::move(doc);
  return spec;
}

std::string_view type_name(ParameterType type) {
  switch (type) {
    case ParameterType::real: return "a number";
    case ParameterType::integer: return "an integer";
    case ParameterType::choice: return "a string";
    case ParameterType::boolean: return "true or false";
    case ParameterType::text: return "a string";
  }
  return "?";
}

std::string format_real(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

std::string format_value(const ParameterValue& value) {
  struct Visitor {
    std::string operator()(double v) const { return format_real(v); }
    std::string operator()(std::int64_t v) const { return std::to_string(v); }
    std::string operator()(const std::string& v) const { return v; }
    std::string operator()(bool v) const { return v ? "true" : "false"; }
  };
  return std::visit(Visitor{}, value);
}

std::string describe_range(const ParameterSpec& spec) {
  std::string out;
  if (!spec.allowed.empty()) {
    out = "one of";
    for (std::size_t i = 0; i < spec.allowed.size(); ++i)
      out += (i ? ", " : " ") + format_real(spec.allowed[i]);
    return out;
  }
  const bool has_min = spec.min > -1e308, has_max = spec.max < 1e308;
  auto bound = [&](double v) {
    return spec.type == ParameterType::integer ? std::to_string(static_cast<std::int64_t>(v))
                                               : format_real(v);
  };
  if (has_min && has_max)
    return fmt::format("in {}{}, {}{}", spec.min_exclusive ? "(" : "[", bound(spec.min),
                       bound(spec.max), spec.max_exclusive ? ")" : "]");
  if (has_min) return fmt::format("{} {}", spec.min_exclusive ? ">" : ">=", bound(spec.min));
  if (has_max) return fmt::format("{} {}", spec.max_exclusive ? "<" : "<=", bound(spec.max));
  return "any number";
}

namespace {

// Checks `value` (already of the spec's type) and returns what is wrong, or "".
std::string check_value(const ParameterSpec& spec, const ParameterValue& value) {
  switch (spec.type) {
    case ParameterType::real:
    case ParameterType::integer: {
      const double v = std::holds_alternative<double>(value)
                           ? std::get<double>(value)
                           : static_cast<double>(std::get<std::int64_t>(value));
      if (!std::isfinite(v)) return "must be finite";
      if (!spec.allowed.empty()) {
        if (std::find(spec.allowed.begin(), spec.allowed.end(), v) == spec.allowed.end())
          return "must be " + describe_range(spec);
        return "";
      }
      const bool below = spec.min_exclusive ? v <= spec.min : v < spec.min;
      const bool above = spec.max_exclusive ? v >= spec.max : v > spec.max;
      if (below || above) return "must be " + describe_range(spec);
      return "";
    }
    case ParameterType::choice: {
      const auto& s = std::get<std::string>(value);
      if (std::find(spec.choices.begin(), spec.choices.end(), s) == spec.choices.end()) {
        std::string list;
        for (std::size_t i = 0; i < spec.choices.size(); ++i)
          list += (i ? ", " : "") + ("\"" + spec.choices[i] + "\"");
        return "must be one of " + list;
      }
      return "";
    }
    case ParameterType::boolean:
    case ParameterType::text: return "";
  }
  return "";
}

// Converts `value` to the spec's type where that is lossless; returns false when impossible.
bool coerce(const ParameterSpec& spec, ParameterValue& value) {
  switch (spec.type) {
    case ParameterType::real:
      if (std::holds_alternative<std::int64_t>(value))
        value = static_cast<double>(std::get<std::int64_t>(value));
      return std::holds_alternative<double>(value);
    case ParameterType::integer:
      if (auto* d = std::get_if<double>(&value); d && std::floor(*d) == *d && std::abs(*d) < 9e15)
        value = static_cast<std::int64_t>(*d);
      return std::holds_alternative<std::int64_t>(value);
    case ParameterType::choice:
    case ParameterType::text: return std::holds_alternative<std::string>(value);
    case ParameterType::boolean: return std::holds_alternative<bool>(value);
  }
  return false;
}

std::string_view found_type(const ParameterValue& value) {
  switch (value.index()) {
    case 0: return "a number";
    case 1: return "an integer";
    case 2: return "a string";
    default: return "a boolean";
  }
}

}  // namespace

std::string validate_spec(const ParameterSpec& spec) {
  if (spec.name.empty()) return "empty name";
  if (spec.min > spec.max) return "min > max";
  if (spec.type == ParameterType::choice && spec.choices.empty()) return "no choices";
  ParameterValue v = spec.default_value;
  if (!coerce(spec, v)) return "default is not " + std::string(type_name(spec.type));
  if (!spec.default_doc.empty()) return "";  // the default is a placeholder
  if (auto why = check_value(spec, v); !why.empty()) return "default " + why;
  return "";
}

std::string check_user_parameter_name(std::string_view name) {
  const auto letter = [](char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
  };
  const auto letter_or_digit = [&](char c) {
    return letter(c) || std::isdigit(static_cast<unsigned char>(c));
  };
  if (name.empty() || !letter(name[0]) || !std::all_of(name.begin(), name.end(), letter_or_digit))
    return "is not a name: a letter or _ followed by letters, digits and _";
  return "";
}

ParameterSet ParameterSet::resolve(const std::vector<ParameterSpec>& specs,
                                   const std::map<std::string, ParameterValue>& given,
                                   const ParameterSpec* user_parameters) {
  std::vector<ParameterSpec> users;  // one spec per parameter the user named, by name
  for (const auto& entry : given) {
    const std::string& name = entry.first;  // not a structured binding: the lambda captures it
    if (std::any_of(specs.begin(), specs.end(), [&](const auto& s) { return s.name == name; }))
      continue;
    if (!user_parameters) {
      std::string known;
      for (std::size_t i = 0; i < specs.size(); ++i) known += (i ? ", " : "") + specs[i].name;
      throw ParameterError(name, fmt::format("unknown parameter '{}' (known: {})", name,
                                             known.empty() ? "none" : known));
    }
    if (auto why = check_user_parameter_name(name); !why.empty())
      throw ParameterError(name, fmt::format("parameter name '{}' {}", name, why));
    users.push_back(*user_parameters);
    users.back().name = name;
  }
  ParameterSet set;
  const auto add = [&](const ParameterSpec& spec) {
    auto it = given.find(spec.name);
    ParameterValue value = it == given.end() ? spec.default_value : it->second;
    if (it == given.end() && spec.default_doc.starts_with("= ")) {
      const auto other = spec.default_doc.substr(2);
      for (const auto& [key, v] : set.values_)
        if (key == other) value = v;
    }
    if (!coerce(spec, value))
      throw ParameterError(spec.name, fmt::format("parameter '{}' must be {}, found {}", spec.name,
                                                  type_name(spec.type), found_type(value)));
    if (auto why = check_value(spec, value); !why.empty())
      throw ParameterError(spec.name, fmt::format("parameter '{}' {}, found {}", spec.name, why,
                                                  format_value(value)));
    set.values_.emplace_back(spec.name, std::move(value));
    if (it != given.end()) set.given_.push_back(spec.name);
  };
  for (const auto& spec : specs) add(spec);
  for (const auto& spec : users) add(spec);
  return set;
}

const ParameterValue& ParameterSet::find(std::string_view name) const {
  for (const auto& [key, value] : values_)
    if (key == name) return value;
  throw std::out_of_range(fmt::format("no parameter '{}'", name));
}

double ParameterSet::real(std::string_view name) const {
  const auto& v = find(name);
  if (auto* d = std::get_if<double>(&v)) return *d;
  if (auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  throw std::invalid_argument(fmt::format("parameter '{}' is not a number", name));
}

std::int64_t ParameterSet::integer(std::string_view name) const {
  const auto& v = find(name);
  if (auto* i = std::get_if<std::int64_t>(&v)) return *i;
  throw std::invalid_argument(fmt::format("parameter '{}' is not an integer", name));
}

const std::string& ParameterSet::choice(std::string_view name) const {
  const auto& v = find(name);
  if (auto* s = std::get_if<std::string>(&v)) return *s;
  throw std::invalid_argument(fmt::format("parameter '{}' is not a string", name));
}

bool ParameterSet::boolean(std::string_view name) const {
  const auto& v = find(name);
  if (auto* b = std::get_if<bool>(&v)) return *b;
  throw std::invalid_argument(fmt::format("parameter '{}' is not a boolean", name));
}

bool ParameterSet::given(std::string_view name) const {
  return std::find(given_.begin(), given_.end(), name) != given_.end();
}

std::string ParameterSet::canonical() const {
  std::string out;
  for (const auto& [name, value] : values_) {
    if (!out.empty()) out += ' ';
    out += name + "=" + format_value(value);
  }
  return out;
}

std::string ParameterSet::given_canonical() const {
  std::string out;
  for (const auto& [name, value] : values_) {
    if (!given(name)) continue;
    if (!out.empty()) out += ' ';
    out += name + "=" + format_value(value);
  }
  return out;
}

}  // namespace rkhs
