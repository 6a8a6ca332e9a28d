#pragma once
// Splitting a solid into convex parts for contact detection.

#include <vector>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

/// Exact convex decomposition (CGAL Nef polyhedra, convex_decomposition_3): each part is
/// returned as the closed triangle mesh of its convex hull; the parts' volumes add up to
/// the solid's. A solid that is already convex is returned as one part without building
/// a Nef polyhedron.
std::vector<TriMesh> convex_parts(const TriMesh& solid);

/// True when the closed mesh equals its convex hull (volumes agree to 1e-12 relative).
bool is_convex(const TriMesh& solid);

}  // namespace vproto::geometry
