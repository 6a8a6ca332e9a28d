#include "vproto/sim/contact_surface.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <set>

#include "vproto/geometry/aabb_tree.h"
#include "vproto/sim/fe_elasticity.h"

namespace vproto::sim {

ContactSurface make_contact_surface(const geometry::TetMesh& mesh) {
  ContactSurface s;
  s.surface_index.assign(static_cast<std::size_t>(mesh.nodes.rows()), -1);
  auto index_of = [&](int node) {
    int& k = s.surface_index[static_cast<std::size_t>(node)];
    if (k < 0) {
      k = static_cast<int>(s.nodes.size());
      s.nodes.push_back(node);
    }
    return k;
  };
  std::vector<std::array<int, 3>> tris;
  for (const BoundaryFace& f : boundary_faces(mesh)) {
    const int a = index_of(f.corners[0]), b = index_of(f.corners[1]), c = index_of(f.corners[2]);
    if (f.mids[0] < 0) {
      tris.push_back({a, b, c});
      continue;
    }
    // the quadratic face split at its mid-edge nodes: three corner triangles, one middle
    const int ab = index_of(f.mids[0]), bc = index_of(f.mids[1]), ca = index_of(f.mids[2]);
    tris.push_back({a, ab, ca});
    tris.push_back({ab, b, bc});
    tris.push_back({ca, bc, c});
    tris.push_back({ab, bc, ca});
  }
  s.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) s.triangles(static_cast<Eigen::Index>(t), k) = tris[t][k];
  // edge adjacency (a closed, manifold surface: two triangles per edge)
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> by_edge;
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = tris[t][k], b = tris[t][(k + 1) % 3];
      by_edge[{std::min(a, b), std::max(a, b)}].push_back({static_cast<int>(t), k});
    }
  s.neighbours = Eigen::MatrixX3i::Constant(static_cast<Eigen::Index>(tris.size()), 3, -1);
  for (const auto& [edge, sides] : by_edge)
    if (sides.size() == 2) {
      s.neighbours(sides[0].first, sides[0].second) = sides[1].first;
      s.neighbours(sides[1].first, sides[1].second) = sides[0].first;
    }
  // each surface node's neighbours along the triangles' edges
  std::vector<std::set<int>> around(s.nodes.size());
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      around[static_cast<std::size_t>(s.triangles(t, k))].insert(s.triangles(t, (k + 1) % 3));
      around[static_cast<std::size_t>(s.triangles(t, (k + 1) % 3))].insert(s.triangles(t, k));
    }
  s.node_neighbour_start.assign(1, 0);
  for (const std::set<int>& a : around) {
    s.node_neighbours.insert(s.node_neighbours.end(), a.begin(), a.end());
    s.node_neighbour_start.push_back(static_cast<int>(s.node_neighbours.size()));
  }
  return s;
}

namespace {

// whether vertex v of the part is extreme in direction `dir` among its neighbours (but
// `skip`), within an angle whose sine is `slack`
bool supports(const geometry::ConvexPolytope& part, int v, const Eigen::Vector3d& dir, int skip,
              double slack) {
  const Eigen::Vector3d& p = part.vertices[static_cast<std::size_t>(v)];
  for (int w : part.neighbours[static_cast<std::size_t>(v)]) {
    if (w == skip) continue;
    const Eigen::Vector3d d = part.vertices[static_cast<std::size_t>(w)] - p;
    if (dir.dot(d) > slack * d.norm()) return false;
  }
  return true;
}

// whether segment [p, q] passes through the interior of triangle (a, b, c), or with
// `edges`, through the triangle or its edges (a segment through a mesh edge meets the
// surface, though through neither triangle's interior); away from the segment's ends
bool segment_crosses(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, const Eigen::Vector3d& c, bool edges = false) {
  const double inside = edges ? -1e-9 : 1e-9;
  const Eigen::Vector3d d = q - p, e1 = b - a, e2 = c - a;
  const Eigen::Vector3d h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-300) return false;
  const Eigen::Vector3d s = p - a;
  const double u = s.dot(h) / det;
  if (u <= inside || u >= 1 - inside) return false;
  const Eigen::Vector3d qv = s.cross(e1);
  const double v = d.dot(qv) / det;
  if (v <= inside || u + v >= 1 - inside) return false;
  const double t = e2.dot(qv) / det;
  return t > 1e-9 && t < 1 - 1e-9;
}

// whether surface node j (positions x) is the surface's extreme point in direction -normal
// among its neighbours, and some of its triangles (outward normals `own`) look that way,
// both within an angle whose sine is `slack`
// The candidate triangles' nodes (increasing) and, node by node, the outward unit normals
// of those of its triangles among the candidates: flat arrays, built every step for
// thousands of triangles (a map of vectors cost an allocation per node).
struct NormalSpan {
  const Eigen::Vector3d* first;
  const Eigen::Vector3d* last;
  const Eigen::Vector3d* begin() const { return first; }
  const Eigen::Vector3d* end() const { return last; }
  std::size_t size() const { return static_cast<std::size_t>(last - first); }
  const Eigen::Vector3d& operator[](std::size_t k) const { return first[k]; }
};

