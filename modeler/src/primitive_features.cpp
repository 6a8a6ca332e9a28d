// Evaluation of the primitive solids (box, cylinder, sphere, wedge, prism, import) into
// feature-tree leaves, with the work limits on facets and triangles.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "evaluator_impl.h"

namespace vproto::modeler {

long estimated_triangles(const Feature& f) {
  const long n = f.segments;
  switch (f.kind) {
    case Feature::Kind::kBox:
      return 12;
    case Feature::Kind::kWedge:
      return 8;
    case Feature::Kind::kCylinder:
      return 4 * n;
    case Feature::Kind::kSphere:
      return 2 * n * ((n + 1) / 2);
    case Feature::Kind::kPrism:
      return 4 * static_cast<long>(f.polygon.rows());
    default:
      return 0;
  }
}

namespace detail {
namespace {
using units::Dimension;
}  // namespace

Feature Evaluator::primitive(const Stmt& s, const Scope& scope, const Eigen::Affine3d& placement) {
  Feature f;
  f.loc = s.loc;
  f.transform = placement;
  const Dimension length = Dimension::of_length();
  auto size3 = [&](const BoundArgs& a, const std::string& what) {
    const Value* v = a.get("size");
    if (!v) throw InputError(s.loc, what + "() needs size=[x, y, z]");
    const SourceLoc loc = a.loc_of("size", s.loc);
    Eigen::Vector3d size;
    if (v->is_number())
      size.setConstant(quantity(*v, length, loc, what + "() size"));
    else
      size = vec3(*v, length, loc, what + "() size");
    if (!(size.array() > 0).all())
      throw InputError(loc, what + "() size must be positive in x, y and z");
    return size;
  };

  if (s.name == "box") {
    const BoundArgs a = bind("box", s.args, scope, {"size", "center"}, {}, s.loc);
    f.kind = Feature::Kind::kBox;
    f.size = size3(a, "box");
    if (const Value* c = a.get("center")) f.center = flag(*c, a.loc_of("center", s.loc), "center");
  } else if (s.name == "wedge") {
    const BoundArgs a = bind("wedge", s.args, scope, {"size"}, {}, s.loc);
    f.kind = Feature::Kind::kWedge;
    f.size = size3(a, "wedge");
  } else if (s.name == "cylinder") {
    const BoundArgs a = bind("cylinder", s.args, scope, {"h", "r1", "r2", "center"},
                             {"r", "d", "d1", "d2", "segments"}, s.loc);
    f.kind = Feature::Kind::kCylinder;
    if (!a.get("h")) throw InputError(s.loc, "cylinder() needs a height h");
    f.height = positive(*a.get("h"), length, a.loc_of("h", s.loc), "cylinder() h");
    auto radius = [&](const char* r, const char* d) -> std::optional<double> {
      const Value* rv = a.get(r);
      const Value* dv = a.get(d);
      if (rv && dv)
        throw InputError(a.loc_of(d, s.loc),
                         std::string("cylinder(): give ") + r + " or " + d + ", not both");
      if (rv) return quantity(*rv, length, a.loc_of(r, s.loc), std::string("cylinder() ") + r);
      if (dv)
        return 0.5 * quantity(*dv, length, a.loc_of(d, s.loc), std::string("cylinder() ") + d);
      return std::nullopt;
    };
    const auto r = radius("r", "d");
    auto r1 = radius("r1", "d1");
    auto r2 = radius("r2", "d2");
    if (r && (r1 || r2))
      throw InputError(s.loc,
                       "cylinder(): give r (or d) for a cylinder, or r1 and r2 for a cone, "
                       "not both");
    if (r) r1 = r2 = r;
    if (r1 && !r2) r2 = r1;  // cylinder(h, r1) is a cylinder, not a cone to radius 1
    if (!r1 && r2) r1 = r2;
    if (!r1) throw InputError(s.loc, "cylinder() needs a radius: r, d, or r1 and r2");
    f.r1 = *r1;
    f.r2 = *r2;
    if (f.r1 < 0 || f.r2 < 0) throw InputError(s.loc, "cylinder() radii must not be negative");
    if (!(f.r1 > 0 || f.r2 > 0)) throw InputError(s.loc, "cylinder() needs a radius above zero");
    if (const Value* c = a.get("center")) f.center = flag(*c, a.loc_of("center", s.loc), "center");
    f.segments = segments_for(a, s.loc);
  } else if (s.name == "sphere") {
    const BoundArgs a = bind("sphere", s.args, scope, {"r"}, {"d", "segments"}, s.loc);
    f.kind = Feature::Kind::kSphere;
    if (a.get("r") && a.get("d")) throw InputError(s.loc, "sphere(): give r or d, not both");
    if (a.get("r"))
      f.r1 = positive(*a.get("r"), length, a.loc_of("r", s.loc), "sphere() r");
    else if (a.get("d"))
      f.r1 = 0.5 * positive(*a.get("d"), length, a.loc_of("d", s.loc), "sphere() d");
    else
      throw InputError(s.loc, "sphere() needs a radius r or a diameter d");
    f.segments = segments_for(a, s.loc);
  } else if (s.name == "prism") {
    const BoundArgs a = bind("prism", s.args, scope, {"points", "h"}, {}, s.loc);
    f.kind = Feature::Kind::kPrism;
    const Value* pts = a.get("points");
    const SourceLoc ploc = a.loc_of("points", s.loc);
    if (!pts || !pts->is_vector() || pts->items->size() < 3)
      throw InputError(ploc, "prism() needs points=[[x,y], ...] with at least 3 points");
    f.polygon.resize(static_cast<Eigen::Index>(pts->items->size()), 2);
    for (std::size_t i = 0; i < pts->items->size(); ++i) {
      const Value& p = (*pts->items)[i];
      if (!p.is_vector() || p.items->size() != 2)
        throw InputError(
            ploc, "prism() point " + std::to_string(i) + " must be [x, y], got " + describe(p));
      for (int k = 0; k < 2; ++k)
        f.polygon(static_cast<Eigen::Index>(i), k) =
            quantity((*p.items)[k], length, ploc, "prism() point " + std::to_string(i));
    }
    for (Eigen::Index i = 0; i < f.polygon.rows(); ++i)
      if ((f.polygon.row(i) - f.polygon.row((i + 1) % f.polygon.rows())).norm() == 0)
        throw InputError(ploc, "prism() points " + std::to_string(i) + " and " +
                                   std::to_string((i + 1) % f.polygon.rows()) +
                                   " are the same; remove one");
    if (!a.get("h")) throw InputError(s.loc, "prism() needs a height h");
    f.height = positive(*a.get("h"), length, a.loc_of("h", s.loc), "prism() h");
  } else if (s.name == "fillet") {
    // the solid that rounds an inside corner: the square [0, r]^2 less the quarter disc of
    // radius r about (r, r), extruded along +z by h; placed in a corner whose faces are the
    // planes x = 0 and y = 0 (its edge the z axis) and united with the part, it leaves a
    // round of radius r. Its arc has a quarter of the circle's segments (3 at least).
    const BoundArgs a = bind("fillet", s.args, scope, {"r", "h"}, {"segments"}, s.loc);
    f.kind = Feature::Kind::kPrism;
    if (!a.get("r")) throw InputError(s.loc, "fillet() needs a radius r");
    if (!a.get("h")) throw InputError(s.loc, "fillet() needs a length h (along the edge, +z)");
    const double r = positive(*a.get("r"), length, a.loc_of("r", s.loc), "fillet() r");
    f.height = positive(*a.get("h"), length, a.loc_of("h", s.loc), "fillet() h");
    const double pi = std::acos(-1.0);
    const int arc = std::max(3, segments_for(a, s.loc) / 4);
    f.polygon.resize(arc + 2, 2);
    f.polygon.row(0) << 0, 0;
    for (int k = 0; k <= arc; ++k) {  // from (r, 0) round to (0, r), about (r, r)
      const double angle = -0.5 * pi - 0.5 * pi * k / arc;
      f.polygon.row(k + 1) << r + r * std::cos(angle), r + r * std::sin(angle);
    }
    f.polygon(1, 0) = r, f.polygon(1, 1) = 0;  // exactly on the faces' planes
    f.polygon(arc + 1, 0) = 0, f.polygon(arc + 1, 1) = r;
  } else {  // import
    const BoundArgs a = bind("import", s.args, scope, {"file"}, {}, s.loc);
    const Value* file = a.get("file");
    if (!file || file->type != Value::Type::kString)
      throw InputError(s.loc, "import() needs a file name in quotes: import(\"part.stl\")");
    namespace fs = std::filesystem;
    fs::path path(file->text);
    if (path.is_relative()) path = fs::path(script_dir_) / path;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw InputError(a.loc_of("file", s.loc), "import(): cannot find the file '" + path.string() +
                                                    "' (paths are relative to the script)");
    f.kind = Feature::Kind::kImport;
    f.path = fs::weakly_canonical(path, ec).string();
    if (ec) f.path = path.string();
  }

  // work limits, checked before anything is built
  if (++leaves_ > limits_.max_leaves)
    throw InputError(
        s.loc, "the script makes more than " + std::to_string(limits_.max_leaves) + " primitives");
  const long tris = estimated_triangles(f);
  body_triangles_ += tris;
  total_triangles_ += tris;
  if (body_triangles_ > limits_.max_body_triangles)
    throw InputError(s.loc, "this body would have more than " +
                                std::to_string(limits_.max_body_triangles) +
                                " triangles before Booleans: lower segments or facets");
  if (total_triangles_ > limits_.max_total_triangles)
    throw InputError(s.loc, "the script would make more than " +
                                std::to_string(limits_.max_total_triangles) +
                                " triangles: lower segments or facets");
  return f;
}

}  // namespace detail
}  // namespace vproto::modeler
