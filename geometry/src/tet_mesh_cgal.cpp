// The one translation unit that instantiates CGAL Mesh_3 (and the AABB tree used to
// measure wall thickness).
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>

#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/tet_mesh.h"

namespace vproto::geometry {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using MeshDomain = CGAL::Polyhedral_mesh_domain_with_features_3<K>;
using Polyhedron = MeshDomain::Polyhedron;
using Tr = CGAL::Mesh_triangulation_3<MeshDomain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 =
    CGAL::Mesh_complex_3_in_triangulation_3<Tr, MeshDomain::Corner_index, MeshDomain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;

constexpr double kPi = 3.14159265358979323846;

template <typename Mesh>
void fill_from(const TriMesh& tm, Mesh& out) {
  std::vector<K::Point_3> pts(static_cast<std::size_t>(tm.V.rows()));
  for (Eigen::Index i = 0; i < tm.V.rows(); ++i) pts[i] = {tm.V(i, 0), tm.V(i, 1), tm.V(i, 2)};
  std::vector<std::array<std::size_t, 3>> faces(static_cast<std::size_t>(tm.F.rows()));
  for (Eigen::Index f = 0; f < tm.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) faces[f][k] = static_cast<std::size_t>(tm.F(f, k));
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(pts, faces, out);
}

double signed_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

// the wall under each face: the distance from its centre inward along its normal to the
// opposite surface (infinity when the ray leaves through nothing, a degenerate face); with
// `corners`, the least of that and the walls under three points near its corners (a long
// triangle of a merged planar face can span a thin part and a thick one)
std::vector<double> face_walls(const TriMesh& surface, bool corners = false) {
  SurfaceMesh mesh;
  fill_from(surface, mesh);
  using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  Tree tree(faces(mesh).first, faces(mesh).second, mesh);
  std::vector<double> walls(mesh.number_of_faces(), std::numeric_limits<double>::infinity());
  for (auto f : mesh.faces()) {
    const auto h = mesh.halfedge(f);
    const K::Point_3 a = mesh.point(mesh.source(h)), b = mesh.point(mesh.target(h)),
                     c = mesh.point(mesh.target(mesh.next(h)));
    const K::Vector_3 n = CGAL::cross_product(b - a, c - a);
    const double len = std::sqrt(CGAL::to_double(n.squared_length()));
    if (!(len > 0)) continue;
    std::vector<K::Point_3> samples{CGAL::centroid(a, b, c)};
    if (corners)
      for (const auto& [p, q, r] : {std::array{a, b, c}, std::array{b, c, a}, std::array{c, a, b}})
        samples.push_back(CGAL::barycenter(p, 0.8, q, 0.1, r, 0.1));
    // start a hair inside so the ray does not hit its own face
    const K::Vector_3 inward = -n / len;
    for (const K::Point_3& centre : samples) {
      const K::Ray_3 ray(centre + inward * 1e-9, inward);
      const auto hit =
          tree.first_intersection(ray, [f](SurfaceMesh::Face_index g) { return g == f; });
      if (!hit) continue;
      if (const K::Point_3* p = boost::get<K::Point_3>(&hit->first)) {
        double& w = walls[static_cast<std::size_t>(f.idx())];
        w = std::min(w, std::sqrt(CGAL::to_double(CGAL::squared_distance(centre, *p))));
      }
    }
  }
  return walls;
}

}  // namespace

std::vector<double> ray_distances(const TriMesh& surface,
                                  const std::vector<Eigen::Vector3d>& origins,
                                  const std::vector<Eigen::Vector3d>& directions) {
  std::vector<double> out(origins.size(), std::numeric_limits<double>::infinity());
  if (origins.empty()) return out;
  SurfaceMesh mesh;
  fill_from(surface, mesh);
  using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  const Tree tree(faces(mesh).first, faces(mesh).second, mesh);
  for (std::size_t i = 0; i < origins.size(); ++i) {
    const K::Point_3 o(origins[i].x(), origins[i].y(), origins[i].z());
    const K::Ray_3 ray(o, K::Vector_3(directions[i].x(), directions[i].y(), directions[i].z()));
    const auto hit = tree.first_intersection(ray);
    if (!hit) continue;
    if (const K::Point_3* p = boost::get<K::Point_3>(&hit->first))
      out[i] = std::sqrt(CGAL::to_double(CGAL::squared_distance(o, *p)));
  }
  return out;
}

