// Every class of bad input is rejected with FILE:LINE:COL and a message naming what was
// expected (spec "Errors"); the place is given here as the text the error must point at.
#include <gtest/gtest.h>

#include "script_helpers.h"

namespace vproto::modeler {
namespace {

struct Case {
  const char* name;
  std::string src;
  std::string at;    ///< the error points at the first occurrence of this text
  std::string part;  ///< part of the message
  bool compile = false;
  std::vector<ParamOverride> overrides = {};
  friend void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }
};

void place_of(const std::string& src, const std::string& at, int* line, int* col) {
  const std::size_t pos = src.find(at);
  ASSERT_NE(pos, std::string::npos) << at;
  *line = 1;
  *col = 1;
  for (std::size_t i = 0; i < pos; ++i) {
    if (src[i] == '\n') {
      ++*line;
      *col = 1;
    } else {
      ++*col;
    }
  }
}

const char* kBody = "rigid body b (material=steel) ";

std::vector<Case> cases() {
  const std::string b = kBody;
  return {
      {"solid outside a body", "box([1,2,3]);", "box", "must be inside a body"},
      {"missing semicolon", "let a = 1\nlet b = 2;", "let b", "expected ';'"},
      {"unknown unit", "let a = 5furlong;", "furlong", "unknown unit"},
      {"dimension mismatch", "let a = 2in + 3lbf;", "+", "dimensions differ"},
      {"unknown function", "let a = foo(1);", "foo", "unknown function 'foo'"},
      {"unknown name", "let a = b + 1;", "b +", "unknown name 'b'"},
      {"box of forces", b + "{ box([1lbf, 1, 1]); }", "[1lbf", "must be a length, got a force"},
      {"negative size", b + "{ box([1, -1, 1]); }", "[1, -1", "size must be positive"},
      {"too few segments", b + "{ cylinder(h=1, r=1, segments=2); }", "segments=2",
       "between 3 and"},
      {"both r and d", b + "{ cylinder(h=1, r=1, d=2); }", "d=2", "not both"},
      {"no radius", b + "{ cylinder(h=1); }", "cylinder", "needs a radius"},
      {"unknown argument", b + "{ box(size=1, centre=true); }", "centre", "no argument 'centre'"},
      {"argument twice", b + "{ box(1, size=2); }", "size=2", "given twice"},
      {"too many positional", b + "{ sphere(1, 2); }", "2)", "at most 1 positional"},
      {"endless recursion", "module m(n) { m(n + 1); }\n" + b + "{ m(0); }", "m(n + 1)",
       "levels deep"},
      {"range too long", b + "{ for (i = [0:1e7]) box(1); }", "[0:1e7]", "more than"},
      {"loop runs too long", b + "{ for (i = [0:1e5], j = [0:1e5]) ; }", ";", "statements"},
      {"too many triangles", b + "{ sphere(1, segments=4000); }", "sphere", "triangles"},
      {"unknown body", "fix nothing;\n" + b + "{ box(1); }", "nothing", "unknown body 'nothing'"},
      {"duplicate body", b + "{ box(1); }\nelastic body b (material=abs) { box(1); }", "elastic",
       "already defined"},
      {"material without E", "material m { nu = 0.3; density = 1000; }", "material m", "needs E"},
      {"nu too large", "material m { E = 1GPa; nu = 0.5; density = 1000; }", "material m", "nu"},
      {"unknown material property", "material m { E = 1GPa; nu = 0.3; density = 1; color = 1; }",
       "color", "unknown material property"},
      {"body without material", "rigid body b { box(1); }", "rigid", "needs a material"},
      {"unknown material", "rigid body b (material=kryptonite) { box(1); }", "kryptonite",
       "unknown material"},
      {"empty body", b + "{ }", "rigid", "has no solids"},
      {"unknown body attribute", "rigid body b (material=steel, colour=1) { box(1); }", "colour",
       "no attribute 'colour'"},
      {"fixed joint to ground", "joint fixed b;\n" + b + "{ box(1); }", "joint",
       "needs 'to OTHER'"},
      {"slider without axis", "joint slider b;\n" + b + "{ box(1); }", "joint", "needs axis"},
      {"grip on a rigid body", "grip b region=box([0,0,0],[1,1,1]);\n" + b + "{ box(1); }",
       "b region", "elastic bodies only"},
      {"region inside out",
       "elastic body e (material=abs) { box(1); }\nfix e region=box([1,0,0],[0,1,1]);", "box([1",
       "minimum coordinate"},
      {"force without vector", b + "{ box(1); }\nforce b ramp=1s;", "force",
       "needs a force vector"},
      {"force in wrong units", b + "{ box(1); }\nforce b [1, 2, 3m];", "[1, 2", "must be a force"},
      {"unknown setting", b + "{ box(1); }\nmove b by=[0,0,1] over=1s speed=2;", "speed",
       "no setting"},
      {"contact with nothing to set", "contact;", "contact", "needs friction"},
      {"restitution above 1", "contact restitution=1.5;", "restitution", "between 0 and 1"},
      {"unknown mode", "simulate(mode=fast);", "fast", "must be one of static"},
      {"dt longer than run", "simulate(duration=1s, dt=2s);", "dt", "longer than the duration"},
      {"render size zero", "render(size=[0, 720]);", "size", "between 16 and"},
      {"render size huge", "render(size=[100000, 100000]);", "size", "between 16 and"},
      {"division by zero", "let a = 1 / 0;", "/", "division by zero"},
      {"speed out of range", b + "{ box(1); }\nvelocity b linear=[1e300, 0, 0];", "linear",
       "out of range"},
      {"gravity out of range", "gravity [0, 0, -1e300];", "[0, 0", "out of range"},
      {"index out of range", "let v = [1, 2];\nlet a = v[5];", "5]", "out of range"},
      {"keyword as name", "let module = 3;", "module", "keywords are reserved"},
      {"scale by zero", b + "{ scale([1, 0, 1]) box(1); }", "[1, 0", "by zero"},
      {"rotation about nothing", b + "{ rotate(30, axis=[0, 0, 0]) box(1); }", "axis",
       "must not be zero"},
      {"transform without child", b + "{ translate([1,0,0]); }", "translate", "none follows"},
      {"sin of a length", "let a = sin(2in);", "sin", "expects an angle"},
      {"param in a block", "{ param p = 1; }", "param", "top level"},
      {"let redefined", "let a = 1;\nlet a = 2;", "let a = 2", "already defined"},
      {"statement in a body", b + "{ fix b; }", "fix", "not allowed inside a body"},
      {"units of the wrong kind", "units length=lbf;", "lbf", "not a unit of length"},
      {"set of a non-param", "param p = 1;", "", "not a param", false, {{"q", "2"}}},
      {"set with wrong dimension", "param p = 1in;", "", "is a length", false, {{"p", "2lbf"}}},
      {"set that does not parse", "param p = 1in;", "", "expected", false, {{"p", "2in +"}}},
      {"fillet without a radius", b + "{ fillet(h=1); }", "fillet", "needs a radius r"},
      {"fillet of zero radius", b + "{ fillet(r=0, h=1); }", "r=0", "positive"},
      {"import of a missing file", b + "{ import(\"nope.stl\"); }", "\"nope", "cannot find"},
      // found while building geometry, still with the place in the script
      {"self-intersecting prism", b + "{ prism(points=[[0,0],[1,1],[1,0],[0,1]], h=1); }", "prism",
       "not simple", true},
      {"difference removes everything",
       b + "{ difference() { box(1); translate([-1,-1,-1]) box(3); } }", "rigid", "is empty", true},
      {"solids touching at an edge", b + "{ box(1); translate([1, 1, 0]) box(1); }", "rigid",
       "not a 2-manifold", true},
      {"open imported mesh", b + "{ import(\"open_tetra.stl\"); }", "import", "not closed", true},
  };
}

class Errors : public ::testing::TestWithParam<Case> {};

TEST_P(Errors, NameThePlaceAndWhatWasExpected) {
  const Case& c = GetParam();
  if (!c.overrides.empty()) {
    try {
      c.compile ? (void)testing::build(c.src, c.overrides)
                : (void)testing::evaluate(c.src, c.overrides);
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.loc().file.rfind("--set", 0), 0u) << e.what();
      EXPECT_NE(e.message().find(c.part), std::string::npos) << e.what();
    }
    return;
  }
  int line = 0, col = 0;
  place_of(c.src, c.at, &line, &col);
  testing::expect_input_error(c.src, line, col, c.part, c.compile);
}

INSTANTIATE_TEST_SUITE_P(Script, Errors, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           std::string n = info.param.name;
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace vproto::modeler
