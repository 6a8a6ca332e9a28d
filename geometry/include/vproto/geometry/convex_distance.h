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
  /// Each plane's face as a polygon of vertex indices, counter-clockwise about its normal.
  std::vector<std::vector<int>> faces;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

/// The polytope of a closed convex triangle mesh (coplanar triangles merged into one
/// plane). Throws GeometryError for an empty mesh.
ConvexPolytope make_polytope(const TriMesh& convex_mesh);

/// The polytope moved rigidly by `pose`.
ConvexPolytope transformed(const ConvexPolytope& p, const Eigen::Isometry3d& pose);

/// `p` moved rigidly by `pose` into `*world`, reusing its storage: `*world` is empty or was
/// placed from the same `p` before, whose adjacency and faces it then keeps (a narrow phase
/// placing every part each step allocates nothing after the first).
void place(const ConvexPolytope& p, const Eigen::Isometry3d& pose, ConvexPolytope* world);

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

/// Where two convex polytopes touch or nearly touch, as the seed's contact features: a
/// vertex on a face and edge on edge give one point (edge-edge with the normal E_AB x E_CD
/// of Eq. 17; vertex on edge or vertex take the witness line), face on face a contact polygon (B's
/// face clipped by A's, a point per corner). Each point has its place on A and on B and the gap
/// n'(on_b - on_a), negative when they overlap; `normal` points from A towards B.
struct ContactPoint {
  Eigen::Vector3d on_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d on_b = Eigen::Vector3d::Zero();
  double gap = 0;
};
/// kVertexVertex: a vertex on an edge or a vertex (the indeterminate cases), normal along
/// the witness line.
enum class ContactFeature { kVertexFace, kFaceVertex, kEdgeEdge, kFaceFace, kVertexVertex };
struct ContactManifold {
  ContactFeature feature = ContactFeature::kVertexFace;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  std::vector<ContactPoint> points;
};

/// The manifold of a pair whose distance (or overlap) `d` is known. Faces count as
/// parallel to the normal within `angle_tolerance` (radians).
ContactManifold contact_manifold(const ConvexPolytope& a, const ConvexPolytope& b,
                                 const ConvexDistance& d, double angle_tolerance = 1e-3);

/// Penetration depth and direction (from A towards B) of two overlapping polytopes by
/// separating axes; depth <= 0 means they do not overlap.
double penetration_depth(const ConvexPolytope& a, const ConvexPolytope& b, Eigen::Vector3d* normal);

}  // namespace vproto::geometry
