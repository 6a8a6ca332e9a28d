#include "vproto/geometry/csg.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

#include "test_volumes.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/geometry/tet_mesh.h"

namespace vproto::geometry {
namespace {

TriMesh box_at(Eigen::Vector3d lo, Eigen::Vector3d size) {
  return transformed(make_box(size, false), Eigen::Affine3d(Eigen::Translation3d(lo)));
}

CsgNode op(BooleanOp o, std::vector<TriMesh> meshes) {
  CsgNode n;
  n.op = o;
  for (auto& m : meshes) n.children.push_back(CsgNode::make_leaf(std::move(m)));
  return n;
}

double volume(const TriMesh& m) { return mass_properties(m).volume; }

// V - E + F with E = 3F/2: 2 per closed genus-0 component
long euler_characteristic(const TriMesh& m) { return m.V.rows() - m.F.rows() / 2; }

TEST(Csg, UnionOfOverlappingBoxes) {
  CsgStats stats;
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kUnion, {box_at({0, 0, 0}, {2, 2, 2}), box_at({1, 1, 1}, {2, 2, 2})}), &stats);
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 15, 1e-12);
  EXPECT_EQ(stats.corefinements, 1);
}

// The re-entrant edges of an L (a foot and a leg on it): only the inside corner's, whole,
// whichever way the union split it into triangles; a box has none.
TEST(Csg, AnLHasOneReentrantEdgeAndABoxNone) {
  const TriMesh l = evaluate_csg(
      op(BooleanOp::kUnion, {box_at({0, 0, 0}, {3, 1, 1}), box_at({0, 0, 1}, {1, 1, 2})}));
  ASSERT_EQ(solid_validation_error(l), "");
  const std::vector<Edge> inside = reentrant_edges(l, 30);
  ASSERT_FALSE(inside.empty());
  double length = 0;
  for (const Edge& e : inside) {
    length += (e.b - e.a).norm();
    for (const Eigen::Vector3d& p : {e.a, e.b}) {
      EXPECT_NEAR(p.x(), 1, 1e-12);
      EXPECT_NEAR(p.z(), 1, 1e-12);
    }
  }
  EXPECT_NEAR(length, 1, 1e-12);
  // its faces: the leg's (x = 1, outward +x; off the edge up the leg, +z) and the foot's top
  // (z = 1, +z; along the foot, +x), in either order
  for (const Edge& e : inside) {
    const int leg = e.normal[0].x() > 0.5 ? 0 : 1;
    EXPECT_TRUE(e.normal[leg].isApprox(Eigen::Vector3d::UnitX(), 1e-12));
    EXPECT_TRUE(e.into[leg].isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
    EXPECT_TRUE(e.normal[1 - leg].isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
    EXPECT_TRUE(e.into[1 - leg].isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  }
  // the walls there: a ray into the leg crosses it (1), one into the foot too (1); the
  // nearest face of a point just inside the foot's top is that top
  const std::vector<double> walls = ray_distances(
      l,
      {Eigen::Vector3d(0.99, 0.5, 1.5), Eigen::Vector3d(2, 0.5, 0.99),
       Eigen::Vector3d(5, 0.5, 0.5)},
      {-Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()});
  EXPECT_NEAR(walls[0], 0.99, 1e-12);
  EXPECT_NEAR(walls[1], 0.99, 1e-12);
  EXPECT_EQ(walls[2], std::numeric_limits<double>::infinity());  // pointing away
  const std::vector<NearestFace> near = nearest_faces(l, {Eigen::Vector3d(2.5, 0.5, 0.999)});
  EXPECT_NEAR(near[0].distance, 0.001, 1e-12);
  EXPECT_TRUE(near[0].normal.isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_NEAR(distance_to_edges(inside, Eigen::Vector3d(2, 0.5, 2)), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(distance_to_edges(inside, Eigen::Vector3d(1, 3, 1)), 2, 1e-12);
  EXPECT_TRUE(reentrant_edges(make_box({1, 2, 3}, false), 30).empty());
  // a turn of 90 degrees is not re-entrant past 90 degrees
  EXPECT_TRUE(reentrant_edges(l, 95).empty());
}

TEST(Csg, UnionOfBoxesSharingAFaceIsOneSolid) {
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kUnion, {box_at({0, 0, 0}, {1, 1, 1}), box_at({1, 0, 0}, {1, 1, 1})}));
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 2, 1e-14);
  EXPECT_EQ(euler_characteristic(r), 2);
}

TEST(Csg, UnionOfPartlyCoplanarBoxes) {
  // same height, offset sideways: top and bottom faces coplanar and overlapping
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kUnion, {box_at({0, 0, 0}, {2, 2, 1}), box_at({1, 1, 0}, {2, 2, 1})}));
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 7, 1e-14);
  EXPECT_EQ(euler_characteristic(r), 2);
}

