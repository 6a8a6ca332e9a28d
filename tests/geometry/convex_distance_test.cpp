#include "vproto/geometry/convex_distance.h"

#include <gtest/gtest.h>

#include <random>

#include "vproto/geometry/primitives.h"

namespace vproto::geometry {
namespace {

ConvexPolytope box_at(const Eigen::Vector3d& size, const Eigen::Vector3d& at) {
  return transformed(make_polytope(make_box(size, true)),
                     Eigen::Isometry3d(Eigen::Translation3d(at)));
}

// Placing a part again into the storage of its last placement moves it as a fresh copy
// would (the narrow phase keeps each part's world polytope from step to step).
TEST(ConvexDistance, APartPlacedAgainInItsOldStorageMatchesAFreshCopy) {
  const ConvexPolytope local = make_polytope(make_sphere(0.5, 8));
  ConvexPolytope world;
  for (int k = 0; k < 3; ++k) {
    Eigen::Isometry3d pose(Eigen::AngleAxisd(0.3 + k, Eigen::Vector3d(1, 2, 3).normalized()));
    pose.pretranslate(Eigen::Vector3d(0.1 * k, -0.2, 1.5 * k));
    place(local, pose, &world);
    const ConvexPolytope fresh = transformed(local, pose);
    ASSERT_EQ(world.vertices.size(), local.vertices.size());
    for (std::size_t v = 0; v < local.vertices.size(); ++v) {
      EXPECT_EQ(world.vertices[v], fresh.vertices[v]);
      EXPECT_NEAR((world.vertices[v] - pose * local.vertices[v]).norm(), 0, 1e-15);
    }
    for (std::size_t f = 0; f < local.normals.size(); ++f) {
      EXPECT_EQ(world.normals[f], fresh.normals[f]);
      // every vertex of face f lies on its moved plane
      for (int v : world.faces[f])
        EXPECT_NEAR(world.normals[f].dot(world.vertices[static_cast<std::size_t>(v)]),
                    world.offsets[f], 1e-13);
    }
    EXPECT_EQ(world.neighbours, local.neighbours);
    EXPECT_EQ(world.faces, local.faces);
    EXPECT_EQ(world.edges.size(), local.edges.size());
    EXPECT_DOUBLE_EQ(gjk_distance(world, box_at({1, 1, 1}, {0, 3, 0})).distance,
                     gjk_distance(fresh, box_at({1, 1, 1}, {0, 3, 0})).distance);
  }
}

TEST(ConvexDistance, BoxesApartByAKnownGap) {
  const ConvexPolytope a = box_at({1, 1, 1}, {0, 0, 0}), b = box_at({1, 1, 1}, {1.25, 0.3, 0.1});
  for (const ConvexDistance& r : {gjk_distance(a, b), qp_distance(a, b)}) {
    EXPECT_NEAR(r.distance, 0.25, 1e-14);
    EXPECT_FALSE(r.overlap);
    EXPECT_NEAR(r.normal.x(), 1.0, 1e-12);
    EXPECT_NEAR(r.point_a.x(), 0.5, 1e-14);
    EXPECT_NEAR(r.point_b.x(), 0.75, 1e-14);
  }
  // edge against edge: two boxes turned 45 degrees about different axes
  const Eigen::Isometry3d ra(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()));
  Eigen::Isometry3d rb(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()));
  rb.pretranslate(Eigen::Vector3d(0, 0, 0));
  const double half_diag = std::sqrt(0.5);
  Eigen::Isometry3d pb = rb;
  pb.pretranslate(Eigen::Vector3d(2 * half_diag + 0.1, 0, 0));
  const ConvexPolytope ea = transformed(make_polytope(make_box({1, 1, 1}, true)), ra);
  const ConvexPolytope eb = transformed(make_polytope(make_box({1, 1, 1}, true)), pb);
  // A's x-extent is its half diagonal; B (turned about x) still has half-width 0.5 in x
  const double gap = 2 * half_diag + 0.1 - half_diag - 0.5;
  EXPECT_NEAR(gjk_distance(ea, eb).distance, gap, 1e-13);
  EXPECT_NEAR(qp_distance(ea, eb).distance, gap, 1e-13);
}

