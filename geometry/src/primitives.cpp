#include "vproto/geometry/primitives.h"

#include <cmath>
#include <utility>
#include <vector>

#include "vproto/geometry/csg.h"

namespace vproto::geometry {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Builds a mesh from vertex rows and faces (triangles or convex planar polygons, fanned),
// then turns every triangle to face away from the vertex mean. Only valid for convex
// solids, where the vertex mean is an interior point.
TriMesh convex_solid(const std::vector<Eigen::Vector3d>& verts,
                     const std::vector<std::vector<int>>& faces) {
  TriMesh m;
  m.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < verts.size(); ++i) {
    m.V.row(static_cast<Eigen::Index>(i)) = verts[i].transpose();
    mean += verts[i];
  }
  mean /= static_cast<double>(verts.size());
  std::vector<Eigen::Vector3i> tris;
  for (const auto& poly : faces)
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      tris.emplace_back(poly[0], poly[k], poly[k + 1]);
  m.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    Eigen::Vector3i tri = tris[t];
    const Eigen::Vector3d& a = verts[tri[0]];
    const Eigen::Vector3d& b = verts[tri[1]];
    const Eigen::Vector3d& c = verts[tri[2]];
    if ((b - a).cross(c - a).dot(a - mean) < 0) std::swap(tri[1], tri[2]);
    m.F.row(static_cast<Eigen::Index>(t)) = tri.transpose();
  }
  return m;
}

// cos and sin of 2 pi i / n, exact where the angle is a multiple of 90 degrees
std::pair<double, double> ring_cos_sin(int i, int n) {
  if ((4 * i) % n == 0) {
    static constexpr double kCos[4] = {1, 0, -1, 0};
    const int q = (4 * i / n) % 4;
    return {kCos[q], kCos[(q + 3) % 4]};
  }
  const double a = 2 * kPi * i / n;
  return {std::cos(a), std::sin(a)};
}

// Adds a ring of `n` vertices of radius r at height z (vertex 0 at angle 0); returns the
// index of its first vertex.
int add_ring(std::vector<Eigen::Vector3d>& verts, double r, double z, int n) {
  const int first = static_cast<int>(verts.size());
  for (int i = 0; i < n; ++i) {
    const auto [c, s] = ring_cos_sin(i, n);
    verts.emplace_back(r * c, r * s, z);
  }
  return first;
}

std::vector<int> ring_polygon(int first, int n) {
  std::vector<int> poly(n);
  for (int i = 0; i < n; ++i) poly[i] = first + i;
  return poly;
}

}  // namespace

TriMesh make_box(const Eigen::Vector3d& size, bool center) {
  const Eigen::Vector3d lo = center ? Eigen::Vector3d(-0.5 * size) : Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> v;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) v.push_back(lo + Eigen::Vector3d(i, j, k).cwiseProduct(size));
  // corner index i + 2j + 4k
  return convex_solid(
      v, {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}});
}

TriMesh make_cylinder(double height, double r1, double r2, int segments, bool center) {
  const double z0 = center ? -0.5 * height : 0.0;
  const double z1 = z0 + height;
  std::vector<Eigen::Vector3d> v;
  std::vector<std::vector<int>> faces;
  const int n = segments;
  if (r1 > 0 && r2 > 0) {
    const int b = add_ring(v, r1, z0, n);
    const int t = add_ring(v, r2, z1, n);
    for (int i = 0; i < n; ++i) faces.push_back({b + i, b + (i + 1) % n, t + (i + 1) % n, t + i});
    faces.push_back(ring_polygon(b, n));
    faces.push_back(ring_polygon(t, n));
  } else {
    // a cone: one ring and an apex
    const bool apex_on_top = r2 <= 0;
    const int ring = add_ring(v, apex_on_top ? r1 : r2, apex_on_top ? z0 : z1, n);
    const int apex = static_cast<int>(v.size());
    v.emplace_back(0, 0, apex_on_top ? z1 : z0);
    for (int i = 0; i < n; ++i) faces.push_back({ring + i, ring + (i + 1) % n, apex});
    faces.push_back(ring_polygon(ring, n));
  }
  return convex_solid(v, faces);
}

TriMesh make_sphere(double radius, int segments) {
  const int n = segments;
  const int rings = (segments + 1) / 2;
  std::vector<Eigen::Vector3d> v;
  std::vector<std::vector<int>> faces;
  for (int i = 0; i < rings; ++i) {
    const double phi = kPi * (i + 0.5) / rings;
    add_ring(v, radius * std::sin(phi), radius * std::cos(phi), n);
  }
  for (int i = 0; i + 1 < rings; ++i) {
    const int a = i * n, b = (i + 1) * n;
    for (int k = 0; k < n; ++k) faces.push_back({a + k, a + (k + 1) % n, b + (k + 1) % n, b + k});
  }
  faces.push_back(ring_polygon(0, n));
  faces.push_back(ring_polygon((rings - 1) * n, n));
  return convex_solid(v, faces);
}

TriMesh make_wedge(const Eigen::Vector3d& size) {
  const double x = size.x(), y = size.y(), z = size.z();
  std::vector<Eigen::Vector3d> v = {{0, 0, 0}, {x, 0, 0}, {0, 0, z},
                                    {0, y, 0}, {x, y, 0}, {0, y, z}};
  return convex_solid(v, {{0, 1, 2}, {3, 4, 5}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}});
}

TriMesh make_prism(const Eigen::MatrixX2d& polygon, double height) {
  const Eigen::Index n = polygon.rows();
  if (n < 3) throw GeometryError("a prism needs at least 3 points");
  // make the outline counter-clockwise
  double twice_area = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index j = (i + 1) % n;
    twice_area += polygon(i, 0) * polygon(j, 1) - polygon(j, 0) * polygon(i, 1);
  }
  Eigen::MatrixX2d poly = polygon;
  if (twice_area < 0) poly = polygon.colwise().reverse().eval();
  const Eigen::MatrixX3i cap = triangulate_polygon(poly);

  TriMesh m;
  m.V.resize(2 * n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    m.V.row(i) << poly(i, 0), poly(i, 1), 0.0;
    m.V.row(n + i) << poly(i, 0), poly(i, 1), height;
  }
  const Eigen::Index caps = cap.rows();
  m.F.resize(2 * caps + 2 * n, 3);
  const int ni = static_cast<int>(n);
  for (Eigen::Index t = 0; t < caps; ++t) {
    m.F.row(t) << cap(t, 0), cap(t, 2), cap(t, 1);                        // bottom, facing -z
    m.F.row(caps + t) << cap(t, 0) + ni, cap(t, 1) + ni, cap(t, 2) + ni;  // top, facing +z
  }
  for (int i = 0; i < ni; ++i) {
    const int j = (i + 1) % ni;
    m.F.row(2 * caps + 2 * i) << i, j, j + ni;
    m.F.row(2 * caps + 2 * i + 1) << i, j + ni, i + ni;
  }
  return m;
}

}  // namespace vproto::geometry
