#include "rkhs/verify/keyword_expression.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "rkhs/core/printable.hpp"

namespace rkhs {

namespace {

bool identifier_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':' || c == '+' ||
         c == '-' || c == '.' || c == '[' || c == ']' || c == '\\' || c == '/' || c == '=';
}

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

enum class Token { identifier, left, right, and_, or_, not_, end };

}  // namespace

// Recursive descent over the grammar of the header, one token of look-ahead.
class KeywordExpression::Parser {
 public:
  Parser(std::string_view text, KeywordExpression& out) : text_(text), out_(out) { advance(); }

  void parse() {
    if (token_ != Token::end) out_.root_ = or_expression();
    if (token_ != Token::end) error("'and', 'or' or the end of the expression");
  }

 private:
  int or_expression() {
    int left = and_expression();
    while (token_ == Token::or_) {
      advance();
      left = add({Op::or_, {}, left, and_expression()});
    }
    return left;
  }

  int and_expression() {
    int left = not_expression();
    while (token_ == Token::and_) {
      advance();
      left = add({Op::and_, {}, left, not_expression()});
    }
    return left;
  }

  int not_expression() {
    if (token_ == Token::not_ || token_ == Token::left) {
      // The recursion's only way deeper: bounded, so that no expression overflows the stack.
      if (++depth_ > KeywordExpression::max_depth)
        throw std::invalid_argument(
            fmt::format("-k '{}': at column {}: 'not' and '(' nested more than {} deep", shown(),
                        start_ + 1, KeywordExpression::max_depth));
      struct Leave {
        int& depth;
        ~Leave() { --depth; }
      } leave{depth_};
      if (token_ == Token::not_) {
        advance();
        return add({Op::not_, {}, not_expression(), -1});
      }
      advance();
      const int inner = or_expression();
      if (token_ != Token::right) error("')'");
      advance();
      return inner;
    }
    if (token_ != Token::identifier) error("an identifier, 'not' or '('");
    const int node = add({Op::identifier, lower(word_), -1, -1});
    advance();
    return node;
  }

  int add(Node node) {
    out_.nodes_.push_back(std::move(node));
    return static_cast<int>(out_.nodes_.size()) - 1;
  }

  void advance() {
    while (position_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[position_])))
      ++position_;
    start_ = position_;
    word_.clear();
    if (position_ == text_.size()) {
      token_ = Token::end;
      return;
    }
    const char c = text_[position_];
    if (c == '(' || c == ')') {
      ++position_;
      token_ = c == '(' ? Token::left : Token::right;
      return;
    }
    if (!identifier_char(c)) {
      throw std::invalid_argument(fmt::format(
          "-k '{}': at column {}: unexpected character '{}' (an identifier has letters, digits "
          "and _ : + - . [ ] \\ / =; the operators are and, or, not and parentheses)",
          shown(), start_ + 1, printable(std::string_view(&c, 1))));
    }
    while (position_ < text_.size() && identifier_char(text_[position_])) ++position_;
    word_ = std::string(text_.substr(start_, position_ - start_));
    token_ = word_ == "and"   ? Token::and_
             : word_ == "or"  ? Token::or_
             : word_ == "not" ? Token::not_
                              : Token::identifier;
  }

  [[noreturn]] void error(std::string_view expected) const {
    const std::string found = token_ == Token::end ? std::string("the end of the expression")
                              : token_ == Token::left || token_ == Token::right
                                  ? fmt::format("'{}'", text_[start_])
                                  : fmt::format("'{}'", word_);
    throw std::invalid_argument(fmt::format("-k '{}': at column {}: expected {}, found {}", shown(),
                                            start_ + 1, expected, shortened(found, 80)));
  }

  // The expression as messages quote it: around the column they name when it is long.
  std::string shown() const { return printable(excerpt(text_, start_, 60)); }

  std::string_view text_;
  KeywordExpression& out_;
  std::size_t position_ = 0, start_ = 0;
  int depth_ = 0;
  Token token_ = Token::end;
  std::string word_;
};

KeywordExpression KeywordExpression::parse(std::string_view text) {
  KeywordExpression expression;
  expression.text_ = std::string(text);
  Parser(expression.text_, expression).parse();
  return expression;
}

bool KeywordExpression::matches(const std::vector<std::string>& keywords) const {
  if (root_ < 0) return true;
  std::vector<std::string> lowered;
  lowered.reserve(keywords.size());
  for (const auto& keyword : keywords) lowered.push_back(lower(keyword));
  return evaluate(root_, lowered);
}

bool KeywordExpression::evaluate(int index, const std::vector<std::string>& keywords) const {
  const auto& node = nodes_[static_cast<std::size_t>(index)];
  switch (node.op) {
    case Op::identifier:
      return std::any_of(keywords.begin(), keywords.end(), [&](const std::string& keyword) {
        return keyword.find(node.identifier) != std::string::npos;
      });
    case Op::not_:
      return !evaluate(node.left, keywords);
    case Op::and_:
    case Op::or_: {
      // A chain "a or b or c ..." is a left spine as long as the chain: walked in a loop, so
      // that recursion goes only as deep as 'not' and parentheses nest (at most max_depth).
      const bool is_or = node.op == Op::or_;
      const Node* link = &node;
      while (link->op == node.op) {
        if (evaluate(link->right, keywords) == is_or) return is_or;
        link = &nodes_[static_cast<std::size_t>(link->left)];
      }
      return evaluate(static_cast<int>(link - nodes_.data()), keywords);
    }
  }
  return false;
}

}  // namespace rkhs
