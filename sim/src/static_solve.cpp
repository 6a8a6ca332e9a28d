#include "vproto/sim/static_solve.h"

#include <cstdio>

#include "vproto/materials/errors.h"
#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/tet_locator.h"

namespace vproto::sim {
namespace {

[[noreturn]] void refuse(const SourceLoc& loc, const std::string& what) {
  throw InputError(loc, what +
                            " has no meaning in a static solve in this version; use "
                            "mode=dynamic for motion, or remove it");
}

std::string metres(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g m", x);
  return b;
}

}  // namespace

void check_static_supported(const Scene& s) {
  if (!s.joints.empty()) refuse(s.joints[0].loc, "joint");
  if (!s.moves.empty()) refuse(s.moves[0].loc, "move");
  if (!s.velocities.empty()) refuse(s.velocities[0].loc, "velocity");
  for (const auto& t : s.torques) refuse(t.loc, "torque");
  // rigid bodies cannot deform: loading a free one has no equilibrium
  for (const auto& f : s.forces) {
    const Body& b = s.bodies[f.body];
    if (b.kind != BodyKind::kRigid) continue;
    bool held = false;
    for (const auto& fx : s.fixes) held = held || (fx.body == f.body && !fx.region);
    if (!held)
      throw InputError(f.loc, "body '" + b.name +
                                  "' is rigid and free: a static solve cannot balance "
                                  "this force; fix it, make it elastic, or use mode=dynamic");
  }
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const Body& b = s.bodies[i];
    if (b.kind != BodyKind::kElastic) continue;
    bool held = false;
    for (const auto& fx : s.fixes) held = held || (fx.body == static_cast<int>(i) && fx.region);
    for (const auto& g : s.grips) held = held || g.body == static_cast<int>(i);
    if (!held)
      throw InputError(b.loc, "elastic body '" + b.name +
                                  "' is held by nothing, so its static "
                                  "equilibrium is not unique: add 'fix " +
                                  b.name + " region=box([..], [..]);' or a grip");
    if (b.material.poisson_ratio >= 0.495)
      throw InputError(b.loc, "body '" + b.name +
                                  "': nu = " + std::to_string(b.material.poisson_ratio) +
                                  " is too close to 0.5 (incompressible) for displacement-based "
                                  "tetrahedra, which lock; use a material with nu below 0.495");
  }
}

std::vector<ElasticSolution> solve_static_scene(const Scene& s) {
  std::vector<ElasticSolution> out;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const Body& b = s.bodies[i];
    if (b.kind != BodyKind::kElastic) continue;
    VPROTO_DEMAND(b.meshed);
    const geometry::TetMesh& m = b.tet_mesh;
    const int body = static_cast<int>(i);
    const bool quadratic = m.elements.cols() == 10;
    const double e = b.material.youngs_modulus, nu = b.material.poisson_ratio;

    // held nodes: every node inside a fix or grip region
    std::vector<int> held;
    auto hold_region = [&](const Region& r, const SourceLoc& loc, const char* what) {
      std::size_t before = held.size();
      for (Eigen::Index v = 0; v < m.nodes.rows(); ++v)
        if (r.contains(m.nodes.row(v).transpose())) held.push_back(static_cast<int>(v));
      if (held.size() == before)
        throw InputError(loc, std::string(what) + " region selects no node of body '" + b.name +
                                  "': make the box reach into the body (its mesh size is " +
                                  metres(m.mesh_size) + ")");
    };
    for (const auto& fx : s.fixes)
      if (fx.body == body && fx.region) hold_region(*fx.region, fx.loc, "fix");
    for (const auto& g : s.grips)
      if (g.body == body) hold_region(g.region, g.loc, "grip");

    // loads
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * m.nodes.rows());
    TetLocator locator(m);
    for (const auto& fo : s.forces) {
      if (fo.body != body) continue;
      if (fo.region) {
        const Eigen::VectorXd fr = region_force(m, fo.region->lo, fo.region->hi, fo.force);
        if (fr.size() == 0)
          throw InputError(fo.loc, "force region holds no boundary face of body '" + b.name +
                                       "': the box must contain whole faces of the surface");
        f += fr;
      } else {
        const Eigen::Vector3d p = fo.at ? *fo.at : b.mass_properties.centroid;
        const auto at = locator.locate(p);
        if (!at) throw InputError(fo.loc, "force point is outside body '" + b.name + "'");
        const Eigen::VectorXd n = shape_values(at->barycentric, quadratic);
        for (Eigen::Index k = 0; k < n.size(); ++k)
          f.segment<3>(3 * m.elements(at->element, k)) += n[k] * fo.force;
      }
    }
    if (s.gravity) {
      // consistent body force: rho g times the integrals of the shape functions
      for (Eigen::Index el = 0; el < m.elements.rows(); ++el) {
        Eigen::Vector3d x[4];
        for (int k = 0; k < 4; ++k) x[k] = m.nodes.row(m.elements(el, k)).transpose();
        const double v = (x[1] - x[0]).dot((x[2] - x[0]).cross(x[3] - x[0])) / 6;
        const Eigen::Vector3d w = b.material.density * *s.gravity;
        for (int k = 0; k < 4; ++k)
          f.segment<3>(3 * m.elements(el, k)) += (quadratic ? -v / 20 : v / 4) * w;
        if (quadratic)
          for (int k = 4; k < 10; ++k) f.segment<3>(3 * m.elements(el, k)) += (v / 5) * w;
      }
    }

    ElasticSolution sol;
    sol.body = body;
    const auto k = assemble_stiffness(m, e, nu);
    sol.displacement = solve_static(k, f, held);
    sol.load = f;
    sol.held_nodes = held;
    sol.external_work = f.dot(sol.displacement);
    sol.strain_energy = 0.5 * sol.displacement.dot(k * sol.displacement);
    const Eigen::VectorXd vm = element_von_mises(m, sol.displacement, e, nu);
    sol.max_von_mises = vm.size() ? vm.maxCoeff() : 0;
    sol.max_principal_strain = max_principal_strain(m, sol.displacement);
    sol.nodal_von_mises = Eigen::VectorXd::Zero(m.nodes.rows());
    Eigen::VectorXd count = Eigen::VectorXd::Zero(m.nodes.rows());
    for (Eigen::Index el = 0; el < m.elements.rows(); ++el)
      for (Eigen::Index kk = 0; kk < m.elements.cols(); ++kk) {
        sol.nodal_von_mises[m.elements(el, kk)] += vm[el];
        count[m.elements(el, kk)] += 1;
      }
    sol.nodal_von_mises = sol.nodal_von_mises.cwiseQuotient(count.cwiseMax(1.0));
    out.push_back(std::move(sol));
  }
  return out;
}

}  // namespace vproto::sim
