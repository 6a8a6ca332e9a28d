// What a run builds: which bodies get tet meshes and convex parts, and how the meshes of
// held elastic bodies are graded towards their contact partners (compiler.h).
#include "vproto/modeler/compiler.h"
#include "vproto/sim/contact.h"
#include "vproto/sim/dynamics.h"
#include "vproto/sim/elastic_contact.h"

namespace vproto::modeler {

CompileOptions run_compile_options(const sim::Scene& scene, bool static_mode,
                                   bool mesh_every_elastic_body) {
  CompileOptions copts;
  copts.tet_meshes = static_mode;
  if (static_mode) return copts;
  const std::size_t n = scene.bodies.size();
  copts.tet_mesh_bodies = sim::finite_element_bodies(scene);  // rigid-moving bodies stay unmeshed
  if (mesh_every_elastic_body)
    for (std::size_t i = 0; i < n; ++i)
      copts.tet_mesh_bodies[i] |= scene.bodies[i].kind == sim::BodyKind::kElastic;
  copts.convex_part_bodies = sim::contact_bodies(scene);  // only what can touch is split
  auto held = [&](int body) {
    for (const auto& g : scene.grips)
      if (g.body == body) return true;
    for (const auto& f : scene.fixes)
      if (f.body == body && f.region) return true;
    return false;
  };
  // where the drives take each body: the range of its displacement over its legs
  std::vector<geometry::Bounds> driven(n);
  std::vector<Eigen::Vector3d> at(n, Eigen::Vector3d::Zero());
  for (auto& range : driven) range.lo = range.hi = Eigen::Vector3d::Zero();
  for (const auto& m : scene.moves) {
    const auto b = static_cast<std::size_t>(m.body);
    at[b] += m.by;
    driven[b].lo = driven[b].lo.cwiseMin(at[b]);
    driven[b].hi = driven[b].hi.cwiseMax(at[b]);
  }
  copts.contact_partners.resize(n);
  copts.contact_travel.resize(n);
  std::vector<std::pair<int, int>> partners = sim::elastic_contact_pairs(scene);
  for (const auto& [a, b] : sim::elastic_elastic_pairs(scene)) {  // each is the other's
    partners.push_back({a, b});
    partners.push_back({b, a});
  }
  for (const auto& [e, r] : partners) {
    if (!held(e)) continue;
    const auto ei = static_cast<std::size_t>(e), ri = static_cast<std::size_t>(r);
    copts.contact_partners[ei].push_back(r);
    // the partner as the body sees it: its own travel less the body's
    geometry::Bounds relative;
    relative.lo = driven[ri].lo - driven[ei].hi;
    relative.hi = driven[ri].hi - driven[ei].lo;
    copts.contact_travel[ei].push_back(relative);
  }
  return copts;
}

}  // namespace vproto::modeler