std::vector<NearestFace> nearest_faces(const TriMesh& surface,
                                       const std::vector<Eigen::Vector3d>& points) {
  std::vector<NearestFace> out(points.size());
  if (points.empty()) return out;
  SurfaceMesh mesh;
  fill_from(surface, mesh);
  using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  Tree tree(faces(mesh).first, faces(mesh).second, mesh);
  tree.accelerate_distance_queries();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const K::Point_3 q(points[i].x(), points[i].y(), points[i].z());
    const auto [at, face] = tree.closest_point_and_primitive(q);
    out[i].distance = std::sqrt(CGAL::to_double(CGAL::squared_distance(q, at)));
    const auto h = mesh.halfedge(face);
    const K::Point_3 a = mesh.point(mesh.source(h)), b = mesh.point(mesh.target(h)),
                     c = mesh.point(mesh.target(mesh.next(h)));
    const K::Vector_3 n = CGAL::cross_product(b - a, c - a);
    out[i].normal =
        Eigen::Vector3d(CGAL::to_double(n.x()), CGAL::to_double(n.y()), CGAL::to_double(n.z()))
            .normalized();
  }
  return out;
}

double thinnest_wall(const TriMesh& surface) { return thinnest_wall_at(surface).thickness; }

Wall thinnest_wall_at(const TriMesh& surface) {
  const std::vector<double> walls = face_walls(surface);
  Wall out;
  out.thickness = std::numeric_limits<double>::infinity();
  // (the soup's faces keep their order in the face graph, when it took them all)
  const bool same = walls.size() == static_cast<std::size_t>(surface.F.rows());
  for (std::size_t f = 0; f < walls.size(); ++f)
    if (walls[f] < out.thickness) {
      out.thickness = walls[f];
      const auto i = static_cast<Eigen::Index>(f);
      if (same)
        out.at = (surface.V.row(surface.F(i, 0)) + surface.V.row(surface.F(i, 1)) +
                  surface.V.row(surface.F(i, 2)))
                     .transpose() /
                 3;
    }
  return out;
}

namespace {

// The part of a convex polygon inside an axis-aligned box (Sutherland-Hodgman, one plane
// of the box after another): empty, or a convex polygon.
std::vector<Eigen::Vector3d> clip_to_box(std::vector<Eigen::Vector3d> poly, const Bounds& box) {
  for (int axis = 0; axis < 3 && !poly.empty(); ++axis)
    for (const int side : {-1, 1}) {
      const double limit = side < 0 ? box.lo[axis] : box.hi[axis];
      // inside: side * (p[axis] - limit) <= 0
      auto inside = [&](const Eigen::Vector3d& p) { return side * (p[axis] - limit) <= 0; };
      std::vector<Eigen::Vector3d> out;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Eigen::Vector3d& p = poly[i];
        const Eigen::Vector3d& q = poly[(i + 1) % poly.size()];
        if (inside(p)) out.push_back(p);
        if (inside(p) != inside(q)) {
          const double t = (limit - p[axis]) / (q[axis] - p[axis]);
          Eigen::Vector3d x = p + t * (q - p);
          x[axis] = limit;
          out.push_back(x);
        }
      }
      poly = std::move(out);
    }
  return poly;
}

