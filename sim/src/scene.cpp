#include "vproto/sim/scene.h"

namespace vproto::sim {

int Scene::find_body(const std::string& name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace vproto::sim
