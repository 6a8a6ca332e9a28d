#pragma once
// Tokens of the feature-script language (spec "Lexical rules").

#include <string>
#include <string_view>
#include <vector>

#include "vproto/materials/errors.h"

namespace vproto::modeler {

enum class TokenKind {
  kEnd,
  kIdentifier,
  kKeyword,
  kNumber,  ///< `number` holds the value as written, `text` the unit ("" when bare)
  kString,  ///< `text` holds the unescaped contents
  kPunct,   ///< `text` holds the operator or punctuation: ( ) [ ] { } , ; : ? = + - * / % ^
            ///< == != < <= > >= && || !
};

struct Token {
  TokenKind kind = TokenKind::kEnd;
  std::string text;
  double number = 0;
  SourceLoc loc;

  bool is(TokenKind k, std::string_view t) const { return kind == k && text == t; }
  bool is_punct(std::string_view t) const { return is(TokenKind::kPunct, t); }
  bool is_keyword(std::string_view t) const { return is(TokenKind::kKeyword, t); }
};

/// Splits `source` into tokens (ending with a kEnd token). Throws InputError with the
/// place of the first bad character, unterminated string or comment, or unknown unit.
std::vector<Token> tokenize(std::string_view source, const std::string& filename);

/// The reserved words.
bool is_keyword(std::string_view word);

}  // namespace vproto::modeler
