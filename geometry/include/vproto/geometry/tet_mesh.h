#pragma once
// Tetrahedral meshes of closed solids (CGAL Mesh_3, sharp edges kept as features) for the
// finite-element solver, with quadratic (tet10) elements made by adding mid-edge nodes.

#include <vector>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

/// A volume mesh. Elements are 4 corner nodes (tet4) or 10 nodes (tet10) in VTK order:
/// corners 0-3, then mid-edge nodes of edges 01, 12, 20, 03, 13, 23. Every element is
/// positively oriented (det[x1-x0, x2-x0, x3-x0] > 0).
struct TetMesh {
  Eigen::MatrixX3d nodes;    ///< #N by 3, m
  Eigen::MatrixXi elements;  ///< #E by 4 or 10
  double mesh_size = 0;      ///< the size the mesher was asked for, m (the finest)
  double max_size = 0;       ///< the coarsest size of a graded mesh, m (0: uniform)
  long fine_faces = 0;       ///< surface triangles in the fine zone of a graded mesh
};

/// Quality figures of the linear tetrahedra (corner nodes).
struct TetQuality {
  double min_dihedral_angle = 0;     ///< degrees, over all elements
  double max_radius_edge_ratio = 0;  ///< circumradius / shortest edge; 0.61 for a regular tet
  double min_volume = 0;             ///< m^3; > 0 for a valid mesh
  double volume = 0;                 ///< m^3, total
};

struct TetMeshOptions {
  double size = 0;  ///< target edge length, m (> 0): the finest size
  /// Grading: when max_size > size, the size grows with the distance d from the fine
  /// zone as min(max_size, size + grading d). The fine zone is every surface triangle
  /// thinner than `thin_wall` (its wall, measured inward along its normal: the parts that
  /// bend) and the parts of the others inside `fine_boxes` (where other bodies can touch).
  double max_size = 0;
  double grading = 0.5;
  double thin_wall = 0;
  std::vector<Bounds> fine_boxes;
  bool quadratic = true;      ///< tet10 (true) or tet4
  double feature_angle = 30;  ///< degrees: edges whose faces turn more than this are kept sharp
  long max_elements = 3'000'000;
};

/// Meshes the closed, outward-oriented `surface`. Throws GeometryError when the size is
/// impossible (the estimate exceeds max_elements, or the body is too thin for it) or the
/// mesher produces no valid element.
TetMesh make_tet_mesh(const TriMesh& surface, const TetMeshOptions& options);

TetQuality tet_quality(const TetMesh& mesh);

/// A piece of a volume mesh: elements joined through shared faces (a shared edge or corner
/// does not join them: the elements could turn about it, and the stiffness is singular).
struct TetPiece {
  long elements = 0;
  Bounds box;  ///< of its corner nodes
};
/// The pieces of a mesh (`elements`' first four columns are the corners), largest first.
std::vector<TetPiece> tet_pieces(const Eigen::MatrixX3d& nodes, const Eigen::MatrixXi& elements);

/// How many separate pieces a surface has (triangles joined through shared vertices).
int surface_pieces(const TriMesh& surface);

/// Where rays from `origins` along `directions` (unit, one each) first meet a closed
/// surface: the distance to it, m, or infinity where a ray meets none. One AABB tree over
/// the surface serves all of them.
std::vector<double> ray_distances(const TriMesh& surface,
                                  const std::vector<Eigen::Vector3d>& origins,
                                  const std::vector<Eigen::Vector3d>& directions);

/// The surface's nearest triangle to a point: how far, and its outward unit normal.
struct NearestFace {
  double distance = 0;  ///< m
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};
std::vector<NearestFace> nearest_faces(const TriMesh& surface,
                                       const std::vector<Eigen::Vector3d>& points);

/// The smallest wall thickness of a solid: the shortest distance, over its faces, from a
/// face centre inward along the normal to the opposite surface, m.
double thinnest_wall(const TriMesh& surface);

/// The thinnest wall (as thinnest_wall) and the centre of the face it was measured from.
struct Wall {
  double thickness = 0;  ///< m; infinity for a solid with no measurable wall
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
};
Wall thinnest_wall_at(const TriMesh& surface);

}  // namespace vproto::geometry