TEST(Csg, DifferenceFlushWithTheTopFace) {
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kDifference, {box_at({0, 0, 0}, {3, 3, 3}), box_at({1, 1, 2}, {1, 1, 1})}));
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 26, 1e-13);
}

TEST(Csg, DifferenceSharingEdgesAndCorner) {
  // the cutter fills one corner exactly: coincident faces, edges and a vertex
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kDifference, {box_at({0, 0, 0}, {2, 2, 2}), box_at({1, 1, 1}, {1, 1, 1})}));
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 7, 1e-14);
}

TEST(Csg, IntersectionAndEmptyIntersection) {
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kIntersection, {box_at({0, 0, 0}, {2, 2, 2}), box_at({1, 1, 1}, {2, 2, 2})}));
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 1, 1e-14);
  CsgStats stats;
  const TriMesh none = evaluate_csg(
      op(BooleanOp::kIntersection, {box_at({0, 0, 0}, {1, 1, 1}), box_at({5, 5, 5}, {1, 1, 1})}),
      &stats);
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(stats.corefinements, 0);
}

TEST(Csg, DifferenceThatRemovesEverythingIsEmpty) {
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kDifference, {box_at({0, 0, 0}, {1, 1, 1}), box_at({-1, -1, -1}, {3, 3, 3})}));
  EXPECT_TRUE(r.empty());
}

TEST(Csg, DisjointOperandsNeedNoBoolean) {
  CsgStats stats;
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kUnion, {box_at({0, 0, 0}, {1, 1, 1}), box_at({3, 0, 0}, {1, 1, 1}),
                             box_at({6, 0, 0}, {1, 1, 1})}),
      &stats);
  EXPECT_EQ(stats.corefinements, 0);
  EXPECT_EQ(stats.skipped_disjoint, 2);
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 3, 1e-14);
  // a cutter far away is dropped
  CsgStats s2;
  const TriMesh d = evaluate_csg(
      op(BooleanOp::kDifference, {box_at({0, 0, 0}, {1, 1, 1}), box_at({3, 0, 0}, {1, 1, 1})}),
      &s2);
  EXPECT_EQ(s2.corefinements, 0);
  EXPECT_NEAR(volume(d), 1, 1e-14);
}

TEST(Csg, FortyNineHolesTakeOneCorefinement) {
  std::vector<TriMesh> parts = {make_box({100, 100, 10}, false)};
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 7; ++j)
      parts.push_back(transformed(
          make_cylinder(12, 4, 4, 64, false),
          Eigen::Affine3d(Eigen::Translation3d(10 + 80.0 / 6 * i, 10 + 80.0 / 6 * j, -1))));
  CsgStats stats;
  const TriMesh r = evaluate_csg(op(BooleanOp::kDifference, std::move(parts)), &stats);
  EXPECT_EQ(stats.corefinements, 1);
  EXPECT_EQ(solid_validation_error(r), "");
  const double expected = 100 * 100 * 10 - 49 * 10 * testing::ngon_area(4, 64);
  EXPECT_NEAR(volume(r), expected, 1e-10 * expected);
}

TEST(Csg, CylinderThroughRotatedBoxAndSphereShell) {
  const double n = 48;
  Eigen::Affine3d rot(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  const TriMesh box = transformed(make_box({4, 4, 4}, true), rot);
  const TriMesh cyl = transformed(make_cylinder(10, 1, 1, static_cast<int>(n), true), rot);
  const TriMesh r = evaluate_csg(op(BooleanOp::kDifference, {box, cyl}));
  EXPECT_EQ(solid_validation_error(r), "");
  const double expected = 64 - 4 * testing::ngon_area(1, static_cast<int>(n));
  EXPECT_NEAR(volume(r), expected, 1e-9 * expected);

  const TriMesh shell =
      evaluate_csg(op(BooleanOp::kDifference, {make_sphere(2, 32), make_sphere(1, 32)}));
  EXPECT_EQ(solid_validation_error(shell), "");
  const double vs = testing::faceted_sphere_volume(2, 32) - testing::faceted_sphere_volume(1, 32);
  EXPECT_NEAR(volume(shell), vs, 1e-12 * vs);
}

TEST(Csg, NestedTreesStayExact) {
  // (A u B) - (C n D), with an operand shared in several places
  CsgNode tree;
  tree.op = BooleanOp::kDifference;
  tree.children.push_back(
      op(BooleanOp::kUnion, {box_at({0, 0, 0}, {2, 1, 1}), box_at({0, 0, 0}, {1, 2, 1})}));
  // a 0.5 x 0.5 through-hole inside the L's leg
  tree.children.push_back(op(BooleanOp::kIntersection, {box_at({0.25, 0.25, -1}, {1, 1, 3}),
                                                        box_at({0, 0, -1}, {0.75, 0.75, 3})}));
  const TriMesh r = evaluate_csg(tree);
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 3 - 0.25, 1e-14);
}

