#include "vproto/sim/scene.h"

#include <cmath>
#include <cstdio>

#include "vproto/materials/errors.h"

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

void check_step_count(const SimulationSettings& st, double dt, const std::string& why,
                      const SourceLoc& where) {
  const double steps = st.duration / dt;
  if (std::isfinite(steps) && steps <= kMaxSteps) return;
  char text[400];
  std::snprintf(text, sizeof text,
                "%.3g s at steps of %.3g s (%s) is %.3g steps, more than %.0f: it would run for "
                "hours and write gigabytes of history; use a larger dt (at least %.3g s), a "
                "shorter duration",
                st.duration, dt, why.c_str(), steps, kMaxSteps, st.duration / kMaxSteps);
  std::string message = text;
  if (why.find("tolerance") != std::string::npos) message += ", or a looser tolerance";
  throw InputError(st.given ? st.loc : where, message);
}

int Scene::find_body(const std::string& name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace vproto::sim
