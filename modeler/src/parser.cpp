#include "vproto/modeler/parser.h"

#include <array>

#include "vproto/modeler/lexer.h"

namespace vproto::modeler {
namespace {

constexpr std::array<std::string_view, 11> kSceneWords = {
    "fix",     "grip",     "joint",   "force",     "torque", "move",
    "gravity", "velocity", "contact", "nocontact", "probe"};
constexpr std::array<std::string_view, 3> kSettingWords = {"simulate", "render", "export"};

std::string describe(const Token& t) {
  switch (t.kind) {
    case TokenKind::kEnd:
      return "the end of the file";
    case TokenKind::kIdentifier:
      return "name '" + t.text + "'";
    case TokenKind::kKeyword:
      return "keyword '" + t.text + "'";
    case TokenKind::kNumber:
      return "a number";
    case TokenKind::kString:
      return "a string";
    case TokenKind::kPunct:
      return "'" + t.text + "'";
  }
  return "a token";
}

class Parser {
 public:
  Parser(std::vector<Token> tokens) : toks_(std::move(tokens)) {}

  std::vector<Stmt> statements_until_end() {
    std::vector<Stmt> out;
    while (peek().kind != TokenKind::kEnd) out.push_back(statement());
    return out;
  }

  ExprPtr whole_expression() {
    ExprPtr e = expression();
    if (peek().kind != TokenKind::kEnd) fail_expected("the end of the expression");
    return e;
  }

 private:
  // --- token helpers ---
  const Token& peek(std::size_t ahead = 0) const {
    const std::size_t i = std::min(pos_ + ahead, toks_.size() - 1);
    return toks_[i];
  }
  const Token& next() {
    const Token& t = toks_[pos_];
    if (pos_ + 1 < toks_.size()) ++pos_;
    return t;
  }
  bool accept_punct(std::string_view p) {
    if (!peek().is_punct(p)) return false;
    next();
    return true;
  }
  [[noreturn]] void fail_expected(const std::string& what) const {
    throw InputError(peek().loc, "expected " + what + ", got " + describe(peek()));
  }
  void expect_punct(std::string_view p, const std::string& context = "") {
    if (!accept_punct(p))
      fail_expected("'" + std::string(p) + "'" + (context.empty() ? "" : " " + context));
  }
  std::string expect_identifier(const std::string& what) {
    if (peek().kind == TokenKind::kKeyword)
      throw InputError(peek().loc, "expected " + what + ", got keyword '" + peek().text +
                                       "' (keywords are reserved; pick another name)");
    if (peek().kind != TokenKind::kIdentifier) fail_expected(what);
    return next().text;
  }

  // guards recursion so deeply nested input is an error, not a stack overflow
  struct Depth {
    Parser& p;
    explicit Depth(Parser& parser, const SourceLoc& loc) : p(parser) {
      if (++p.depth_ > kMaxNesting)
        throw InputError(loc, "nesting deeper than " + std::to_string(kMaxNesting) +
                                  " levels: simplify the expression or split the block");
    }
    ~Depth() { --p.depth_; }
  };

  // --- statements ---
  Stmt statement() {
    Depth guard(*this, peek().loc);
    const Token& t = peek();
    Stmt s;
    s.loc = t.loc;
    if (t.is_punct(";")) {
      next();
      return s;
    }
    if (t.is_punct("{")) {
      s.kind = Stmt::Kind::kBlock;
      s.children = block();
      return s;
    }
    if (t.kind == TokenKind::kKeyword) return keyword_statement();
    if (t.kind == TokenKind::kIdentifier) {
      if (is_scene_keyword(t.text) && (peek(1).kind == TokenKind::kIdentifier ||
                                       (t.text == "gravity" && peek(1).is_punct("[")) ||
                                       (t.text == "contact" && peek(1).is_punct(";"))))
        return scene_statement();
      for (auto w : kSettingWords)
        if (t.text == w && peek(1).is_punct("(")) return setting_statement();
      if (peek(1).is_punct("(")) return call_statement();
      if (peek(1).is_punct("="))
        throw InputError(t.loc, "expected a statement, got an assignment: write 'let " + t.text +
                                    " = ...;' to define a constant");
      fail_expected("a statement (a solid, a transform, a body or a scene statement)");
    }
    fail_expected("a statement");
  }

