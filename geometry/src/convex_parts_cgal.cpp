// The one translation unit that instantiates CGAL Nef polyhedra: exact convex
// decomposition (convex_decomposition_3) and convex hulls of its parts.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_decomposition_3.h>
#include <CGAL/convex_hull_3.h>

#include "cgal_convert.h"
#include "vproto/geometry/convex_parts.h"
#include "vproto/geometry/mass_properties.h"

namespace vproto::geometry {
namespace {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;
using ExactPolyhedron = CGAL::Polyhedron_3<Exact>;
using Nef = CGAL::Nef_polyhedron_3<Exact>;
using InexactMesh = CGAL::Surface_mesh<Inexact::Point_3>;

TriMesh hull_of(const std::vector<Inexact::Point_3>& points) {
  InexactMesh hull;
  CGAL::convex_hull_3(points.begin(), points.end(), hull);
  return detail::to_trimesh(hull, [](double x) { return x; });
}

std::vector<Inexact::Point_3> points_of(const TriMesh& tm) {
  std::vector<Inexact::Point_3> pts(static_cast<std::size_t>(tm.V.rows()));
  for (Eigen::Index i = 0; i < tm.V.rows(); ++i) pts[i] = {tm.V(i, 0), tm.V(i, 1), tm.V(i, 2)};
  return pts;
}

}  // namespace

bool is_convex(const TriMesh& solid) {
  if (solid.empty()) return false;
  const double volume = mass_properties(solid).volume;
  const double hull_volume = mass_properties(hull_of(points_of(solid))).volume;
  return std::abs(hull_volume - volume) <= 1e-12 * std::abs(hull_volume);
}

std::vector<TriMesh> convex_parts(const TriMesh& solid) {
  if (solid.empty()) return {};
  if (is_convex(solid)) return {hull_of(points_of(solid))};

  // build the Nef polyhedron from an exact polyhedral surface
  ExactPolyhedron poly;
  {
    std::vector<Exact::Point_3> pts;
    pts.reserve(static_cast<std::size_t>(solid.V.rows()));
    for (Eigen::Index i = 0; i < solid.V.rows(); ++i)
      pts.emplace_back(solid.V(i, 0), solid.V(i, 1), solid.V(i, 2));
    std::vector<std::vector<std::size_t>> faces(static_cast<std::size_t>(solid.F.rows()));
    for (Eigen::Index f = 0; f < solid.F.rows(); ++f)
      faces[f] = {static_cast<std::size_t>(solid.F(f, 0)), static_cast<std::size_t>(solid.F(f, 1)),
                  static_cast<std::size_t>(solid.F(f, 2))};
    CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(pts, faces, poly);
  }
  Nef nef(poly);
  CGAL::convex_decomposition_3(nef);

  // every marked volume but the outer one is a convex part
  std::vector<TriMesh> parts;
  auto volume = nef.volumes_begin();
  for (++volume; volume != nef.volumes_end(); ++volume) {
    if (!volume->mark()) continue;
    ExactPolyhedron part;
    nef.convert_inner_shell_to_polyhedron(volume->shells_begin(), part);
    std::vector<Inexact::Point_3> pts;
    for (auto v = part.vertices_begin(); v != part.vertices_end(); ++v)
      pts.emplace_back(CGAL::to_double(v->point().x()), CGAL::to_double(v->point().y()),
                       CGAL::to_double(v->point().z()));
    parts.push_back(hull_of(pts));
  }
  return parts;
}

}  // namespace vproto::geometry
