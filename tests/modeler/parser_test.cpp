#include "vproto/modeler/parser.h"

#include <gtest/gtest.h>

namespace vproto::modeler {
namespace {

TEST(Parser, PrecedenceAndAssociativity) {
  // -2^2 = -(2^2); 2^3^2 = 2^(3^2); a - b - c = (a - b) - c
  const ExprPtr e = parse_expression("-2^2 + 2^3^2 - 1 - 1", "x");
  ASSERT_EQ(e->kind, Expr::Kind::kBinary);
  EXPECT_EQ(e->text, "-");
  EXPECT_EQ(e->items[0]->text, "-");
  const ExprPtr t = parse_expression("a < b ? c : d || e", "x");
  EXPECT_EQ(t->kind, Expr::Kind::kTernary);
}

TEST(Parser, BracketForms) {
  EXPECT_EQ(parse_expression("[]", "x")->kind, Expr::Kind::kVector);
  EXPECT_EQ(parse_expression("[1, 2, 3,]", "x")->items.size(), 3u);
  EXPECT_EQ(parse_expression("[0:5]", "x")->kind, Expr::Kind::kRange);
  EXPECT_EQ(parse_expression("[0:2:10]", "x")->items.size(), 3u);
  EXPECT_EQ(parse_expression("[for (k = [0:5]) k * 2]", "x")->kind, Expr::Kind::kComprehension);
  EXPECT_EQ(parse_expression("v[1][2]", "x")->kind, Expr::Kind::kIndex);
}

TEST(Parser, StatementsAndScene) {
  const Program p = parse_program(R"(
    units length=in force=lbf;
    param gap = 0.002in;
    module peg(r, h=2) { cylinder(h=h, r=r); }
    rigid body a (material=steel) { translate([1,0,0]) { peg(1); box([1,1,1]); } }
    for (i = [0:2], j = [0:1]) ;
    joint revolute a at=[0,0,0] axis=[0,0,1];
    joint fixed a to b;
    contact friction=0.3;
    contact a b restitution=0.5;
    gravity [0, 0, -9.81];
    force a [0, 0, -50] at=[0,0,1] ramp=0.1s;
    simulate(mode=dynamic, duration=0.5s);
  )",
                                  "p.vp");
  ASSERT_EQ(p.statements.size(), 12u);
  EXPECT_EQ(p.statements[3].kind, Stmt::Kind::kBody);
  EXPECT_EQ(p.statements[3].args[0].name, "material");
  const Stmt& loop = p.statements[4];
  EXPECT_EQ(loop.kind, Stmt::Kind::kFor);
  EXPECT_EQ(loop.children.at(0).kind, Stmt::Kind::kFor);  // two variables: nested loops
  EXPECT_EQ(p.statements[5].idents, (std::vector<std::string>{"revolute", "a"}));
  EXPECT_EQ(p.statements[6].idents, (std::vector<std::string>{"fixed", "a", "to", "b"}));
  EXPECT_TRUE(p.statements[7].idents.empty());
  EXPECT_EQ(p.statements[8].idents.size(), 2u);
  EXPECT_TRUE(p.statements[9].value);
  EXPECT_EQ(p.statements[10].args.size(), 2u);
  EXPECT_EQ(p.statements[11].name, "simulate");
}

TEST(Parser, DeepNestingIsAnErrorNotACrash) {
  std::string deep(100000, '(');
  deep += "1";
  deep += std::string(100000, ')');
  EXPECT_THROW(parse_expression(deep, "x"), InputError);
  std::string blocks = "rigid body a (material=steel) ";
  for (int i = 0; i < 50000; ++i) blocks += "{";
  EXPECT_THROW(parse_program(blocks, "x"), InputError);
  // a long chain nests to the left, just as deeply
  std::string chain = "1";
  for (int i = 0; i < 200000; ++i) chain += "+1";
  EXPECT_THROW(parse_expression(chain, "x"), InputError);
  std::string ok = "1";
  for (int i = 0; i < 1000; ++i) ok += "+1";
  EXPECT_NO_THROW(parse_expression(ok, "x"));
}

}  // namespace
}  // namespace vproto::modeler