  std::vector<Stmt> block() {
    const SourceLoc open = peek().loc;
    expect_punct("{");
    std::vector<Stmt> out;
    while (!peek().is_punct("}")) {
      if (peek().kind == TokenKind::kEnd)
        throw InputError(open, "unclosed '{': expected '}' before the end of the file");
      out.push_back(statement());
    }
    next();
    return out;
  }

  // the statement or block a transform, loop or condition applies to
  std::vector<Stmt> child_statement() {
    if (peek().is_punct("{")) return block();
    std::vector<Stmt> out;
    out.push_back(statement());
    return out;
  }

  Stmt keyword_statement() {
    const Token t = next();
    Stmt s;
    s.loc = t.loc;
    if (t.text == "let" || t.text == "param") {
      s.kind = t.text == "let" ? Stmt::Kind::kLet : Stmt::Kind::kParam;
      s.name = expect_identifier("a name after '" + t.text + "'");
      expect_punct("=", "after the name");
      s.value = expression();
      expect_punct(";", "after the value");
      return s;
    }
    if (t.text == "units") {
      s.kind = Stmt::Kind::kUnits;
      while (!accept_punct(";")) {
        Arg a;
        a.loc = peek().loc;
        a.name = expect_identifier("a quantity (length, mass, time, force, pressure, angle)");
        expect_punct("=", "after '" + a.name + "'");
        auto unit = std::make_unique<Expr>();
        unit->kind = Expr::Kind::kIdent;
        unit->loc = peek().loc;
        unit->text = expect_identifier("a unit name such as in, mm, lbf, psi, deg");
        a.value = std::move(unit);
        s.args.push_back(std::move(a));
        accept_punct(",");
      }
      return s;
    }
    if (t.text == "facets") {
      s.kind = Stmt::Kind::kFacets;
      s.value = expression();
      expect_punct(";", "after the facet count");
      return s;
    }
    if (t.text == "material") {
      s.kind = Stmt::Kind::kMaterial;
      s.name = expect_identifier("a material name");
      const SourceLoc open = peek().loc;
      expect_punct("{", "to open the material's properties");
      while (!accept_punct("}")) {
        if (peek().kind == TokenKind::kEnd)
          throw InputError(open, "unclosed '{': expected '}' before the end of the file");
        Arg a;
        a.loc = peek().loc;
        a.name = expect_identifier("a material property (E, nu, density, ...)");
        expect_punct("=", "after '" + a.name + "'");
        a.value = expression();
        expect_punct(";", "after the property value");
        s.args.push_back(std::move(a));
      }
      return s;
    }
    if (t.text == "module") {
      s.kind = Stmt::Kind::kModule;
      s.name = expect_identifier("a module name");
      expect_punct("(", "to open the parameter list");
      if (!peek().is_punct(")")) {
        do {
          Arg p;
          p.loc = peek().loc;
          p.name = expect_identifier("a parameter name");
          if (accept_punct("=")) p.value = expression();
          s.args.push_back(std::move(p));
        } while (accept_punct(","));
      }
      expect_punct(")", "to close the parameter list");
      s.children = child_statement();
      return s;
    }
    if (t.text == "rigid" || t.text == "elastic") {
      s.kind = Stmt::Kind::kBody;
      s.subkind = t.text;
      if (!peek().is_keyword("body")) fail_expected("'body' after '" + t.text + "'");
      next();
      s.name = expect_identifier("a body name");
      if (accept_punct("(")) {
        if (!peek().is_punct(")")) s.args = arguments(true);
        expect_punct(")", "to close the body's attributes");
      }
      if (!peek().is_punct("{")) fail_expected("'{' to open the body's solids");
      s.children = block();
      return s;
    }
    if (t.text == "for") {
      // for (i = A, j = B) S is for (i = A) for (j = B) S
      expect_punct("(", "after 'for'");
      std::vector<std::pair<std::string, ExprPtr>> loops;
      std::vector<SourceLoc> locs;
      do {
        locs.push_back(peek().loc);
        std::string var = expect_identifier("a loop variable");
        expect_punct("=", "after the loop variable");
        loops.emplace_back(std::move(var), expression());
      } while (accept_punct(","));
      expect_punct(")", "to close the loop header");
      std::vector<Stmt> body = child_statement();
      for (std::size_t k = loops.size(); k-- > 0;) {
        Stmt loop;
        loop.kind = Stmt::Kind::kFor;
        loop.loc = k == 0 ? t.loc : locs[k];
        loop.name = std::move(loops[k].first);
        loop.value = std::move(loops[k].second);
        loop.children = std::move(body);
        body.clear();
        body.push_back(std::move(loop));
      }
      return std::move(body.front());
    }
    if (t.text == "if") {
      s.kind = Stmt::Kind::kIf;
      expect_punct("(", "after 'if'");
      s.value = expression();
      expect_punct(")", "to close the condition");
      s.children = child_statement();
      if (peek().is_keyword("else")) {
        next();
        s.else_children = child_statement();
      }
      return s;
    }
    throw InputError(t.loc, "expected a statement, got keyword '" + t.text + "'");
  }

