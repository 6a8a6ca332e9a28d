#include "vproto/modeler/lexer.h"

#include <gtest/gtest.h>

namespace vproto::modeler {
namespace {

TEST(Lexer, NumbersWithUnitsAndPositions) {
  const auto t = tokenize("let w = 0.002in;\n  x = 1e-3 + 2.3GPa * 1050kg/m^3;", "a.vp");
  ASSERT_GE(t.size(), 14u);
  EXPECT_TRUE(t[0].is_keyword("let"));
  EXPECT_EQ(t[3].kind, TokenKind::kNumber);
  EXPECT_DOUBLE_EQ(t[3].number, 0.002);
  EXPECT_EQ(t[3].text, "in");
  EXPECT_EQ(t[3].loc.line, 1);
  EXPECT_EQ(t[3].loc.column, 9);
  EXPECT_EQ(t[5].loc.line, 2);
  EXPECT_EQ(t[5].loc.column, 3);
  EXPECT_DOUBLE_EQ(t[7].number, 1e-3);
  EXPECT_EQ(t[7].text, "");
  EXPECT_EQ(t[9].text, "GPa");
  EXPECT_EQ(t[11].text, "kg/m^3");
}

TEST(Lexer, UnitStopsBeforeAVariable) {
  // 60deg*k is 60 degrees times k; 1in/s is a velocity
  const auto t = tokenize("60deg*k 1in/s 2mm/2", "a.vp");
  EXPECT_EQ(t[0].text, "deg");
  EXPECT_TRUE(t[1].is_punct("*"));
  EXPECT_EQ(t[2].text, "k");
  EXPECT_EQ(t[3].text, "in/s");
  EXPECT_EQ(t[4].text, "mm");
  EXPECT_TRUE(t[5].is_punct("/"));
}

TEST(Lexer, CommentsStringsAndOperators) {
  const auto t = tokenize("/* block\n comment */ \"a \\\"q\\\" \\\\\" // line\n<= && ||", "a.vp");
  EXPECT_EQ(t[0].kind, TokenKind::kString);
  EXPECT_EQ(t[0].text, "a \"q\" \\");
  EXPECT_EQ(t[0].loc.line, 2);
  EXPECT_TRUE(t[1].is_punct("<="));
  EXPECT_TRUE(t[2].is_punct("&&"));
  EXPECT_TRUE(t[3].is_punct("||"));
  EXPECT_EQ(t[4].kind, TokenKind::kEnd);
}

TEST(Lexer, ErrorsNameThePlace) {
  auto where = [](const char* src) {
    try {
      tokenize(src, "e.vp");
    } catch (const InputError& e) {
      return std::to_string(e.loc().line) + ":" + std::to_string(e.loc().column) + " " +
             e.message();
    }
    return std::string("no error");
  };
  EXPECT_EQ(where("let a = 5furlong;").substr(0, 5), "1:10 ");
  EXPECT_NE(where("let a = 5furlong;").find("unknown unit 'furlong'"), std::string::npos);
  EXPECT_NE(where("\n  \"open").find("2:3 unterminated string"), std::string::npos);
  EXPECT_NE(where("/* never closed").find("1:1 unterminated comment"), std::string::npos);
  EXPECT_NE(where("let a = 1 @ 2;").find("1:11 unexpected character '@'"), std::string::npos);
  EXPECT_NE(where("\"bad \\q\"").find("unknown escape"), std::string::npos);
}

}  // namespace
}  // namespace vproto::modeler
