// Expressions (rkhs/core/expression.hpp): values against the same formulas in C++, names and
// constants, several variables, every kind of mistake with its position, what was found and
// what was expected, and evaluation from several threads at once.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <thread>
#include <vector>

#include "rkhs/core/expression.hpp"

using namespace rkhs;

namespace {

// The error `text` gives with the variable s and the constants L = 10 and a = 2.
ExpressionError error_of(const std::string& text) {
  try {
    Expression(text, {"s"}, {{"L", 10.0}, {"a", 2.0}});
  } catch (const ExpressionError& e) {
    return e;
  }
  FAIL("no error for \"" << text << "\"");
  throw std::logic_error("unreachable");
}

}  // namespace

TEST_CASE("an expression of s takes its values as C++ computes the same formula", "[expression]") {
  const Expression f("a * sin(2 * pi * s / L) + b * s^2 - exp(-s) / 3", {"s"},
                     {{"L", 7.5}, {"pi", std::numbers::pi}, {"a", 2.0}, {"b", -0.25}});
  for (double s : {0.0, 0.3, 1.0, 3.75, 7.4}) {
    INFO("s = " << s);
    const double expected =
        2.0 * std::sin(2 * std::numbers::pi * s / 7.5) - 0.25 * s * s - std::exp(-s) / 3;
    CHECK(f(std::span<const double>(&s, 1)) == Approx(expected).epsilon(1e-15).margin(1e-15));
  }
  // evaluate() gives exactly what the point form gives.
  const std::vector<double> points{0.1, 0.2, 5.0, 6.5};
  std::vector<double> values(points.size());
  f.evaluate(points, values);
  for (std::size_t m = 0; m < points.size(); ++m)
    CHECK(values[m] == f(std::span<const double>(&points[m], 1)));
  CHECK(f.text() == "a * sin(2 * pi * s / L) + b * s^2 - exp(-s) / 3");
}

TEST_CASE("operators, comparisons, conditionals and functions follow muparser's syntax",
          "[expression]") {
  const auto at = [](const std::string& text, double s) {
    return Expression(text, {"s"}, {})(std::span<const double>(&s, 1));
  };
  CHECK(at("2^3^2", 0) == 512);  // ^ is right-associative
  CHECK(at("-2^2", 0) == -4);    // unary minus binds weaker than ^
  CHECK(at("s > 1 ? 5 : 7", 2) == 5);
  CHECK(at("s > 1 ? 5 : 7", 0) == 7);
  CHECK(at("(s >= 1) && (s != 3)", 2) == 1);
  CHECK(at("abs(s) + sign(s) + sqrt(4) + ln(exp(1)) + log10(100) + log2(8)", -3) ==
        3 - 1 + 2 + 1 + 2 + 3);
  CHECK(at("atan2(1, 1)", 0) == Approx(std::numbers::pi / 4).epsilon(1e-15));
  CHECK(at("min(s, 2, 3) + max(s, 2) + sum(1, 2, 3) + avg(2, 4)", 1) == 1 + 2 + 6 + 3);
  // IEEE arithmetic, no exceptions: the owner checks for values that are not finite.
  CHECK(std::isnan(at("log(s)", -1)));
  CHECK(std::isinf(at("1 / s", 0)));
}

TEST_CASE("an expression of several variables reads each point's coordinates in order",
          "[expression]") {
  // The form a d-dimensional target would use: variables x1 .. xd.
  const Expression f("x1 * x2 - x3 / c", {"x1", "x2", "x3"}, {{"c", 4.0}});
  const std::vector<double> points{1, 2, 3, 4, 5, 6};  // two points of three coordinates
  std::vector<double> values(2);
  f.evaluate(points, values);
  CHECK(values[0] == 1.0 * 2.0 - 3.0 / 4.0);
  CHECK(values[1] == 4.0 * 5.0 - 6.0 / 4.0);
  CHECK_THROWS_AS(f(std::span<const double>(points.data(), 2)), std::invalid_argument);
  std::vector<double> wrong(3);
  CHECK_THROWS_AS(f.evaluate(points, wrong), std::invalid_argument);
}

TEST_CASE("an expression knows which names it reads", "[expression]") {
  const Expression f("a * s + L", {"s", "t"}, {{"L", 1.0}, {"a", 2.0}, {"b", 3.0}});
  CHECK(f.uses("a"));
  CHECK(f.uses("s"));
  CHECK(f.uses("L"));
  CHECK_FALSE(f.uses("b"));
  CHECK_FALSE(f.uses("t"));
  CHECK_FALSE(f.uses("sin"));
}

