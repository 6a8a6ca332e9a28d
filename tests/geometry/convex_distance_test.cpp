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

}  // namespace
}  // namespace vproto::geometry
