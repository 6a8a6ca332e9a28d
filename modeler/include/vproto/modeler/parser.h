#pragma once
// Recursive-descent parser of the feature-script language (spec "Values and
// expressions", "Solids", "Bodies", "Holding, driving and loading").

#include <string>
#include <string_view>

#include "vproto/modeler/ast.h"

namespace vproto::modeler {

/// Parses a whole script. Throws InputError at the first syntax error, naming what was
/// expected. Nesting deeper than kMaxNesting is an error, never a stack overflow.
Program parse_program(std::string_view source, const std::string& filename);

/// Parses one expression (for `--set NAME=EXPR`); `filename` names the origin in errors.
ExprPtr parse_expression(std::string_view source, const std::string& filename);

inline constexpr int kMaxNesting = 200;
/// Most operators one expression chain may hold (a + b + c ... nests to the left).
inline constexpr int kMaxExpressionDepth = 2000;

/// The scene statements (contextual words, not reserved).
bool is_scene_keyword(std::string_view word);

}  // namespace vproto::modeler
