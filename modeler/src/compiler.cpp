#include "vproto/modeler/compiler.h"

#include <unistd.h>
#include <xxhash.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "vproto/geometry/convex_parts.h"
#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/geometry/tet_mesh.h"
#include "vproto/sim/contact_surface.h"

namespace vproto::modeler {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Bumped whenever meshing of primitives or the CSG changes, so old cache entries die.
constexpr char kCacheVersion[] = "vproto-csg-3";

class Hasher {
 public:
  Hasher() : state_(XXH3_createState()) { XXH3_128bits_reset(state_); }
  ~Hasher() { XXH3_freeState(state_); }
  Hasher(const Hasher&) = delete;
  Hasher& operator=(const Hasher&) = delete;

  void bytes(const void* p, std::size_t n) { XXH3_128bits_update(state_, p, n); }
  void number(double x) { bytes(&x, sizeof x); }
  void integer(long x) { bytes(&x, sizeof x); }
  void text(const std::string& s) {
    integer(static_cast<long>(s.size()));
    bytes(s.data(), s.size());
  }
  std::string hex() const {
    const XXH128_hash_t h = XXH3_128bits_digest(state_);
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                  static_cast<unsigned long long>(h.low64));
    return buf;
  }

 private:
  XXH3_state_t* state_;
};

void hash_file(Hasher& h, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char buf[1 << 16];
  while (in) {
    in.read(buf, sizeof buf);
    h.bytes(buf, static_cast<std::size_t>(in.gcount()));
  }
}

void hash_feature(Hasher& h, const Feature& f) {
  h.integer(static_cast<long>(f.kind));
  if (f.is_leaf()) {
    for (int i = 0; i < 3; ++i) h.number(f.size[i]);
    h.integer(f.center);
    h.number(f.height);
    h.number(f.r1);
    h.number(f.r2);
    h.integer(f.segments);
    h.integer(static_cast<long>(f.polygon.rows()));
    for (Eigen::Index i = 0; i < f.polygon.size(); ++i) h.number(f.polygon.data()[i]);
    for (int i = 0; i < 16; ++i) h.number(f.transform.matrix().data()[i]);
    if (f.kind == Feature::Kind::kImport) {
      h.text(f.path);
      hash_file(h, f.path);
    }
  }
  h.integer(static_cast<long>(f.children.size()));
  for (const auto& c : f.children) hash_feature(h, c);
}

// --- cache files: magic, counts, raw arrays, then a checksum of all that ---
// (issue 13: a damaged entry of the right size was trusted, and gave a wrong volume)

std::uint64_t checksum(const std::string& bytes) { return XXH3_64bits(bytes.data(), bytes.size()); }

template <typename T>
void put(std::string& out, const T* data, std::size_t count) {
  out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

// Writes a cache entry whole, or not at all.
void write_file(const fs::path& path, const std::string& bytes) {
  // a name of this process's own: runs sharing a cache (a sweep over MPI ranks) may
  // write one entry at once
  const fs::path tmp = path.string() + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return;  // a cache that cannot be written is skipped, not an error
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) {
      out.close();
      fs::remove(tmp);
      return;
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) fs::remove(tmp, ec);
}

// Reads a cache entry whose 8-byte magic is `magic` and whose checksum (its last 8 bytes)
// covers everything before it; false for anything else.
bool read_checked(const fs::path& path, const char* magic, std::string* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  bytes->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (bytes->size() < 24 || std::memcmp(bytes->data(), magic, 8) != 0) return false;
  const std::size_t payload = bytes->size() - sizeof(std::uint64_t);
  std::uint64_t sum = 0;
  std::memcpy(&sum, bytes->data() + payload, sizeof sum);
  return checksum(bytes->substr(0, payload)) == sum;
}

// Reads an entry's fields in order, up to its checksum.
class Cursor {
 public:
  explicit Cursor(const std::string& bytes)
      : bytes_(bytes), end_(bytes.size() - sizeof(std::uint64_t)) {}
  bool take(void* to, std::size_t size) {
    if (size > end_ - at_) return false;
    std::memcpy(to, bytes_.data() + at_, size);
    at_ += size;
    return true;
  }
  bool at_end() const { return at_ == end_; }

 private:
  const std::string& bytes_;
  std::size_t end_, at_ = 8;  // past the magic
};

