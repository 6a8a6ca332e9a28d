#include "vproto/geometry/primitives.h"

#include <gtest/gtest.h>

#include "test_volumes.h"
#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"

namespace vproto::geometry {
namespace {

using testing::faceted_sphere_volume;
using testing::ngon_frustum_volume;

void expect_solid(const TriMesh& m, double volume) {
  EXPECT_EQ(solid_validation_error(m), "");
  EXPECT_NEAR(mass_properties(m).volume, volume, 1e-12 * volume);
}

TEST(Primitives, BoxIsClosedWithExactVolume) {
  expect_solid(make_box({1, 2, 3}, false), 6);
  const TriMesh c = make_box({2, 2, 2}, true);
  expect_solid(c, 8);
  EXPECT_TRUE(mass_properties(c).centroid.isZero(1e-15));
  EXPECT_EQ(c.F.rows(), 12);
}

TEST(Primitives, CylinderConeAndFrustumMatchThePolygonFormula) {
  for (int n : {3, 7, 32, 64, 200}) {
    expect_solid(make_cylinder(2.0, 0.5, 0.5, n, false), ngon_frustum_volume(2.0, 0.5, 0.5, n));
    expect_solid(make_cylinder(1.5, 0.7, 0.2, n, true), ngon_frustum_volume(1.5, 0.7, 0.2, n));
    expect_solid(make_cylinder(1.0, 0.0, 0.4, n, false), ngon_frustum_volume(1.0, 0.0, 0.4, n));
    expect_solid(make_cylinder(1.0, 0.4, 0.0, n, false), ngon_frustum_volume(1.0, 0.4, 0.0, n));
  }
  // a vertex at angle 0, on the true circle
  const TriMesh c = make_cylinder(1, 2, 2, 16, false);
  bool found = false;
  for (Eigen::Index i = 0; i < c.V.rows(); ++i)
    found = found || (c.V.row(i) - Eigen::RowVector3d(2, 0, 0)).norm() < 1e-15;
  EXPECT_TRUE(found);
}

TEST(Primitives, SphereVerticesLieOnTheSphere) {
  for (int n : {3, 4, 9, 32, 65}) {
    const TriMesh s = make_sphere(1.3, n);
    expect_solid(s, faceted_sphere_volume(1.3, n));
    EXPECT_NEAR(s.V.rowwise().norm().maxCoeff(), 1.3, 1e-14);
    EXPECT_NEAR(s.V.rowwise().norm().minCoeff(), 1.3, 1e-14);
  }
}

TEST(Primitives, WedgeIsHalfItsBox) {
  const TriMesh w = make_wedge({0.1, 0.5, 0.2});
  expect_solid(w, 0.1 * 0.5 * 0.2 / 2);
  // the triangle (0,0), (x,0), (0,z) in xz: centroid at x/3, z/3
  const Eigen::Vector3d c = mass_properties(w).centroid;
  EXPECT_NEAR(c.x(), 0.1 / 3, 1e-15);
  EXPECT_NEAR(c.y(), 0.25, 1e-15);
  EXPECT_NEAR(c.z(), 0.2 / 3, 1e-15);
}

TEST(Primitives, PrismOfANonConvexPolygonInEitherOrientation) {
  Eigen::MatrixX2d star(10, 2);
  for (int i = 0; i < 10; ++i) {
    const double r = i % 2 ? 0.4 : 1.0, a = testing::kPi * i / 5;
    star.row(i) << r * std::cos(a), r * std::sin(a);
  }
  double area = 0;
  for (int i = 0; i < 10; ++i) {
    const int j = (i + 1) % 10;
    area += 0.5 * (star(i, 0) * star(j, 1) - star(j, 0) * star(i, 1));
  }
  expect_solid(make_prism(star, 0.3), area * 0.3);
  expect_solid(make_prism(star.colwise().reverse(), 0.3), area * 0.3);
}

TEST(Primitives, PrismRejectsSelfIntersectingPolygons) {
  Eigen::MatrixX2d bowtie(4, 2);
  bowtie << 0, 0, 1, 1, 1, 0, 0, 1;
  EXPECT_THROW(make_prism(bowtie, 1), GeometryError);
  Eigen::MatrixX2d line(3, 2);
  line << 0, 0, 1, 0, 2, 0;
  EXPECT_THROW(make_prism(line, 1), GeometryError);
}

TEST(Primitives, DefaultSegmentsKeepChordalErrorBelowHalfAPercent) {
  const int n = default_segments();
  EXPECT_LE(1 - std::cos(testing::kPi / n), 0.005);
  EXPECT_GT(1 - std::cos(testing::kPi / (n - 4)), 0.005);
  EXPECT_EQ(n % 4, 0);
}

TEST(Primitives, MirroringKeepsTheSolidOutward) {
  Eigen::Affine3d m = Eigen::Affine3d::Identity();
  m.linear() = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  const TriMesh w = transformed(make_wedge({1, 2, 3}), m);
  expect_solid(w, 3);
}

}  // namespace
}  // namespace vproto::geometry
