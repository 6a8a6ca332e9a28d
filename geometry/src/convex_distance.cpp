#include "vproto/geometry/convex_distance.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "vproto/geometry/mass_properties.h"

namespace vproto::geometry {

ConvexPolytope make_polytope(const TriMesh& m) {
  if (m.empty()) throw GeometryError("a convex part has no triangles");
  ConvexPolytope p;
  const double scale = (bounds(m).hi - bounds(m).lo).norm();
  // vertices used by the faces
  std::vector<int> used(static_cast<std::size_t>(m.V.rows()), -1);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = m.F(f, k);
      if (used[v] < 0) {
        used[v] = static_cast<int>(p.vertices.size());
        p.vertices.push_back(m.V.row(v).transpose());
      }
    }
  // planes, coplanar triangles merged; each triangle remembers its plane
  std::vector<int> plane_of(static_cast<std::size_t>(m.F.rows()));
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const double d = n.dot(a);
    int found = -1;
    for (std::size_t k = 0; k < p.normals.size() && found < 0; ++k)
      if (p.normals[k].dot(n) > 1 - 1e-12 && std::abs(p.offsets[k] - d) <= 1e-12 * scale)
        found = static_cast<int>(k);
    if (found < 0) {
      found = static_cast<int>(p.normals.size());
      p.normals.push_back(n);
      p.offsets.push_back(d);
    }
    plane_of[f] = found;
  }
  // edges between faces of different planes; the vertex graph of the surface
  p.neighbours.assign(p.vertices.size(), {});
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
      auto& faces = edge_faces[{std::min(a, b), std::max(a, b)}];
      if (faces.empty()) {
        p.neighbours[used[a]].push_back(used[b]);
        p.neighbours[used[b]].push_back(used[a]);
      }
      faces.push_back(plane_of[f]);
    }
  for (const auto& [e, faces] : edge_faces) {
    if (faces.size() == 2 && faces[0] == faces[1]) continue;
    const Eigen::Vector3d dir = (m.V.row(e.second) - m.V.row(e.first)).transpose();
    if (dir.norm() == 0) continue;
    const Eigen::Vector3d u = dir.normalized();
    bool seen = false;
    for (const auto& q : p.edges) seen = seen || std::abs(q.dot(u)) > 1 - 1e-12;
    if (!seen) p.edges.push_back(u);
  }
  // each plane's polygon: its vertices in angular order about the face centre
  p.faces.assign(p.normals.size(), {});
  for (std::size_t k = 0; k < p.normals.size(); ++k) {
    std::vector<int>& face = p.faces[k];
    for (std::size_t v = 0; v < p.vertices.size(); ++v)
      if (std::abs(p.normals[k].dot(p.vertices[v]) - p.offsets[k]) <= 1e-9 * scale)
        face.push_back(static_cast<int>(v));
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : face) c += p.vertices[v];
    c /= static_cast<double>(face.size());
    const Eigen::Vector3d n = p.normals[k];
    const Eigen::Vector3d e1 = (p.vertices[face[0]] - c).normalized(), e2 = n.cross(e1);
    std::sort(face.begin(), face.end(), [&](int x, int y) {
      const Eigen::Vector3d dx = p.vertices[x] - c, dy = p.vertices[y] - c;
      return std::atan2(dx.dot(e2), dx.dot(e1)) < std::atan2(dy.dot(e2), dy.dot(e1));
    });
  }
  p.centroid = mass_properties(m).centroid;
  return p;
}

