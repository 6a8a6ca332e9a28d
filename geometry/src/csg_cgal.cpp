// The one translation unit that instantiates CGAL Polygon Mesh Processing for CSG:
// corefinement Booleans, solid validation and polygon triangulation.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <cmath>
#include <numeric>

#include "cgal_convert.h"
#include "vproto/geometry/csg.h"
#include "vproto/materials/errors.h"

namespace vproto::geometry {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;
using ExactMesh = CGAL::Surface_mesh<Exact::Point_3>;
using InexactMesh = CGAL::Surface_mesh<Inexact::Point_3>;

// A solid during evaluation: exact mesh plus conservative bounds.
struct Solid {
  ExactMesh mesh;
  Bounds box;
  bool empty() const { return mesh.number_of_faces() == 0; }
};

Bounds exact_bounds(const ExactMesh& mesh) {
  Bounds b;
  for (auto v : mesh.vertices()) {
    const CGAL::Bbox_3 p = mesh.point(v).bbox();  // interval bounds: never too small
    b.lo = b.lo.cwiseMin(Eigen::Vector3d(p.xmin(), p.ymin(), p.zmin()));
    b.hi = b.hi.cwiseMax(Eigen::Vector3d(p.xmax(), p.ymax(), p.zmax()));
  }
  return b;
}

// Rounds to a multiple of `grid` (a power of two, so the result is exact).
double snap(double x, double grid) { return std::round(x / grid) * grid; }

// Operands are snapped to a grid of 2^-44 of the tree's extent (about 6e-14 relative)
// before the exact Booleans: faces and vertices that float arithmetic left 1e-17 apart
// (0.1 + 0.2 next to 0.3, sin(pi) = 1.2e-16) become exactly coincident, which the exact
// corefinement handles, instead of slivers far thinner than double precision.
double snap_grid(const CsgNode& node) {
  double extent = 0;
  std::vector<const CsgNode*> stack = {&node};
  while (!stack.empty()) {
    const CsgNode* n = stack.back();
    stack.pop_back();
    if (n->children.empty() && n->leaf.V.rows() > 0)
      extent = std::max(extent, n->leaf.V.cwiseAbs().maxCoeff());
    for (const auto& c : n->children) stack.push_back(&c);
  }
  if (!(extent > 0) || !std::isfinite(extent)) return 0;
  return std::ldexp(1.0, std::ilogb(extent) + 1 - 44);
}

Solid to_exact(const TriMesh& tm, double grid) {
  Solid s;
  TriMesh snapped = tm;
  if (grid > 0) snapped.V = tm.V.unaryExpr([grid](double x) { return snap(x, grid); });
  std::vector<ExactMesh::Vertex_index> vid(static_cast<std::size_t>(tm.V.rows()));
  for (Eigen::Index i = 0; i < tm.V.rows(); ++i)
    vid[i] = s.mesh.add_vertex(Exact::Point_3(snapped.V(i, 0), snapped.V(i, 1), snapped.V(i, 2)));
  for (Eigen::Index f = 0; f < tm.F.rows(); ++f) {
    if (s.mesh.add_face(vid[tm.F(f, 0)], vid[tm.F(f, 1)], vid[tm.F(f, 2)]) ==
        ExactMesh::null_face())
      throw GeometryError("an operand is not a 2-manifold surface");
  }
  s.box = bounds(snapped);
  return s;
}

double rounded(const Exact::FT& x) {
  const std::pair<double, double> iv = CGAL::to_interval(x);
  if (iv.first == iv.second) return iv.first;
  const double scale = std::max(std::abs(iv.first), std::abs(iv.second));
  if (iv.second - iv.first <= 1e-12 * scale) return 0.5 * (iv.first + iv.second);
  return CGAL::to_double(CGAL::exact(x));
}

TriMesh to_double(ExactMesh& mesh) { return detail::to_trimesh(mesh, rounded); }

// Runs one corefinement Boolean; `what` names it in errors.
Solid corefine(BooleanOp op, Solid a, Solid b, CsgStats& stats) {
  Solid out;
  bool ok = false;
  const auto np = CGAL::parameters::throw_on_self_intersection(true);
  try {
    switch (op) {
      case BooleanOp::kUnion:
        ok = PMP::corefine_and_compute_union(a.mesh, b.mesh, out.mesh, np, np);
        break;
      case BooleanOp::kDifference:
        ok = PMP::corefine_and_compute_difference(a.mesh, b.mesh, out.mesh, np, np);
        break;
      case BooleanOp::kIntersection:
        ok = PMP::corefine_and_compute_intersection(a.mesh, b.mesh, out.mesh, np, np);
        break;
    }
  } catch (const PMP::Corefinement::Self_intersection_exception&) {
    throw GeometryError("an operand of a Boolean intersects itself");
  }
  ++stats.corefinements;
  if (!ok)
    throw GeometryError(
        "the result of a Boolean is not a 2-manifold: solids touch along an edge or at a "
        "single point; overlap them or move them apart");
  out.box = exact_bounds(out.mesh);
  return out;
}

// Union of solids: groups whose bounds meet are corefined, separate groups appended.
Solid unite(std::vector<Solid> parts, CsgStats& stats) {
  parts.erase(std::remove_if(parts.begin(), parts.end(), [](const Solid& s) { return s.empty(); }),
              parts.end());
  if (parts.empty()) return {};
  // union-find over overlapping bounds
  std::vector<std::size_t> parent(parts.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < parts.size(); ++i)
    for (std::size_t j = i + 1; j < parts.size(); ++j)
      if (parts[i].box.overlaps(parts[j].box)) parent[find(i)] = find(j);
  std::vector<std::vector<std::size_t>> groups(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i) groups[find(i)].push_back(i);

  Solid result;
  for (const auto& group : groups) {
    if (group.empty()) continue;
    Solid acc = std::move(parts[group[0]]);
    for (std::size_t k = 1; k < group.size(); ++k)
      acc = corefine(BooleanOp::kUnion, std::move(acc), std::move(parts[group[k]]), stats);
    if (result.empty()) {
      result = std::move(acc);
    } else {
      ++stats.skipped_disjoint;
      result.mesh += acc.mesh;
      result.box.extend(acc.box);
    }
  }
  return result;
}

Solid evaluate(const CsgNode& node, double grid, CsgStats& stats, bool skips) {
  if (node.children.empty()) return node.leaf.empty() ? Solid{} : to_exact(node.leaf, grid);
  std::vector<Solid> parts;
  parts.reserve(node.children.size());
  for (const auto& child : node.children) parts.push_back(evaluate(child, grid, stats, skips));
  if (!skips) {
    // every operand through its own Boolean, in order
    Solid acc = std::move(parts[0]);
    for (std::size_t i = 1; i < parts.size(); ++i) {
      if (acc.empty() || parts[i].empty()) {
        if (node.op == BooleanOp::kUnion && acc.empty()) acc = std::move(parts[i]);
        if (node.op == BooleanOp::kIntersection) return {};
        continue;
      }
      acc = corefine(node.op, std::move(acc), std::move(parts[i]), stats);
    }
    return acc;
  }

  switch (node.op) {
    case BooleanOp::kUnion:
      return unite(std::move(parts), stats);
    case BooleanOp::kDifference: {
      Solid first = std::move(parts[0]);
      if (first.empty()) return first;
      // only subtrahends that reach the first solid matter; cut them all at once
      std::vector<Solid> cutters;
      for (std::size_t i = 1; i < parts.size(); ++i) {
        if (parts[i].empty()) continue;
        if (parts[i].box.overlaps(first.box))
          cutters.push_back(std::move(parts[i]));
        else
          ++stats.skipped_disjoint;
      }
      if (cutters.empty()) return first;
      Solid tool = unite(std::move(cutters), stats);
      return corefine(BooleanOp::kDifference, std::move(first), std::move(tool), stats);
    }
    case BooleanOp::kIntersection: {
      Solid acc = std::move(parts[0]);
      for (std::size_t i = 1; i < parts.size(); ++i) {
        if (acc.empty() || parts[i].empty() || !acc.box.overlaps(parts[i].box)) {
          ++stats.skipped_disjoint;
          return {};
        }
        acc = corefine(BooleanOp::kIntersection, std::move(acc), std::move(parts[i]), stats);
      }
      return acc;
    }
  }
  return {};
}

// What is wrong with a closed-or-not surface mesh as the boundary of a solid, or "".
std::string surface_problem(const InexactMesh& mesh) {
  if (!CGAL::is_closed(mesh)) {
    std::size_t open = 0;
    for (auto h : mesh.halfedges()) open += mesh.is_border(h) ? 1 : 0;
    return "it is not closed (" + std::to_string(open) + " boundary edges)";
  }
  for (auto f : mesh.faces())
    if (PMP::is_degenerate_triangle_face(f, mesh))
      return "it has a degenerate (zero-area) triangle";
  if (PMP::does_self_intersect(mesh)) return "it intersects itself";
  if (!PMP::is_outward_oriented(mesh)) return "its triangles face inward";
  return {};
}

// The rounded result as a halfedge mesh; false when rounding broke 2-manifoldness.
bool build_inexact(const TriMesh& tm, InexactMesh& mesh) {
  std::vector<InexactMesh::Vertex_index> vid;
  vid.reserve(static_cast<std::size_t>(tm.V.rows()));
  for (Eigen::Index i = 0; i < tm.V.rows(); ++i)
    vid.push_back(mesh.add_vertex({tm.V(i, 0), tm.V(i, 1), tm.V(i, 2)}));
  for (Eigen::Index f = 0; f < tm.F.rows(); ++f)
    if (mesh.add_face(vid[tm.F(f, 0)], vid[tm.F(f, 1)], vid[tm.F(f, 2)]) ==
        InexactMesh::null_face())
      return false;
  return true;
}

TriMesh evaluate_tree(const CsgNode& tree, CsgStats* stats, bool skips) {
  CsgStats local;
  Solid s = evaluate(tree, snap_grid(tree), stats ? *stats : local, skips);
  if (s.empty()) return {};
  // corefinement may leave exactly collinear triangles where operands share edges
  PMP::remove_degenerate_faces(s.mesh);
  TriMesh out = to_double(s.mesh);
  InexactMesh rounded_mesh;
  if (!build_inexact(out, rounded_mesh))
    throw GeometryError("the result is not a 2-manifold after rounding to double precision");
  // rounding can flatten a sliver: collapse those too, with exact predicates
  bool flat = false;
  for (auto f : rounded_mesh.faces())
    flat = flat || PMP::is_degenerate_triangle_face(f, rounded_mesh);
  if (flat && PMP::remove_degenerate_faces(rounded_mesh))
    out = detail::to_trimesh(rounded_mesh, [](double x) { return x; });
  const std::string problem = surface_problem(rounded_mesh);
  if (problem == "it intersects itself")
    throw GeometryError(
        "the result is not a valid solid: parts of it touch at a single point or along an "
        "edge, or cross each other; overlap such solids or move them apart");
  if (!problem.empty()) throw GeometryError("the result is not a valid solid: " + problem);
  // corefinement's output order follows the heap's layout (ties between equal boxes
  // broken by address), and Mesh_3 and the contact surfaces follow that order
  return canonically_ordered(out);
}

}  // namespace

