#include "vproto/sim/static_solve.h"

#include <algorithm>
#include <chrono>
#include <limits>

#include "vproto/materials/errors.h"
#include "vproto/sim/elastic_model.h"
#include "vproto/sim/hot_spot.h"

namespace vproto::sim {
namespace {

[[noreturn]] void refuse(const SourceLoc& loc, const std::string& what) {
  throw InputError(loc, what +
                            " has no meaning in a static solve in this version; use "
                            "mode=dynamic for motion, or remove it");
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
  // nor does a free one that gravity pulls (issue 13: it was ignored and the run "ok")
  if (s.gravity && s.gravity->norm() > 0)
    for (std::size_t i = 0; i < s.bodies.size(); ++i) {
      const Body& b = s.bodies[i];
      if (b.kind != BodyKind::kRigid) continue;
      bool held = false;
      for (const auto& fx : s.fixes) held = held || (fx.body == static_cast<int>(i) && !fx.region);
      if (!held)
        throw InputError(b.loc, "body '" + b.name +
                                    "' is rigid and free, and gravity pulls it: a static solve "
                                    "cannot balance its weight; fix it ('fix " +
                                    b.name +
                                    ";'), make it elastic and hold it, or use "
                                    "mode=dynamic");
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
    check_element_material(b);
  }
}

std::vector<ElasticSolution> solve_static_scene(const Scene& s) {
  std::vector<ElasticSolution> out;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const Body& b = s.bodies[i];
    if (b.kind != BodyKind::kElastic) continue;
    using Clock = std::chrono::steady_clock;
    auto seconds_since = [](Clock::time_point t) {
      return std::chrono::duration<double>(Clock::now() - t).count();
    };
    const auto started = Clock::now();
    const geometry::TetMesh& m = b.tet_mesh;
    const double e = b.material.youngs_modulus, nu = b.material.poisson_ratio;
    // shared between MPI ranks (PETSc): each rank computes only the elements its rows
    // need, and nobody assembles the whole K and M
    const bool by_elements = launched_ranks() > 1 && petsc_available() &&
                             s.simulation.solver != SolverChoice::kCholmod &&
                             m.elements.cols() == 10;
    ElasticModel model = make_elastic_model(s, static_cast<int>(i), false, !by_elements);
    ElasticSolution sol;
    sol.body = model.body;
    sol.load = model.load_at(std::numeric_limits<double>::infinity());
    sol.held_nodes = model.held_nodes();  // in a static solve the gripper does not move
    sol.assemble_seconds = seconds_since(started);
    const auto solving = Clock::now();
    SolverSetup setup;
    setup.choice = s.simulation.solver;
    setup.use = SolveUse::kStatic;
    setup.dofs = model.fe.dofs;
    setup.coordinates = m.nodes;
    setup.elements = m.elements;
    const double extent = (m.nodes.colwise().maxCoeff() - m.nodes.colwise().minCoeff()).norm();
    setup.relative_tolerance = relative_tolerance_for(m.mesh_size, extent);
    bool solved = false;
    if (by_elements) {
      const std::vector<char> held = dof_mask(model.fe.dofs, sol.held_nodes);
      std::unique_ptr<LinearSolver> solver = make_linear_solver(setup);
      if (solver->factor_elements(e, nu, held, "the stiffness matrix")) {
        Eigen::VectorXd u = sol.load;
        for (Eigen::Index k = 0; k < u.size(); ++k)
          if (held[static_cast<std::size_t>(k)]) u[k] = 0;
        solver->solve_in_place(u);
        if (!u.allFinite()) throw SimulationError("the static solve gave non-finite displacements");
        sol.displacement = std::move(u);
        sol.factor = solver->stats();
        solved = true;
      } else {  // the backend wants the whole matrix after all
        const auto assembling = Clock::now();
        model.fe = assemble(m, e, nu, b.material.density);
        sol.assemble_seconds += seconds_since(assembling);
      }
    }
    if (!solved) {
      try {
        sol.displacement = solve_static(model.fe, sol.load, sol.held_nodes, &sol.factor, &setup);
      } catch (const FactorMemoryError& e) {
        refuse_factor(b, e);
      }
    }
    sol.solve_seconds = std::max(
        0.0, seconds_since(solving) - sol.factor.analyze_seconds - sol.factor.factor_seconds);
    const auto figures = Clock::now();
    sol.external_work = sol.load.dot(sol.displacement);
    if (model.fe.nonzeros() > 0) {
      const Eigen::VectorXd ku = symmetric_times(model.fe.stiffness(), sol.displacement);
      sol.strain_energy = 0.5 * sol.displacement.dot(ku);
      for (int v : sol.held_nodes) sol.reaction += (ku - sol.load).segment<3>(3 * v);
    } else {
      // from the elements: K u at the held nodes (their elements only), and the energy
      // 1/2 u.K u = 1/2 u.f (K u = f at the free dofs, u = 0 at the held ones)
      const std::vector<char> held = dof_mask(model.fe.dofs, sol.held_nodes);
      sol.strain_energy = 0;
      for (Eigen::Index k = 0; k < sol.load.size(); ++k)
        if (!held[static_cast<std::size_t>(k)])
          sol.strain_energy += 0.5 * sol.load[k] * sol.displacement[k];
      Eigen::VectorXd ku = Eigen::VectorXd::Zero(model.fe.dofs);
      for (Eigen::Index el = 0; el < m.elements.rows(); ++el) {
        bool touches = false;
        for (Eigen::Index k = 0; k < m.elements.cols(); ++k)
          touches = touches || held[static_cast<std::size_t>(3 * m.elements(el, k))];
        if (!touches) continue;
        const Eigen::MatrixXd ke = element_stiffness(m, el, e, nu);
        Eigen::VectorXd ue(ke.rows());
        for (Eigen::Index k = 0; k < m.elements.cols(); ++k)
          ue.segment<3>(3 * k) = sol.displacement.segment<3>(3 * m.elements(el, k));
        const Eigen::VectorXd fe = ke * ue;
        for (Eigen::Index k = 0; k < m.elements.cols(); ++k)
          ku.segment<3>(3 * m.elements(el, k)) += fe.segment<3>(3 * k);
      }
      for (int v : sol.held_nodes) sol.reaction += (ku - sol.load).segment<3>(3 * v);
    }
    const ElementStressStrain fields = element_stress_strain(m, sol.displacement, e, nu);
    const std::vector<char> at_corner =
        elements_at_sharp_corners(m, b.surface, 0.4 * b.thinnest_wall);
    const auto [vm, strain] =
        track_material_peaks(m, fields, {}, 0, at_corner, b.material.yield_strength,
                             b.material.yield_strain, 1, &sol.peaks);
    sol.concentrated_nodes = concentration_nodes(m, {}, 0, at_corner);
    const std::vector<CornerRead> reads = corner_reads(b.surface, TetLocator(m), m.mesh_size);
    track_corner_peaks(reads, corner_hot_spot(reads, m, sol.displacement, e, nu),
                       b.material.yield_strength, b.material.yield_strain, 1, &sol.peaks);
    sol.max_von_mises = vm;
    sol.max_principal_strain = strain;
    // linear in the load: the yield is passed at the load factor 1 / the larger ratio
    auto passed_at = [&](double stress, double eps) {
      double ratio = 0;
      if (b.material.yield_strength) ratio = std::max(ratio, stress / *b.material.yield_strength);
      if (b.material.yield_strain) ratio = std::max(ratio, eps / *b.material.yield_strain);
      return 1 / ratio;
    };
    if (sol.peaks.yielded_at >= 0) sol.peaks.yielded_at = passed_at(vm, strain);
    if (sol.peaks.bulk_yielded_at >= 0)
      sol.peaks.bulk_yielded_at =
          passed_at(sol.peaks.bulk_von_mises.value, sol.peaks.bulk_strain.value);
    if (sol.peaks.regular_yielded_at >= 0)
      sol.peaks.regular_yielded_at =
          passed_at(sol.peaks.regular_von_mises.value, sol.peaks.regular_strain.value);
    if (sol.peaks.corner_yielded_at >= 0)
      sol.peaks.corner_yielded_at =
          passed_at(sol.peaks.corner_von_mises.value, sol.peaks.corner_strain.value);
    const ElementStressStrain at_nodes = nodal_stress_strain(m, sol.displacement, e, nu);
    sol.nodal_von_mises = at_nodes.von_mises;
    sol.nodal_strain = at_nodes.principal_strain;
    sol.stress_seconds = seconds_since(figures);
    out.push_back(std::move(sol));
  }
  return out;
}

}  // namespace vproto::sim