// The mesh size at a point: the finest size in the fine zone, growing with the distance
// from it (CGAL calls it for edges, facets and cells alike). The fine zone is made of the
// thin faces and of the parts of faces inside the fine boxes (a long face that reaches
// into a box is fine only there). Elsewhere a wall keeps four elements across it (a
// quarter of its thickness near its faces, or the size if that is larger): a wall thinner
// than `thin_wall` (4 sizes) is fine throughout, and one just thicker must not come out
// coarser, or a finer mesh_size would give a coarser beam (a 0.25 in paw was meshed at
// 0.07 in throughout with mesh_size 0.07 in, and at up to 0.2 in with 0.05 in).
class GradedSize {
 public:
  GradedSize(const TriMesh& surface, const TetMeshOptions& o, long* fine_faces)
      : size_(o.size), max_size_(o.max_size), grading_(o.grading) {
    const std::vector<double> walls =
        o.thin_wall > 0 ? face_walls(surface, true) : std::vector<double>();
    for (Eigen::Index f = 0; f < surface.F.rows(); ++f) {
      const Eigen::Vector3d a = surface.V.row(surface.F(f, 0)), b = surface.V.row(surface.F(f, 1)),
                            c = surface.V.row(surface.F(f, 2));
      auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
        // a sliver of a clip (a face grazing a box's side) adds nothing but a degenerate
        // triangle for the distance queries
        if (!((q - p).cross(r - p).norm() > 1e-12 * (q - p).squaredNorm() + 1e-300)) return;
        fine_->emplace_back(point(p), point(q), point(r));
      };
      if (!walls.empty() && walls[static_cast<std::size_t>(f)] < o.thin_wall) {
        add(a, b, c);
        ++*fine_faces;
        continue;
      }
      if (!walls.empty() && walls[static_cast<std::size_t>(f)] / 4 < max_size_) {
        walled_->emplace_back(point(a), point(b), point(c));
        wall_size_->push_back(std::max(size_, walls[static_cast<std::size_t>(f)] / 4));
      }
      bool counted = false;
      for (const Bounds& box : o.fine_boxes) {
        const std::vector<Eigen::Vector3d> piece = clip_to_box({a, b, c}, box);
        for (std::size_t k = 2; k < piece.size(); ++k) add(piece[0], piece[k - 1], piece[k]);
        if (piece.size() >= 3 && !counted) {
          ++*fine_faces;
          counted = true;
        }
      }
    }
    if (!fine_->empty()) {
      tree_ = std::make_shared<Tree>(fine_->cbegin(), fine_->cend());
      tree_->accelerate_distance_queries();
    }
    if (!walled_->empty()) {
      walls_ = std::make_shared<Tree>(walled_->cbegin(), walled_->cend());
      walls_->accelerate_distance_queries();
    }
  }
  template <typename Index>
  double operator()(const K::Point_3& p, int, const Index&) const {
    double size = max_size_;
    if (tree_)
      size =
          std::min(size, size_ + grading_ * std::sqrt(CGAL::to_double(tree_->squared_distance(p))));
    if (walls_) {  // the nearest wall's own size, growing from it as from the fine zone
      const auto [q, id] = walls_->closest_point_and_primitive(p);
      const double d = std::sqrt(CGAL::to_double(CGAL::squared_distance(p, q)));
      size = std::min(
          size, (*wall_size_)[static_cast<std::size_t>(id - walled_->cbegin())] + grading_ * d);
    }
    return size;
  }

 private:
  using Triangles = std::vector<K::Triangle_3>;
  using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  double size_, max_size_, grading_;
  static K::Point_3 point(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
  // CGAL copies the field; the trees' primitives point into the faces, which the copies
  // share with the first
  std::shared_ptr<Triangles> fine_ = std::make_shared<Triangles>();  ///< the fine zone
  std::shared_ptr<Tree> tree_;
  /// faces whose wall is thinner than four times max_size, and per face a quarter of its
  /// wall (at least the size)
  std::shared_ptr<Triangles> walled_ = std::make_shared<Triangles>();
  std::shared_ptr<std::vector<double>> wall_size_ = std::make_shared<std::vector<double>>();
  std::shared_ptr<Tree> walls_;
};