  Stmt call_statement() {
    Stmt s;
    s.kind = Stmt::Kind::kCall;
    s.loc = peek().loc;
    s.name = next().text;
    expect_punct("(");
    if (!peek().is_punct(")")) s.args = arguments(false);
    expect_punct(")", "to close the argument list of '" + s.name + "'");
    if (accept_punct(";")) return s;
    s.children = child_statement();
    return s;
  }

  Stmt setting_statement() {
    Stmt s;
    s.kind = Stmt::Kind::kScene;
    s.loc = peek().loc;
    s.name = next().text;
    expect_punct("(");
    if (!peek().is_punct(")")) s.args = arguments(true);
    expect_punct(")", "to close '" + s.name + "('");
    expect_punct(";", "after '" + s.name + "(...)'");
    return s;
  }

  Stmt scene_statement() {
    Stmt s;
    s.kind = Stmt::Kind::kScene;
    s.loc = peek().loc;
    s.name = next().text;
    auto take_ident = [&](const std::string& what) {
      s.ident_locs.push_back(peek().loc);
      s.idents.push_back(expect_identifier(what));
    };
    auto ident_not_named_arg = [&]() {
      return peek().kind == TokenKind::kIdentifier && !peek(1).is_punct("=");
    };
    const std::string& kw = s.name;
    if (kw == "joint") {
      take_ident("a joint type (slider, revolute, spherical, fixed)");
      take_ident("a body name");
      if (peek().is(TokenKind::kIdentifier, "to") && !peek(1).is_punct("=")) {
        take_ident("'to'");
        take_ident("a body name after 'to'");
      }
    } else if (kw == "nocontact" || kw == "probe") {
      take_ident(kw == "probe" ? "a probe name" : "a body name");
      take_ident("a body name");
    } else if (kw == "contact") {
      if (ident_not_named_arg()) {
        take_ident("a body name");
        take_ident("a second body name (contact settings name a pair)");
      }
    } else if (kw != "gravity") {
      take_ident("a body name");
    }
    if (kw == "force" || kw == "torque" || kw == "gravity") {
      if (!(peek().kind == TokenKind::kIdentifier && peek(1).is_punct("=")) &&
          !peek().is_punct(";"))
        s.value = expression();
    }
    while (!accept_punct(";")) {
      if (peek().kind != TokenKind::kIdentifier || !peek(1).is_punct("="))
        fail_expected("a setting 'name=value' or ';' to end the '" + kw + "' statement");
      Arg a;
      a.loc = peek().loc;
      a.name = next().text;
      next();
      a.value = expression();
      s.args.push_back(std::move(a));
      accept_punct(",");
    }
    return s;
  }

