#pragma once
// Private to geometry: CGAL Surface_mesh to TriMesh, shared by the CGAL translation units.

#include <CGAL/boost/graph/iterator.h>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry::detail {

/// Copies a triangulated Surface_mesh (garbage collected first) into a TriMesh, turning
/// each coordinate into a double with `to_double`. Throws GeometryError on a face that is
/// not a triangle.
template <typename Mesh, typename Convert>
TriMesh to_trimesh(Mesh& mesh, Convert to_double) {
  mesh.collect_garbage();
  TriMesh tm;
  tm.V.resize(static_cast<Eigen::Index>(mesh.number_of_vertices()), 3);
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    tm.V.row(v.idx()) << to_double(p.x()), to_double(p.y()), to_double(p.z());
  }
  tm.F.resize(static_cast<Eigen::Index>(mesh.number_of_faces()), 3);
  for (auto f : mesh.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      if (k < 3) tm.F(f.idx(), k) = static_cast<int>(v.idx());
      ++k;
    }
    if (k != 3) throw GeometryError("a face of the result is not a triangle");
  }
  return tm;
}

}  // namespace vproto::geometry::detail