// How many tetrahedra the graded mesh of `surface` will have, about: the integral of 8.5 /
// size^3 over the solid, its sizing sampled at the centres of a grid of cells no larger
// than the coarsest size, up to 64 a side (those inside the solid).
double graded_estimate(const TriMesh& surface, const TetMeshOptions& options) {
  long fine_faces = 0;
  const GradedSize sizing(surface, options, &fine_faces);
  Polyhedron poly;
  fill_from(surface, poly);
  const CGAL::Side_of_triangle_mesh<Polyhedron, K> side(poly);
  const Bounds box = bounds(surface);
  const Eigen::Vector3d extent = box.hi - box.lo;
  const double cell =
      std::max(extent.maxCoeff() / 64, std::min(options.max_size, extent.minCoeff()));
  Eigen::Vector3i cells;
  for (int a = 0; a < 3; ++a) cells[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / cell)));
  const Eigen::Vector3d step = extent.cwiseQuotient(cells.cast<double>());
  const double cell_volume = step.prod();
  double sum = 0;
  for (int i = 0; i < cells.x(); ++i)
    for (int j = 0; j < cells.y(); ++j)
      for (int k = 0; k < cells.z(); ++k) {
        const Eigen::Vector3d c =
            box.lo + step.cwiseProduct(Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5));
        const K::Point_3 p(c.x(), c.y(), c.z());
        if (side(p) == CGAL::ON_UNBOUNDED_SIDE) continue;
        const double size = sizing(p, 3, 0);
        sum += 8.5 * cell_volume / (size * size * size);
      }
  return sum;
}

}  // namespace

