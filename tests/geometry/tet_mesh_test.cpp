#include "vproto/geometry/tet_mesh.h"

#include <gtest/gtest.h>

#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"

namespace vproto::geometry {
namespace {

TEST(TetMesh, BoxIsFilledExactlyWithPositiveElements) {
  const TriMesh box = make_box({0.2, 0.05, 0.05}, false);
  TetMeshOptions o;
  o.size = 0.01;
  const TetMesh m = make_tet_mesh(box, o);
  ASSERT_EQ(m.elements.cols(), 10);
  const TetQuality q = tet_quality(m);
  EXPECT_NEAR(q.volume, 0.2 * 0.05 * 0.05, 1e-9 * 0.2 * 0.05 * 0.05);
  EXPECT_GT(q.min_volume, 0);
  EXPECT_GT(q.min_dihedral_angle, 5);
  EXPECT_LT(q.max_radius_edge_ratio, 5);
  // mid-edge nodes sit at the middle of their edges, in VTK order
  static constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (Eigen::Index e = 0; e < m.elements.rows(); e += 97)
    for (int k = 0; k < 6; ++k) {
      const Eigen::RowVector3d expected = 0.5 * (m.nodes.row(m.elements(e, kEdges[k][0])) +
                                                 m.nodes.row(m.elements(e, kEdges[k][1])));
      EXPECT_LT((m.nodes.row(m.elements(e, 4 + k)) - expected).norm(), 1e-15);
    }
  // every node lies in the box
  EXPECT_GE(m.nodes.minCoeff(), -1e-12);
  o.quadratic = false;
  EXPECT_EQ(make_tet_mesh(box, o).elements.cols(), 4);
}

// the mean corner-edge length of the elements whose centroids `where` selects
template <typename Where>
double mean_edge(const TetMesh& m, Where where) {
  double sum = 0;
  int count = 0;
  for (Eigen::Index e = 0; e < m.elements.rows(); ++e) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += 0.25 * m.nodes.row(m.elements(e, k)).transpose();
    if (!where(c)) continue;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        sum += (m.nodes.row(m.elements(e, a)) - m.nodes.row(m.elements(e, b))).norm();
        ++count;
      }
  }
  return count ? sum / count : 0.0;
}

// A graded mesh is fine where another body can touch it, even on a face that reaches
// far out of that zone (only the part inside is fine: the face's centre is elsewhere).
TEST(TetMesh, GradedMeshIsFineOnThePartOfALongFaceInsideTheZone) {
  // a bar 0.5 long, 0.1 thick; the zone covers a band of its top face, and no face's centre
  const TriMesh bar = make_box({0.5, 0.1, 0.1}, false);
  TetMeshOptions o;
  o.size = 0.01;
  o.quadratic = false;
  o.max_size = 0.04;
  o.thin_wall = 0.04;  // the bar is thicker: only the zone is fine
  Bounds zone;
  zone.lo = Eigen::Vector3d(0.2, -0.01, 0.09);
  zone.hi = Eigen::Vector3d(0.3, 0.11, 0.11);
  o.fine_boxes.push_back(zone);
  const TetMesh m = make_tet_mesh(bar, o);
  EXPECT_GT(m.fine_faces, 0);
  const double near = mean_edge(
      m, [](const Eigen::Vector3d& c) { return c.x() > 0.22 && c.x() < 0.28 && c.z() > 0.08; });
  const double far = mean_edge(m, [](const Eigen::Vector3d& c) { return c.x() > 0.42; });
  EXPECT_LT(near, 2.2 * o.size);  // CGAL's sizes bound radii: edges come out about twice
  EXPECT_GT(far, 1.5 * near);
}

// Refining mesh_size never coarsens a graded mesh: a wall just thicker than the thin-wall
// threshold keeps four elements across (it was meshed at up to 4 sizes, coarser than at
// a larger mesh_size that made it thin).
TEST(TetMesh, GradedWallsDoNotCoarsenAsTheSizeFalls) {
  const TriMesh beam = make_box({0.00635, 0.0127, 0.0508}, false);  // the paw: 1/4 x 1/2 x 2 in
  long last = 0;
  for (const double h : {0.00254, 0.001778, 0.00127}) {
    TetMeshOptions o;
    o.size = h;
    o.quadratic = false;
    o.max_size = 4 * h;
    o.thin_wall = 4 * h;
    const TetMesh m = make_tet_mesh(beam, o);
    SCOPED_TRACE(h);
    EXPECT_GT(m.elements.rows(), last);
    last = m.elements.rows();
    // across the 6.35 mm wall: elements of about a quarter of it (or the size), in the bulk
    const double bulk = mean_edge(m, [](const Eigen::Vector3d& c) { return c.z() > 0.02; });
    EXPECT_LT(bulk, 2.2 * std::max(h, 0.00635 / 4));
  }
}