struct NodeNormals {
  std::vector<int> nodes;
  std::vector<int> start;  ///< per node (its index in `nodes`), where its normals begin
  std::vector<Eigen::Vector3d> normals;
  /// The normals of node j, which must be one of `nodes`.
  NormalSpan of(int j) const {
    const auto k =
        static_cast<std::size_t>(std::lower_bound(nodes.begin(), nodes.end(), j) - nodes.begin());
    return {normals.data() + start[k], normals.data() + start[k + 1]};
  }
};

NodeNormals node_normals(const ContactSurface& s, const Eigen::MatrixX3d& x,
                         const std::vector<int>& triangles) {
  NodeNormals out;
  // the nodes (increasing), each one's slot in them, then each node's normals in the order
  // of the triangles: a counting sort (the narrow phase asks every step, for each rigid part)
  std::vector<int> slot(static_cast<std::size_t>(x.rows()), -1);
  for (int t : triangles)
    for (int k = 0; k < 3; ++k) {
      int& at = slot[static_cast<std::size_t>(s.triangles(t, k))];
      if (at < 0) {
        at = 0;
        out.nodes.push_back(s.triangles(t, k));
      }
    }
  std::sort(out.nodes.begin(), out.nodes.end());
  for (std::size_t k = 0; k < out.nodes.size(); ++k)
    slot[static_cast<std::size_t>(out.nodes[k])] = static_cast<int>(k);
  std::vector<Eigen::Vector3d> unit(triangles.size());
  std::vector<char> valid(triangles.size(), 0);
  out.start.assign(out.nodes.size() + 1, 0);
  for (std::size_t q = 0; q < triangles.size(); ++q) {
    const int t = triangles[q];
    const Eigen::Vector3d a = x.row(s.triangles(t, 0)).transpose();
    const Eigen::Vector3d n =
        (x.row(s.triangles(t, 1)).transpose() - a).cross(x.row(s.triangles(t, 2)).transpose() - a);
    if (!(n.norm() > 0)) continue;
    unit[q] = n.normalized();
    valid[q] = 1;
    for (int k = 0; k < 3; ++k)
      ++out.start[static_cast<std::size_t>(slot[static_cast<std::size_t>(s.triangles(t, k))]) + 1];
  }
  for (std::size_t k = 0; k < out.nodes.size(); ++k) out.start[k + 1] += out.start[k];
  out.normals.resize(static_cast<std::size_t>(out.start.back()));
  std::vector<int> fill(out.start.begin(), out.start.end() - 1);
  for (std::size_t q = 0; q < triangles.size(); ++q) {
    if (!valid[q]) continue;
    for (int k = 0; k < 3; ++k) {
      const auto at =
          static_cast<std::size_t>(slot[static_cast<std::size_t>(s.triangles(triangles[q], k))]);
      out.normals[static_cast<std::size_t>(fill[at]++)] = unit[q];
    }
  }
  return out;
}

bool extreme_and_facing(const ContactSurface& s, const Eigen::MatrixX3d& x, int j, NormalSpan own,
                        const Eigen::Vector3d& normal, double slack) {
  const Eigen::Vector3d towards = -normal, here = x.row(j).transpose();
  for (int q = s.node_neighbour_start[static_cast<std::size_t>(j)];
       q < s.node_neighbour_start[static_cast<std::size_t>(j) + 1]; ++q) {
    const Eigen::Vector3d d =
        x.row(s.node_neighbours[static_cast<std::size_t>(q)]).transpose() - here;
    if (towards.dot(d) > slack * d.norm()) return false;
  }
  for (const Eigen::Vector3d& n : own)
    if (n.dot(normal) < slack) return true;
  return false;
}

// closest point of segment [a, b] to p
Eigen::Vector3d closest_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  if (!(len2 > 0)) return a;
  return a + std::clamp((p - a).dot(d) / len2, 0.0, 1.0) * d;
}

}  // namespace

double signed_distance(const geometry::ConvexPolytope& part, const Eigen::Vector3d& p,
                       Eigen::Vector3d* closest, Eigen::Vector3d* normal, bool* on_face) {
  // inside: the face it is least deep under
  int deepest = -1;
  double s_max = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < part.normals.size(); ++k) {
    const double s = part.normals[k].dot(p) - part.offsets[k];
    if (s > s_max) {
      s_max = s;
      deepest = static_cast<int>(k);
    }
  }
  if (s_max <= 0) {
    *normal = part.normals[static_cast<std::size_t>(deepest)];
    *closest = p - s_max * *normal;
    *on_face = true;
    return s_max;
  }
  // outside: the closest point lies on a face p is in front of
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < part.normals.size(); ++k) {
    const Eigen::Vector3d& n = part.normals[k];
    const double s = n.dot(p) - part.offsets[k];
    if (s <= 0) continue;
    const Eigen::Vector3d q = p - s * n;
    const std::vector<int>& poly = part.faces[k];
    bool inside = true;
    for (std::size_t i = 0; i < poly.size() && inside; ++i) {
      const Eigen::Vector3d& v0 = part.vertices[static_cast<std::size_t>(poly[i])];
      const Eigen::Vector3d& v1 =
          part.vertices[static_cast<std::size_t>(poly[(i + 1) % poly.size()])];
      inside = n.dot((v1 - v0).cross(q - v0)) >= 0;
    }
    if (inside) {
      *closest = q;
      *normal = n;
      *on_face = true;
      return s;
    }
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Eigen::Vector3d c =
          closest_on_segment(p, part.vertices[static_cast<std::size_t>(poly[i])],
                             part.vertices[static_cast<std::size_t>(poly[(i + 1) % poly.size()])]);
      const double d = (p - c).norm();
      if (d < best) {
        best = d;
        *closest = c;
      }
    }
  }
  *normal = (p - *closest) / best;
  *on_face = false;
  return best;
}