namespace {

// the face of p whose normal is closest to direction n
int best_face(const ConvexPolytope& p, const Eigen::Vector3d& n, double* alignment) {
  int best = 0;
  *alignment = -2;
  for (std::size_t k = 0; k < p.normals.size(); ++k) {
    const double x = p.normals[k].dot(n);
    if (x > *alignment) {
      *alignment = x;
      best = static_cast<int>(k);
    }
  }
  return best;
}

// clips the polygon `poly` by the side planes of face `f` of `p` (Sutherland-Hodgman)
std::vector<Eigen::Vector3d> clip_by_face(std::vector<Eigen::Vector3d> poly,
                                          const ConvexPolytope& p, int f) {
  const std::vector<int>& face = p.faces[f];
  const Eigen::Vector3d n = p.normals[f];
  for (std::size_t k = 0; k < face.size() && !poly.empty(); ++k) {
    const Eigen::Vector3d a = p.vertices[face[k]], b = p.vertices[face[(k + 1) % face.size()]];
    const Eigen::Vector3d side = (b - a).cross(n);  // outward in the face plane (CCW face)
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Eigen::Vector3d& p0 = poly[i];
      const Eigen::Vector3d& p1 = poly[(i + 1) % poly.size()];
      const double d0 = side.dot(p0 - a), d1 = side.dot(p1 - a);
      if (d0 <= 0) out.push_back(p0);
      if ((d0 < 0 && d1 > 0) || (d0 > 0 && d1 < 0))
        out.push_back(p0 + (d0 / (d0 - d1)) * (p1 - p0));
    }
    poly = std::move(out);
  }
  return poly;
}

}  // namespace

ContactManifold contact_manifold(const ConvexPolytope& a, const ConvexPolytope& b,
                                 const ConvexDistance& d, double angle_tolerance) {
  ContactManifold m;
  m.normal = d.normal;
  const Eigen::Vector3d n = d.normal;
  double align_a = 0, align_b = 0;
  const int fa = best_face(a, n, &align_a);   // A's face towards B
  const int fb = best_face(b, -n, &align_b);  // B's face towards A
  const double parallel = std::cos(angle_tolerance);
  auto point = [&](const Eigen::Vector3d& on_a, const Eigen::Vector3d& on_b) {
    m.points.push_back({on_a, on_b, n.dot(on_b - on_a)});
  };
  if (align_a >= parallel && align_b >= parallel) {
    // face on face: B's face clipped by A's side planes; each corner projected on A's face
    m.feature = ContactFeature::kFaceFace;
    std::vector<Eigen::Vector3d> poly;
    for (int v : b.faces[fb]) poly.push_back(b.vertices[v]);
    const Eigen::Vector3d na = a.normals[fa];
    for (const Eigen::Vector3d& q : clip_by_face(poly, a, fa)) {
      const double h = na.dot(q) - a.offsets[fa];
      point(q - h * na, q);
    }
    if (!m.points.empty()) return m;
  }
  // one face square to the normal: the other body's nearest vertex, or its nearest edge
  // clipped by the face (two points, so an edge resting on a face does not rock); the
  // other body's nearest vertices are those lowest along `towards` (from it to the face)
  auto edge_on_face = [&](const ConvexPolytope& face_body, int f, const ConvexPolytope& other,
                          const Eigen::Vector3d& towards, bool face_is_a) {
    double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
    for (const auto& v : other.vertices) {
      lowest = std::min(lowest, towards.dot(v));
      highest = std::max(highest, towards.dot(v));
    }
    std::vector<Eigen::Vector3d> near;
    for (const auto& v : other.vertices)
      if (towards.dot(v) <= lowest + 1e-9 * (highest - lowest)) near.push_back(v);
    if (near.empty() || near.size() > 2) return false;
    const Eigen::Vector3d nf = face_body.normals[f];
    std::vector<Eigen::Vector3d> kept;
    for (const auto& q : clip_by_face(near, face_body, f)) {
      bool seen = false;
      for (const auto& k : kept) seen = seen || (k - q).norm() <= 1e-12 * (highest - lowest + 1);
      if (!seen) kept.push_back(q);
    }
    if (kept.empty()) return false;
    for (const auto& q : kept) {
      const Eigen::Vector3d on_face = q - (nf.dot(q) - face_body.offsets[f]) * nf;
      if (face_is_a)
        point(on_face, q);
      else
        point(q, on_face);
    }
    return true;
  };
  if (align_a >= parallel) {
    m.feature = ContactFeature::kVertexFace;  // B's vertex (or edge) on A's face
    if (edge_on_face(a, fa, b, n, true)) return m;
  } else if (align_b >= parallel) {
    m.feature = ContactFeature::kFaceVertex;  // A's vertex (or edge) on B's face
    if (edge_on_face(b, fb, a, -n, false)) return m;
  } else {
    // edge on edge: the normal is the cross product of the two edges (Eq. 17), oriented
    // from A to B; the edges are those most square to the distance direction
    m.feature = ContactFeature::kEdgeEdge;
    double best = -1;
    Eigen::Vector3d cross = n;
    for (const auto& ea : a.edges)
      for (const auto& eb : b.edges) {
        const Eigen::Vector3d c = ea.cross(eb);
        const double len = c.norm();
        if (len < 1e-9) continue;
        const double x = std::abs(c.dot(n)) / len;
        if (x > best) {
          best = x;
          cross = c / len;
        }
      }
    if (best >= parallel) {
      m.normal = cross.dot(n) >= 0 ? cross : Eigen::Vector3d(-cross);
    } else {
      // no edge pair is square to the witness line: vertex on edge or vertex on vertex,
      // whose normal is indeterminate; the witness direction is the robust choice
      m.feature = ContactFeature::kVertexVertex;
    }
  }
  if (d.overlap) {
    // overlapping: B's deepest vertex along the normal and its place pushed out of A
    // (the support points of an overlap can lie far apart on large bodies)
    Eigen::Vector3d deepest = b.vertices[0];
    for (const auto& v : b.vertices)
      if (m.normal.dot(v) < m.normal.dot(deepest)) deepest = v;
    point(deepest + d.penetration * m.normal, deepest);
    m.points.back().gap = -d.penetration;
    return m;
  }
  m.points.push_back({d.point_a, d.point_b, m.normal.dot(d.point_b - d.point_a)});
  return m;
}