void write_meshes(const fs::path& path, const std::vector<geometry::TriMesh>& meshes) {
  std::string bytes("VPMESH2", 8);
  const std::int64_t n = static_cast<std::int64_t>(meshes.size());
  put(bytes, &n, 1);
  for (const auto& m : meshes) {
    const std::int64_t nv = m.V.rows(), nf = m.F.rows();
    put(bytes, &nv, 1);
    put(bytes, &nf, 1);
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v = m.V;
    const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> f = m.F;
    put(bytes, v.data(), static_cast<std::size_t>(v.size()));
    put(bytes, f.data(), static_cast<std::size_t>(f.size()));
  }
  const std::uint64_t sum = checksum(bytes);
  put(bytes, &sum, 1);
  write_file(path, bytes);
}

bool read_meshes(const fs::path& path, std::vector<geometry::TriMesh>* meshes) {
  std::string bytes;
  if (!read_checked(path, "VPMESH2", &bytes)) return false;
  Cursor c(bytes);
  std::int64_t n = 0;
  if (!c.take(&n, sizeof n) || n < 0 || n > 10'000'000) return false;
  meshes->clear();
  for (std::int64_t k = 0; k < n; ++k) {
    std::int64_t nv = 0, nf = 0;
    if (!c.take(&nv, sizeof nv) || !c.take(&nf, sizeof nf)) return false;
    if (nv < 0 || nf < 0 || nv > 100'000'000 || nf > 100'000'000) return false;
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v(nv, 3);
    Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> f(nf, 3);
    if (!c.take(v.data(), static_cast<std::size_t>(v.size()) * sizeof(double)) ||
        !c.take(f.data(), static_cast<std::size_t>(f.size()) * sizeof(int)))
      return false;
    if (f.size() && (f.minCoeff() < 0 || f.maxCoeff() >= nv)) return false;
    geometry::TriMesh m;
    m.V = v;
    m.F = f;
    meshes->push_back(std::move(m));
  }
  return c.at_end();
}

// A body's volume mesh in the cache, under the hash of its surface's subtree and every
// meshing option (the annular cap's Mesh_3 took 25 s of each run; a run that changes a
// load, a drive or a material meshes nothing). Only what make_tet_mesh returns is kept;
// the quality, the walls and the display surface are recomputed from it.
// Bumped whenever make_tet_mesh changes what it makes, so old volume meshes die.
constexpr char kTetCacheVersion[] = "vproto-tets-1";

std::string tet_cache_key(const std::string& surface_hash, const geometry::TetMeshOptions& o) {
  Hasher h;
  h.text(kCacheVersion);
  h.text(kTetCacheVersion);
  h.text(surface_hash);
  h.number(o.size);
  h.number(o.max_size);
  h.number(o.grading);
  h.number(o.thin_wall);
  h.integer(static_cast<long>(o.fine_boxes.size()));
  for (const geometry::Bounds& b : o.fine_boxes)
    for (int k = 0; k < 3; ++k) {
      h.number(b.lo[k]);
      h.number(b.hi[k]);
    }
  h.integer(o.quadratic ? 1 : 0);
  h.number(o.feature_angle);
  h.integer(o.max_elements);
  return h.hex();
}

void write_tets(const fs::path& path, const geometry::TetMesh& mesh) {
  std::string bytes("VPTETS1", 8);
  const std::int64_t counts[3] = {mesh.nodes.rows(), mesh.elements.rows(), mesh.elements.cols()};
  put(bytes, counts, 3);
  const double sizes[2] = {mesh.mesh_size, mesh.max_size};
  put(bytes, sizes, 2);
  const std::int64_t fine = mesh.fine_faces;
  put(bytes, &fine, 1);
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v = mesh.nodes;
  const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> e = mesh.elements;
  put(bytes, v.data(), static_cast<std::size_t>(v.size()));
  put(bytes, e.data(), static_cast<std::size_t>(e.size()));
  const std::uint64_t sum = checksum(bytes);
  put(bytes, &sum, 1);
  write_file(path, bytes);
}