TEST(ConvexDistance, OverlapGivesThePenetrationDepth) {
  const ConvexPolytope a = box_at({1, 1, 1}, {0, 0, 0}), b = box_at({1, 1, 1}, {0.9, 0.2, 0});
  for (const ConvexDistance& r : {gjk_distance(a, b), qp_distance(a, b)}) {
    EXPECT_TRUE(r.overlap);
    EXPECT_NEAR(r.penetration, 0.1, 1e-14);
    EXPECT_NEAR(r.normal.x(), 1.0, 1e-14);
  }
}

// random convex parts: boxes, wedges, faceted spheres and cylinders (8 to 500 vertices),
// stretched, turned and placed at random
ConvexPolytope random_part(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  TriMesh m;
  switch (static_cast<int>(u(rng) * 4)) {
    case 0:
      m = make_box({0.2 + u(rng), 0.2 + u(rng), 0.2 + u(rng)}, true);
      break;
    case 1:
      m = make_wedge({0.2 + u(rng), 0.2 + u(rng), 0.2 + u(rng)});
      break;
    case 2:
      m = make_sphere(0.3 + 0.5 * u(rng), 4 + static_cast<int>(u(rng) * 28));
      break;
    default:
      m = make_cylinder(0.2 + u(rng), 0.2 + 0.5 * u(rng), 0.05 + 0.5 * u(rng),
                        3 + static_cast<int>(u(rng) * 60), true);
  }
  // a fifth keep their axes, so parallel faces (non-unique witnesses) come up often
  const Eigen::Quaterniond q =
      u(rng) < 0.2
          ? Eigen::Quaterniond::Identity()
          : Eigen::Quaterniond(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
  Eigen::Isometry3d pose(q);
  pose.pretranslate(Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3);
  return transformed(make_polytope(m), pose);
}

TEST(ConvexDistance, GjkAndTheSeedsQuadraticProgramAgreeOnRandomPairs) {
  std::mt19937_64 rng(20261122);
  int separated = 0, overlapping = 0;
  for (int k = 0; k < 5000; ++k) {
    const ConvexPolytope a = random_part(rng), b = random_part(rng);
    const ConvexDistance g = gjk_distance(a, b), q = qp_distance(a, b);
    ASSERT_EQ(g.overlap, q.overlap)
        << "pair " << k << ": gjk " << g.distance << " qp " << q.distance;
    if (g.overlap) {
      ++overlapping;
      EXPECT_GT(g.penetration, 0) << k;
      continue;
    }
    ++separated;
    ASSERT_NEAR(g.distance, q.distance, 1e-10 * std::max(1.0, q.distance)) << "pair " << k;
    // the contact features of the pair: no gap below the distance (but for faces taken
    // as parallel within 1e-3 rad over parts about 1 m across)
    const ContactManifold mf = contact_manifold(a, b, g);
    ASSERT_FALSE(mf.points.empty()) << k;
    for (const auto& p : mf.points) {
      EXPECT_TRUE(std::isfinite(p.gap)) << k;
      EXPECT_GE(p.gap, g.distance - 3e-3) << k;
    }
    // the witnesses are as far apart as the distance, and each lies in its body
    EXPECT_NEAR((g.point_b - g.point_a).norm(), g.distance, 1e-10);
    for (std::size_t f = 0; f < a.normals.size(); ++f)
      EXPECT_LE(a.normals[f].dot(g.point_a) - a.offsets[f], 1e-10) << k;
    for (std::size_t f = 0; f < b.normals.size(); ++f)
      EXPECT_LE(b.normals[f].dot(g.point_b) - b.offsets[f], 1e-10) << k;
  }
  EXPECT_GT(separated, 1000);
  EXPECT_GT(overlapping, 100);
}

}  // namespace
}  // namespace vproto::geometry

