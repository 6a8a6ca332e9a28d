#include "vproto/geometry/mass_properties.h"

#include <gtest/gtest.h>

#include "test_volumes.h"
#include "vproto/geometry/primitives.h"

namespace vproto::geometry {
namespace {

TEST(MassProperties, BoxAgainstTheClosedForm) {
  const double a = 0.3, b = 0.5, c = 0.7;
  const Eigen::Vector3d offset(1.5, -2, 0.25);
  const TriMesh box =
      transformed(make_box({a, b, c}, true), Eigen::Affine3d(Eigen::Translation3d(offset)));
  const MassProperties mp = mass_properties(box);
  const double v = a * b * c;
  EXPECT_NEAR(mp.volume, v, 1e-15);
  EXPECT_NEAR(mp.area, 2 * (a * b + b * c + a * c), 1e-14);
  EXPECT_TRUE(mp.centroid.isApprox(offset, 1e-14));
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected.diagonal() << v / 12 * (b * b + c * c), v / 12 * (a * a + c * c),
      v / 12 * (a * a + b * b);
  EXPECT_LT((mp.unit_inertia - expected).norm(), 1e-15);
}

TEST(MassProperties, InertiaRotatesAsATensor) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const TriMesh box = make_box({1, 2, 3}, true);
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.linear() = r;
  t.translation() << 4, 5, 6;
  const MassProperties a = mass_properties(box);
  const MassProperties b = mass_properties(transformed(box, t));
  EXPECT_NEAR(b.volume, a.volume, 1e-13);
  EXPECT_TRUE(b.centroid.isApprox(Eigen::Vector3d(4, 5, 6), 1e-13));
  EXPECT_LT((b.unit_inertia - r * a.unit_inertia * r.transpose()).norm(), 1e-12);
}

TEST(MassProperties, CylinderConvergesToTheSolidCylinder) {
  // prism of a 1024-gon: inertia about the axis m r^2 / 2 within the faceting error
  const double r = 0.2, h = 1.0;
  const MassProperties mp = mass_properties(make_cylinder(h, r, r, 1024, true));
  const double v = testing::ngon_frustum_volume(h, r, r, 1024);
  EXPECT_NEAR(mp.volume, v, 1e-14);
  EXPECT_NEAR(mp.unit_inertia(2, 2), v * r * r / 2, 1e-4 * v * r * r);
  EXPECT_NEAR(mp.unit_inertia(0, 0), v * (3 * r * r + h * h) / 12, 1e-4 * v * h * h);
  EXPECT_NEAR(mp.unit_inertia(0, 1), 0, 1e-15);
}

}  // namespace
}  // namespace vproto::geometry