  // positional and named arguments; `named_only` for attribute lists
  std::vector<Arg> arguments(bool named_only) {
    std::vector<Arg> out;
    do {
      if (peek().is_punct(")")) break;  // trailing comma
      Arg a;
      a.loc = peek().loc;
      // a keyword may name a setting: (material=steel)
      if ((peek().kind == TokenKind::kIdentifier || peek().kind == TokenKind::kKeyword) &&
          peek(1).is_punct("=")) {
        a.name = next().text;
        next();
      } else if (named_only) {
        fail_expected("a setting 'name=value'");
      }
      a.value = expression();
      out.push_back(std::move(a));
    } while (accept_punct(","));
    return out;
  }

  // --- expressions ---
  ExprPtr make(Expr::Kind kind, const SourceLoc& loc, std::string text = {}) {
    auto e = std::make_unique<Expr>();
    e->kind = kind;
    e->loc = loc;
    e->text = std::move(text);
    return e;
  }

  ExprPtr expression() {
    Depth guard(*this, peek().loc);
    ExprPtr cond = binary(0);
    if (peek().is_punct("?")) {
      const SourceLoc loc = next().loc;
      auto e = make(Expr::Kind::kTernary, loc);
      e->items.push_back(std::move(cond));
      e->items.push_back(expression());
      expect_punct(":", "in 'condition ? a : b'");
      e->items.push_back(expression());
      return e;
    }
    return cond;
  }

  static int precedence(const Token& t) {
    if (t.kind != TokenKind::kPunct) return -1;
    const std::string& o = t.text;
    if (o == "||") return 1;
    if (o == "&&") return 2;
    if (o == "==" || o == "!=") return 3;
    if (o == "<" || o == "<=" || o == ">" || o == ">=") return 4;
    if (o == "+" || o == "-") return 5;
    if (o == "*" || o == "/" || o == "%") return 6;
    return -1;
  }

  // precedence climbing over the left-associative binary operators
  ExprPtr binary(int min_prec) {
    ExprPtr lhs = unary();
    int chain = 0;
    while (true) {
      const int prec = precedence(peek());
      if (prec < 0 || prec < min_prec) break;
      const Token op = next();
      // a chain a + b + c ... nests to the left: bound its depth like any other nesting
      if (depth_ + ++chain > kMaxExpressionDepth)
        throw InputError(op.loc, "expression longer than " + std::to_string(kMaxExpressionDepth) +
                                     " operations: split it into several 'let' steps");
      Depth guard(*this, op.loc);
      ExprPtr rhs = binary(prec + 1);
      auto e = make(Expr::Kind::kBinary, op.loc, op.text);
      e->items.push_back(std::move(lhs));
      e->items.push_back(std::move(rhs));
      lhs = std::move(e);
    }
    return lhs;
  }

  ExprPtr unary() {
    if (peek().is_punct("-") || peek().is_punct("!") || peek().is_punct("+")) {
      const Token op = next();
      Depth guard(*this, op.loc);
      auto e = make(Expr::Kind::kUnary, op.loc, op.text);
      e->items.push_back(unary());
      return e;
    }
    return power();
  }

  // '^' is right-associative and binds tighter than unary minus: -2^2 = -4
  ExprPtr power() {
    ExprPtr base = postfix();
    if (peek().is_punct("^")) {
      const Token op = next();
      Depth guard(*this, op.loc);
      auto e = make(Expr::Kind::kBinary, op.loc, "^");
      e->items.push_back(std::move(base));
      e->items.push_back(unary());
      return e;
    }
    return base;
  }

