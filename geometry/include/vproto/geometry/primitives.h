#pragma once
// Closed, outward-oriented triangle meshes of the script's primitives (spec "Solids").
// Round solids are faceted with their vertices on the true surface, a vertex at angle 0.

#include <vector>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

/// Rectangular block of `size` (all > 0); min corner at the origin or centred.
TriMesh make_box(const Eigen::Vector3d& size, bool center);

/// Frustum along +z of height h with bottom radius r1 and top radius r2 (one may be 0,
/// a cone), `segments` >= 3 vertices per ring; base centre at the origin or centred in z.
TriMesh make_cylinder(double height, double r1, double r2, int segments, bool center);

/// Sphere of radius r centred at the origin: (segments+1)/2 rings of `segments` vertices
/// at polar angles 180 (i + 1/2) / rings degrees, as OpenSCAD facets it.
TriMesh make_sphere(double radius, int segments);

/// Right triangular prism: triangle (0,0), (x,0), (0,z) in the xz-plane extruded along +y.
TriMesh make_wedge(const Eigen::Vector3d& size);

/// A simple polygon (#P by 2, either orientation, no repeated points) extruded along +z
/// by `height`. Throws GeometryError when the polygon is not simple or has no area.
TriMesh make_prism(const Eigen::MatrixX2d& polygon, double height);

/// The number of segments that keeps the chordal error (r - r cos(pi/N)) of a circle of
/// radius r below `relative_error` r; at least 8 and a multiple of 4.
int default_segments(double relative_error = 0.005);

}  // namespace vproto::geometry