geometry::TriMesh display_surface(const geometry::TetMesh& mesh) {
  const ContactSurface s = make_contact_surface(mesh);
  geometry::TriMesh out;
  out.V.resize(static_cast<Eigen::Index>(s.nodes.size()), 3);
  for (std::size_t k = 0; k < s.nodes.size(); ++k)
    out.V.row(static_cast<Eigen::Index>(k)) = mesh.nodes.row(s.nodes[k]);
  out.F = s.triangles;
  return out;
}

namespace {

// One row per spot: a part's edge crossing the mesh gives the same point from every
// triangle that shares the crossing (on a shared edge, at a shared node), and a point at a
// node repeats the node's own row. Identical rows make the Delassus matrix singular (the
// sweeps then crawl along its null space, shifting force between copies) and cost solves
// for nothing; rows at one spot whose normals differ by more than 10 degrees (a crease)
// are all kept. The first of each spot is kept (node rows come first).
std::vector<SurfaceContact> one_row_per_spot(const std::vector<SurfaceContact>& rows,
                                             const Eigen::MatrixX3d& x) {
  const std::size_t n = rows.size();
  std::vector<Eigen::Vector3d> at(n, Eigen::Vector3d::Zero());
  double scale = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < 3; ++k)
      if (rows[i].nodes[k] >= 0) at[i] += rows[i].weights[k] * x.row(rows[i].nodes[k]).transpose();
    scale = std::max(scale, at[i].cwiseAbs().maxCoeff());
  }
  const double close = 1e-9 * std::max(scale, 1e-3), same = std::cos(10 * M_PI / 180);
  // sorted along x, a spot's copies are neighbours within `close`
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return at[a].x() < at[b].x(); });
  std::vector<char> drop(n, 0);
  for (std::size_t p = 0; p < n; ++p) {
    const std::size_t i = order[p];
    for (std::size_t q = p + 1; q < n && at[order[q]].x() - at[i].x() <= close; ++q) {
      const std::size_t j = order[q];
      if (drop[j] || drop[i] || (at[i] - at[j]).norm() > close ||
          rows[i].normal.dot(rows[j].normal) < same)
        continue;
      drop[std::max(i, j)] = 1;  // keep the earlier
    }
  }
  std::vector<SurfaceContact> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    if (!drop[i]) out.push_back(rows[i]);
  return out;
}

}  // namespace

