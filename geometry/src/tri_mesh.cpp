#include "vproto/geometry/tri_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
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

std::vector<Edge> reentrant_edges(const TriMesh& mesh, double min_turn_degrees) {
  // each undirected edge with the triangles on it (the third vertex of each)
  std::map<std::pair<int, int>, std::vector<std::pair<Eigen::Index, int>>> faces_of;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = mesh.F(f, k), v = mesh.F(f, (k + 1) % 3);
      faces_of[{std::min(u, v), std::max(u, v)}].emplace_back(f, mesh.F(f, (k + 2) % 3));
    }
  auto normal = [&](Eigen::Index f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                          c = mesh.V.row(mesh.F(f, 2));
    return (b - a).cross(c - a).normalized().eval();
  };
  const double cos_turn = std::cos(min_turn_degrees * std::acos(-1.0) / 180);
  std::vector<Edge> out;
  for (const auto& [edge, faces] : faces_of) {
    if (faces.size() != 2) continue;
    const Eigen::Vector3d a = mesh.V.row(edge.first), b = mesh.V.row(edge.second);
    const Eigen::Vector3d n1 = normal(faces[0].first), n2 = normal(faces[1].first);
    if (!(n1.dot(n2) < cos_turn)) continue;  // flat enough (or a degenerate triangle)
    // concave: the second triangle's far vertex lies outside the first one's plane
    const Eigen::Vector3d c2 = mesh.V.row(faces[1].second);
    if (!(n1.dot(c2 - a) > 1e-9 * (b - a).norm())) continue;
    Edge e{a, b};
    const Eigen::Vector3d along = (b - a).normalized();
    for (int k = 0; k < 2; ++k) {
      e.normal[static_cast<std::size_t>(k)] = k == 0 ? n1 : n2;
      Eigen::Vector3d into = (k == 0 ? n1 : n2).cross(along).normalized();
      const Eigen::Vector3d far = mesh.V.row(faces[static_cast<std::size_t>(k)].second);
      if (into.dot(far - a) < 0) into = -into;  // towards the face's third vertex
      e.into[static_cast<std::size_t>(k)] = into;
    }
    out.push_back(e);
  }
  return out;
}

double distance_to_edges(const std::vector<Edge>& edges, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Edge& e : edges) {
    const Eigen::Vector3d d = e.b - e.a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - e.a).dot(d) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (e.a + t * d - p).norm());
  }
  return best;
}

}  // namespace vproto::geometry
