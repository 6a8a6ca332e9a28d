#pragma once
// Compiles evaluated feature trees into solid bodies: CSG, checks, mass properties and
// (on request) convex parts, with a content-addressed cache on disk so that a rebuild
// recomputes only the bodies whose feature subtree changed (and meshes only the elastic
// bodies whose surface or meshing options changed).

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "vproto/geometry/csg.h"
#include "vproto/geometry/tet_mesh.h"
#include "vproto/geometry/tri_mesh.h"
#include "vproto/modeler/evaluator.h"

namespace vproto::modeler {

/// Reads a closed mesh from a file (STL, OBJ, ...); throws InputError when it cannot.
using MeshLoader = std::function<geometry::TriMesh(const std::string& path)>;

struct CompileOptions {
  std::filesystem::path cache_dir;  ///< empty: no cache
  bool convex_parts = false;
  /// When not empty (one flag per body): only the flagged bodies get convex parts,
  /// whatever `convex_parts` says (a run splits only bodies that can touch another).
  std::vector<char> convex_part_bodies;
  bool tet_meshes = false;  ///< give elastic bodies their tetrahedral meshes
  /// When not empty (one flag per body): only the flagged elastic bodies get a tet mesh,
  /// whatever `tet_meshes` says (a run meshes only what its FE solver advances).
  std::vector<char> tet_mesh_bodies;
  /// When not empty (one entry per body): the bodies that can touch each elastic body. A
  /// body with such partners gets a graded mesh: its mesh_size near their bounding boxes
  /// and in its thin parts, up to four times coarser in the bulk.
  std::vector<std::vector<int>> contact_partners;
  /// Parallel to contact_partners (or empty): how far each partner can move relative to
  /// the body over the run (by the drives), as a range of displacements (m) that the
  /// partner's box is swept over.
  std::vector<std::vector<geometry::Bounds>> contact_travel;
  /// Keep the cache files in the report instead of writing them (a caller that may still
  /// refuse the input writes them with commit_cache once it writes its outputs).
  bool defer_cache = false;
  MeshLoader load_mesh;  ///< needed only when the script imports files
  /// Called as each body starts a stage: a message ("csg: socket"), bodies done, total.
  std::function<void(const std::string& message, int done, int total)> progress;
};

/// The compile options of a run of `scene` (`vproto run` and what drives runs like it): a
/// static run meshes every elastic body; a dynamic or quasistatic one meshes only the bodies
/// its FE solver advances (every elastic body with `mesh_every_elastic_body`: the vtu export
/// of a body that moves rigidly), splits only the bodies that can touch another into convex
/// parts, and grades the meshes of held (clamped or gripped) elastic bodies towards where their
/// contact partners can go: each partner's box swept by the drives of both. An elastic body
/// nothing holds can touch anywhere, so its mesh stays uniform. Sets what to build only
/// (cache, loader, progress are the caller's).
CompileOptions run_compile_options(const sim::Scene& scene, bool static_mode,
                                   bool mesh_every_elastic_body = false);

struct BodyReport {
  std::string hash;  ///< content hash of the body's feature subtree (hex)
  bool from_cache = false;
  bool convex_from_cache = false;
  bool tets_from_cache = false;  ///< its volume mesh read from the cache (build.json)
  int corefinements = 0;
  double csg_seconds = 0;
  double convex_seconds = 0;
  double tetmesh_seconds = 0;
};

struct CompileReport {
  std::vector<BodyReport> bodies;
  double csg_seconds = 0;
  double convex_seconds = 0;
  double tetmesh_seconds = 0;
  /// "FILE:LINE:COL: warning: ..." lines: bodies whose mesh cannot follow a feature (a
  /// wall thinner than a sixteenth of the mesh size under it).
  std::vector<std::string> warnings;
  /// Cache files not written yet (CompileOptions::defer_cache).
  std::vector<std::pair<std::filesystem::path, std::vector<geometry::TriMesh>>> pending_cache;
  /// Volume meshes not written to the cache yet (the same).
  std::vector<std::pair<std::filesystem::path, geometry::TetMesh>> pending_tets;
};

/// The mesh size an elastic body gets when its script gives none: about 10 elements
/// across its thinnest wall, but never so fine that a uniform mesh passes ~100k elements.
double default_mesh_size(const geometry::TriMesh& surface);

/// Fills each body's surface, mass properties, mass and inertia (and convex parts when
/// asked). Throws InputError naming the body when its solid is empty, open or invalid.
CompileReport compile_bodies(EvaluatedScript& script, const CompileOptions& options);

/// Writes the cache files a deferred compile kept (best effort: a cache that cannot be
/// written is skipped).
void commit_cache(CompileReport& report);

/// The content hash of one body's feature tree (128-bit, hex): equal trees, equal hashes.
std::string feature_hash(const Feature& tree);

/// The feature tree as a CSG tree of meshes (leaves built and placed).
geometry::CsgNode to_csg(const Feature& tree, const MeshLoader& load_mesh);

}  // namespace vproto::modeler
