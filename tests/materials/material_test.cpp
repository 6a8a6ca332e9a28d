#include "vproto/materials/material.h"

#include <gtest/gtest.h>

namespace vproto::materials {
namespace {

TEST(Materials, BuiltinLibraryIsCompleteAndValid) {
  for (const char* name :
       {"steel", "aluminum", "abs", "polycarbonate", "nylon", "hdpe", "pom", "rubber"}) {
    const Material* m = find_builtin(name);
    ASSERT_NE(m, nullptr) << name;
    EXPECT_EQ(validation_error(*m), "") << name;
    EXPECT_FALSE(m->source.empty()) << name;
  }
  // the values references.md uses for HDPE
  EXPECT_DOUBLE_EQ(find_builtin("hdpe")->youngs_modulus, 0.9e9);
  EXPECT_DOUBLE_EQ(find_builtin("hdpe")->poisson_ratio, 0.42);
  EXPECT_DOUBLE_EQ(find_builtin("steel")->youngs_modulus, 210e9);
  EXPECT_EQ(find_builtin("unobtainium"), nullptr);
}

TEST(Materials, ValidationRejectsNonPhysicalValues) {
  Material m = *find_builtin("steel");
  EXPECT_EQ(validation_error(m), "");
  m.youngs_modulus = 0;
  EXPECT_NE(validation_error(m).find("E"), std::string::npos);
  m = *find_builtin("steel");
  m.poisson_ratio = 0.5;
  EXPECT_NE(validation_error(m).find("nu"), std::string::npos);
  m.poisson_ratio = -1;
  EXPECT_NE(validation_error(m), "");
  m.poisson_ratio = -0.99;
  EXPECT_EQ(validation_error(m), "");
  m.density = -1;
  EXPECT_NE(validation_error(m).find("density"), std::string::npos);
  m = *find_builtin("steel");
  m.restitution = 1.5;
  EXPECT_NE(validation_error(m).find("restitution"), std::string::npos);
}

}  // namespace
}  // namespace vproto::materials