TEST(Csg, RotatedOperandsStayCoplanar) {
  // a wedge turned 180 degrees about y sits flush on a box face; no slivers, no flat faces
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.linear() << -1, 0, 0, 0, 1, 0, 0, 0, -1;
  t.translation() << 0, 0, 0.1;
  const TriMesh r =
      evaluate_csg(op(BooleanOp::kUnion, {make_box({0.5, 0.5, 2}, false),
                                          transformed(make_wedge({0.1, 0.5, 0.1}), t)}));
  EXPECT_EQ(solid_validation_error(r), "");
  EXPECT_NEAR(volume(r), 0.5 + 0.0025, 1e-12);  // operands snap to a 6e-14 grid
}

TEST(Csg, SolidsTouchingAlongAnEdgeOnlyAreRejected) {
  EXPECT_THROW(evaluate_csg(op(BooleanOp::kUnion,
                               {box_at({0, 0, 0}, {1, 1, 1}), box_at({1, 1, 0}, {1, 1, 1})})),
               GeometryError);
}

TEST(Csg, ValidationNamesTheDefect) {
  TriMesh open = make_box({1, 1, 1}, false);
  open.F.conservativeResize(open.F.rows() - 1, 3);
  EXPECT_NE(solid_validation_error(open).find("not closed"), std::string::npos);
  TriMesh inward = make_box({1, 1, 1}, false);
  inward.F.col(1).swap(inward.F.col(2));
  EXPECT_NE(solid_validation_error(inward).find("inward"), std::string::npos);
  const TriMesh two = concatenated(make_box({1, 1, 1}, false), box_at({0.5, 0.5, 0.5}, {1, 1, 1}));
  EXPECT_NE(solid_validation_error(two).find("intersects itself"), std::string::npos);
  TriMesh bad_index = make_box({1, 1, 1}, false);
  bad_index.F(0, 0) = 99;
  EXPECT_NE(solid_validation_error(bad_index).find("missing vertex"), std::string::npos);
}

// The result's order is its geometry's alone: the same surface numbered and listed any other
// way (vertices renumbered, triangles shuffled and rotated) orders to the same mesh, so a
// library's heap-dependent output order cannot reach the tet mesh.
TEST(Csg, TheResultIsInCanonicalOrder) {
  const TriMesh r = evaluate_csg(
      op(BooleanOp::kDifference, {make_box({4, 4, 4}, true), make_cylinder(10, 1, 1, 24, true)}));
  ASSERT_GT(r.F.rows(), 48);
  const TriMesh again = canonically_ordered(r);
  EXPECT_TRUE(again.V == r.V);
  EXPECT_TRUE(again.F == r.F);

  std::mt19937 rng(7);
  std::vector<int> perm(static_cast<std::size_t>(r.V.rows()));
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  TriMesh shuffled;
  shuffled.V.resize(r.V.rows(), 3);
  for (Eigen::Index i = 0; i < r.V.rows(); ++i) shuffled.V.row(perm[i]) = r.V.row(i);
  std::vector<Eigen::Index> faces(static_cast<std::size_t>(r.F.rows()));
  std::iota(faces.begin(), faces.end(), 0);
  std::shuffle(faces.begin(), faces.end(), rng);
  shuffled.F.resize(r.F.rows(), 3);
  for (Eigen::Index f = 0; f < r.F.rows(); ++f) {
    const int turn = static_cast<int>(f % 3);  // each triangle started at another corner
    for (int k = 0; k < 3; ++k) shuffled.F(f, k) = perm[r.F(faces[f], (k + turn) % 3)];
  }
  ASSERT_FALSE(shuffled.F == r.F);
  const TriMesh ordered = canonically_ordered(shuffled);
  EXPECT_TRUE(ordered.V == r.V);
  EXPECT_TRUE(ordered.F == r.F);
}

}  // namespace
}  // namespace vproto::geometry