void place(const ConvexPolytope& p, const Eigen::Isometry3d& pose, ConvexPolytope* world) {
  ConvexPolytope& q = *world;
  if (q.faces.size() != p.faces.size() || q.neighbours.size() != p.neighbours.size()) {
    q.neighbours = p.neighbours;
    q.faces = p.faces;
  }
  const Eigen::Matrix3d r = pose.linear();
  q.vertices.resize(p.vertices.size());
  for (std::size_t k = 0; k < p.vertices.size(); ++k) q.vertices[k] = pose * p.vertices[k];
  q.normals.resize(p.normals.size());
  q.offsets.resize(p.offsets.size());
  for (std::size_t k = 0; k < p.normals.size(); ++k) {
    q.normals[k] = r * p.normals[k];
    q.offsets[k] = p.offsets[k] + q.normals[k].dot(pose.translation());
  }
  q.edges.resize(p.edges.size());
  for (std::size_t k = 0; k < p.edges.size(); ++k) q.edges[k] = r * p.edges[k];
  q.centroid = pose * p.centroid;
}

ConvexPolytope transformed(const ConvexPolytope& p, const Eigen::Isometry3d& pose) {
  ConvexPolytope q;
  place(p, pose, &q);
  return q;
}

namespace {

int support(const std::vector<Eigen::Vector3d>& v, const Eigen::Vector3d& d) {
  int best = 0;
  double best_dot = v[0].dot(d);
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double x = v[i].dot(d);
    if (x > best_dot) {
      best_dot = x;
      best = static_cast<int>(i);
    }
  }
  return best;
}

// The support vertex by climbing the vertex graph from `start` (a few neighbours per step
// instead of every vertex); small polytopes are scanned whole.
int support(const ConvexPolytope& p, const Eigen::Vector3d& d, int start) {
  if (p.vertices.size() <= 16 || p.neighbours.size() != p.vertices.size())
    return support(p.vertices, d);
  int at = start;
  double best = p.vertices[at].dot(d);
  for (bool moved = true; moved;) {
    moved = false;
    for (int n : p.neighbours[at]) {
      const double x = p.vertices[n].dot(d);
      if (x > best) {
        best = x;
        at = n;
        moved = true;
      }
    }
  }
  return at;
}

