#include "vproto/sim/scene.h"

namespace vproto::sim {

Body make_rigid_body(const std::string& name, const geometry::TriMesh& surface, double density) {
  Body b;
  b.name = name;
  b.kind = BodyKind::kRigid;
  b.material.density = density;
  b.surface = surface;
  b.mass_properties = geometry::mass_properties(surface);
  b.mass = density * b.mass_properties.volume;
  b.inertia = density * b.mass_properties.unit_inertia;
  return b;
}

int Scene::find_body(const std::string& name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace vproto::sim
