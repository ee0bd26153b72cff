#pragma once
// Typed plugin parameters: what a plugin declares (ParameterSpec) and what a trial gets
// (ParameterSet, every declared parameter resolved to a value, defaults filled in).

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rkhs {

/// `text` is a free-form string (e.g. a matrix "-1 0; 0 -2"), `choice` one of `choices`.
enum class ParameterType { real, integer, choice, boolean, text };

/// A value as written in a study file. Integers stay integers so that `degree = 2` and
/// `sigma = 2` print as the user wrote them.
using ParameterValue = std::variant<double, std::int64_t, std::string, bool>;

/// Declaration of one plugin parameter.
///
/// For `real` and `integer`: the value must lie in [min, max] (open at an end whose
/// `*_exclusive` flag is set); a non-empty `allowed` restricts it to those values.
/// For `choice`: the value must be one of `choices`. `default_value` must itself be valid.
/// `default_doc`, when set, replaces the printed default. When it reads "= other" and `other` is
/// a parameter declared before this one, the default is the value of `other` (for example the
/// B-spline kernel's `r` defaults to "= degree"); `default_value` then only fixes the type.
struct ParameterSpec {
  std::string name;
  ParameterType type = ParameterType::real;
  ParameterValue default_value = 0.0;
  std::string doc;
  double min = -1e308;
  double max = 1e308;
  bool min_exclusive = false;
  bool max_exclusive = false;
  std::vector<double> allowed;
  std::vector<std::string> choices;
  std::string default_doc;
};

/// Builders that keep plugin declarations one line per parameter.
ParameterSpec real_parameter(std::string name, double default_value, std::string doc,
                             double min = -1e308, double max = 1e308);
ParameterSpec positive_parameter(std::string name, double default_value, std::string doc);
ParameterSpec integer_parameter(std::string name, std::int64_t default_value, std::string doc,
                                std::int64_t min, std::int64_t max);
ParameterSpec choice_parameter(std::string name, std::string default_value, std::string doc,
                               std::vector<std::string> choices);
ParameterSpec boolean_parameter(std::string name, bool default_value, std::string doc);
ParameterSpec text_parameter(std::string name, std::string default_value, std::string doc);

/// A parameter value that does not satisfy its declaration. `what()` is a full sentence;
/// `parameter()` names the offending parameter so a parser can point at its key.
class ParameterError : public std::invalid_argument {
 public:
  ParameterError(std::string parameter, const std::string& message)
      : std::invalid_argument(message), parameter_(std::move(parameter)) {}
  const std::string& parameter() const noexcept { return parameter_; }

 private:
  std::string parameter_;
};

/// Every declared parameter of one plugin instance, in declaration order.
class ParameterSet {
 public:
  ParameterSet() = default;

  /// Resolves `given` against `specs`: fills defaults, converts integers written for real
  /// parameters, checks types, ranges and choices. Throws ParameterError for an unknown name,
  /// a wrong type or an invalid value.
  ///
  /// With `user_parameters` (PluginInfo::user_parameters), a name `specs` does not declare is
  /// not unknown: it is a parameter the user named, checked against `user_parameters` (its
  /// type and range; its name and default are not used) and required to be a valid user
  /// parameter name (check_user_parameter_name). The user's parameters follow the declared ones,
  /// in the order of their names.
  static ParameterSet resolve(const std::vector<ParameterSpec>& specs,
                              const std::map<std::string, ParameterValue>& given,
                              const ParameterSpec* user_parameters = nullptr);

  double real(std::string_view name) const;  ///< real or integer parameter as double
  std::int64_t integer(std::string_view name) const;
  const std::string& choice(std::string_view name) const;  ///< choice or text parameter
  const std::string& text(std::string_view name) const { return choice(name); }
  bool boolean(std::string_view name) const;
  /// True when the study file gave this parameter (false: the default was used).
  bool given(std::string_view name) const;

  const std::vector<std::pair<std::string, ParameterValue>>& values() const { return values_; }

  /// "name=value name=value" in declaration order, reals printed round-trip exactly.
  std::string canonical() const;
  /// The same for the parameters the study file gave only (what an error message quotes).
  std::string given_canonical() const;

 private:
  const ParameterValue& find(std::string_view name) const;
  std::vector<std::pair<std::string, ParameterValue>> values_;
  std::vector<std::string> given_;
};

/// A value printed for humans and CSV: integers without a decimal point, reals with the
/// shortest representation that reads back to the same double.
std::string format_value(const ParameterValue& value);
std::string format_real(double value);

/// The values a numeric parameter accepts, as error messages and `rkhs-study list` say it:
/// "one of 0.5, 1.5", "in [0, 3]", "> 0", "any number".
std::string describe_range(const ParameterSpec& spec);
std::string_view type_name(ParameterType type);

/// Checks a declaration (default valid, bounds ordered, choices non-empty). Returns an empty
/// string when valid, otherwise what is wrong.
std::string validate_spec(const ParameterSpec& spec);

/// "" when `name` may name a parameter a user adds to a plugin that takes them (a letter or _
/// followed by letters, digits and _: it becomes a column of trials.csv and a selector of
/// [[expect]] tables); otherwise what is wrong with it.
std::string check_user_parameter_name(std::string_view name);

}  // namespace rkhs