TetMesh make_tet_mesh(const TriMesh& surface, const TetMeshOptions& options) {
  const double h = options.size;
  if (!(h > 0)) throw GeometryError("the mesh size must be positive");
  // refuse sizes that would take too long or too much memory, before meshing
  const double volume = mass_properties(surface).volume;
  double estimate = 8.5 * volume / (h * h * h);
  // a graded mesh is as fine as that only in its fine zone: its count is the integral of
  // 8.5 / size^3 over the solid, sampled on a grid (the snap-fit socket at mesh_size 0.25 /
  // 0.15 / 0.1 / 0.07 in: 4,481 / 21,859 / 68,078 / 197,879 estimated, 4,359 / 12,828 /
  // 37,796 / 104,598 meshed; the uniform estimate, 4.3 million at 0.1 in, refused it)
  if (estimate > static_cast<double>(options.max_elements) && options.max_size > h)
    estimate = graded_estimate(surface, options);
  if (estimate > static_cast<double>(options.max_elements))
    throw GeometryError("mesh_size " + std::to_string(h) + " m would give about " +
                        std::to_string(static_cast<long>(estimate)) + " tetrahedra (the limit is " +
                        std::to_string(options.max_elements) + "); use a larger mesh_size");
  const Bounds b = bounds(surface);
  const double thinnest_extent = (b.hi - b.lo).minCoeff();
  if (h > thinnest_extent * (1 + 1e-9))  // equal sizes, however rounded, are allowed
    throw GeometryError("the body is too thin for mesh_size " + std::to_string(h) +
                        " m: it is only " + std::to_string(thinnest_extent) +
                        " m thick; use a mesh_size below that");

  Polyhedron poly;
  fill_from(surface, poly);
  MeshDomain domain(poly);
  domain.detect_features(options.feature_angle);
  using namespace CGAL::parameters;
  const bool graded = options.max_size > h;
  long fine_faces = 0;
  std::optional<GradedSize> sizing;
  if (graded) sizing.emplace(surface, options, &fine_faces);
  const Criteria criteria =
      graded ? Criteria(edge_size = *sizing, facet_angle = 25, facet_size = *sizing,
                        facet_distance = h / 50, cell_radius_edge_ratio = 3, cell_size = *sizing)
             : Criteria(edge_size = h, facet_angle = 25, facet_size = h, facet_distance = h / 50,
                        cell_radius_edge_ratio = 3, cell_size = h);
  // Perturbation and exudation remove slivers. CGAL's default time limit for both is the
  // time the refinement took, which makes the mesh depend on the machine's load; without
  // a limit, stopping when no dihedral angle is below the bound or nothing improves, the
  // same input always gives the same mesh (and faster: 2.8 s for the snap-fit socket's
  // 140k tet10 against 5.4 s with the default limits). The perturber's random moves
  // creep slowly from 5 to 10 degrees on curved surfaces: a 900-node ball took 9.4 s
  // there (min angle 10.0) against 0.13 s stopping at 5 (min angle 5.1); exudation still
  // aims at 10.
  const C3t3 c3t3 =
      CGAL::make_mesh_3<C3t3>(domain, criteria, perturb(time_limit = 0, sliver_bound = 5),
                              exude(time_limit = 0, sliver_bound = 10));

  TetMesh out;
  out.mesh_size = h;
  if (graded) {
    out.max_size = options.max_size;
    out.fine_faces = fine_faces;
  }
  std::map<Tr::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::array<int, 4>> tets;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<int, 4> t{};
    for (int k = 0; k < 4; ++k) {
      const auto v = c->vertex(k);
      auto [it, added] = index.try_emplace(v, static_cast<int>(nodes.size()));
      if (added) {
        const auto& p = v->point();
        nodes.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
      }
      t[k] = it->second;
    }
    if (signed_volume(nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]) < 0)
      std::swap(t[2], t[3]);
    tets.push_back(t);
  }
  // Flat tetrahedra: exudation cannot move boundary vertices, so a tet whose four corners
  // lie on one planar face of the body can survive with a volume at rounding level. Its
  // stiffness grows as area^2 / thickness, which makes the system singular to working
  // precision; it holds no material, so it is removed (its nodes stay shared by its
  // neighbours, so the mesh stays conforming).
  auto flat = [&](const std::array<int, 4>& t) {
    double longest = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        longest = std::max(longest, (nodes[t[a]] - nodes[t[b]]).norm());
    return !(signed_volume(nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]) >
             1e-9 * longest * longest * longest);
  };
  tets.erase(std::remove_if(tets.begin(), tets.end(), flat), tets.end());
  if (tets.empty())
    throw GeometryError("the mesher produced no tetrahedra: mesh_size is too large for this body");
  {
    // drop nodes no element uses any more
    std::vector<int> renumber(nodes.size(), -1);
    std::vector<Eigen::Vector3d> used;
    for (auto& t : tets)
      for (int& v : t) {
        if (renumber[v] < 0) {
          renumber[v] = static_cast<int>(used.size());
          used.push_back(nodes[v]);
        }
        v = renumber[v];
      }
    nodes = std::move(used);
  }

  // quadratic elements: one shared node at the middle of every edge (the body is a
  // polyhedron, so straight mid-edge nodes lie exactly on its faces)
  const int per = options.quadratic ? 10 : 4;
  out.elements.resize(static_cast<Eigen::Index>(tets.size()), per);
  std::map<std::pair<int, int>, int> mid;
  static constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (std::size_t e = 0; e < tets.size(); ++e) {
    for (int k = 0; k < 4; ++k) out.elements(static_cast<Eigen::Index>(e), k) = tets[e][k];
    if (!options.quadratic) continue;
    for (int k = 0; k < 6; ++k) {
      const int a = tets[e][kEdges[k][0]], c = tets[e][kEdges[k][1]];
      auto [it, added] =
          mid.try_emplace({std::min(a, c), std::max(a, c)}, static_cast<int>(nodes.size()));
      if (added) nodes.push_back(0.5 * (nodes[a] + nodes[c]));
      out.elements(static_cast<Eigen::Index>(e), 4 + k) = it->second;
    }
  }
  out.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (std::size_t i = 0; i < nodes.size(); ++i)
    out.nodes.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
  // The mesh must hold together as the solid does. Where a feature is thinner than the
  // mesh can follow, elements can hang on the rest by an edge or a corner only (the snap-fit's
  // hooks with 80-degree lead faces, 0.45 mm at their root under 6.35 mm elements: 35 of them
  // in 31 pieces), and the stiffness is singular: until 2026-11-27 the run stopped on "K is
  // not positive definite" with no body named. (Meshed again finer around such pieces, the
  // hooks held together at half the size, but the base part's edge then crossed the 0.45 mm
  // flap, overlapping it by 0.95 mm within the contact's tolerance of a quarter of the
  // finest size: a run that cannot be vouched for, so it is refused.)
  const std::vector<TetPiece> pieces = tet_pieces(out.nodes, out.elements);
  const auto solids = static_cast<std::size_t>(surface_pieces(surface));
  if (pieces.size() > solids) {
    long loose = 0;
    double across = 0;
    for (std::size_t k = solids; k < pieces.size(); ++k) {
      loose += pieces[k].elements;
      across = std::max(across, (pieces[k].box.hi - pieces[k].box.lo).minCoeff());
    }
    const Eigen::Vector3d at = 0.5 * (pieces[solids].box.lo + pieces[solids].box.hi);
    char text[400];
    std::snprintf(text, sizeof text,
                  "the tetrahedral mesh at mesh_size %.4g m does not hold together: %ld "
                  "element(s) in %zu piece(s) (the first near (%.4g, %.4g, %.4g) m, about %.2g m "
                  "across) hang on the rest by an edge or a corner only, where a feature is "
                  "thinner than the mesh can follow; give a smaller mesh_size (near that "
                  "feature's thickness) or thicken the feature",
                  h, loose, pieces.size() - solids, at.x(), at.y(), at.z(), across);
    throw GeometryError(text);
  }
  return out;
}