bool read_tets(const fs::path& path, geometry::TetMesh* mesh) {
  std::string bytes;
  if (!read_checked(path, "VPTETS1", &bytes)) return false;
  Cursor c(bytes);
  std::int64_t counts[3] = {0, 0, 0}, fine = 0;
  double sizes[2] = {0, 0};
  if (!c.take(counts, sizeof counts) || !c.take(sizes, sizeof sizes) || !c.take(&fine, sizeof fine))
    return false;
  const std::int64_t nodes = counts[0], elements = counts[1], corners = counts[2];
  if (nodes < 4 || elements < 1 || (corners != 4 && corners != 10) || nodes > 500'000'000 ||
      elements > 500'000'000)
    return false;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v(nodes, 3);
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> e(elements, corners);
  if (!c.take(v.data(), static_cast<std::size_t>(v.size()) * sizeof(double)) ||
      !c.take(e.data(), static_cast<std::size_t>(e.size()) * sizeof(int)) || !c.at_end())
    return false;
  if (e.minCoeff() < 0 || e.maxCoeff() >= nodes || !v.allFinite()) return false;
  mesh->nodes = v;
  mesh->elements = e;
  mesh->mesh_size = sizes[0];
  mesh->max_size = sizes[1];
  mesh->fine_faces = static_cast<long>(fine);
  return true;
}

geometry::TriMesh leaf_mesh(const Feature& f, const MeshLoader& load_mesh) {
  using geometry::GeometryError;
  geometry::TriMesh local;
  switch (f.kind) {
    case Feature::Kind::kBox:
      local = geometry::make_box(f.size, f.center);
      break;
    case Feature::Kind::kWedge:
      local = geometry::make_wedge(f.size);
      break;
    case Feature::Kind::kCylinder:
      local = geometry::make_cylinder(f.height, f.r1, f.r2, f.segments, f.center);
      break;
    case Feature::Kind::kSphere:
      local = geometry::make_sphere(f.r1, f.segments);
      break;
    case Feature::Kind::kPrism:
      try {
        local = geometry::make_prism(f.polygon, f.height);
      } catch (const GeometryError& e) {
        throw InputError(f.loc, std::string("prism(): ") + e.what());
      }
      break;
    case Feature::Kind::kImport: {
      if (!load_mesh) throw InternalError("import without a mesh loader");
      try {
        local = load_mesh(f.path);
      } catch (const InputError& e) {
        // the place is the import statement (issue 13: the error named only the file)
        throw InputError(f.loc,
                         "import(): cannot read '" + f.path + "': " + e.message() +
                             "; give a mesh file of a closed solid (STL, OBJ, PLY, OFF, ...)");
      }
      // a closed mesh that faces inward is turned outward; anything else must be fixed
      if (geometry::mass_properties(local).volume < 0) local.F.col(1).swap(local.F.col(2));
      const std::string problem = geometry::solid_validation_error(local);
      if (!problem.empty())
        throw InputError(f.loc, "import(): '" + f.path + "' is not a closed solid: " + problem +
                                    "; repair the mesh (e.g. close its holes) and export it again");
      break;
    }
    default:
      throw InternalError("leaf_mesh of a Boolean");
  }
  return geometry::transformed(local, f.transform);
}

}  // namespace

// A body's mesh is said not to follow a wall thinner than this share of its mesh size: the
// paw sample's hook with 85-degree faces (a fin 0.12 mm thin under 2.54 mm elements, 21
// times as thick) pushed over its catch with 2.1 N, against 4.0 N and 2.5 N on meshes two
// and four times as fine (no convergence: the thin fin folds, beyond the linear model), and
// let it through on the way out (exit 3); at 80 degrees (10 times) its push was within 5 %
// of a mesh four times as fine (9.3, 9.1, 8.9 N), and the snap-fit's hooks (7.5 times) are
// validated against CalculiX.
constexpr double kThinWallShare = 1.0 / 16;

double default_mesh_size(const geometry::TriMesh& surface) {
  const double thin = geometry::thinnest_wall(surface);
  const double volume = geometry::mass_properties(surface).volume;
  // about 10 elements across the thinnest wall, but no finer than about 1e5 tetrahedra
  const double coarsest_uniform = std::cbrt(8.5 * volume / 1e5);
  const double h = std::max(std::isfinite(thin) ? thin / 10 : 0.0, coarsest_uniform);
  // and never coarser than that wall: one element across it still bends (tet10), where a
  // coarser size could not mesh a plate thinner than about 8 mm at all (issue 13)
  return std::isfinite(thin) ? std::min(h, thin) : h;
}

std::string feature_hash(const Feature& tree) {
  Hasher h;
  h.text(kCacheVersion);
  hash_feature(h, tree);
  return h.hex();
}