TEST_CASE("names: letters, digits and _, not a function, not given twice", "[expression]") {
  CHECK(Expression::check_name("a") == "");
  CHECK(Expression::check_name("_k2") == "");
  CHECK(Expression::check_name("sin") == "is the function sin");
  CHECK(Expression::check_name("2a").starts_with("is not a name"));
  CHECK(Expression::check_name("a-b").starts_with("is not a name"));
  CHECK(Expression::check_name("").starts_with("is empty"));
  CHECK(Expression::check_name(std::string(101, 'a')) == "is longer than 100 characters");
  CHECK_THROWS_WITH(Expression("s", {"s"}, {{"s", 1.0}}), "the name \"s\" is given twice");
  CHECK_THROWS_WITH(Expression("s", {"s"}, {{"cos", 1.0}}), "the name \"cos\" is the function cos");
  // muparser's own constants are not there: every name is the owner's.
  CHECK(error_of("_pi * s").found() == "the unknown name \"_pi\"");
  const auto& functions = Expression::functions();
  REQUIRE(functions.size() == 26);
  CHECK(functions.front().name == "abs");
  CHECK(std::find_if(functions.begin(), functions.end(), [](const auto& f) {
          return f.name == "atan2" && f.arguments == 2;
        }) != functions.end());
  CHECK(std::find_if(functions.begin(), functions.end(), [](const auto& f) {
          return f.name == "max" && f.arguments == -1;
        }) != functions.end());
}

TEST_CASE("a mistake in an expression names its position, what was found and what was expected",
          "[expression]") {
  struct Case {
    std::string text;
    std::size_t position;
    std::string found, expected;
  };
  const std::vector<Case> cases{
      {"2 * sin(2 * a * s / L", 21, "the end of the expression", "\")\""},
      {"2 * sn(s)", 4, "the unknown function \"sn\"", ""},
      {"2 * b * s", 4, "the unknown name \"b\"", "a variable or constant (s, L, a) or a function"},
      {"2 * * s", 4, "the operator \"*\"", ""},
      {"s +", 3, "the end of the expression", ""},
      {"3 s", 2, "the name \"s\"", "an operator before it (write 2 * s, not 2 s)"},
      {"3 2", 2, "the number \"2\"", "an operator before it (write 2 * s, not 2 s)"},
      {"s)", 1, "\")\"", "a value before it, or a \"(\" that it closes"},
      {"sin(s, 2)", 8, "too many arguments for sin", "1 argument"},
      {"atan2(s)", 7, "too few arguments for atan2", "2 arguments"},
      {"min()", 5, "too few arguments for min", "one or more"},
      {"s ? 1", 5, "\"?\" without its \":\"", "condition ? value : other value"},
      {"s = 3", 2, "\"=\" (an assignment)", "an expression: compare with =="},
      {"1, 2", 1, "2 expressions separated by commas", ""},
      {"", 0, "an empty expression", "an expression"},
      {"s # 2", 2, "\"#\"", "an operator, a number, a name or a parenthesis"},
      {"1e400 * s", 0, "the malformed or out-of-range number \"1e400\"", ""},
  };
  for (const auto& c : cases) {
    INFO("\"" << c.text << "\"");
    const auto e = error_of(c.text);
    CHECK(e.text() == c.text);
    CHECK(e.position() == c.position);
    CHECK(e.found() == c.found);
    if (!c.expected.empty()) CHECK(e.expected() == c.expected);
  }
  // The message says it all in one line.
  CHECK(std::string(error_of("2 * sin(2 * a * s / L").what()) ==
        "at the end of \"2 * sin(2 * a * s / L\": found the end of the expression, expected \")\"");
  CHECK(std::string(error_of("2 * * s").what()) ==
        "at character 5 of \"2 * * s\": found the operator \"*\", expected a value: a number, a "
        "variable, a constant, a function call or \"(\"");
  // A misspelt function or constant is guessed, a one-letter name is not.
  CHECK_THAT(error_of("2 * sn(s)").expected(), Catch::EndsWith("did you mean \"sin\"?"));
  // sign, sin and sinh are each one edit from sinn: sin is sinn with a letter left out.
  CHECK_THAT(error_of("2 * sinn(s)").expected(), Catch::EndsWith("did you mean \"sin\"?"));
  CHECK_THAT(error_of("2 * sqr(s)").expected(), Catch::EndsWith("did you mean \"sqrt\"?"));
  CHECK_THAT(error_of("b * s").expected(), !Catch::Contains("did you mean"));
  CHECK(error_of("b * s").unknown_name() == "b");
  CHECK(error_of("sn(s)").unknown_name() == "");  // a function, not a name to define
  // Comparisons are not assignments.
  CHECK_NOTHROW(Expression("(s == 1) + (s <= 1) + (s >= 1) + (s != 1)", {"s"}, {}));
}

