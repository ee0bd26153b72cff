// Expressions on muparser (rkhs/core/expression.hpp): the check at construction, which turns
// muparser's errors into "found ..., expected ...", and the per-thread compiled copies.
#include "rkhs/core/expression.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <muParser.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <map>

#include "rkhs/core/printable.hpp"  // excerpt, shortened
#include "rkhs/core/registry.hpp"   // closest_name

namespace rkhs {

namespace {

// The expression as a message quotes it: whole up to 2 x 60 bytes, else the part around
// `position` and the length ("...s+s+s..." (10000001 characters)).
std::string quoted_text(std::string_view text, std::size_t position) {
  constexpr std::size_t radius = 60;
  if (text.size() <= 2 * radius) return fmt::format("\"{}\"", text);
  return fmt::format("\"{}\" ({} characters)", excerpt(text, position, radius), text.size());
}

}  // namespace

ExpressionError::ExpressionError(std::string text, std::size_t position, std::string found,
                                 std::string expected, std::string unknown_name)
    : std::invalid_argument(
          position >= text.size()
              ? fmt::format("at the end of {}: found {}, expected {}",
                            quoted_text(text, text.size()), shortened(found, 200), expected)
              : fmt::format("at character {} of {}: found {}, expected {}", position + 1,
                            quoted_text(text, position), shortened(found, 200), expected)),
      text_(std::move(text)),
      position_(position),
      found_(std::move(found)),
      expected_(std::move(expected)),
      unknown_name_(std::move(unknown_name)) {}

struct Expression::Definition {
  std::uint64_t identity = 0;  // never shared by two definitions (the per-thread caches' key)
  std::string text;
  std::vector<std::string> variables;
  std::vector<NamedValue> constants;
  std::vector<std::string> used;  // the variables and constants the text reads, sorted
};

namespace {

// Identities start at 1: 0 marks an empty cache slot.
std::atomic<std::uint64_t> next_identity{1};

bool is_name_start(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}
bool is_name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

// The leading name, number or character of what muparser's token reader stopped at (its token
// is the rest of the line for an unreadable token).
std::string leading_token(std::string_view token) {
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.front())))
    token.remove_prefix(1);
  if (token.empty()) return {};
  std::size_t end = 1;
  if (is_name_start(token[0])) {
    while (end < token.size() && is_name_char(token[end])) ++end;
  } else if (std::isdigit(static_cast<unsigned char>(token[0])) || token[0] == '.') {
    while (end < token.size() &&
           (std::isalnum(static_cast<unsigned char>(token[end])) || token[end] == '.' ||
            ((token[end] == '+' || token[end] == '-') &&
             (token[end - 1] == 'e' || token[end - 1] == 'E'))))
      ++end;
  }
  return std::string(token.substr(0, end));
}

std::string quoted(std::string_view text) {
  return fmt::format("\"{}\"", text);
}

// Whether the characters of `part` appear in `whole` in order ("sn" in "sin").
bool is_subsequence(std::string_view part, std::string_view whole) {
  std::size_t i = 0;
  for (char c : whole)
    if (i < part.size() && part[i] == c) ++i;
  return i == part.size();
}

// The likely meant name for `found` (closest_name), preferring among equally close names one
// whose letters are `found`'s with some left out or added, in order (sin for sn, not ln; sin
// for sinn, not sign), then the longest common beginning; "" when
// none is close, or when either is a single character (a, s, L: any one-letter name is one edit
// from every other).
std::string likely_name(const std::string& found, const std::vector<std::string>& candidates) {
  const auto closest = closest_name(found, candidates);
  if (closest.empty() || found.size() < 2 || closest.size() < 2) return {};
  const auto distance = edit_distance(found, closest);
  const auto score = [&](const std::string& candidate) {
    const bool in_order = is_subsequence(found, candidate) || is_subsequence(candidate, found);
    const auto prefix = static_cast<std::size_t>(
        std::mismatch(found.begin(), found.end(), candidate.begin(), candidate.end()).first -
        found.begin());
    return std::pair{in_order, prefix};
  };
  std::string best = closest;
  for (const auto& candidate : candidates)
    if (candidate.size() >= 2 && edit_distance(found, candidate) == distance &&
        score(candidate) > score(best))
      best = candidate;
  return best;
}

// What may start an operand, for "expected" texts.
constexpr const char* value_expected =
    "a value: a number, a variable, a constant, a function call or \"(\"";
constexpr const char* operator_expected =
    "an operator (+ - * / ^, a comparison, && || or ? :) or the end of the expression";