TEST(TetMesh, SharpFeaturesOfA45DegreeHookSurvive) {
  // a paw with a hook whose lead face meets it at 45 degrees (the snap-fit's)
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.linear() << -1, 0, 0, 0, 1, 0, 0, 0, -1;
  t.translation() << 0, 0, 0.0025;
  CsgNode tree;
  tree.children.push_back(CsgNode::make_leaf(make_box({0.0127, 0.0127, 0.05}, false)));
  tree.children.push_back(CsgNode::make_leaf(transformed(make_wedge({0.0025, 0.0127, 0.0025}), t)));
  const TriMesh paw = evaluate_csg(tree);
  TetMeshOptions o;
  o.size = 0.003;
  const TetMesh m = make_tet_mesh(paw, o);
  // the hook's corners are mesh nodes
  for (const Eigen::Vector3d& corner :
       {Eigen::Vector3d(-0.0025, 0, 0.0025), Eigen::Vector3d(-0.0025, 0.0127, 0.0025),
        Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0.0127, 0)}) {
    const double nearest = (m.nodes.rowwise() - corner.transpose()).rowwise().norm().minCoeff();
    EXPECT_LT(nearest, 1e-9) << corner.transpose();
  }
  const double v = mass_properties(paw).volume;
  EXPECT_NEAR(tet_quality(m).volume, v, 1e-6 * v);
  EXPECT_GT(tet_quality(m).min_volume, 0);
}

TEST(TetMesh, ImpossibleSizesAreRefusedBeforeMeshing) {
  const TriMesh plate = make_box({1, 1, 0.01}, false);
  TetMeshOptions o;
  o.size = 0.05;  // thicker than the plate
  EXPECT_THROW(make_tet_mesh(plate, o), GeometryError);
  o.size = 1e-4;  // billions of elements
  EXPECT_THROW(make_tet_mesh(plate, o), GeometryError);
}

// A mesh's pieces are joined through shared faces only: two tetrahedra that share an edge
// (or a corner) are two pieces, as their stiffness cannot hold one against the other's
// turning about it; sharing a face they are one. A surface's pieces join through vertices.
TEST(TetMesh, PiecesAreJoinedThroughFacesOnly) {
  Eigen::MatrixX3d nodes(6, 3);
  nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 0, 0, -1;
  Eigen::MatrixXi elements(2, 4);
  elements << 0, 1, 2, 3, 0, 1, 4, 5;  // sharing the edge 0-1
  std::vector<TetPiece> pieces = tet_pieces(nodes, elements);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].elements + pieces[1].elements, 2);
  elements << 0, 1, 2, 3, 0, 2, 1, 5;  // sharing the face 0-1-2
  pieces = tet_pieces(nodes, elements);
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(pieces[0].elements, 2);
  EXPECT_EQ(pieces[0].box.lo, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(pieces[0].box.hi, Eigen::Vector3d(1, 1, 1));
  // a box is one piece, two boxes apart two, and the mesh of both holds two
  const TriMesh box = make_box({0.1, 0.1, 0.1}, false);
  TriMesh both = box;
  both.V.conservativeResize(2 * box.V.rows(), 3);
  both.V.bottomRows(box.V.rows()) = box.V.rowwise() + Eigen::RowVector3d(0.3, 0, 0);
  both.F.conservativeResize(2 * box.F.rows(), 3);
  both.F.bottomRows(box.F.rows()) = box.F.array() + static_cast<int>(box.V.rows());
  EXPECT_EQ(surface_pieces(box), 1);
  EXPECT_EQ(surface_pieces(both), 2);
  TetMeshOptions o;
  o.size = 0.04;
  o.quadratic = false;
  const TetMesh m = make_tet_mesh(both, o);
  EXPECT_EQ(tet_pieces(m.nodes, m.elements).size(), 2u);
}

// The element guard counts a graded mesh by its sizes: a plate meshed fine only at one
// corner is allowed where the same size throughout would exceed the limit (the snap-fit
// socket at mesh_size 0.1 in has 37,796 tetrahedra; the uniform count, 4.3 million, refused
// it until 2026-11-27).
TEST(TetMesh, AGradedMeshIsCountedByItsSizes) {
  const TriMesh plate = make_box({0.2, 0.2, 0.05}, false);
  TetMeshOptions o;
  o.size = 0.005;  // 8.5 V / h^3 = 136,000 throughout
  o.quadratic = false;
  o.max_elements = 50'000;
  EXPECT_THROW(make_tet_mesh(plate, o), GeometryError);
  o.max_size = 0.02;
  Bounds corner;
  corner.lo = Eigen::Vector3d(-0.01, -0.01, -0.01);
  corner.hi = Eigen::Vector3d(0.03, 0.03, 0.06);
  o.fine_boxes.push_back(corner);
  const TetMesh m = make_tet_mesh(plate, o);
  EXPECT_GT(m.elements.rows(), 1000);
  EXPECT_LT(m.elements.rows(), 50'000);
}

TEST(TetMesh, ThinnestWall) {
  EXPECT_NEAR(thinnest_wall(make_box({1, 0.2, 0.5}, false)), 0.2, 1e-12);
  CsgNode tube;
  tube.op = BooleanOp::kDifference;
  tube.children.push_back(CsgNode::make_leaf(make_box({1, 1, 1}, true)));
  tube.children.push_back(CsgNode::make_leaf(make_box({0.8, 0.9, 2}, true)));
  EXPECT_NEAR(thinnest_wall(evaluate_csg(tube)), 0.05, 1e-12);
  // where: on one of the box's two faces 0.2 apart (y = 0 or 0.2), inside their extent
  const Wall wall = thinnest_wall_at(make_box({1, 0.2, 0.5}, false));
  EXPECT_NEAR(wall.thickness, 0.2, 1e-12);
  EXPECT_NEAR(std::min(std::abs(wall.at.y()), std::abs(wall.at.y() - 0.2)), 0, 1e-12);
  EXPECT_GT(wall.at.x(), 0);
  EXPECT_LT(wall.at.x(), 1);
  EXPECT_GT(wall.at.z(), 0);
  EXPECT_LT(wall.at.z(), 0.5);
}

}  // namespace
}  // namespace vproto::geometry
