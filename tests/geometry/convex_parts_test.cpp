#include "vproto/geometry/convex_parts.h"

#include <gtest/gtest.h>

#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"

namespace vproto::geometry {
namespace {

double total_volume(const std::vector<TriMesh>& parts) {
  double v = 0;
  for (const auto& p : parts) v += mass_properties(p).volume;
  return v;
}

TEST(ConvexParts, ConvexSolidIsOnePart) {
  const TriMesh s = make_sphere(1, 24);
  EXPECT_TRUE(is_convex(s));
  const auto parts = convex_parts(s);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_NEAR(total_volume(parts), mass_properties(s).volume, 1e-12);
}

TEST(ConvexParts, NonConvexPartsCoverTheSolidExactly) {
  // a box with a slot and a cylindrical hole
  CsgNode tree;
  tree.op = BooleanOp::kDifference;
  tree.children.push_back(CsgNode::make_leaf(make_box({4, 2, 1}, false)));
  tree.children.push_back(CsgNode::make_leaf(transformed(
      make_box({1, 3, 0.5}, false), Eigen::Affine3d(Eigen::Translation3d(1.5, -0.5, 0.5)))));
  tree.children.push_back(CsgNode::make_leaf(transformed(
      make_cylinder(2, 0.4, 0.4, 12, false), Eigen::Affine3d(Eigen::Translation3d(3.2, 1, -0.5)))));
  const TriMesh solid = evaluate_csg(tree);
  ASSERT_EQ(solid_validation_error(solid), "");
  EXPECT_FALSE(is_convex(solid));
  const auto parts = convex_parts(solid);
  EXPECT_GT(parts.size(), 2u);
  const double v = mass_properties(solid).volume;
  EXPECT_NEAR(total_volume(parts), v, 1e-12 * v);
  for (const auto& p : parts) {
    EXPECT_EQ(solid_validation_error(p), "");
    EXPECT_TRUE(is_convex(p));
    // every part lies within the solid's bounds
    const Bounds b = bounds(p), s = bounds(solid);
    EXPECT_TRUE((b.lo.array() >= s.lo.array() - 1e-12).all());
    EXPECT_TRUE((b.hi.array() <= s.hi.array() + 1e-12).all());
  }
}

}  // namespace
}  // namespace vproto::geometry
