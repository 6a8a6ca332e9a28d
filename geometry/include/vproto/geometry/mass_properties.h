#pragma once
// Mass properties of a closed polyhedron, exact for the polyhedron (divergence theorem
// over the tetrahedra that each triangle spans with a reference point).

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

struct MassProperties {
  double volume = 0;                                   ///< m^3
  double area = 0;                                     ///< m^2
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< m
  /// Inertia tensor about the centroid in world axes for unit density (m^5); multiply by
  /// the density for kg m^2.
  Eigen::Matrix3d unit_inertia = Eigen::Matrix3d::Zero();
};

/// Requires a closed, outward-oriented mesh (volume > 0).
MassProperties mass_properties(const TriMesh& mesh);

}  // namespace vproto::geometry
