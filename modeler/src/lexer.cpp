#include "vproto/modeler/lexer.h"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include "vproto/materials/units.h"

namespace vproto::modeler {
namespace {

constexpr std::array<std::string_view, 14> kKeywords = {
    "let",   "param", "module", "for",      "if",    "else",    "true",
    "false", "units", "facets", "material", "rigid", "elastic", "body"};

bool ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }
bool digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

class Lexer {
 public:
  Lexer(std::string_view src, const std::string& file) : src_(src), file_(file) {}

  std::vector<Token> run() {
    std::vector<Token> out;
    while (true) {
      skip_space_and_comments();
      Token t;
      t.loc = here();
      if (pos_ >= src_.size()) {
        out.push_back(t);
        return out;
      }
      const char c = src_[pos_];
      if (digit(c) || (c == '.' && pos_ + 1 < src_.size() && digit(src_[pos_ + 1]))) {
        lex_number(t);
      } else if (ident_start(c)) {
        const std::size_t start = pos_;
        while (pos_ < src_.size() && ident_char(src_[pos_])) advance();
        t.text = std::string(src_.substr(start, pos_ - start));
        t.kind = is_keyword(t.text) ? TokenKind::kKeyword : TokenKind::kIdentifier;
      } else if (c == '"') {
        lex_string(t);
      } else {
        lex_punct(t);
      }
      out.push_back(std::move(t));
    }
  }

 private:
  SourceLoc here() const { return {file_, line_, column_}; }

  void advance() {
    if (src_[pos_] == '\n') {
      ++line_;
      column_ = 1;
    } else if ((static_cast<unsigned char>(src_[pos_]) & 0xC0) != 0x80) {
      ++column_;  // count UTF-8 code points, not bytes
    }
    ++pos_;
  }

  [[noreturn]] void fail(const SourceLoc& loc, const std::string& msg) const {
    throw InputError(loc, msg);
  }

  void skip_space_and_comments() {
    while (pos_ < src_.size()) {
      const char c = src_[pos_];
      if (std::isspace(static_cast<unsigned char>(c))) {
        advance();
      } else if (c == '/' && pos_ + 1 < src_.size() && src_[pos_ + 1] == '/') {
        while (pos_ < src_.size() && src_[pos_] != '\n') advance();
      } else if (c == '/' && pos_ + 1 < src_.size() && src_[pos_ + 1] == '*') {
        const SourceLoc start = here();
        advance();
        advance();
        while (pos_ + 1 < src_.size() && !(src_[pos_] == '*' && src_[pos_ + 1] == '/')) advance();
        if (pos_ + 1 >= src_.size()) fail(start, "unterminated comment: expected '*/'");
        advance();
        advance();
      } else {
        return;
      }
    }
  }

  void lex_number(Token& t) {
    const std::size_t start = pos_;
    while (pos_ < src_.size() && digit(src_[pos_])) advance();
    if (pos_ < src_.size() && src_[pos_] == '.') {
      advance();
      while (pos_ < src_.size() && digit(src_[pos_])) advance();
    }
    // exponent only when digits follow: `1e-3`, but `2em` is not a number
    if (pos_ < src_.size() && (src_[pos_] == 'e' || src_[pos_] == 'E')) {
      std::size_t k = pos_ + 1;
      if (k < src_.size() && (src_[k] == '+' || src_[k] == '-')) ++k;
      if (k < src_.size() && digit(src_[k])) {
        while (pos_ < k) advance();
        while (pos_ < src_.size() && digit(src_[pos_])) advance();
      }
    }
    const std::string text(src_.substr(start, pos_ - start));
    t.kind = TokenKind::kNumber;
    t.number = std::strtod(text.c_str(), nullptr);
    if (!std::isfinite(t.number)) fail(t.loc, "number '" + text + "' is out of range");
    if (pos_ < src_.size() && ident_start(src_[pos_])) t.text = lex_unit();
  }

  // A unit written right after a number: NAME(^INT)? (('*'|'/') NAME(^INT)?)*. A '*' or
  // '/' continues the unit only when a known unit name follows it, so `60deg*k` is
  // 60 degrees times k.
  std::string lex_unit() {
    const SourceLoc loc = here();
    std::string unit;
    auto read_name = [&]() {
      const std::size_t s = pos_;
      while (pos_ < src_.size() && ident_char(src_[pos_])) advance();
      return std::string(src_.substr(s, pos_ - s));
    };
    auto read_power = [&]() {
      if (pos_ < src_.size() && src_[pos_] == '^') {
        std::size_t k = pos_ + 1;
        if (k < src_.size() && src_[k] == '-') ++k;
        if (k < src_.size() && digit(src_[k])) {
          std::string p;
          while (pos_ < k) p += src_[pos_], advance();
          while (pos_ < src_.size() && digit(src_[pos_])) p += src_[pos_], advance();
          return p;
        }
      }
      return std::string();
    };
    const std::string first = read_name();
    if (!units::find_unit(first))
      fail(loc, "unknown unit '" + first +
                    "': expected one of m cm mm um in ft kg g lb s ms us N kN lbf Pa kPa MPa "
                    "GPa psi ksi deg rad");
    unit = first + read_power();
    while (pos_ + 1 < src_.size() && (src_[pos_] == '*' || src_[pos_] == '/') &&
           ident_start(src_[pos_ + 1])) {
      std::size_t k = pos_ + 1;
      while (k < src_.size() && ident_char(src_[k])) ++k;
      if (!units::find_unit(src_.substr(pos_ + 1, k - pos_ - 1))) break;
      unit += src_[pos_];
      advance();
      unit += read_name();
      unit += read_power();
    }
    return unit;
  }

  void lex_string(Token& t) {
    advance();
    t.kind = TokenKind::kString;
    while (true) {
      if (pos_ >= src_.size() || src_[pos_] == '\n')
        fail(t.loc, "unterminated string: expected a closing '\"'");
      const char c = src_[pos_];
      if (c == '"') {
        advance();
        return;
      }
      if (c == '\\') {
        const SourceLoc esc = here();
        advance();
        if (pos_ >= src_.size() || (src_[pos_] != '"' && src_[pos_] != '\\'))
          fail(esc, "unknown escape in string: expected \\\" or \\\\");
      }
      t.text += src_[pos_];
      advance();
    }
  }

  void lex_punct(Token& t) {
    static constexpr std::array<std::string_view, 8> kTwo = {"==", "!=", "<=", ">=", "&&", "||"};
    t.kind = TokenKind::kPunct;
    if (pos_ + 1 < src_.size()) {
      const std::string_view two = src_.substr(pos_, 2);
      for (auto op : kTwo) {
        if (!op.empty() && op == two) {
          t.text = std::string(two);
          advance();
          advance();
          return;
        }
      }
    }
    const char c = src_[pos_];
    static constexpr std::string_view kOne = "()[]{},;:?=+-*/%^<>!";
    if (kOne.find(c) == std::string_view::npos) {
      std::string shown(1, c);
      if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) >= 127)
        shown = "byte " + std::to_string(static_cast<unsigned char>(c));
      fail(t.loc, "unexpected character '" + shown + "'");
    }
    t.text = std::string(1, c);
    advance();
  }

  std::string_view src_;
  std::string file_;
  std::size_t pos_ = 0;
  int line_ = 1;
  int column_ = 1;
};

}  // namespace

bool is_keyword(std::string_view word) {
  for (auto k : kKeywords)
    if (k == word) return true;
  return false;
}

std::vector<Token> tokenize(std::string_view source, const std::string& filename) {
  return Lexer(source, filename).run();
}

}  // namespace vproto::modeler