std::vector<SurfaceContact> surface_part_contacts(const ContactSurface& surface,
                                                  const Eigen::MatrixX3d& x,
                                                  const geometry::ConvexPolytope& part,
                                                  const std::vector<int>& triangles,
                                                  const Eigen::VectorXd& reach) {
  const double slack = std::sin(10 * M_PI / 180);
  std::vector<SurfaceContact> out;
  // 1. surface nodes against the part
  // the outward normals of the triangles around each node (a node near the part has all
  // its triangles among the candidates: their boxes, grown by the reach, hold the node)
  const NodeNormals around = node_normals(surface, x, triangles);
  for (int j : around.nodes) {
    SurfaceContact c;
    bool on_face = false;
    c.gap = signed_distance(part, x.row(j).transpose(), &c.on_b, &c.normal, &on_face);
    if (c.gap >= reach[j]) continue;
    // the node must be the surface's extreme point towards the part (within 10 degrees):
    // a node inside a face of the surface that meets the part's face at an angle (a lead
    // face riding over the part's edge) is not where they touch; the part's edge on the
    // surface's triangles is
    // and the surface must face the part there: some triangle around the node looks towards
    // it (a face whose outside looks the way the part's face does, like a hook's top face
    // level with the part's top face, has the body on the part's side: it cannot touch it)
    if (!extreme_and_facing(surface, x, j, around.of(j), c.normal, slack)) continue;
    c.nodes = {j, -1, -1};
    c.key = j;
    c.weights = {1, 0, 0};
    c.on_face = on_face;
    out.push_back(c);
  }
  // 2. the part's edges (and so its vertices) against the triangles
  std::vector<std::pair<int, int>> edges;
  std::map<std::pair<int, int>, Eigen::Vector3d> edge_normal;  // sum of the adjacent faces'
  for (std::size_t k = 0; k < part.faces.size(); ++k) {
    const std::vector<int>& poly = part.faces[k];
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const int a = poly[i], b = poly[(i + 1) % poly.size()];
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      auto [it, added] = edge_normal.try_emplace(key, Eigen::Vector3d::Zero());
      it->second += part.normals[k];
      if (added) edges.push_back(key);
    }
  }
  // An edge whose faces turn by less than kShallowTurn (a faceted cylinder's or sphere's)
  // and a vertex whose faces' normals all lie that close together make no rows of their
  // own: the surface's nodes held outside the faces on either side keep it out to within
  // half a triangle times tan(turn / 2), 4.4 % of the triangle's size at most: about as far
  // as the facets themselves are off the curve they stand for (a 48-gon of radius 11 mm,
  // 23 um; 0.3 mm triangles, 13 um at most). Their rows carried little the node rows did
  // not: an LDPE cap pushed over a rigid 48-facet bottle neck's bead and off again (tet10
  // at 0.6 mm, its lip pressed all round the bead) had up to 8,941 points in one solve with
  // them, 7,889 without, and took 582 s instead of 841 s, the peak forces within 0.3 %.
  constexpr double kShallowTurn = 10 * M_PI / 180;
  const double flat = std::cos(kShallowTurn);
  std::vector<char> shallow_edge(edges.size(), 0);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    // the sum of two unit normals at an angle a apart is 2 cos(a / 2) long
    const double half = 0.5 * edge_normal.at(edges[e]).norm();
    shallow_edge[e] = half >= std::cos(0.5 * kShallowTurn);
  }
  std::vector<char> sharp_vertex(part.vertices.size(), 0);
  {
    std::vector<std::vector<std::size_t>> faces_at(part.vertices.size());
    for (std::size_t k = 0; k < part.faces.size(); ++k)
      for (int v : part.faces[k]) faces_at[static_cast<std::size_t>(v)].push_back(k);
    for (std::size_t v = 0; v < faces_at.size(); ++v)
      for (std::size_t i = 0; i < faces_at[v].size() && !sharp_vertex[v]; ++i)
        for (std::size_t j = i + 1; j < faces_at[v].size() && !sharp_vertex[v]; ++j)
          sharp_vertex[v] = part.normals[faces_at[v][i]].dot(part.normals[faces_at[v][j]]) < flat;
  }
  std::set<std::pair<int, int>> seen;  // (triangle, part vertex) rows already made
  // the candidates' boxes: a feature found under a triangle checks its way out against them
  std::vector<Eigen::Vector3d> tri_lo(triangles.size()), tri_hi(triangles.size());
  for (std::size_t o = 0; o < triangles.size(); ++o) {
    const int t = triangles[o];
    const Eigen::Vector3d a = x.row(surface.triangles(t, 0)).transpose(),
                          b = x.row(surface.triangles(t, 1)).transpose(),
                          c = x.row(surface.triangles(t, 2)).transpose();
    tri_lo[o] = a.cwiseMin(b).cwiseMin(c);
    tri_hi[o] = a.cwiseMax(b).cwiseMax(c);
  }
  const auto vertices = static_cast<std::int64_t>(part.vertices.size());
  const std::int64_t features = vertices + 2 * static_cast<std::int64_t>(edges.size());
  for (int t : triangles) {
    const Eigen::Vector3d a = x.row(surface.triangles(t, 0)).transpose(),
                          b = x.row(surface.triangles(t, 1)).transpose(),
                          c = x.row(surface.triangles(t, 2)).transpose();
    Eigen::Vector3d n = (b - a).cross(c - a);
    const double twice_area = n.norm();
    if (!(twice_area > 0)) continue;
    n /= twice_area;
    const double size = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const double tri_reach =
        std::max({reach[surface.triangles(t, 0)], reach[surface.triangles(t, 1)],
                  reach[surface.triangles(t, 2)]});
    // a feature may be found under the triangle by at most this much (deeper ones belong
    // to the body's other side)
    const double depth_limit = std::max(tri_reach, 0.25 * size);
    const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c).array() - tri_reach;
    const Eigen::Vector3d hi = a.cwiseMax(b).cwiseMax(c).array() + tri_reach;
    const std::array<Eigen::Vector3d, 3> corner{a, b, c};
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const auto [ia, ib] = edges[e];
      const Eigen::Vector3d& e0 = part.vertices[static_cast<std::size_t>(ia)];
      const Eigen::Vector3d& e1 = part.vertices[static_cast<std::size_t>(ib)];
      if ((e0.cwiseMax(e1).array() < lo.array()).any() ||
          (e0.cwiseMin(e1).array() > hi.array()).any())
        continue;
      // the part must lie on the triangle's outer side here
      if (edge_normal.at({ia, ib}).dot(n) >= 0) continue;
      const bool edge_supports = std::abs(n.dot(e1 - e0)) <= slack * (e1 - e0).norm() &&
                                 supports(part, ia, -n, ib, slack) &&
                                 supports(part, ib, -n, ia, slack);
      // the segment clipped to the triangle's prism
      double t0 = 0, t1 = 1;
      const Eigen::Vector3d d = e1 - e0;
      for (int k = 0; k < 3 && t0 <= t1; ++k) {
        const Eigen::Vector3d& p = corner[static_cast<std::size_t>(k)];
        const Eigen::Vector3d m = n.cross(corner[static_cast<std::size_t>((k + 1) % 3)] - p);
        const double f0 = m.dot(e0 - p), fd = m.dot(d);
        if (std::abs(fd) < 1e-300) {
          if (f0 < 0) t1 = -1;
          continue;
        }
        const double tc = -f0 / fd;
        if (fd > 0)
          t0 = std::max(t0, tc);
        else
          t1 = std::min(t1, tc);
      }
      if (t0 > t1) continue;
      const double h0 = n.dot(e0 + t0 * d - a), h1 = n.dot(e0 + t1 * d - a);
      std::vector<double> at;
      if (std::abs(h0 - h1) <= 1e-3 * std::max(size, (t1 - t0) * d.norm()))
        at = {t0, t1};  // lying along the face: both ends carry
      else
        at = {h0 < h1 ? t0 : t1};
      for (std::size_t end = 0; end < at.size(); ++end) {
        const double tt = at[end];
        const Eigen::Vector3d q = e0 + tt * d;
        const double h = n.dot(q - a);
        if (h >= tri_reach || h < -depth_limit) continue;
        // one row per (triangle, part vertex) when the point is a vertex
        const int vertex = tt <= 0 ? ia : tt >= 1 ? ib : -1;
        if (shallow_edge[e] && (vertex < 0 || !sharp_vertex[static_cast<std::size_t>(vertex)]))
          continue;
        if (vertex >= 0 ? !supports(part, vertex, -n, -1, slack) : !edge_supports) continue;
        // a feature found under the triangle must be inside the body: the way out to its
        // foot on the triangle crosses no other face (near a ridge, the space under one
        // face is outside the body)
        if (h < 0) {
          const Eigen::Vector3d foot = q - h * n;
          const Eigen::Vector3d seg_lo = q.cwiseMin(foot), seg_hi = q.cwiseMax(foot);
          bool crossed = false;
          for (std::size_t o = 0; o < triangles.size(); ++o) {
            const int other = triangles[o];
            // (only a triangle whose box meets the segment's can cross it)
            if (other == t || (tri_hi[o].array() < seg_lo.array()).any() ||
                (tri_lo[o].array() > seg_hi.array()).any())
              continue;
            if (segment_crosses(q, foot, x.row(surface.triangles(other, 0)).transpose(),
                                x.row(surface.triangles(other, 1)).transpose(),
                                x.row(surface.triangles(other, 2)).transpose())) {
              crossed = true;
              break;
            }
          }
          if (crossed) continue;
        }
        if (vertex >= 0 && !seen.insert({t, vertex}).second) continue;
        // barycentric coordinates of the foot on the triangle
        const Eigen::Vector3d y = q - h * n;
        const double wa = n.dot((b - y).cross(c - y)) / twice_area;
        const double wb = n.dot((c - y).cross(a - y)) / twice_area;
        Eigen::Vector3d w(std::max(wa, 0.0), std::max(wb, 0.0), std::max(1 - wa - wb, 0.0));
        w /= w.sum();
        SurfaceContact r;
        for (int k = 0; k < 3; ++k) {
          r.nodes[static_cast<std::size_t>(k)] = surface.triangles(t, k);
          r.weights[static_cast<std::size_t>(k)] = w[k];
        }
        r.on_b = q;
        r.normal = -n;
        r.gap = h;
        r.node_row = false;
        const std::int64_t feature =
            vertex >= 0 ? vertex
                        : vertices + 2 * static_cast<std::int64_t>(e) +
                              static_cast<int>(end == 1 || (at.size() == 1 && tt >= t1));
        r.key = -(1 + static_cast<std::int64_t>(t) * features + feature);
        r.part_vertex = vertex;
        if (vertex < 0) r.part_edge = static_cast<int>(e);
        out.push_back(r);
      }
    }
  }
  return one_row_per_spot(out, x);
}

}  // namespace vproto::sim