class Translator {
 public:
  explicit Translator(const Expression::Definition& definition) : definition_(definition) {}

  // muparser's error as "found ..., expected ..." at a position of the text.
  ExpressionError operator()(const mu::ParserError& error) const {
    const std::string& text = definition_.text;
    const int raw_position = error.GetPos();
    std::size_t position = raw_position < 0 ? text.size() : static_cast<std::size_t>(raw_position);
    position = std::min(position, text.size());
    const std::string token = leading_token(error.GetToken());
    const auto fail = [&](std::string found, std::string expected) {
      return ExpressionError(text, position, std::move(found), std::move(expected));
    };
    switch (error.GetCode()) {
      case mu::ecUNASSIGNABLE_TOKEN:
        return unreadable(token, position);
      case mu::ecUNEXPECTED_OPERATOR:
        if (token == "=") return fail("\"=\" (an assignment)", "an expression: compare with ==");
        return fail("the operator " + quoted(token), value_expected);
      case mu::ecUNEXPECTED_EOF:
        return fail("the end of the expression", value_expected);
      case mu::ecUNEXPECTED_ARG_SEP:
        return fail("\",\"", std::string(operator_expected) +
                                 " (a comma only separates a function's arguments)");
      case mu::ecUNEXPECTED_ARG:
        return fail("a list of arguments in parentheses", "a function name before it");
      case mu::ecUNEXPECTED_VAL:
        return fail("the number " + quoted(token), "an operator before it (write 2 * s, not 2 s)");
      case mu::ecUNEXPECTED_VAR:
        return fail("the name " + quoted(token), "an operator before it (write 2 * s, not 2 s)");
      case mu::ecUNEXPECTED_FUN:
        return fail("the function " + quoted(token), "an operator before it");
      case mu::ecUNEXPECTED_PARENS:
        if (token == ")") return fail("\")\"", "a value before it, or a \"(\" that it closes");
        return fail("\"(\"", "an operator before it (write 2 * (s + 1), not 2 (s + 1))");
      case mu::ecMISSING_PARENS:
        return fail("the end of the expression", "\")\"");
      case mu::ecTOO_MANY_PARAMS:
      case mu::ecTOO_FEW_PARAMS:
        return arguments(error, token, position);
      case mu::ecMISSING_ELSE_CLAUSE:
        return fail("\"?\" without its \":\"", "condition ? value : other value");
      case mu::ecMISPLACED_COLON:
        return fail("\":\" without a \"?\" before it", "condition ? value : other value");
      case mu::ecUNEXPECTED_CONDITIONAL:
        return fail("\"?\" after an incomplete condition",
                    "condition ? value : other value, the condition complete");
      case mu::ecUNEXPECTED_STR:
      case mu::ecUNTERMINATED_STRING:
      case mu::ecSTR_RESULT:
      case mu::ecSTRING_EXPECTED:
      case mu::ecVAL_EXPECTED:
        return fail("a string (\"...\")", "a number: there are no strings");
      case mu::ecEMPTY_EXPRESSION:
        return fail("an empty expression", "an expression");
      case mu::ecEXPRESSION_TOO_LONG:
        return fail(fmt::format("an expression of {} characters", text.size()),
                    fmt::format("fewer than {}", mu::MaxLenExpression));
      default:
        return fail(fmt::format("an error muparser reports as \"{}\"", error.GetMsg()),
                    "an expression in its syntax");
    }
  }

 private:
  // Every name the expression may use: variables, constants and functions.
  std::vector<std::string> known_names() const {
    std::vector<std::string> names = definition_.variables;
    for (const auto& constant : definition_.constants) names.push_back(constant.name);
    for (const auto& function : Expression::functions()) names.push_back(function.name);
    return names;
  }
  std::string names_text() const {
    std::vector<std::string> values = definition_.variables;
    for (const auto& constant : definition_.constants) values.push_back(constant.name);
    return values.empty() ? std::string("none") : fmt::format("{}", fmt::join(values, ", "));
  }