#include "vproto/geometry/aabb_tree.h"

namespace vproto::geometry {
namespace {

TEST(AabbTree, FindsExactlyThePairsADoubleLoopFinds) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int n : {1, 2, 7, 300, 2000}) {
    std::vector<Bounds> boxes(static_cast<std::size_t>(n));
    for (auto& b : boxes) {
      b.lo = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 10;
      b.hi = b.lo + Eigen::Vector3d(u(rng), u(rng), u(rng)) * (n > 100 ? 0.6 : 3);
    }
    if (n > 2) boxes[1] = boxes[0];  // identical boxes
    std::vector<std::pair<int, int>> expected;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (overlap(boxes[i], boxes[j])) expected.emplace_back(i, j);
    const AabbTree tree(boxes);
    EXPECT_EQ(tree.overlapping_pairs(), expected) << n;
    Bounds probe;
    probe.lo = Eigen::Vector3d(4, 4, 4);
    probe.hi = Eigen::Vector3d(6, 6, 6);
    std::vector<int> hits;
    for (int i = 0; i < n; ++i)
      if (overlap(boxes[i], probe)) hits.push_back(i);
    EXPECT_EQ(tree.overlapping(probe), hits) << n;
  }
}

TEST(AabbTree, RefittedToMovedBoxesFindsWhatANewTreeFinds) {
  // a deforming surface: boxes on a grid, then each moved and grown at random by up to a
  // box's size (neighbours change, the hierarchy is kept)
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Bounds> boxes;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      Bounds b;
      b.lo = Eigen::Vector3d(i, j, 0);
      b.hi = b.lo + Eigen::Vector3d(1.2, 1.2, 0.1);
      boxes.push_back(b);
    }
  AabbTree tree(boxes);
  for (int round = 0; round < 3; ++round) {
    for (auto& b : boxes) {
      const Eigen::Vector3d shift(u(rng), u(rng), u(rng));
      b.lo += shift;
      b.hi += shift + Eigen::Vector3d(u(rng) + 1, u(rng) + 1, u(rng) + 1) * 0.5;
    }
    tree.refit(boxes);
    const AabbTree fresh(boxes);
    EXPECT_EQ(tree.overlapping_pairs(), fresh.overlapping_pairs()) << round;
    EXPECT_GT(tree.overlapping_pairs().size(), 500u);
    Bounds probe;
    probe.lo = Eigen::Vector3d(5, 5, -1);
    probe.hi = Eigen::Vector3d(9, 12, 1);
    EXPECT_EQ(tree.overlapping(probe), fresh.overlapping(probe)) << round;
    EXPECT_FALSE(tree.overlapping(probe).empty());
  }
  EXPECT_THROW(tree.refit(std::vector<Bounds>(3)), std::invalid_argument);
}

}  // namespace
}  // namespace vproto::geometry