TetQuality tet_quality(const TetMesh& mesh) {
  TetQuality q;
  q.min_dihedral_angle = 180;
  q.min_volume = std::numeric_limits<double>::infinity();
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (Eigen::Index e = 0; e < mesh.elements.rows(); ++e) {
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = mesh.nodes.row(mesh.elements(e, k)).transpose();
    const double v = signed_volume(p[0], p[1], p[2], p[3]);
    q.volume += v;
    q.min_volume = std::min(q.min_volume, v);
    // dihedral angle at edge (i, j) between the two faces holding it
    for (const auto& edge : kEdges) {
      int others[2], n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != edge[0] && k != edge[1]) others[n++] = k;
      const Eigen::Vector3d axis = (p[edge[1]] - p[edge[0]]).normalized();
      Eigen::Vector3d u = p[others[0]] - p[edge[0]], w = p[others[1]] - p[edge[0]];
      u -= u.dot(axis) * axis;
      w -= w.dot(axis) * axis;
      const double angle =
          std::acos(std::clamp(u.normalized().dot(w.normalized()), -1.0, 1.0)) * 180 / kPi;
      q.min_dihedral_angle = std::min(q.min_dihedral_angle, angle);
    }
    // circumradius over shortest edge
    const Eigen::Vector3d a = p[1] - p[0], b = p[2] - p[0], c = p[3] - p[0];
    const Eigen::Vector3d centre = (a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) +
                                    c.squaredNorm() * a.cross(b)) /
                                   (2 * a.dot(b.cross(c)));
    double shortest = std::numeric_limits<double>::infinity();
    for (const auto& edge : kEdges) shortest = std::min(shortest, (p[edge[1]] - p[edge[0]]).norm());
    q.max_radius_edge_ratio = std::max(q.max_radius_edge_ratio, centre.norm() / shortest);
  }
  return q;
}

}  // namespace vproto::geometry