// The point of the simplex (1 to 4 points; the last one the newest) closest to the
// origin: over the faces of the simplex that hold the newest point (the closest point of
// the previous simplex is not improved on otherwise) whose affine projection of the
// origin falls inside them, the nearest. Returns the barycentric weights (zero off the
// chosen face); `inside` when the origin is in the tetrahedron. Fixed-size arithmetic.
Eigen::Vector4d closest_on_simplex(const std::array<Eigen::Vector3d, 4>& w, int n, bool* inside) {
  *inside = false;
  Eigen::Vector4d best_l = Eigen::Vector4d::Zero();
  double best = std::numeric_limits<double>::infinity();
  const int last = n - 1;
  for (int mask = 0; mask < (1 << last); ++mask) {
    int idx[4], m = 0;
    for (int i = 0; i < last; ++i)
      if (mask & (1 << i)) idx[m++] = i;
    idx[m++] = last;
    Eigen::Vector4d l = Eigen::Vector4d::Zero();
    const Eigen::Vector3d& p0 = w[idx[0]];
    if (m == 1) {
      l[idx[0]] = 1;
    } else {
      // min |p0 + D mu| with D = [p_i - p0]: the normal equations, 1 to 3 unknowns
      Eigen::Matrix3d d = Eigen::Matrix3d::Zero();
      for (int k = 1; k < m; ++k) d.col(k - 1) = w[idx[k]] - p0;
      const int k = m - 1;
      Eigen::Vector3d mu = Eigen::Vector3d::Zero();
      if (k == 1) {
        const double dd = d.col(0).squaredNorm();
        if (!(dd > 0)) continue;
        mu[0] = -p0.dot(d.col(0)) / dd;
      } else if (k == 2) {
        const Eigen::Matrix<double, 3, 2> d2 = d.leftCols<2>();
        const Eigen::Matrix2d g = d2.transpose() * d2;
        const double det = g.determinant();
        if (!(det > 1e-24 * g(0, 0) * g(1, 1))) continue;
        mu.head<2>() = g.inverse() * (-(d2.transpose() * p0));
      } else {
        const Eigen::Matrix3d g = d.transpose() * d;
        const double det = g.determinant();
        if (!(det > 1e-24 * g(0, 0) * g(1, 1) * g(2, 2))) continue;
        mu = g.inverse() * (-(d.transpose() * p0));
      }
      double sum = 0;
      bool ok = true;
      for (int j = 1; j < m; ++j) {
        l[idx[j]] = mu[j - 1];
        sum += mu[j - 1];
        ok = ok && mu[j - 1] > 0;
      }
      l[idx[0]] = 1 - sum;
      if (!ok || !(l[idx[0]] > 0)) continue;
      if (m == 4) {
        *inside = true;
        return l;
      }
    }
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) p += l[i] * w[i];
    const double dist = p.squaredNorm();
    if (dist < best) {
      best = dist;
      best_l = l;
    }
  }
  return best_l;
}

}  // namespace

double penetration_depth(const ConvexPolytope& a, const ConvexPolytope& b,
                         Eigen::Vector3d* normal) {
  double depth = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best = Eigen::Vector3d::UnitZ();
  // the polytopes' extents along an axis by climbing their vertex graphs, each climb
  // starting where the last one ended (neighbouring axes have neighbouring supports)
  int a_hi = 0, a_lo = 0, b_hi = 0, b_lo = 0;
  auto axis = [&](const Eigen::Vector3d& n) {
    a_hi = support(a, n, a_hi);
    a_lo = support(a, -n, a_lo);
    b_hi = support(b, n, b_hi);
    b_lo = support(b, -n, b_lo);
    const double amax = a.vertices[a_hi].dot(n), amin = a.vertices[a_lo].dot(n);
    const double bmax = b.vertices[b_hi].dot(n), bmin = b.vertices[b_lo].dot(n);
    // push B along +n (overlap amax - bmin) or along -n (bmax - amin)
    const double plus = amax - bmin, minus = bmax - amin;
    if (plus < depth) {
      depth = plus;
      best = n;
    }
    if (minus < depth) {
      depth = minus;
      best = -n;
    }
  };
  for (const auto& n : a.normals) axis(n);
  for (const auto& n : b.normals) axis(n);
  // touching to rounding along a face's normal: no edge pair can do better (it would
  // separate bodies that touch), and the face's normal is the one wanted. This skips the
  // edge pairs that cost a 64-segment sphere resting on a slab 9 ms per step (issue 13).
  const double size = (a.vertices[0] - a.centroid).norm() + (b.vertices[0] - b.centroid).norm();
  if (depth <= 1e-9 * size) {
    if (normal) *normal = best;
    return depth;
  }
  for (const auto& ea : a.edges)
    for (const auto& eb : b.edges) {
      const Eigen::Vector3d c = ea.cross(eb);
      const double len = c.norm();
      if (len > 1e-9) axis(c / len);
    }
  if (normal) *normal = best;
  return depth;
}