namespace vproto::geometry {
namespace {

ConvexPolytope posed_box(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose) {
  return transformed(make_polytope(make_box(size, true)), pose);
}

TEST(ContactManifold, FaceOnFaceGivesTheClippedPolygon) {
  // a 0.2 box hovering 1 mm over a 1 m plate, half over its edge
  const ConvexPolytope plate = box_at({1, 1, 0.1}, {0, 0, -0.05});
  const ConvexPolytope box = box_at({0.2, 0.2, 0.2}, {0.5, 0, 0.101});
  const ContactManifold m = contact_manifold(plate, box, gjk_distance(plate, box));
  EXPECT_EQ(m.feature, ContactFeature::kFaceFace);
  EXPECT_NEAR(m.normal.z(), 1.0, 1e-12);
  ASSERT_EQ(m.points.size(), 4u);
  for (const auto& p : m.points) {
    EXPECT_NEAR(p.gap, 0.001, 1e-12);
    EXPECT_NEAR(p.on_a.z(), 0.0, 1e-12);
    EXPECT_LE(p.on_a.x(), 0.5 + 1e-12);  // clipped at the plate's edge
    EXPECT_GE(p.on_a.x(), 0.4 - 1e-12);
  }
  // overlapping: negative gaps of the penetration depth
  const ConvexPolytope sunk = box_at({0.2, 0.2, 0.2}, {0, 0, 0.098});
  const ContactManifold o = contact_manifold(plate, sunk, gjk_distance(plate, sunk));
  ASSERT_EQ(o.points.size(), 4u);
  for (const auto& p : o.points) EXPECT_NEAR(p.gap, -0.002, 1e-12);
}

TEST(ContactManifold, EdgeOnFaceGivesTwoPointsAndVertexOnFaceOne) {
  const ConvexPolytope plate = box_at({1, 1, 0.1}, {0, 0, -0.05});
  // a box turned 45 degrees about x: an edge along x at its bottom, 1 mm up
  Eigen::Isometry3d edge(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()));
  edge.pretranslate(Eigen::Vector3d(0, 0, 0.1 * std::sqrt(2.0) + 0.001));
  const ConvexPolytope e = posed_box({0.2, 0.2, 0.2}, edge);
  const ContactManifold me = contact_manifold(plate, e, gjk_distance(plate, e));
  ASSERT_EQ(me.points.size(), 2u);
  EXPECT_NEAR(std::abs(me.points[0].on_b.x() - me.points[1].on_b.x()), 0.2, 1e-12);
  for (const auto& p : me.points) EXPECT_NEAR(p.gap, 0.001, 1e-12);
  // a cube on its corner
  Eigen::Isometry3d corner(
      Eigen::AngleAxisd(std::atan(std::sqrt(2.0)), Eigen::Vector3d(1, -1, 0).normalized()));
  const ConvexPolytope c0 = posed_box({0.2, 0.2, 0.2}, corner);
  double lowest = 1e9;
  for (const auto& v : c0.vertices) lowest = std::min(lowest, v.z());
  Eigen::Isometry3d lifted = corner;
  lifted.pretranslate(Eigen::Vector3d(0, 0, 0.001 - lowest));
  const ConvexPolytope c = posed_box({0.2, 0.2, 0.2}, lifted);
  const ContactManifold mc = contact_manifold(plate, c, gjk_distance(plate, c));
  EXPECT_EQ(mc.feature, ContactFeature::kVertexFace);
  ASSERT_EQ(mc.points.size(), 1u);
  EXPECT_NEAR(mc.points[0].gap, 0.001, 1e-12);
}

TEST(ContactManifold, CrossingEdgesUseTheirCrossProduct) {
  // two boxes turned 45 degrees about x and about y: their edges cross at right angles
  const double half_diag = 0.1 * std::sqrt(2.0);
  const ConvexPolytope a = posed_box(
      {0.2, 0.2, 0.2}, Eigen::Isometry3d(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX())));
  Eigen::Isometry3d pb(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()));
  pb.pretranslate(Eigen::Vector3d(0, 0, 2 * half_diag + 0.003));
  const ConvexPolytope b = posed_box({0.2, 0.2, 0.2}, pb);
  const ContactManifold m = contact_manifold(a, b, gjk_distance(a, b));
  EXPECT_EQ(m.feature, ContactFeature::kEdgeEdge);
  EXPECT_NEAR(m.normal.z(), 1.0, 1e-12);  // E_AB x E_CD, from A to B
  ASSERT_EQ(m.points.size(), 1u);
  EXPECT_NEAR(m.points[0].gap, 0.003, 1e-12);
  EXPECT_NEAR(m.points[0].on_a.norm() - half_diag, 0.0, 1e-12);
}

}  // namespace
}  // namespace vproto::geometry