  ExprPtr postfix() {
    ExprPtr e = primary();
    while (peek().is_punct("[")) {
      const SourceLoc loc = next().loc;
      auto idx = make(Expr::Kind::kIndex, loc);
      idx->items.push_back(std::move(e));
      idx->items.push_back(expression());
      expect_punct("]", "to close the index");
      e = std::move(idx);
    }
    return e;
  }

  ExprPtr primary() {
    const Token& t = peek();
    switch (t.kind) {
      case TokenKind::kNumber: {
        auto e = make(Expr::Kind::kNumber, t.loc, t.text);
        e->number = t.number;
        next();
        return e;
      }
      case TokenKind::kString: {
        auto e = make(Expr::Kind::kString, t.loc, t.text);
        next();
        return e;
      }
      case TokenKind::kKeyword:
        if (t.text == "true" || t.text == "false") {
          auto e = make(Expr::Kind::kBool, t.loc);
          e->boolean = t.text == "true";
          next();
          return e;
        }
        fail_expected("a value");
      case TokenKind::kIdentifier: {
        const Token id = next();
        if (peek().is_punct("(")) {
          next();
          auto e = make(Expr::Kind::kCall, id.loc, id.text);
          if (!peek().is_punct(")")) e->args = arguments(false);
          expect_punct(")", "to close the call of '" + id.text + "'");
          return e;
        }
        return make(Expr::Kind::kIdent, id.loc, id.text);
      }
      case TokenKind::kPunct:
        if (t.text == "(") {
          next();
          ExprPtr e = expression();
          expect_punct(")", "to close '('");
          return e;
        }
        if (t.text == "[") return bracket();
        break;
      case TokenKind::kEnd:
        break;
    }
    fail_expected("a value");
  }

  // [] vector, [a:b] or [a:s:b] range, [for (v = R) expr] comprehension
  ExprPtr bracket() {
    const SourceLoc loc = next().loc;
    if (peek().is_keyword("for")) return comprehension(loc, true);
    auto vec = make(Expr::Kind::kVector, loc);
    if (accept_punct("]")) return vec;
    ExprPtr first = expression();
    if (accept_punct(":")) {
      auto range = make(Expr::Kind::kRange, loc);
      range->items.push_back(std::move(first));
      range->items.push_back(expression());
      if (accept_punct(":")) range->items.push_back(expression());
      expect_punct("]", "to close the range");
      return range;
    }
    vec->items.push_back(std::move(first));
    while (accept_punct(",")) {
      if (peek().is_punct("]")) break;
      vec->items.push_back(expression());
    }
    expect_punct("]", "or ',' in the vector");
    return vec;
  }

  ExprPtr comprehension(const SourceLoc& loc, bool closing_bracket) {
    Depth guard(*this, loc);
    next();  // 'for'
    auto e = make(Expr::Kind::kComprehension, loc);
    expect_punct("(", "after 'for'");
    e->text = expect_identifier("a loop variable");
    expect_punct("=", "after the loop variable");
    e->items.push_back(expression());
    expect_punct(")", "to close the loop header");
    if (peek().is_keyword("for"))
      e->items.push_back(comprehension(peek().loc, false));
    else
      e->items.push_back(expression());
    if (closing_bracket) expect_punct("]", "to close the list comprehension");
    return e;
  }

  std::vector<Token> toks_;
  std::size_t pos_ = 0;
  int depth_ = 0;
};

}  // namespace

bool is_scene_keyword(std::string_view word) {
  for (auto w : kSceneWords)
    if (w == word) return true;
  return false;
}

Program parse_program(std::string_view source, const std::string& filename) {
  Program p;
  p.filename = filename;
  p.statements = Parser(tokenize(source, filename)).statements_until_end();
  return p;
}

ExprPtr parse_expression(std::string_view source, const std::string& filename) {
  return Parser(tokenize(source, filename)).whole_expression();
}

}  // namespace vproto::modeler
