#include "vproto/geometry/tri_mesh.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <vector>

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

TriMesh canonically_ordered(const TriMesh& mesh) {
  const Eigen::Index n = mesh.V.rows();
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  // stable: vertices at one position (not in a valid solid) keep their relative order
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (mesh.V(a, k) != mesh.V(b, k)) return mesh.V(a, k) < mesh.V(b, k);
    return false;
  });
  std::vector<int> rank(static_cast<std::size_t>(n));
  TriMesh out;
  out.V.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    rank[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])] = static_cast<int>(i);
    out.V.row(i) = mesh.V.row(order[static_cast<std::size_t>(i)]);
  }
  std::vector<std::array<int, 3>> tris(static_cast<std::size_t>(mesh.F.rows()));
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    std::array<int, 3> t;
    for (int k = 0; k < 3; ++k) t[k] = rank[static_cast<std::size_t>(mesh.F(f, k))];
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    tris[static_cast<std::size_t>(f)] = t;
  }
  std::sort(tris.begin(), tris.end());
  out.F.resize(mesh.F.rows(), 3);
  for (std::size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) out.F(static_cast<Eigen::Index>(f), k) = tris[f][k];
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
