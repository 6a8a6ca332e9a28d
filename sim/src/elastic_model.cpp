#include "vproto/sim/elastic_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "vproto/sim/sparse_cholesky.h"
#include "vproto/sim/tet_locator.h"

namespace vproto::sim {
namespace {

std::string metres(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g m", x);
  return b;
}

}  // namespace

void check_element_material(const Body& b) {
  if (b.material.poisson_ratio >= 0.495)
    throw InputError(b.loc, "body '" + b.name +
                                "': nu = " + std::to_string(b.material.poisson_ratio) +
                                " is too close to 0.5 (incompressible) for displacement-based "
                                "tetrahedra, which lock; use a material with nu below 0.495");
}

void refuse_factor(const Body& b, const FactorMemoryError& error) {
  const double h = b.tet_mesh.mesh_size;
  const double fits = h * std::pow(error.needed() / error.available(), 0.25);
  throw InputError(b.loc, "body '" + b.name + "' (mesh_size " + metres(h) + ", " +
                              std::to_string(3 * b.tet_mesh.nodes.rows()) +
                              " unknowns): " + error.what() + "; use a mesh_size of at least " +
                              metres(1.05 * fits) +
                              ", or set VPROTO_MEMORY_LIMIT (e.g. 20GB) if more memory can "
                              "be used");
}

Eigen::VectorXd ElasticModel::load_at(double t) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(fe.dofs);
  for (const Load& l : loads) {
    const double scale = l.ramp > 0 ? std::clamp(t / l.ramp, 0.0, 1.0) : 1.0;
    if (scale > 0) f += scale * l.nodal;
  }
  return f;
}

std::vector<int> ElasticModel::held_nodes() const {
  std::vector<int> all = fixed_nodes;
  all.insert(all.end(), grip_nodes.begin(), grip_nodes.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

ElasticModel make_elastic_model(const Scene& s, int body, bool floating, bool matrices) {
  const Body& b = s.bodies[body];
  VPROTO_DEMAND(b.kind == BodyKind::kElastic && b.meshed);
  const geometry::TetMesh& m = b.tet_mesh;
  ElasticModel model;
  model.body = body;

  auto select = [&](const Region& r, const SourceLoc& loc, const char* what,
                    std::vector<int>& into) {
    const std::size_t before = into.size();
    for (Eigen::Index v = 0; v < m.nodes.rows(); ++v)
      if (r.contains(m.nodes.row(v).transpose())) into.push_back(static_cast<int>(v));
    if (into.size() == before)
      throw InputError(loc, std::string(what) + " region selects no node of body '" + b.name +
                                "': make the box reach into the body (its mesh size is " +
                                metres(m.mesh_size) + ")");
  };
  for (const auto& fx : s.fixes)
    if (fx.body == body && fx.region) select(*fx.region, fx.loc, "fix", model.fixed_nodes);
  for (const auto& g : s.grips)
    if (g.body == body) select(g.region, g.loc, "grip", model.grip_nodes);
  // a node both clamped and gripped stays clamped
  std::vector<int> fixed_sorted = model.fixed_nodes;
  std::sort(fixed_sorted.begin(), fixed_sorted.end());
  model.grip_nodes.erase(
      std::remove_if(
          model.grip_nodes.begin(), model.grip_nodes.end(),
          [&](int v) { return std::binary_search(fixed_sorted.begin(), fixed_sorted.end(), v); }),
      model.grip_nodes.end());

  const TetLocator locator(m);
  if (floating && model.grip_nodes.empty() && model.fixed_nodes.empty()) {
    // the frame rides on the element at the centroid (for a body whose centroid lies
    // outside it, a ring, on an element of the node nearest to it): its corner nodes fix
    // the six rigid motions and stiffen no more than one element
    const Eigen::Vector3d c = b.mass_properties.centroid;
    const auto located = locator.locate(c);
    int element = -1;
    if (located && located->barycentric.minCoeff() > -1e-9) {
      element = located->element;
    } else {
      Eigen::Index nearest = 0;
      (m.nodes.rowwise() - c.transpose()).rowwise().squaredNorm().minCoeff(&nearest);
      for (Eigen::Index e = 0; e < m.elements.rows() && element < 0; ++e)
        for (int k = 0; k < 4; ++k)
          if (m.elements(e, k) == nearest) element = static_cast<int>(e);
    }
    VPROTO_DEMAND(element >= 0);
    for (int k = 0; k < 4; ++k) model.grip_nodes.push_back(m.elements(element, k));
    model.frame_grip = true;
  }

  if (matrices)
    model.fe = assemble(m, b.material.youngs_modulus, b.material.poisson_ratio, b.material.density);
  else
    model.fe.dofs = 3 * m.nodes.rows();
  const bool quadratic = m.elements.cols() == 10;
  for (const auto& fo : s.forces) {
    if (fo.body != body || (floating && !fo.region)) continue;
    ElasticModel::Load load;
    load.ramp = fo.ramp;
    if (fo.region) {
      load.nodal = region_force(m, fo.region->lo, fo.region->hi, fo.force);
      if (load.nodal.size() == 0)
        throw InputError(fo.loc, "force region holds no boundary face of body '" + b.name +
                                     "': the box must contain whole faces of the surface");
    } else {
      const Eigen::Vector3d p = fo.at ? *fo.at : b.mass_properties.centroid;
      const auto at = locator.locate(p);
      if (!at) throw InputError(fo.loc, "force point is outside body '" + b.name + "'");
      load.nodal = Eigen::VectorXd::Zero(model.fe.dofs);
      const Eigen::VectorXd n = shape_values(at->barycentric, quadratic);
      for (Eigen::Index k = 0; k < n.size(); ++k)
        load.nodal.segment<3>(3 * m.elements(at->element, k)) += n[k] * fo.force;
    }
    for (Eigen::Index v = 0; v < m.nodes.rows(); ++v)
      load.moment += (m.nodes.row(v).transpose() - b.mass_properties.centroid)
                         .cross(Eigen::Vector3d(load.nodal.segment<3>(3 * v)));
    model.loads.push_back(std::move(load));
  }
  if (s.gravity && !floating)
    model.loads.push_back({matrices ? body_force(model.fe, *s.gravity)
                                    : body_force(m, b.material.density, *s.gravity),
                           0.0});
  return model;
}

}  // namespace vproto::sim