namespace vproto::sim {

namespace {

// A convex edge of a surface between two triangles at more than 30 degrees: its nodes and
// the mean of the two outward normals.
struct SharpEdge {
  int v0, v1;
  Eigen::Vector3d outward;
  int triangle, corner;  ///< v0, v1 are the triangle's corners `corner` and `corner` + 1
};

std::vector<SharpEdge> sharp_edges(const ContactSurface& s, const Eigen::MatrixX3d& x,
                                   const std::vector<int>& triangles) {
  auto normal = [&](int t) {
    const Eigen::Vector3d a = x.row(s.triangles(t, 0)).transpose();
    return (x.row(s.triangles(t, 1)).transpose() - a)
        .cross(x.row(s.triangles(t, 2)).transpose() - a)
        .normalized()
        .eval();
  };
  std::vector<SharpEdge> out;
  std::set<std::pair<int, int>> seen;  // each edge once
  for (int t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int other = s.neighbours(t, k);
      if (other < 0 || !seen.insert({std::min(t, other), std::max(t, other)}).second) continue;
      const Eigen::Vector3d nt = normal(t), no = normal(other);
      if (!(nt.dot(no) < std::cos(30 * M_PI / 180))) continue;
      const int v0 = s.triangles(t, k), v1 = s.triangles(t, (k + 1) % 3);
      // convex: the other triangle's far corner lies behind this triangle's plane
      int far = -1;
      for (int q = 0; q < 3; ++q)
        if (s.triangles(other, q) != v0 && s.triangles(other, q) != v1) far = s.triangles(other, q);
      if (far < 0 || nt.dot((x.row(far) - x.row(v0)).transpose()) >= 0) continue;
      out.push_back({v0, v1, (nt + no).normalized(), t, k});
    }
  return out;
}

// A node of surface `s` (positions x) against the triangles of surface `o` (positions xo):
// its point on the nearest triangle whose prism holds it, or none.
struct NodeOnTriangle {
  int triangle = -1;
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();  // barycentric, of the foot
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();   // the triangle's outward normal
  double gap = 0;                                     // normal'(x - foot)
};

std::vector<std::pair<int, NodeOnTriangle>> nodes_on_triangles(
    const ContactSurface& s, const Eigen::MatrixX3d& x, const std::vector<int>& s_triangles,
    const Eigen::VectorXd& reach, const ContactSurface& o, const Eigen::MatrixX3d& xo,
    const std::vector<int>& o_triangles, const Eigen::VectorXd& o_reach, bool second) {
  const double slack = std::sin(10 * M_PI / 180);
  std::vector<std::pair<int, NodeOnTriangle>> out;
  if (s_triangles.empty() || o_triangles.empty()) return out;
  // the other side's candidate triangles in a tree, their boxes grown by their reach
  struct Tri {
    Eigen::Vector3d a, b, c, n;
    double twice_area, size, reach;
  };
  std::vector<Tri> tris;
  std::vector<geometry::Bounds> boxes;
  for (int t : o_triangles) {
    Tri tr;
    tr.a = xo.row(o.triangles(t, 0)).transpose();
    tr.b = xo.row(o.triangles(t, 1)).transpose();
    tr.c = xo.row(o.triangles(t, 2)).transpose();
    tr.n = (tr.b - tr.a).cross(tr.c - tr.a);
    tr.twice_area = tr.n.norm();
    if (!(tr.twice_area > 0))
      tr.twice_area = 0;
    else
      tr.n /= tr.twice_area;
    tr.size = std::max({(tr.b - tr.a).norm(), (tr.c - tr.b).norm(), (tr.a - tr.c).norm()});
    tr.reach = std::max(
        {o_reach[o.triangles(t, 0)], o_reach[o.triangles(t, 1)], o_reach[o.triangles(t, 2)]});
    geometry::Bounds box;
    box.lo = tr.a.cwiseMin(tr.b).cwiseMin(tr.c).array() - tr.reach - 0.25 * tr.size;
    box.hi = tr.a.cwiseMax(tr.b).cwiseMax(tr.c).array() + tr.reach + 0.25 * tr.size;
    tris.push_back(tr);
    boxes.push_back(box);
  }
  const geometry::AabbTree tree(boxes);
  const std::vector<SharpEdge> edges = sharp_edges(o, xo, o_triangles);
  // the outward normals of the node's own triangles (among the candidates)
  const NodeNormals around = node_normals(s, x, s_triangles);
  for (int j : around.nodes) {
    const Eigen::Vector3d p = x.row(j).transpose();
    const NormalSpan own = around.of(j);
    // the second side's node only where it is on an edge or a corner of its surface (two of
    // its triangles at more than 30 degrees) or finer than the other side there
    bool sharp = !second;
    for (std::size_t u = 0; u < own.size() && !sharp; ++u)
      for (std::size_t v = u + 1; v < own.size() && !sharp; ++v)
        sharp = own[u].dot(own[v]) < std::cos(30 * M_PI / 180);
    double own_edge = 0;
    if (!sharp) {
      const int first = s.node_neighbour_start[static_cast<std::size_t>(j)],
                last = s.node_neighbour_start[static_cast<std::size_t>(j) + 1];
      for (int q = first; q < last; ++q)
        own_edge += (x.row(s.node_neighbours[static_cast<std::size_t>(q)]).transpose() - p).norm();
      own_edge /= std::max(1, last - first);
    }
    geometry::Bounds at;
    at.lo = p.array() - reach[j];
    at.hi = p.array() + reach[j];
    NodeOnTriangle best;
    int best_index = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    for (int q : tree.overlapping(at)) {
      const Tri& tr = tris[static_cast<std::size_t>(q)];
      if (tr.twice_area == 0) continue;
      // the faces must meet face to face: a triangle of the node's own surface looks
      // against it (within 60 degrees); where the node's edge lies in the plane of the other
      // surface's side, that side is not what it touches
      bool opposed = false;
      for (const Eigen::Vector3d& n : own) opposed = opposed || n.dot(tr.n) < -0.5;
      if (!opposed) continue;
      const double h = tr.n.dot(p - tr.a);
      const double limit = std::max(reach[j] + tr.reach, 0.25 * tr.size);
      if (h >= reach[j] + tr.reach || h < -limit) continue;
      const Eigen::Vector3d y = p - h * tr.n;  // the foot, in the triangle's plane
      const double wa = tr.n.dot((tr.b - y).cross(tr.c - y)) / tr.twice_area;
      const double wb = tr.n.dot((tr.c - y).cross(tr.a - y)) / tr.twice_area;
      const double wc = 1 - wa - wb;
      const double tol = -1e-3;  // a foot a thousandth of the triangle off its edge (the
                                 // mesher places edge nodes to about 1e-7 m): on it
      if (wa < tol || wb < tol || wc < tol) continue;  // outside the prism
      if (std::abs(h) >= best_distance) continue;
      if (h < 0) {
        // under the triangle, the node must be inside the other body: the way out to its
        // foot crosses no other triangle (near a ridge or a thin wall, the space under one
        // face is outside the body, or beyond its other side)
        bool crossed = false;
        for (std::size_t w = 0; w < tris.size() && !crossed; ++w)
          crossed = static_cast<int>(w) != q &&
                    segment_crosses(p, y, tris[w].a, tris[w].b, tris[w].c, true);
        if (crossed) continue;
      }
      best_distance = std::abs(h);
      best_index = q;
      best.triangle = o_triangles[static_cast<std::size_t>(q)];
      best.weights = Eigen::Vector3d(wa, wb, wc).cwiseMax(0.0);
      best.weights /= best.weights.sum();
      best.normal = tr.n;
      best.gap = h;
    }
    if (best.triangle < 0) {
      // in no prism: beside a convex edge of the other surface (a hook's apex passing a
      // plate's corner), the nearest such edge, along the line from it
      double nearest = std::numeric_limits<double>::infinity();
      for (const SharpEdge& edge : edges) {
        const Eigen::Vector3d e0 = xo.row(edge.v0).transpose(), e1 = xo.row(edge.v1).transpose();
        const double len2 = (e1 - e0).squaredNorm();
        if (!(len2 > 0)) continue;
        const double u = (p - e0).dot(e1 - e0) / len2;
        if (u < 0 || u > 1) continue;
        const Eigen::Vector3d foot = e0 + u * (e1 - e0), away = p - foot;
        const double d = away.norm();
        const double edge_reach = std::max(o_reach[edge.v0], o_reach[edge.v1]);
        if (d >= reach[j] + edge_reach || d >= nearest) continue;
        const Eigen::Vector3d n = d > 1e-9 * std::sqrt(len2) ? (away / d).eval() : edge.outward;
        if (n.dot(edge.outward) <= 0) continue;
        bool opposed = false;
        for (const Eigen::Vector3d& m : own) opposed = opposed || m.dot(n) < -0.5;
        if (!opposed) continue;
        nearest = d;
        best.triangle = edge.triangle;
        best.weights.setZero();
        best.weights[edge.corner] = 1 - u;
        best.weights[(edge.corner + 1) % 3] = u;
        best.normal = n;
        best.gap = d;
        best_index = -1;
      }
      if (best.triangle < 0) continue;
      if (!sharp) continue;  // a second side's node beside an edge: the first side's hold it
    }
    if (!sharp) {
      const Tri& tr = tris[static_cast<std::size_t>(best_index)];
      const double other_edge =
          ((tr.b - tr.a).norm() + (tr.c - tr.b).norm() + (tr.a - tr.c).norm()) / 3;
      if (own_edge >= 0.8 * other_edge) continue;
    }
    // extreme towards the other surface, and facing it (as for a rigid part)
    if (!extreme_and_facing(s, x, j, own, best.normal, slack)) continue;
    out.push_back({j, best});
  }
  return out;
}

}  // namespace

bool deep_inside(const ContactSurface& surface, const Eigen::MatrixX3d& x, const Eigen::Vector3d& p,
                 double depth) {
  // a direction no mesh of boxes and cylinders lines up with
  const Eigen::Vector3d ray = Eigen::Vector3d(0.5377, 0.6129, 0.5789).normalized();
  int crossings = 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t) {
    const Eigen::Vector3d a = x.row(surface.triangles(t, 0)).transpose(),
                          b = x.row(surface.triangles(t, 1)).transpose(),
                          c = x.row(surface.triangles(t, 2)).transpose();
    // the ray from p
    const Eigen::Vector3d e1 = b - a, e2 = c - a, h = ray.cross(e2), s = p - a;
    const double det = e1.dot(h);
    if (std::abs(det) > 1e-300) {
      const double u = s.dot(h) / det;
      const Eigen::Vector3d q = s.cross(e1);
      const double v = ray.dot(q) / det;
      if (u >= 0 && v >= 0 && u + v <= 1 && e2.dot(q) / det > 0) ++crossings;
    }
    // the distance to the triangle: to its plane inside it, else to its nearest edge
    const Eigen::Vector3d n = e1.cross(e2).normalized();
    const Eigen::Vector3d y = p - n.dot(p - a) * n;
    const bool over = n.dot((b - a).cross(y - a)) >= 0 && n.dot((c - b).cross(y - b)) >= 0 &&
                      n.dot((a - c).cross(y - c)) >= 0;
    const double d = over ? (p - y).norm()
                          : std::min({(p - closest_on_segment(p, a, b)).norm(),
                                      (p - closest_on_segment(p, b, c)).norm(),
                                      (p - closest_on_segment(p, c, a)).norm()});
    nearest = std::min(nearest, d);
  }
  return crossings % 2 == 1 && nearest > depth;
}