geometry::CsgNode to_csg(const Feature& f, const MeshLoader& load_mesh) {
  if (f.is_leaf()) return geometry::CsgNode::make_leaf(leaf_mesh(f, load_mesh));
  geometry::CsgNode node;
  node.op = f.kind == Feature::Kind::kUnion        ? geometry::BooleanOp::kUnion
            : f.kind == Feature::Kind::kDifference ? geometry::BooleanOp::kDifference
                                                   : geometry::BooleanOp::kIntersection;
  for (const auto& c : f.children) node.children.push_back(to_csg(c, load_mesh));
  return node;
}

CompileReport compile_bodies(EvaluatedScript& script, const CompileOptions& options) {
  CompileReport report;
  // cache entries are written only once every body has compiled, so a failed build
  // leaves nothing behind
  std::vector<std::pair<fs::path, std::vector<geometry::TriMesh>>> to_cache;
  const int total = static_cast<int>(script.scene.bodies.size());
  int done = 0;
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line, done, total);
  };
  for (std::size_t i = 0; i < script.scene.bodies.size(); ++i) {
    sim::Body& body = script.scene.bodies[i];
    const Feature& tree = script.body_trees[i];
    BodyReport br;
    br.hash = feature_hash(tree);
    const fs::path cached =
        options.cache_dir.empty() ? fs::path() : options.cache_dir / (br.hash + ".mesh");

    // surface: from the cache when this exact subtree was built before
    const auto t0 = Clock::now();
    std::vector<geometry::TriMesh> meshes;
    if (!cached.empty() && read_meshes(cached, &meshes) && meshes.size() == 1 &&
        geometry::mass_properties(meshes[0]).volume > 0) {
      body.surface = std::move(meshes[0]);
      br.from_cache = true;
      say("csg: " + body.name + " (cached)");
    } else {
      say("csg: " + body.name);
      geometry::CsgStats stats;
      try {
        body.surface = geometry::evaluate_csg(to_csg(tree, options.load_mesh), &stats);
      } catch (const geometry::GeometryError& e) {
        throw InputError(body.loc, "body '" + body.name + "': " + e.what());
      }
      br.corefinements = stats.corefinements;
      if (body.surface.empty())
        throw InputError(body.loc,
                         "body '" + body.name +
                             "' is empty: its Booleans remove "
                             "everything (check difference() and intersection() operands)");
      if (!cached.empty()) to_cache.push_back({cached, {body.surface}});
    }
    br.csg_seconds = seconds_since(t0);
    report.csg_seconds += br.csg_seconds;

    // mass properties
    body.mass_properties = geometry::mass_properties(body.surface);
    body.mass = body.material.density * body.mass_properties.volume;
    body.inertia = body.material.density * body.mass_properties.unit_inertia;

    // convex parts only when asked, cached by the same hash
    const bool wants_convex = options.convex_part_bodies.empty()
                                  ? options.convex_parts
                                  : options.convex_part_bodies.at(i) != 0;
    if (wants_convex) {
      const auto t1 = Clock::now();
      const fs::path cparts =
          options.cache_dir.empty() ? fs::path() : options.cache_dir / (br.hash + ".convex");
      if (!cparts.empty() && read_meshes(cparts, &body.convex_parts) &&
          !body.convex_parts.empty()) {
        br.convex_from_cache = true;
        say("convex parts: " + body.name + " (cached)");
      } else {
        say("convex parts: " + body.name);
        try {
          body.convex_parts = geometry::convex_parts(body.surface);
        } catch (const geometry::GeometryError& e) {
          throw InputError(body.loc,
                           "body '" + body.name + "': convex decomposition failed: " + e.what());
        }
        if (!cparts.empty()) to_cache.push_back({cparts, body.convex_parts});
      }
      body.convex_parts_computed = true;
      br.convex_seconds = seconds_since(t1);
      report.convex_seconds += br.convex_seconds;
    }
    report.bodies.push_back(br);
    ++done;
  }
  // tetrahedral meshes for elastic bodies only (rigid bodies are never meshed), once every
  // surface is known (a graded mesh is fine near the bodies that can touch it)
  for (std::size_t i = 0; i < script.scene.bodies.size(); ++i) {
    sim::Body& body = script.scene.bodies[i];
    BodyReport& br = report.bodies[i];
    const bool wants_tets =
        options.tet_mesh_bodies.empty() ? options.tet_meshes : options.tet_mesh_bodies.at(i) != 0;
    if (wants_tets && body.kind == sim::BodyKind::kElastic) {
      const auto t2 = Clock::now();
      geometry::TetMeshOptions mo;
      mo.size = body.mesh_size > 0 ? body.mesh_size : default_mesh_size(body.surface);
      mo.quadratic = body.element == sim::ElementType::kTet10;
      if (i < options.contact_partners.size() && !options.contact_partners[i].empty()) {
        // graded: fine where bodies can touch and where the body is thin (it bends there)
        mo.max_size = 4 * mo.size;
        mo.thin_wall = 4 * mo.size;
        const auto& partners = options.contact_partners[i];
        for (std::size_t k = 0; k < partners.size(); ++k) {
          geometry::Bounds box = geometry::bounds(script.scene.bodies.at(partners[k]).surface);
          if (i < options.contact_travel.size() && k < options.contact_travel[i].size()) {
            box.lo += options.contact_travel[i][k].lo;
            box.hi += options.contact_travel[i][k].hi;
          }
          box.lo.array() -= 2 * mo.size;
          box.hi.array() += 2 * mo.size;
          mo.fine_boxes.push_back(box);
        }
      }
      const fs::path tets = options.cache_dir.empty()
                                ? fs::path()
                                : options.cache_dir / (tet_cache_key(br.hash, mo) + ".tets");
      if (!tets.empty() && read_tets(tets, &body.tet_mesh)) {
        br.tets_from_cache = true;
        say("tet mesh: " + body.name + " (cached)");
      } else {
        say("tet mesh: " + body.name);
        try {
          body.tet_mesh = geometry::make_tet_mesh(body.surface, mo);
        } catch (const geometry::GeometryError& e) {
          // a size the script did not give is said to be the default, and how it was chosen
          const std::string whose =
              body.mesh_size > 0 ? ""
                                 : " (that is the default mesh_size: about 10 elements across "
                                   "the thinnest wall, no finer than about 1e5 tetrahedra, no "
                                   "coarser than the wall; give mesh_size= to choose)";
          throw InputError(body.loc, "body '" + body.name + "': " + e.what() + whose);
        }
        if (!tets.empty()) report.pending_tets.push_back({tets, body.tet_mesh});
      }
      body.tet_quality = geometry::tet_quality(body.tet_mesh);
      // A wall far thinner than the elements under it (a hook's fin under 85-degree faces,
      // 0.12 mm thick under 2.54 mm elements) meshes, but one element across it is many
      // times its thickness: it bends too stiffly, and a partner's corner can pass through
      // it (the fin let the catch through, 1.7 mm deep, on the paw's way back out: exit 3).
      const geometry::Wall wall = geometry::thinnest_wall_at(body.surface);
      body.thinnest_wall = std::isfinite(wall.thickness) ? wall.thickness : 0.0;
      if (body.thinnest_wall > 0 && body.thinnest_wall < kThinWallShare * mo.size) {
        char text[480];
        std::snprintf(text, sizeof text,
                      ":%d:%d: warning: body '%s': its thinnest wall, %.3g m thick near (%.3g, "
                      "%.3g, %.3g) m, is meshed with elements of %.3g m, %.0f times as thick: "
                      "it bends too stiffly and a partner can pass through it; give a "
                      "mesh_size of %.3g m or less (one element across it) or thicken it",
                      body.loc.line, body.loc.column, body.name.c_str(), wall.thickness,
                      wall.at.x(), wall.at.y(), wall.at.z(), mo.size, mo.size / wall.thickness,
                      wall.thickness);
        report.warnings.push_back(body.loc.file + text);
      }
      body.display = sim::display_surface(body.tet_mesh);
      body.meshed = true;
      br.tetmesh_seconds = seconds_since(t2);
      report.tetmesh_seconds += br.tetmesh_seconds;
    }
  }
  if (options.progress) options.progress("bodies compiled", done, total);
  report.pending_cache = std::move(to_cache);
  if (!options.defer_cache) commit_cache(report);
  return report;
}

void commit_cache(CompileReport& report) {
  for (const auto& [path, meshes] : report.pending_cache) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (ec) break;
    write_meshes(path, meshes);
  }
  for (const auto& [path, mesh] : report.pending_tets) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (ec) break;
    write_tets(path, mesh);
  }
  report.pending_cache.clear();
  report.pending_tets.clear();
}

}  // namespace vproto::modeler