  ExpressionError unreadable(const std::string& token, std::size_t position) const {
    const std::string& text = definition_.text;
    if (!token.empty() && is_name_start(token[0])) {
      std::size_t after = position + token.size();
      while (after < text.size() && std::isspace(static_cast<unsigned char>(text[after]))) ++after;
      const bool call = after < text.size() && text[after] == '(';
      std::vector<std::string> candidates;
      if (call)
        for (const auto& function : Expression::functions()) candidates.push_back(function.name);
      else
        candidates = known_names();
      const auto guess = likely_name(token, candidates);
      std::string expected =
          call ? fmt::format("a function: {}", fmt::join(function_names(), ", "))
               : fmt::format("a variable or constant ({}) or a function", names_text());
      if (!guess.empty()) expected += fmt::format("; did you mean \"{}\"?", guess);
      return ExpressionError(
          text, position, fmt::format("the unknown {} \"{}\"", call ? "function" : "name", token),
          expected, call ? std::string() : token);
    }
    if (!token.empty() && (std::isdigit(static_cast<unsigned char>(token[0])) || token[0] == '.'))
      return ExpressionError(text, position,
                             "the malformed or out-of-range number " + quoted(token),
                             "a number such as 2, 0.5 or 1e-3 (at most 1.8e308)");
    return ExpressionError(text, position, quoted(token.empty() ? std::string("?") : token),
                           "an operator, a number, a name or a parenthesis");
  }

  ExpressionError arguments(const mu::ParserError& error, const std::string& function,
                            std::size_t position) const {
    int count = 1;
    for (const auto& f : Expression::functions())
      if (f.name == function) count = f.arguments;
    const bool too_many = error.GetCode() == mu::ecTOO_MANY_PARAMS;
    return ExpressionError(
        definition_.text, position,
        fmt::format("too {} arguments for {}", too_many ? "many" : "few", function),
        count < 0 ? std::string("one or more")
                  : fmt::format("{} argument{}", count, count == 1 ? "" : "s"));
  }

  static std::vector<std::string> function_names() {
    std::vector<std::string> names;
    for (const auto& f : Expression::functions()) names.push_back(f.name);
    return names;
  }

  const Expression::Definition& definition_;
};

// The first "=" that is an assignment (not part of <=, >=, !=, ==), or npos.
std::size_t assignment_position(const std::string& text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '=') continue;
    const bool after_comparison = i > 0 && (text[i - 1] == '<' || text[i - 1] == '>' ||
                                            text[i - 1] == '!' || text[i - 1] == '=');
    const bool before_equals = i + 1 < text.size() && text[i + 1] == '=';
    if (after_comparison || before_equals) {
      if (before_equals) ++i;  // "==": skip its second character
      continue;
    }
    return i;
  }
  return std::string::npos;
}

// The first "," outside every parenthesis, or npos.
std::size_t top_level_comma(const std::string& text) {
  int depth = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '(')
      ++depth;
    else if (text[i] == ')')
      --depth;
    else if (text[i] == ',' && depth <= 0)
      return i;
  }
  return std::string::npos;
}

// One thread's compiled copy of a definition. The parser holds the addresses of `arguments_`,
// which is sized once and never resized; a compiled copy is neither copied nor moved.
class Compiled {
 public:
  explicit Compiled(const Expression::Definition& definition)
      : identity_(definition.identity), arguments_(definition.variables.size(), 0.0) {
    parser_.ClearConst();  // muparser's _pi and _e: the names are the definition's alone
    for (std::size_t v = 0; v < definition.variables.size(); ++v)
      parser_.DefineVar(definition.variables[v], &arguments_[v]);
    for (const auto& constant : definition.constants)
      parser_.DefineConst(constant.name, constant.value);
    parser_.SetExpr(definition.text);
    parser_.Eval();  // compiles the text to muparser's bytecode (checked by the constructor)
  }
  Compiled(const Compiled&) = delete;
  Compiled& operator=(const Compiled&) = delete;

  std::uint64_t identity() const noexcept { return identity_; }
  double operator()(const double* point) {
    std::copy(point, point + arguments_.size(), arguments_.begin());
    return parser_.Eval();
  }

 private:
  std::uint64_t identity_;
  std::vector<double> arguments_;
  mu::Parser parser_;
};

// The compiled copies of the expressions this thread evaluated last, replaced in turn.
class ThreadCache {
 public:
  Compiled& get(const Expression::Definition& definition) {
    for (auto& slot : slots_)
      if (slot && slot->identity() == definition.identity) return *slot;
    auto& slot = slots_[next_];
    next_ = (next_ + 1) % slots_.size();
    slot.reset();  // the old copy first: at most slots_.size() exist at once
    slot = std::make_unique<Compiled>(definition);
    return *slot;
  }

 private:
  std::array<std::unique_ptr<Compiled>, 8> slots_;
  std::size_t next_ = 0;
};