TriMesh evaluate_csg(const CsgNode& tree, CsgStats* stats) {
  return evaluate_tree(tree, stats, true);
}

TriMesh evaluate_csg_unskipped(const CsgNode& tree, CsgStats* stats) {
  return evaluate_tree(tree, stats, false);
}

std::string solid_validation_error(const TriMesh& tm) {
  if (tm.F.rows() == 0) return "it has no triangles";
  const Eigen::Index nv = tm.V.rows();
  if (!tm.V.allFinite()) return "it has non-finite vertex coordinates";
  std::vector<std::array<std::size_t, 3>> polygons(static_cast<std::size_t>(tm.F.rows()));
  for (Eigen::Index f = 0; f < tm.F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (tm.F(f, k) < 0 || tm.F(f, k) >= nv) return "a triangle refers to a missing vertex";
      polygons[f][k] = static_cast<std::size_t>(tm.F(f, k));
    }
    if (tm.F(f, 0) == tm.F(f, 1) || tm.F(f, 1) == tm.F(f, 2) || tm.F(f, 0) == tm.F(f, 2))
      return "triangle " + std::to_string(f) + " repeats a vertex";
  }
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    return "it is not a 2-manifold surface (an edge shared by more than two triangles, "
           "inconsistent orientation, or surfaces that meet at a single vertex)";
  std::vector<Inexact::Point_3> points(static_cast<std::size_t>(nv));
  for (Eigen::Index i = 0; i < nv; ++i) points[i] = {tm.V(i, 0), tm.V(i, 1), tm.V(i, 2)};
  InexactMesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  return surface_problem(mesh);
}