// Issue 50: a 10 MB expression was echoed whole, twice, in an 20 MB message.
TEST_CASE("a long expression is quoted around the mistake, with its length", "[expression]") {
  std::string huge;
  for (int i = 0; i < 5'000'000; ++i) huge += "s+";
  huge += "s";
  const std::string message = error_of(huge).what();
  CHECK(message.size() < 300);
  CHECK_THAT(message, Catch::StartsWith("at character 1 of \"s+s+s+") &&
                          Catch::Contains("...\" (10000001 characters): found an expression of "
                                          "10000001 characters, expected fewer than 20000"));
  // Within muparser's length: the part around the position.
  const std::string deep = error_of(std::string(9000, '(') + "s" + std::string(8999, ')')).what();
  CHECK(deep.size() < 300);
  CHECK_THAT(deep, Catch::StartsWith("at the end of \"...))))") &&
                       Catch::Contains("\" (18000 characters): found the end of the expression"));
}

TEST_CASE("threads evaluating one expression at once get the values one thread gets",
          "[expression][threads]") {
  const Expression f("a * sin(k * s) + cos(s / 3) * s^2 / (1 + s)", {"s"},
                     {{"a", 1.5}, {"k", 3.0}});
  const Expression g("exp(-s) * a", {"s"}, {{"a", 2.0}});
  constexpr std::size_t count = 20000;
  std::vector<double> points(count);
  for (std::size_t m = 0; m < count; ++m) points[m] = 0.001 * static_cast<double>(m);
  std::vector<double> serial_f(count), serial_g(count);
  f.evaluate(points, serial_f);
  g.evaluate(points, serial_g);

  constexpr int thread_count = 8;
  std::vector<std::vector<double>> results_f(thread_count, std::vector<double>(count)),
      results_g(thread_count, std::vector<double>(count));
  std::vector<std::thread> threads;
  for (int t = 0; t < thread_count; ++t)
    threads.emplace_back([&, t] {
      // Interleaved, point by point and in blocks, two expressions and a copy of one: every
      // thread's own compiled copies, never another's.
      const Expression copy = f;
      for (std::size_t m = 0; m < count; ++m) {
        const double s = points[m];
        results_g[t][m] = g(std::span<const double>(&s, 1));
        if (m % 2) results_f[t][m] = copy(std::span<const double>(&s, 1));
      }
      for (std::size_t m = 0; m < count; m += 2)
        f.evaluate(std::span<const double>(&points[m], 1), std::span<double>(&results_f[t][m], 1));
    });
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < thread_count; ++t) {
    INFO("thread " << t);
    CHECK(results_f[t] == serial_f);
    CHECK(results_g[t] == serial_g);
  }
}

TEST_CASE("a thread alternating between more expressions than it keeps compiled stays exact",
          "[expression]") {
  // 12 expressions (the per-thread cache keeps 8): each keeps its own constants.
  std::vector<Expression> expressions;
  for (int k = 0; k < 12; ++k)
    expressions.emplace_back("k * s + 1", std::vector<std::string>{"s"},
                             std::vector<NamedValue>{{"k", static_cast<double>(k)}});
  for (int round = 0; round < 3; ++round)
    for (int k = 0; k < 12; ++k) {
      const double s = 0.5 + round;
      CHECK(expressions[static_cast<std::size_t>(k)](std::span<const double>(&s, 1)) == k * s + 1);
    }
  // An expression made after another was destroyed is never taken for it.
  for (int k = 0; k < 20; ++k) {
    const Expression e("s + c", {"s"}, {{"c", static_cast<double>(k)}});
    const double s = 1;
    CHECK(e(std::span<const double>(&s, 1)) == 1 + k);
  }
}
