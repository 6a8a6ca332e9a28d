// The hot-spot stress at sharp inside corners (hot_spot.h): where it is read, and that the
// extrapolation returns the surface field at the corner for a field linear along the face.
#include "vproto/sim/hot_spot.h"

#include <gtest/gtest.h>

#include "vproto/geometry/csg.h"
#include "vproto/geometry/primitives.h"

namespace vproto::sim {
namespace {

geometry::TriMesh box_at(const Eigen::Vector3d& lo, const Eigen::Vector3d& size) {
  return geometry::transformed(geometry::make_box(size, false),
                               Eigen::Affine3d(Eigen::Translation3d(lo)));
}

// an L of 20 mm square sections: a foot along x from 0 to `foot` (m), a leg 60 mm tall on
// its first 20 mm; the inside corner's edge runs along y at x = z = 20 mm
geometry::TriMesh l_bracket(double foot) {
  geometry::CsgNode n;
  n.op = geometry::BooleanOp::kUnion;
  n.children.push_back(geometry::CsgNode::make_leaf(box_at({0, 0, 0}, {foot, 0.02, 0.02})));
  n.children.push_back(geometry::CsgNode::make_leaf(box_at({0, 0, 0.02}, {0.02, 0.02, 0.06})));
  return geometry::evaluate_csg(n);
}

geometry::TetMesh tet10(const geometry::TriMesh& s, double h) {
  geometry::TetMeshOptions o;
  o.size = h;
  o.quadratic = true;
  return geometry::make_tet_mesh(s, o);
}

// u_x = a x z, u_z = -a x^2 / 2: the only strain is e_xx = a z, linear (a tet10 carries it
// exactly). Up the leg's face it grows from the corner; along the foot's top it is a z0.
// Both faces' reads extrapolate to a z0 at the corner (z0 = 20 mm), and the von Mises
// stress of that uniaxial strain is 2 mu a z0.
TEST(HotSpot, ExtrapolatesALinearFieldToItsValueAtTheCorner) {
  const geometry::TriMesh l = l_bracket(0.06);
  const geometry::TetMesh m = tet10(l, 0.005);
  const TetLocator locator(m);
  const std::vector<CornerRead> reads = corner_reads(l, locator, 0.005);
  // every 5 mm or less along the 20 mm edge (its pieces, as the union split it), both faces
  ASSERT_GE(reads.size(), 8u);
  int up_the_leg = 0;
  for (const CornerRead& r : reads) {
    EXPECT_NEAR(r.corner.x(), 0.02, 1e-12);
    EXPECT_NEAR(r.corner.z(), 0.02, 1e-12);
    EXPECT_NEAR(r.wall, 0.02, 1e-9);  // both walls are 20 mm thick
    up_the_leg += r.into.isApprox(Eigen::Vector3d::UnitZ(), 1e-12);
    EXPECT_TRUE(r.into.isApprox(Eigen::Vector3d::UnitZ(), 1e-12) ||
                r.into.isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  }
  EXPECT_EQ(2 * up_the_leg, static_cast<int>(reads.size()));
  const double a = 1e-2, e = 2e11, nu = 0.3;
  Eigen::VectorXd u(3 * m.nodes.rows());
  for (Eigen::Index v = 0; v < m.nodes.rows(); ++v) {
    const double x = m.nodes(v, 0), z = m.nodes(v, 2);
    u.segment<3>(3 * v) = Eigen::Vector3d(a * x * z, 0, -a * x * x / 2);
  }
  const CornerHotSpot hot = corner_hot_spot(reads, m, u, e, nu);
  EXPECT_NEAR(hot.strain, a * 0.02, 1e-9 * a);
  EXPECT_NEAR(hot.von_mises, e / (1 + nu) * a * 0.02, 1e-9 * e * a);
  // the read at 0.4 t alone would say 1.4 times as much on the leg's face
  const CornerRead& leg = *std::find_if(reads.begin(), reads.end(), [](const CornerRead& r) {
    return r.into.isApprox(Eigen::Vector3d::UnitZ(), 1e-12);
  });
  EXPECT_NEAR(element_strain_at(m, u, leg.near.element, leg.near.barycentric)[0], a * 0.028,
              1e-9 * a);
  // peaks: where and when, and past the yield strain of 1e-4
  MaterialPeaks peaks;
  track_corner_peaks(reads, hot, std::nullopt, 1e-4, 0.5, &peaks);
  EXPECT_EQ(peaks.corner_strain.value, hot.strain);
  EXPECT_EQ(peaks.corner_strain.time, 0.5);
  EXPECT_TRUE(peaks.corner_strain.at_sharp_corner);
  EXPECT_NEAR(peaks.corner_strain.at.z(), 0.02, 1e-12);
  EXPECT_EQ(peaks.corner_yielded_at, 0.5);
  // a contact pressing at every read leaves none to read
  std::vector<Eigen::Vector3d> pressed;
  for (const CornerRead& r : reads) pressed.push_back(r.corner + 0.4 * r.wall * r.into);
  const CornerHotSpot none = corner_hot_spot(reads, m, u, e, nu, pressed, 0.002);
  EXPECT_EQ(none.strain_read, -1);
  EXPECT_EQ(none.von_mises_read, -1);
}

// A face that ends before 1.0 t from the edge has no reads: a foot reaching 10 mm past the
// leg, under its 20 mm wall, is read on the leg's face only.
TEST(HotSpot, AFaceShorterThanItsWallIsNotRead) {
  const geometry::TriMesh l = l_bracket(0.03);
  const geometry::TetMesh m = tet10(l, 0.005);
  const std::vector<CornerRead> reads = corner_reads(l, TetLocator(m), 0.005);
  ASSERT_GE(reads.size(), 4u);
  for (const CornerRead& r : reads) EXPECT_TRUE(r.into.isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  // a box has no sharp inside corner
  const geometry::TriMesh box = geometry::make_box({0.02, 0.02, 0.02}, false);
  const geometry::TetMesh bm = tet10(box, 0.005);
  EXPECT_TRUE(corner_reads(box, TetLocator(bm), 0.005).empty());
}

}  // namespace
}  // namespace vproto::sim