Compiled& compiled_for_this_thread(const Expression::Definition& definition) {
  thread_local ThreadCache cache;
  return cache.get(definition);
}

}  // namespace

const std::vector<ExpressionFunction>& Expression::functions() {
  static const std::vector<ExpressionFunction> list = [] {
    std::vector<ExpressionFunction> out;
    const mu::Parser parser;
    for (const auto& [name, callback] : parser.GetFunDef())
      out.push_back({name, callback.GetArgc() < 0 ? -1 : callback.GetArgc()});
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    return out;
  }();
  return list;
}

std::string Expression::check_name(std::string_view name) {
  if (name.empty()) return "is empty";
  if (!is_name_start(name[0]) || !std::all_of(name.begin(), name.end(), is_name_char))
    return "is not a name: a name is a letter or _ followed by letters, digits and _";
  if (name.size() > static_cast<std::size_t>(mu::MaxLenIdentifier))
    return fmt::format("is longer than {} characters", mu::MaxLenIdentifier);
  for (const auto& function : functions())
    if (function.name == name) return fmt::format("is the function {}", name);
  return "";
}

Expression::Expression(std::string text, std::vector<std::string> variables,
                       std::vector<NamedValue> constants) {
  auto definition = std::make_shared<Definition>();
  definition->identity = next_identity.fetch_add(1, std::memory_order_relaxed);
  definition->text = std::move(text);
  definition->variables = std::move(variables);
  definition->constants = std::move(constants);

  std::vector<std::string> names = definition->variables;
  for (const auto& constant : definition->constants) names.push_back(constant.name);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (auto why = check_name(names[i]); !why.empty())
      throw std::invalid_argument(fmt::format("the name \"{}\" {}", names[i], why));
    if (std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) !=
        names.begin() + static_cast<std::ptrdiff_t>(i))
      throw std::invalid_argument(fmt::format("the name \"{}\" is given twice", names[i]));
  }

  // The check: every name a variable of one parser, so that muparser also says which it reads.
  const Translator translate(*definition);
  const std::string& source = definition->text;
  std::vector<double> values(names.size(), 0.0);
  mu::Parser checker;
  checker.ClearConst();
  try {
    for (std::size_t i = 0; i < names.size(); ++i) checker.DefineVar(names[i], &values[i]);
    checker.SetExpr(source);
    checker.Eval();
  } catch (const mu::ParserError& error) {
    throw translate(error);
  }
  if (const auto at = assignment_position(source); at != std::string::npos)
    throw ExpressionError(source, at, "\"=\" (an assignment)", "an expression: compare with ==");
  if (checker.GetNumResults() != 1) {
    const auto at = top_level_comma(source);
    throw ExpressionError(
        source, at == std::string::npos ? 0 : at,
        fmt::format("{} expressions separated by commas", checker.GetNumResults()),
        "one expression (a comma only separates a function's arguments)");
  }
  for (const auto& [name, pointer] : checker.GetUsedVar()) definition->used.push_back(name);
  std::sort(definition->used.begin(), definition->used.end());

  // The form every thread evaluates (constants folded): compiled once here, so that a
  // definition that muparser would refuse in that form is refused now, not in a trial.
  try {
    Compiled compiled(*definition);
  } catch (const mu::ParserError& error) {
    throw translate(error);
  }
  definition_ = std::move(definition);
}

Expression::~Expression() = default;

const std::string& Expression::text() const noexcept {
  return definition_->text;
}
const std::vector<std::string>& Expression::variables() const noexcept {
  return definition_->variables;
}
const std::vector<NamedValue>& Expression::constants() const noexcept {
  return definition_->constants;
}

bool Expression::uses(std::string_view name) const {
  return std::binary_search(definition_->used.begin(), definition_->used.end(), name);
}

double Expression::operator()(std::span<const double> point) const {
  if (point.size() != definition_->variables.size())
    throw std::invalid_argument(fmt::format("an expression of {} variables given a point of {}",
                                            definition_->variables.size(), point.size()));
  return compiled_for_this_thread(*definition_)(point.data());
}

void Expression::evaluate(std::span<const double> points, std::span<double> out) const {
  const std::size_t d = definition_->variables.size();
  if (points.size() != out.size() * d)
    throw std::invalid_argument(fmt::format(
        "{} values for {} points of an expression of {} variables", points.size(), out.size(), d));
  auto& compiled = compiled_for_this_thread(*definition_);
  for (std::size_t m = 0; m < out.size(); ++m) out[m] = compiled(points.data() + m * d);
}

}  // namespace rkhs
