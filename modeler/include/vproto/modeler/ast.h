#pragma once
// The syntax tree of a feature script, as the parser builds it.

#include <memory>
#include <string>
#include <vector>

#include "vproto/materials/errors.h"

namespace vproto::modeler {

struct Expr;
using ExprPtr = std::unique_ptr<Expr>;

/// An argument `value` or `name = value` (name empty when positional).
struct Arg {
  std::string name;
  SourceLoc loc;
  ExprPtr value;
};

struct Expr {
  enum class Kind {
    kNumber,         ///< number, text = unit ("" when bare)
    kString,         ///< text
    kBool,           ///< boolean
    kIdent,          ///< text = name
    kVector,         ///< items
    kRange,          ///< items = start, end or start, step, end
    kComprehension,  ///< text = variable, items = {range, body}
    kUnary,          ///< text = operator, items = {operand}
    kBinary,         ///< text = operator, items = {lhs, rhs}
    kTernary,        ///< items = {cond, then, else}
    kIndex,          ///< items = {value, index}
    kCall,           ///< text = function, args
  };
  Kind kind = Kind::kNumber;
  SourceLoc loc;
  double number = 0;
  bool boolean = false;
  std::string text;
  std::vector<ExprPtr> items;
  std::vector<Arg> args;
};

struct Stmt {
  enum class Kind {
    kLet,       ///< name, value
    kParam,     ///< name, value
    kUnits,     ///< args: quantity = unit name (an identifier expression)
    kFacets,    ///< value
    kMaterial,  ///< name, args: property = value
    kModule,    ///< name, args: parameters (value = default or null), children
    kBody,      ///< subkind = rigid|elastic, name, args = attributes, children
    kCall,      ///< name, args, children (the statement or block a transform applies to)
    kFor,       ///< name = variable, value = range or vector, children = {body}
    kIf,        ///< value = condition, children = then, else_children
    kBlock,     ///< children
    kScene,     ///< name = keyword, idents, value = positional expression or null, args
    kEmpty,     ///< a lone ';'
  };
  Kind kind = Kind::kEmpty;
  SourceLoc loc;
  std::string name;
  std::string subkind;
  ExprPtr value;
  std::vector<Arg> args;
  std::vector<std::string> idents;
  std::vector<SourceLoc> ident_locs;
  std::vector<Stmt> children;
  std::vector<Stmt> else_children;
};

/// A parsed script.
struct Program {
  std::string filename;
  std::vector<Stmt> statements;
};

}  // namespace vproto::modeler
