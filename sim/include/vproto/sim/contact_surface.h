#pragma once
// The part of an elastic body's volume mesh that takes part in contact (after
// ipc-toolkit's CollisionMesh): its boundary nodes and boundary triangles, and the
// contact points between that surface, deformed, and a rigid convex part.
//
// A quadratic (tet10) boundary face is split at its mid-edge nodes into four linear
// triangles, so the contact surface is piecewise linear over every boundary node and a
// contact force at a point spreads over the three nodes of its triangle by the linear
// shape functions (the seed's load distribution, Eq. 21).
//
// Two kinds of contact point, so that neither side can slip between the features of the
// other (DESIGN.md "Elastic bodies"):
//  - a surface node against the part: the node must stay outside the part, along the
//    normal of the part's closest feature (a face, or the line from a vertex or edge);
//  - a vertex or edge of the part against a surface triangle: the part's feature must stay
//    outside the elastic body, along the triangle's outward normal. This is what carries a
//    sharp rigid edge riding over an elastic face (a catch's edge over a hook's lead face).

#include <array>
#include <cstdint>
#include <vector>

#include "vproto/geometry/convex_distance.h"
#include "vproto/geometry/tet_mesh.h"

namespace vproto::sim {

struct ContactSurface {
  std::vector<int> nodes;  ///< volume-mesh node of each surface node
  /// Linear triangles over surface-node indices (#T by 3), normals pointing out.
  Eigen::MatrixX3i triangles;
  /// Per triangle, the triangle across its edge k (from corner k to corner k+1), or -1.
  Eigen::MatrixX3i neighbours;
  /// Per volume-mesh node: its surface-node index, or -1.
  std::vector<int> surface_index;
  /// Per surface node k, its neighbours along the triangles' edges:
  /// node_neighbours[node_neighbour_start[k] .. node_neighbour_start[k + 1]).
  std::vector<int> node_neighbour_start, node_neighbours;
};

/// The boundary of a tet4 or tet10 mesh as a contact surface.
ContactSurface make_contact_surface(const geometry::TetMesh& mesh);

/// The same boundary as a triangle mesh at the nodes' places (for drawing: Body::display).
geometry::TriMesh display_surface(const geometry::TetMesh& mesh);

/// One contact point between an elastic surface (side A) and a rigid part (side B). The
/// point on A is sum_k weights[k] x(nodes[k]) (surface-node indices, -1 unused); the
/// unilateral row is normal'(x_A - on_b) >= 0 with `normal` pointing from B towards A.
struct SurfaceContact {
  std::array<int, 3> nodes{-1, -1, -1};
  std::array<double, 3> weights{0, 0, 0};
  Eigen::Vector3d on_b = Eigen::Vector3d::Zero();  ///< world, on B's surface
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double gap = 0;        ///< normal'(x_A - on_b) now; negative when they overlap
  bool node_row = true;  ///< a surface node against the part (else a part feature on a triangle)
  /// A node row whose closest point on the part lies inside one of its faces; false: on an
  /// edge or a vertex, where the normal turns as the node moves past it.
  bool on_face = true;
  /// Identifies the point from step to step (for warm starts, and for telling a point
  /// found again from a new one), unique among one part's points: the surface node of a
  /// node row; for a part's feature on a triangle, -(1 + triangle F + feature) with F the
  /// part's vertices plus twice its edges, the feature its vertex or, for a point inside an
  /// edge, V + 2 edge + which end of the edge's stretch over the triangle. Two surfaces:
  /// A's node, 2^40 + B's node on A, or -(1 + A's edge, B's edge) for two crossing edges.
  std::int64_t key = 0;
  /// A part's feature on a triangle: the part's vertex, or the edge a point inside it is on
  /// (the other -1); -1 both for a node row.
  int part_vertex = -1, part_edge = -1;
};

/// The contact points between the surface, its nodes at world positions `x` (#surface
/// nodes by 3), and the convex `part` (world), whose gap is below the reach of their
/// nodes (`reach`, per surface node: how far it can move towards the part in the step).
/// Only the listed triangles (and their nodes) are examined (the broad phase's
/// candidates). A node takes the part only where it is the surface's extreme point
/// towards the part (within 10 degrees of its neighbours). A part's vertex or edge takes a triangle
/// only where it supports the part in the direction of the triangle (within 10 degrees): the part
/// lies beyond the triangle there, not across it.
std::vector<SurfaceContact> surface_part_contacts(const ContactSurface& surface,
                                                  const Eigen::MatrixX3d& x,
                                                  const geometry::ConvexPolytope& part,
                                                  const std::vector<int>& triangles,
                                                  const Eigen::VectorXd& reach);

/// One contact point between two elastic surfaces: side A's point and normal as in
/// SurfaceContact (`on_b` the point on B, `normal` from B towards A), and B's point as
/// sum_k b_weights[k] x_B(b_nodes[k]).
struct SurfacePairContact {
  SurfaceContact a;
  std::array<int, 3> b_nodes{-1, -1, -1};
  std::array<double, 3> b_weights{0, 0, 0};
  /// true: a node of A on a triangle of B (a.key is A's node); false: a node of B on a
  /// triangle of A (a.key is B's node).
  bool a_node = true;
};

/// The contact points between two elastic surfaces (world positions `xa`, `xb`, #surface
/// nodes by 3), in both directions: each surface's nodes against the other's triangles (a
/// node takes the triangle whose prism holds it, the nearest one, with the triangle's
/// outward normal), so that neither surface's nodes can slip between the other's. Only
/// the listed candidate triangles of each side (and their nodes) are examined; a point is
/// kept when its gap is below its node's reach and it lies above the triangle or at most
/// the reach (or a quarter of the triangle's size) below it. As for a rigid part, a node
/// takes the other surface only where it is its own surface's extreme point towards it and
/// its surface faces it (within 10 degrees). A node of B whose foot on A is a node of A that
/// already has a point is left out (the same point twice).
std::vector<SurfacePairContact> surface_surface_contacts(
    const ContactSurface& a, const Eigen::MatrixX3d& xa, const std::vector<int>& a_triangles,
    const Eigen::VectorXd& a_reach, const ContactSurface& b, const Eigen::MatrixX3d& xb,
    const std::vector<int>& b_triangles, const Eigen::VectorXd& b_reach);

/// Whether `p` lies inside the closed surface (its nodes at `x`) farther than `depth` from
/// it: the parity of a ray's crossings of the triangles, then the distance to the nearest.
bool deep_inside(const ContactSurface& surface, const Eigen::MatrixX3d& x, const Eigen::Vector3d& p,
                 double depth);

/// The closest point of a convex polytope to `p` when `p` is outside (distance > 0), or,
/// when inside, the foot of `p` on the face it is least deep under (distance < 0, minus
/// that depth). `normal`: unit, from the polytope towards p.
double signed_distance(const geometry::ConvexPolytope& part, const Eigen::Vector3d& p,
                       Eigen::Vector3d* closest, Eigen::Vector3d* normal, bool* on_face);

}  // namespace vproto::sim
