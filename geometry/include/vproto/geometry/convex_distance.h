#pragma once
// Minimum distance between convex polytopes (the narrow phase of contact detection), by
// two independent methods that must agree:
//  - GJK on the Minkowski difference (the fast path), with witness points from the
//    barycentric coordinates of the final simplex;
//  - the seed's quadratic program (Fang & Liou, Eqs. 12-15): min 1/2 |x - y|^2 with x in
//    A's face half-spaces and y in B's, solved by an active-set projection method started
//    where the line between the centroids crosses each surface.
// When the polytopes overlap, both report distance 0 and the penetration depth: the
// smallest translation that separates them, found over the face normals of both and the
// cross products of their edges (for polytopes the exact minimum lies on one of these).

#include <vector>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

/// A convex polytope in world coordinates: its vertices (for support queries), its face
/// planes n.x <= d with unit n (for the QP and separating axes), its edge directions, and
/// its centroid.
struct ConvexPolytope {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> offsets;
  std::vector<Eigen::Vector3d> edges;  ///< unit directions of edges between distinct faces
  /// Vertex adjacency of the surface (support queries climb it: a linear function has no
  /// local maximum on a convex polytope other than the global one).
  std::vector<std::vector<int>> neighbours;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

/// The polytope of a closed convex triangle mesh (coplanar triangles merged into one
/// plane). Throws GeometryError for an empty mesh.
ConvexPolytope make_polytope(const TriMesh& convex_mesh);

/// The polytope moved rigidly by `pose`.
ConvexPolytope transformed(const ConvexPolytope& p, const Eigen::Isometry3d& pose);

struct ConvexDistance {
  double distance = 0;                                ///< >= 0; 0 when touching or overlapping
  Eigen::Vector3d point_a = Eigen::Vector3d::Zero();  ///< witness on A (closest to B)
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();  ///< witness on B
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();   ///< unit, from A towards B
  bool overlap = false;
  double penetration = 0;  ///< when overlapping: depth along `normal`
  int iterations = 0;
};

/// GJK. `tolerance`: relative accuracy of the distance.
ConvexDistance gjk_distance(const ConvexPolytope& a, const ConvexPolytope& b,
                            double tolerance = 1e-13);

/// The seed's quadratic program, solved exactly by an active-set method.
ConvexDistance qp_distance(const ConvexPolytope& a, const ConvexPolytope& b);

/// Penetration depth and direction (from A towards B) of two overlapping polytopes by
/// separating axes; depth <= 0 means they do not overlap.
double penetration_depth(const ConvexPolytope& a, const ConvexPolytope& b, Eigen::Vector3d* normal);

}  // namespace vproto::geometry
