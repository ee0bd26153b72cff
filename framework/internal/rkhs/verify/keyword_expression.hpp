#pragma once
// `rkhs-study check -k EXPRESSION`: which test cases (expectation and group) to judge, in the
// syntax of pytest's -k (docs/verification.md):
//
//   expression := or_expr?
//   or_expr    := and_expr ("or" and_expr)*
//   and_expr   := not_expr ("and" not_expr)*
//   not_expr   := "not" not_expr | "(" or_expr ")" | identifier
//
// An identifier is a run of letters, digits and the characters _ : + - . [ ] \ / = (pytest's,
// with '=' for selectors such as degree=2); it matches a test case when it is a
// case-insensitive substring of one of the case's keywords (its name, metric, study, ...). The
// words and, or, not are operators, never identifiers. The empty expression matches every case.

#include <string>
#include <string_view>
#include <vector>

namespace rkhs {

class KeywordExpression {
 public:
  /// Parses `text`. Throws std::invalid_argument naming the expression, the 1-based column,
  /// what was expected and what was found ("-k 'power and': at column 10: expected an
  /// identifier, 'not' or '(', found the end of the expression").
  /// 'not' and parentheses nest at most max_depth deep ("-k '((((a': at column 201: 'not' and '('
  /// nested more than 200 deep"), so that parsing and matching never overflow the stack; a
  /// long expression is quoted in messages by its part around the column.
  static KeywordExpression parse(std::string_view text);

  /// How deep 'not' and '(' may nest.
  static constexpr int max_depth = 200;

  /// Whether a test case with these keywords is selected.
  bool matches(const std::vector<std::string>& keywords) const;

  /// The expression as given.
  const std::string& text() const noexcept { return text_; }

 private:
  enum class Op { identifier, not_, and_, or_ };
  struct Node {
    Op op = Op::identifier;
    std::string identifier;  ///< lower case (identifier only)
    int left = -1, right = -1;
  };
  bool evaluate(int node, const std::vector<std::string>& keywords) const;

  std::string text_;
  std::vector<Node> nodes_;
  int root_ = -1;  ///< -1: the empty expression
  class Parser;
};

}  // namespace rkhs
