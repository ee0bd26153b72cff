#pragma once
// Real-valued expressions of named real variables, written as text in a study file (e.g. the
// target f = "2 * sin(2 * pi * s / L)"), checked and compiled once, then evaluated from any
// number of threads.
//
// The syntax is muparser's (Debian libmuparser-dev): numbers (1, 2.5, 1e-3), the operators
// + - * / ^ (power), unary -, comparisons < <= > >= == != (1 or 0), && and ||, a ? b : c, and
// parentheses; the functions sin cos tan asin acos atan atan2 sinh cosh tanh asinh acosh atanh
// exp ln log (= ln) log2 log10 sqrt abs sign rint, and min max sum avg of one or more arguments
// (Expression::functions() lists them with their argument counts). The names an expression may
// use are exactly the variables and constants its owner declares: muparser's own constants
// (_pi, _e) are removed, so that every name means what the owner documents.
//
// Arithmetic is IEEE double as written: log(-1) is NaN and 1/0 is inf, never an exception. An
// owner that must not pass such values on checks them (the expression target does).
//
// Evaluation never locks and never allocates after a thread's first call: each thread compiles
// its own copy of an expression (muparser's parser keeps its evaluation stack in the object, so
// one object cannot be evaluated concurrently) on first use and keeps it in a small per-thread
// cache of the expressions it used last (8), keyed by an identity no other expression ever has.
// A thread that alternates between more than 8 expressions recompiles (a few microseconds each
// time); nothing else depends on how many there are. muparser's bulk mode (Eval(results, n)) is
// not used: the Debian build runs it on an OpenMP team and sets OpenMP's global thread count,
// which has no place inside a trial that already runs on one of the scheduler's threads.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rkhs {

/// A mistake in an expression's text. what() reads
///   at character 23 of "2 * sin(2 * pi * s / L": found the end of the expression, expected ")"
/// position() is the offset (from 0) of the first character that is wrong, text().size() for
/// the end of the text. A text longer than 120 bytes is quoted in what() by its part around
/// position() and its length ("...s+s+s..." (10000001 characters)); text() is the whole.
class ExpressionError : public std::invalid_argument {
 public:
  ExpressionError(std::string text, std::size_t position, std::string found, std::string expected,
                  std::string unknown_name = {});
  const std::string& text() const noexcept { return text_; }
  std::size_t position() const noexcept { return position_; }
  /// What stands at position(): "unknown name \"sn\"", "the end of the expression", ...
  const std::string& found() const noexcept { return found_; }
  /// What the grammar or the names allow there: "\")\"", "an operator", ...
  const std::string& expected() const noexcept { return expected_; }
  /// The name when the mistake is a name that is neither a variable, a constant nor a function
  /// (not followed by "("); empty otherwise.
  const std::string& unknown_name() const noexcept { return unknown_name_; }

 private:
  std::string text_;
  std::size_t position_;
  std::string found_, expected_, unknown_name_;
};

/// A name an expression may use, bound to a fixed value.
struct NamedValue {
  std::string name;
  double value = 0;
};

/// A function of the expression syntax and its argument count (-1: one or more).
struct ExpressionFunction {
  std::string name;
  int arguments = 1;
};

/// An expression of the variables `variables()` (its point: one value per variable, in that
/// order), reading the named constants `constants()`. Copies share the compiled definition.
class Expression {
 public:
  /// Checks and compiles `text`. Throws
  ///  - ExpressionError for a mistake in the text: a syntax error, a name that is neither a
  ///    variable nor a constant nor a function, a wrong number of arguments, an assignment
  ///    ("s = 1"; write == to compare), several comma-separated expressions, an empty text;
  ///  - std::invalid_argument when the names themselves are unusable: check_name() fails for
  ///    one, or a name is given twice. Callers that take names from users call check_name()
  ///    first, to say which name is wrong where the user wrote it.
  Expression(std::string text, std::vector<std::string> variables,
             std::vector<NamedValue> constants);
  ~Expression();
  Expression(const Expression&) = default;
  Expression& operator=(const Expression&) = default;

  const std::string& text() const noexcept;
  const std::vector<std::string>& variables() const noexcept;
  const std::vector<NamedValue>& constants() const noexcept;
  /// Whether the text reads `name` (a variable or a constant).
  bool uses(std::string_view name) const;

  /// The value at one point; `point.size() == variables().size()`. Thread-safe.
  double operator()(std::span<const double> point) const;
  /// The values at `out.size()` points stored one after another (point m is
  /// points[m d .. m d + d - 1], d = variables().size()); `points.size() == out.size() * d`.
  /// Thread-safe; out[m] is exactly operator()(point m).
  void evaluate(std::span<const double> points, std::span<double> out) const;

  /// "" when `name` can name a variable or a constant; otherwise why not ("is the function
  /// sin", "is not a name: ..."). A name is a letter or _ followed by letters, digits and _, at
  /// most 100 characters, and not a function's name.
  static std::string check_name(std::string_view name);
  /// Every function the syntax has, sorted by name.
  static const std::vector<ExpressionFunction>& functions();

  struct Definition;

 private:
  std::shared_ptr<const Definition> definition_;
};

}  // namespace rkhs
