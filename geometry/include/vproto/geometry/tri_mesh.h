#pragma once
// The plain triangle-mesh type that crosses module boundaries (CGAL stays inside
// geometry's .cpp files).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace vproto::geometry {

/// A triangle mesh: V is #V by 3 vertex positions (m), F is #F by 3 vertex indices,
/// counter-clockwise seen from outside for a closed solid.
struct TriMesh {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;

  bool empty() const { return F.rows() == 0; }
};

/// Axis-aligned box; `lo` > `hi` componentwise when empty.
struct Bounds {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return (lo.array() > hi.array()).any(); }
  /// Closed-interval overlap: boxes that only touch overlap.
  bool overlaps(const Bounds& o) const {
    return !empty() && !o.empty() && (lo.array() <= o.hi.array()).all() &&
           (o.lo.array() <= hi.array()).all();
  }
  void extend(const Bounds& o) {
    lo = lo.cwiseMin(o.lo);
    hi = hi.cwiseMax(o.hi);
  }
};

/// A geometric operation that cannot produce a valid solid (degenerate or open input, an
/// empty result). Callers add where in the script it came from.
class GeometryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

Bounds bounds(const TriMesh& mesh);

/// Applies x -> A x + b to every vertex; a mirroring transform (det A < 0) also reverses
/// every triangle so the solid stays outward-oriented.
TriMesh transformed(const TriMesh& mesh, const Eigen::Affine3d& transform);

/// Disjoint union of meshes without any Boolean (vertex and face lists appended).
TriMesh concatenated(const TriMesh& a, const TriMesh& b);

/// The same surface in an order that depends on its geometry only: vertices sorted by
/// (x, y, z), each triangle rotated (orientation kept) to start at its smallest vertex,
/// triangles sorted. Libraries whose output order follows the heap (CGAL's corefinement
/// breaks ties between equal boxes by their addresses) give the same mesh every run.
TriMesh canonically_ordered(const TriMesh& mesh);

/// Total area of the triangles (m^2).
double surface_area(const TriMesh& mesh);

/// An edge of a surface (its two end points, m).
struct Edge {
  Eigen::Vector3d a, b;
  /// reentrant_edges: the outward unit normals of the edge's two faces, and the unit
  /// directions in each face's plane, square to the edge, from it into the face
  std::array<Eigen::Vector3d, 2> normal{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<Eigen::Vector3d, 2> into{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
};

/// The re-entrant (concave) edges of a closed, outward-oriented surface whose faces turn by
/// more than `min_turn_degrees` across them: where a linear-elastic solid's stress is
/// singular (an inside corner with no fillet, such as a snap-fit arm's root on its base).
/// Edges with other than two triangles are skipped.
std::vector<Edge> reentrant_edges(const TriMesh& mesh, double min_turn_degrees);

/// The distance from `p` to the nearest of `edges` (infinity when there is none).
double distance_to_edges(const std::vector<Edge>& edges, const Eigen::Vector3d& p);

}  // namespace vproto::geometry