namespace {

void fill_overlap(const ConvexPolytope& a, const ConvexPolytope& b, ConvexDistance* r) {
  r->overlap = true;
  r->distance = 0;
  r->penetration = penetration_depth(a, b, &r->normal);
  // the deepest points along the separating direction
  r->point_a = a.vertices[support(a.vertices, r->normal)];
  r->point_b = b.vertices[support(b.vertices, -r->normal)];
}

}  // namespace

ConvexDistance gjk_distance(const ConvexPolytope& a, const ConvexPolytope& b, double tolerance) {
  ConvexDistance r;
  std::array<Eigen::Vector3d, 4> w, pa, pb;
  int n = 0;
  Eigen::Vector3d v = a.vertices[0] - b.vertices[0];
  Eigen::Vector4d lambda(1, 0, 0, 0);
  w[0] = v;
  pa[0] = a.vertices[0];
  pb[0] = b.vertices[0];
  n = 1;
  const double scale2 = std::max(v.squaredNorm(), 1e-300);
  int last_a = 0, last_b = 0;
  for (int it = 0; it < 128; ++it) {
    r.iterations = it + 1;
    const double vv = v.squaredNorm();
    if (vv <= 1e-28 * scale2) {
      fill_overlap(a, b, &r);
      return r;
    }
    const int ia = support(a, -v, last_a), ib = support(b, v, last_b);
    last_a = ia;
    last_b = ib;
    const Eigen::Vector3d wn = a.vertices[ia] - b.vertices[ib];
    // converged: the support point gets no closer than v (relative gap)
    if (vv - v.dot(wn) <= tolerance * vv) break;
    bool repeated = false;
    for (int i = 0; i < n; ++i) repeated = repeated || (w[i] - wn).squaredNorm() == 0;
    if (repeated) break;
    w[n] = wn;
    pa[n] = a.vertices[ia];
    pb[n] = b.vertices[ib];
    ++n;
    bool inside = false;
    const Eigen::Vector4d l = closest_on_simplex(w, n, &inside);
    if (inside) {
      fill_overlap(a, b, &r);
      return r;
    }
    // keep only the points that carry weight
    int m = 0;
    Eigen::Vector3d next = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i)
      if (l[i] > 0) {
        next += l[i] * w[i];
        w[m] = w[i];
        pa[m] = pa[i];
        pb[m] = pb[i];
        lambda[m] = l[i];
        ++m;
      }
    if (m == 0 || next.squaredNorm() >= vv) break;  // no progress: v is the answer
    n = m;
    v = next;
  }
  r.point_a.setZero();
  r.point_b.setZero();
  for (int i = 0; i < n; ++i) {
    r.point_a += lambda[i] * pa[i];
    r.point_b += lambda[i] * pb[i];
  }
  r.distance = v.norm();
  r.normal = r.distance > 0 ? Eigen::Vector3d(-v / r.distance) : Eigen::Vector3d::UnitZ();
  return r;
}