Eigen::MatrixX3i triangulate_polygon(const Eigen::MatrixX2d& polygon) {
  CGAL::Polygon_2<Inexact> poly;
  for (Eigen::Index i = 0; i < polygon.rows(); ++i) poly.push_back({polygon(i, 0), polygon(i, 1)});
  if (!poly.is_simple())
    throw GeometryError("the polygon is not simple (its edges cross or it repeats a point)");
  if (poly.area() <= 0) throw GeometryError("the polygon has no area");
  // one polygonal face, triangulated without new vertices (CDT inside CGAL)
  InexactMesh mesh;
  std::vector<InexactMesh::Vertex_index> vid;
  for (const auto& p : poly.vertices()) vid.push_back(mesh.add_vertex({p.x(), p.y(), 0.0}));
  const auto face = mesh.add_face(vid);
  if (face == InexactMesh::null_face()) throw GeometryError("the polygon is degenerate");
  PMP::triangulate_faces(mesh);
  Eigen::MatrixX3i tris(static_cast<Eigen::Index>(mesh.number_of_faces()), 3);
  Eigen::Index t = 0;
  for (auto f : mesh.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
      tris(t, k++) = static_cast<int>(v.idx());
    ++t;
  }
  if (tris.rows() != polygon.rows() - 2)
    throw GeometryError("the polygon could not be triangulated");
  return tris;
}

}  // namespace vproto::geometry
