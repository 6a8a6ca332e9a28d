#pragma once
// Constructive solid geometry on closed triangle meshes with CGAL's Polygon Mesh
// Processing corefinement (exact predicates and exact constructions: intermediate results
// of one tree stay exact; rounding to double happens once, at the end).

#include <memory>
#include <vector>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

enum class BooleanOp { kUnion, kDifference, kIntersection };

/// A CSG tree: a leaf holds a closed mesh in its final position; an inner node combines
/// its children (difference: the first minus all the others).
struct CsgNode {
  BooleanOp op = BooleanOp::kUnion;
  TriMesh leaf;  ///< used when `children` is empty
  std::vector<CsgNode> children;

  static CsgNode make_leaf(TriMesh mesh) {
    CsgNode n;
    n.leaf = std::move(mesh);
    return n;
  }
};

/// Work counters of one evaluation, for reports and benchmarks.
struct CsgStats {
  int corefinements = 0;     ///< Boolean operations actually run through CGAL
  int skipped_disjoint = 0;  ///< operands combined or dropped by bounding boxes alone
};

/// Evaluates the tree into one closed, outward-oriented, 2-manifold mesh. Operand vertices
/// are first snapped to a power-of-two grid of about 6e-14 of the tree's extent, so that
/// near-coincident features (float noise) become exactly coincident. Operands whose
/// bounding boxes do not meet are appended or dropped without a Boolean; the subtrahends
/// of a difference are united first, so many holes take one corefinement. An empty
/// result is returned as an empty mesh; any other result has passed the checks of
/// solid_validation_error. Throws GeometryError when an operand is not a closed manifold
/// or the result is not a valid solid.
TriMesh evaluate_csg(const CsgNode& tree, CsgStats* stats = nullptr);

/// The same without the bounding-box skips and the batched difference: every operand goes
/// through its own Boolean, one after another (what the skips save, measured by `vproto
/// bench`; the result is the same solid).
TriMesh evaluate_csg_unskipped(const CsgNode& tree, CsgStats* stats = nullptr);

/// Why `mesh` does not bound a solid (not closed, not 2-manifold, self-intersecting,
/// inward-oriented, degenerate), or an empty string.
std::string solid_validation_error(const TriMesh& mesh);

/// Triangulates a simple polygon (#P by 2, counter-clockwise); returns #T by 3 indices.
Eigen::MatrixX3i triangulate_polygon(const Eigen::MatrixX2d& polygon);

}  // namespace vproto::geometry
