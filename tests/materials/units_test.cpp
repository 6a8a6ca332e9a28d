#include "vproto/materials/units.h"

#include <gtest/gtest.h>

namespace vproto::units {
namespace {

TEST(Units, SimpleUnitsHaveExactSIFactors) {
  EXPECT_DOUBLE_EQ(find_unit("in")->scale, 0.0254);
  EXPECT_DOUBLE_EQ(find_unit("ft")->scale, 0.3048);
  EXPECT_DOUBLE_EQ(find_unit("lb")->scale, 0.45359237);
  EXPECT_NEAR(find_unit("lbf")->scale, 4.4482216152605, 1e-12);
  EXPECT_NEAR(find_unit("psi")->scale, 6894.757293168, 1e-6);
  EXPECT_NEAR(find_unit("deg")->scale, 3.14159265358979 / 180, 1e-15);
  EXPECT_EQ(find_unit("lbf")->dimension, Dimension::of_force());
  EXPECT_EQ(find_unit("GPa")->dimension, Dimension::of_pressure());
  EXPECT_FALSE(find_unit("furlong"));
}

TEST(Units, CompoundUnits) {
  const auto density = parse_unit("lb/in^3");
  ASSERT_TRUE(density);
  EXPECT_EQ(density->dimension, Dimension::of_density());
  EXPECT_NEAR(density->scale, 0.45359237 / (0.0254 * 0.0254 * 0.0254), 1e-9);
  EXPECT_EQ(parse_unit("m/s^2")->dimension, Dimension::of_acceleration());
  EXPECT_EQ(parse_unit("deg/s")->dimension, Dimension::of_angular_velocity());
  EXPECT_NEAR(parse_unit("g/cm^3")->scale, 1000.0, 1e-9);
  EXPECT_EQ(parse_unit("N*m")->dimension, (Dimension{2, 1, -2, 0}));
  EXPECT_FALSE(parse_unit("kg/"));
  EXPECT_FALSE(parse_unit("kg/m^"));
  EXPECT_FALSE(parse_unit("kg/parsec"));
}

TEST(Units, DescribeNamesCommonDimensions) {
  EXPECT_EQ(describe(Dimension::of_length()), "a length");
  EXPECT_EQ(describe(Dimension::of_force()), "a force");
  EXPECT_EQ(describe(Dimension{}), "a plain number");
  EXPECT_EQ(describe(Dimension{4, 0, 0, 0}), "a quantity in m^4");
}

TEST(Units, DefaultUnitsCompose) {
  UnitSystem sys;
  sys.length = *find_unit("in");
  sys.force = *find_unit("lbf");
  EXPECT_DOUBLE_EQ(sys.scale_for(Dimension::of_length()), 0.0254);
  EXPECT_DOUBLE_EQ(sys.scale_for(Dimension::of_force()), find_unit("lbf")->scale);
  EXPECT_DOUBLE_EQ(sys.scale_for(Dimension::of_velocity()), 0.0254);
  EXPECT_NEAR(sys.scale_for(Dimension::of_angle()), 3.14159265358979 / 180, 1e-15);
  EXPECT_NEAR(sys.scale_for(Dimension{3, 0, 0, 0}), 0.0254 * 0.0254 * 0.0254, 1e-18);
}

}  // namespace
}  // namespace vproto::units