std::vector<SurfacePairContact> surface_surface_contacts(
    const ContactSurface& a, const Eigen::MatrixX3d& xa, const std::vector<int>& a_triangles,
    const Eigen::VectorXd& a_reach, const ContactSurface& b, const Eigen::MatrixX3d& xb,
    const std::vector<int>& b_triangles, const Eigen::VectorXd& b_reach) {
  // every node of A on B's triangles, and B's nodes on A's triangles where they are on an
  // edge or a corner of B (where an edge or corner presses into a face between the face's
  // nodes) or finer than A there; elsewhere A's nodes hold B's flat triangles, and taking
  // both would double the points of a face lying on a face
  std::vector<SurfacePairContact> out;
  // A's nodes on B's triangles: the normal is B's, from B towards A
  auto a_on_b = [&](int j, const NodeOnTriangle& on) {
    SurfacePairContact c;
    c.a.nodes = {j, -1, -1};
    c.a.weights = {1, 0, 0};
    c.a.node_row = true;
    c.a.key = j;
    c.a.normal = on.normal;
    c.a.gap = on.gap;
    c.a.on_b.setZero();
    for (int k = 0; k < 3; ++k) {
      c.b_nodes[static_cast<std::size_t>(k)] = b.triangles(on.triangle, k);
      c.b_weights[static_cast<std::size_t>(k)] = on.weights[k];
      c.a.on_b += on.weights[k] * xb.row(b.triangles(on.triangle, k)).transpose();
    }
    c.a_node = true;
    return c;
  };
  // B's nodes on A's triangles: A's outward normal points from A towards B
  auto b_on_a = [&](int j, const NodeOnTriangle& on) {
    SurfacePairContact c;
    c.a.node_row = false;
    c.a.key = (std::int64_t{1} << 40) + j;
    c.a.normal = -on.normal;
    c.a.gap = on.gap;
    c.a.on_b = xb.row(j).transpose();
    for (int k = 0; k < 3; ++k) {
      c.a.nodes[static_cast<std::size_t>(k)] = a.triangles(on.triangle, k);
      c.a.weights[static_cast<std::size_t>(k)] = on.weights[k];
    }
    c.b_nodes = {j, -1, -1};
    c.b_weights = {1, 0, 0};
    c.a_node = false;
    return c;
  };
  std::set<int> taken;
  for (const auto& [j, on] :
       nodes_on_triangles(a, xa, a_triangles, a_reach, b, xb, b_triangles, b_reach, false)) {
    out.push_back(a_on_b(j, on));
    taken.insert(j);
  }
  for (const auto& [j, on] :
       nodes_on_triangles(b, xb, b_triangles, b_reach, a, xa, a_triangles, a_reach, true)) {
    // a node of B whose foot is a node of A with a point already is that point again
    bool again = false;
    for (int k = 0; k < 3; ++k)
      again = again || (on.weights[k] > 1 - 1e-9 && taken.count(a.triangles(on.triangle, k)));
    if (!again) out.push_back(b_on_a(j, on));
  }
  // the convex sharp edges of each surface crossing the other's: two edges passing each
  // other (a hook's apex over a plate's corner) have neither's nodes in the other's prisms
  // while they cross, so the crossing is a point of its own, along the edges' common normal
  const std::vector<SharpEdge> ea = sharp_edges(a, xa, a_triangles),
                               eb = sharp_edges(b, xb, b_triangles);
  if (ea.empty() || eb.empty()) return out;
  std::vector<geometry::Bounds> boxes;
  for (const SharpEdge& e : eb) {
    geometry::Bounds box;
    const double grow = std::max(b_reach[e.v0], b_reach[e.v1]);
    box.lo = xb.row(e.v0).transpose().cwiseMin(xb.row(e.v1).transpose()).array() - grow;
    box.hi = xb.row(e.v0).transpose().cwiseMax(xb.row(e.v1).transpose()).array() + grow;
    boxes.push_back(box);
  }
  const geometry::AabbTree tree(boxes);
  // a crossing's key: the two edges, each as its triangle's corner
  const std::int64_t b_edges = 3 * static_cast<std::int64_t>(b.triangles.rows());
  for (const SharpEdge& e : ea) {
    const Eigen::Vector3d p0 = xa.row(e.v0).transpose(), p1 = xa.row(e.v1).transpose();
    const double reach = std::max(a_reach[e.v0], a_reach[e.v1]);
    geometry::Bounds box;
    box.lo = p0.cwiseMin(p1).array() - reach;
    box.hi = p0.cwiseMax(p1).array() + reach;
    for (int q : tree.overlapping(box)) {
      const SharpEdge& f = eb[static_cast<std::size_t>(q)];
      const Eigen::Vector3d q0 = xb.row(f.v0).transpose(), q1 = xb.row(f.v1).transpose();
      const Eigen::Vector3d da = p1 - p0, db = q1 - q0;
      Eigen::Vector3d n = da.cross(db);
      if (n.norm() < 0.2 * da.norm() * db.norm()) continue;  // near parallel: the nodes hold it
      n.normalize();
      if (n.dot(f.outward) < 0) n = -n;                                 // from B towards A
      if (n.dot(f.outward) < 0.5 || n.dot(e.outward) > -0.5) continue;  // facing each other
      // the closest points of the two lines, both inside their segments
      const Eigen::Vector3d r = p0 - q0;
      const double aa = da.dot(da), bb = da.dot(db), cc = db.dot(db), dd = da.dot(r),
                   ee = db.dot(r), den = aa * cc - bb * bb;
      if (!(den > 0)) continue;
      const double sa = (bb * ee - cc * dd) / den, sb = (aa * ee - bb * dd) / den;
      if (sa <= 0.02 || sa >= 0.98 || sb <= 0.02 || sb >= 0.98) continue;
      const Eigen::Vector3d pa = p0 + sa * da, pb = q0 + sb * db;
      const double gap = n.dot(pa - pb);
      const double size = std::min(da.norm(), db.norm());
      if (gap >= reach + std::max(b_reach[f.v0], b_reach[f.v1]) || gap < -0.25 * size) continue;
      SurfacePairContact c;
      c.a.nodes = {e.v0, e.v1, -1};
      c.a.weights = {1 - sa, sa, 0};
      c.a.node_row = false;
      c.a.normal = n;
      c.a.gap = gap;
      c.a.on_b = pb;
      c.a.key = -1 - (3 * static_cast<std::int64_t>(e.triangle) + e.corner) * b_edges -
                (3 * static_cast<std::int64_t>(f.triangle) + f.corner);
      c.b_nodes = {f.v0, f.v1, -1};
      c.b_weights = {1 - sb, sb, 0};
      c.a_node = true;
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace vproto::sim
