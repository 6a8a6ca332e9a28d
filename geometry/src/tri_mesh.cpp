#include "vproto/geometry/tri_mesh.h"

namespace vproto::geometry {

Bounds bounds(const TriMesh& mesh) {
  Bounds b;
  if (mesh.V.rows() == 0) return b;
  b.lo = mesh.V.colwise().minCoeff().transpose();
  b.hi = mesh.V.colwise().maxCoeff().transpose();
  return b;
}

TriMesh transformed(const TriMesh& mesh, const Eigen::Affine3d& transform) {
  TriMesh out;
  out.V = (mesh.V * transform.linear().transpose()).rowwise() + transform.translation().transpose();
  out.F = mesh.F;
  // a mirror turns the solid inside out: restore outward orientation
  if (transform.linear().determinant() < 0) out.F.col(1).swap(out.F.col(2));
  return out;
}

TriMesh concatenated(const TriMesh& a, const TriMesh& b) {
  TriMesh out;
  out.V.resize(a.V.rows() + b.V.rows(), 3);
  out.V << a.V, b.V;
  out.F.resize(a.F.rows() + b.F.rows(), 3);
  out.F << a.F, (b.F.array() + static_cast<int>(a.V.rows())).matrix();
  return out;
}

double surface_area(const TriMesh& mesh) {
  double area = 0;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0));
    const Eigen::Vector3d b = mesh.V.row(mesh.F(f, 1));
    const Eigen::Vector3d c = mesh.V.row(mesh.F(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

}  // namespace vproto::geometry