ConvexDistance qp_distance(const ConvexPolytope& a, const ConvexPolytope& b) {
  // z = (x, y); constraints G z <= h: A's faces on x, B's on y
  const int na = static_cast<int>(a.normals.size()), nb = static_cast<int>(b.normals.size());
  const int m = na + nb;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(m, 6);
  Eigen::VectorXd h(m);
  for (int i = 0; i < na; ++i) {
    g.block<1, 3>(i, 0) = a.normals[i].transpose();
    h[i] = a.offsets[i];
  }
  for (int i = 0; i < nb; ++i) {
    g.block<1, 3>(na + i, 3) = b.normals[i].transpose();
    h[na + i] = b.offsets[i];
  }
  const double scale = std::max((a.centroid - b.centroid).norm(), 1e-300);
  // start where the centroid line leaves each body (the seed's starting point)
  auto exit_point = [](const ConvexPolytope& p, const Eigen::Vector3d& to) {
    const Eigen::Vector3d d = to - p.centroid;
    double t = 1;
    for (std::size_t k = 0; k < p.normals.size(); ++k) {
      const double nd = p.normals[k].dot(d);
      if (nd > 0) t = std::min(t, (p.offsets[k] - p.normals[k].dot(p.centroid)) / nd);
    }
    return Eigen::Vector3d(p.centroid + std::max(t, 0.0) * d);
  };
  Eigen::Matrix<double, 6, 1> z;
  z << exit_point(a, b.centroid), exit_point(b, a.centroid);
  const double tol = 1e-12 * scale;
  std::vector<int> active;
  for (int i = 0; i < m; ++i)
    if (g.row(i).dot(z) >= h[i] - tol) active.push_back(i);
  Eigen::Matrix<double, 6, 6> hess = Eigen::Matrix<double, 6, 6>::Zero();
  hess.topLeftCorner<3, 3>().setIdentity();
  hess.bottomRightCorner<3, 3>().setIdentity();
  hess.topRightCorner<3, 3>() = -Eigen::Matrix3d::Identity();
  hess.bottomLeftCorner<3, 3>() = -Eigen::Matrix3d::Identity();
  ConvexDistance r;
  for (int it = 0; it < 500; ++it) {
    r.iterations = it + 1;
    const Eigen::Matrix<double, 6, 1> grad = hess * z;
    // null space of the active constraints
    Eigen::MatrixXd z_basis;
    if (active.empty()) {
      z_basis = Eigen::MatrixXd::Identity(6, 6);
    } else {
      Eigen::MatrixXd ga(active.size(), 6);
      for (std::size_t k = 0; k < active.size(); ++k) ga.row(k) = g.row(active[k]);
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(ga, Eigen::ComputeFullV);
      const double cut = 1e-10 * svd.singularValues()[0];
      int rank = 0;
      for (Eigen::Index k = 0; k < svd.singularValues().size(); ++k)
        rank += svd.singularValues()[k] > cut;
      z_basis = svd.matrixV().rightCols(6 - rank);
    }
    Eigen::Matrix<double, 6, 1> p = Eigen::Matrix<double, 6, 1>::Zero();
    if (z_basis.cols() > 0) {
      // minimize over the subspace (the reduced Hessian may be singular: pseudo-inverse)
      const Eigen::MatrixXd rh = z_basis.transpose() * hess * z_basis;
      const Eigen::VectorXd rg = z_basis.transpose() * grad;
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(rh);
      Eigen::VectorXd q = Eigen::VectorXd::Zero(rh.rows());
      for (Eigen::Index k = 0; k < rh.rows(); ++k) {
        const double ev = es.eigenvalues()[k];
        if (ev > 1e-12) q -= es.eigenvectors().col(k) * (es.eigenvectors().col(k).dot(rg) / ev);
      }
      p = z_basis * q;
    }
    if (p.norm() <= 1e-15 * scale) {
      // optimal on this face set unless a multiplier is negative: G_W' lambda = -grad
      if (active.empty()) break;
      Eigen::MatrixXd gat(6, active.size());
      for (std::size_t k = 0; k < active.size(); ++k) gat.col(k) = g.row(active[k]).transpose();
      const Eigen::VectorXd lambda = gat.completeOrthogonalDecomposition().solve(-grad);
      Eigen::Index worst = 0;
      const double most_negative = lambda.minCoeff(&worst);
      if (most_negative >= -1e-12 * std::max(1.0, grad.norm())) break;
      active.erase(active.begin() + worst);
      continue;
    }
    // ratio test against the inactive constraints
    double alpha = 1;
    int blocking = -1;
    for (int i = 0; i < m; ++i) {
      if (std::find(active.begin(), active.end(), i) != active.end()) continue;
      const double gp = g.row(i).dot(p);
      if (gp <= 0) continue;
      const double step = (h[i] - g.row(i).dot(z)) / gp;
      if (step < alpha) {
        alpha = std::max(step, 0.0);
        blocking = i;
      }
    }
    z += alpha * p;
    if (blocking >= 0) active.push_back(blocking);
  }
  r.point_a = z.head<3>();
  r.point_b = z.tail<3>();
  r.distance = (r.point_b - r.point_a).norm();
  if (r.distance <= 1e-12 * scale) {
    fill_overlap(a, b, &r);
    return r;
  }
  r.normal = (r.point_b - r.point_a) / r.distance;
  return r;
}

}  // namespace vproto::geometry
