#include "vproto/sim/dynamics.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <optional>
#include <set>

#include "dynamics_internal.h"
#include "vproto/geometry/aabb_tree.h"
#include "vproto/geometry/convex_parts.h"
#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

[[noreturn]] void unsupported(const SourceLoc& loc, const std::string& what) {
  throw InputError(loc, what +
                            " is not simulated in this version; 'vproto run' handles rigid "
                            "bodies (free, fixed, moved or jointed) touching one another, and "
                            "elastic bodies (clamped, gripped to a moved or jointed frame, or "
                            "free) touching rigid bodies (docs/contracts.md)");
}

bool has_region_fix(const Scene& s, int body) {
  for (const auto& f : s.fixes)
    if (f.body == body && f.region) return true;
  return false;
}

bool has_grip(const Scene& s, int body) {
  for (const auto& g : s.grips)
    if (g.body == body) return true;
  return false;
}

double ramp_factor(double ramp, double t) { return ramp > 0 ? std::min(t / ramp, 1.0) : 1.0; }

}  // namespace

std::vector<char> finite_element_bodies(const Scene& s) {
  std::vector<char> fe(s.bodies.size(), 0);
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    if (s.bodies[i].kind != BodyKind::kElastic) continue;
    const int b = static_cast<int>(i);
    bool loaded = false;
    for (const auto& f : s.forces) loaded = loaded || f.body == b;
    fe[i] = has_region_fix(s, b) || has_grip(s, b) || loaded;
  }
  for (const auto& [e, r] : elastic_contact_pairs(s)) fe[static_cast<std::size_t>(e)] = 1;
  for (const auto& [a, b] : elastic_elastic_pairs(s))
    fe[static_cast<std::size_t>(a)] = fe[static_cast<std::size_t>(b)] = 1;
  return fe;
}

void check_dynamics_supported(const Scene& scene) {
  const std::vector<char> fe = finite_element_bodies(scene);
  auto whole_fix = [&](int body) {
    for (const auto& f : scene.fixes)
      if (f.body == body && !f.region) return true;
    return false;
  };
  // a jointed FE body is floating: its frame takes the joint, its grips hold it to the frame
  for (const auto& j : scene.joints)
    for (int b : {j.body, j.other}) {
      if (b == kGround || !fe[b]) continue;
      const std::string& name = scene.bodies[b].name;
      if (has_region_fix(scene, b))
        throw InputError(j.loc, "elastic body '" + name +
                                    "' is clamped to the ground by 'fix ... region=', so it "
                                    "cannot also be jointed; remove one of them");
      if (!has_grip(scene, b))
        throw InputError(j.loc, "elastic body '" + name +
                                    "' is jointed, but nothing ties its nodes to its reference "
                                    "frame, which the joint holds: add 'grip " +
                                    name + " region=box([..], [..]);'");
      const int other = b == j.body ? j.other : j.body;
      if (other != kGround && fe[other] && !whole_fix(other))
        unsupported(j.loc, "a joint between elastic bodies '" + name + "' and '" +
                               scene.bodies[other].name +
                               "' (an elastic body's joints go to the ground, a fixed body or "
                               "rigid bodies)");
    }
  // a fixed frame holds an elastic body only through its grips (as a moved one): without
  // them its material is free to drift off the frame (K is singular; a dynamic run would
  // let contact push it away)
  for (const auto& f : scene.fixes) {
    const Body& b = scene.bodies[static_cast<std::size_t>(f.body)];
    if (f.region || b.kind != BodyKind::kElastic || has_grip(scene, f.body) ||
        has_region_fix(scene, f.body))
      continue;
    throw InputError(f.loc, "elastic body '" + b.name +
                                "' has its reference frame fixed, but nothing holds it to the "
                                "frame: clamp a region of it with 'fix " +
                                b.name + " region=box([..], [..]);', or add 'grip " + b.name +
                                " region=box([..], [..]);'");
  }
  std::vector<int> moved(scene.bodies.size(), 0);
  for (const auto& m : scene.moves) {
    if (!(m.over > 0)) throw InputError(m.loc, "move needs a positive duration 'over='");
    if (whole_fix(m.body))
      throw InputError(m.loc, "body '" + scene.bodies[m.body].name +
                                  "' is fixed, so it cannot also be moved; remove one of them");
    if (scene.bodies[m.body].kind == BodyKind::kElastic && !has_grip(scene, m.body))
      throw InputError(m.loc, "elastic body '" + scene.bodies[m.body].name +
                                  "' is moved by its reference frame, but nothing holds it to "
                                  "the frame: add 'grip " +
                                  scene.bodies[m.body].name + " region=box([..], [..]);'");
    moved[m.body] = 1;
  }
  for (const auto& j : scene.joints)
    for (int b : {j.body, j.other})
      if (b != kGround && moved[b])
        throw InputError(j.loc, "body '" + scene.bodies[b].name +
                                    "' is driven by 'move' and also jointed; drive it or joint "
                                    "it, not both");
  for (const auto& f : scene.forces) {
    const Body& b = scene.bodies[f.body];
    if (moved[f.body] && b.kind == BodyKind::kRigid)
      throw InputError(f.loc, "body '" + b.name +
                                  "' is driven by 'move', which prescribes its motion, so a "
                                  "force on it does nothing; remove one of them");
    if (b.kind == BodyKind::kRigid && f.region)
      throw InputError(f.loc, "body '" + b.name +
                                  "' is rigid: a force spread over a region needs an elastic "
                                  "body; give a point with at=[..] instead");
  }
  for (const auto& t : scene.torques) {
    if (scene.bodies[t.body].kind == BodyKind::kElastic)
      unsupported(t.loc, "torque on an elastic body");
    if (moved[t.body])
      throw InputError(t.loc, "body '" + scene.bodies[t.body].name +
                                  "' is driven by 'move', so a torque on it does nothing");
  }
  for (const auto& v : scene.velocities) {
    if (fe[v.body] && (has_grip(scene, v.body) || has_region_fix(scene, v.body)))
      throw InputError(v.loc, "elastic body '" + scene.bodies[v.body].name +
                                  "' is held, so its velocity is set by what holds it; use "
                                  "'move' to drive its grip");
    if (moved[v.body])
      throw InputError(v.loc, "body '" + scene.bodies[v.body].name +
                                  "' is driven by 'move', which sets its velocity");
    if (scene.bodies[v.body].kind == BodyKind::kElastic && v.angular.norm() > 0)
      unsupported(v.loc, "spinning an elastic body (it would load it centrifugally)");
  }
  for (std::size_t i = 0; i < scene.bodies.size(); ++i)
    if (fe[i]) check_element_material(scene.bodies[i]);
}

void check_quasistatic_supported(const Scene& scene) {
  const std::vector<char> fe = finite_element_bodies(scene);
  std::vector<char> held(scene.bodies.size(), 0);  // fixed or driven frames
  for (const auto& f : scene.fixes)
    if (!f.region) held[f.body] = 1;
  for (const auto& m : scene.moves) held[m.body] = 1;
  const std::string why =
      "mode=quasistatic is a sequence of equilibria as the drives ('move' legs) and the "
      "force ramps advance: ";
  for (const auto& j : scene.joints)
    throw InputError(j.loc, why +
                                "a joint leaves its body free to move, which has no "
                                "equilibrium of its own; drive the body with 'move' legs, or "
                                "use mode=dynamic");
  for (const auto& v : scene.velocities)
    throw InputError(v.loc, why +
                                "an initial velocity has no meaning there; drive the body "
                                "with 'move' legs, or use mode=dynamic");
  for (const auto& t : scene.torques)
    if (!held[t.body])
      throw InputError(t.loc, why + "a torque on body '" + scene.bodies[t.body].name +
                                  "', which nothing holds, has no equilibrium; use mode=dynamic");
  for (const auto& f : scene.forces)
    if (!held[f.body] && !(fe[f.body] && has_region_fix(scene, f.body)) && !f.region)
      throw InputError(f.loc, why + "a force on body '" + scene.bodies[f.body].name +
                                  "', whose frame nothing holds, has no equilibrium; drive it "
                                  "with 'move' legs (the reaction columns then give the force), "
                                  "or use mode=dynamic");
  for (const auto& g : scene.grips)
    if (!held[g.body] && !has_region_fix(scene, g.body))
      throw InputError(g.loc, why + "'" + scene.bodies[g.body].name +
                                  "' is gripped to a frame that nothing fixes or drives; drive "
                                  "it with 'move' legs (displacement control), or use "
                                  "mode=dynamic to push it with a force");
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const int b = static_cast<int>(i);
    if (fe[i] && !held[i] && !has_region_fix(scene, b) && !has_grip(scene, b))
      throw InputError(scene.bodies[i].loc,
                       why + "nothing holds elastic body '" + scene.bodies[i].name +
                           "', so it has no equilibrium of its own; clamp it with 'fix " +
                           scene.bodies[i].name +
                           " region=box([..], [..]);', grip it and "
                           "drive it with 'move' legs, or use mode=dynamic");
  }
  if (scene.gravity && scene.gravity->norm() > 0)
    for (std::size_t i = 0; i < scene.bodies.size(); ++i)
      if (!held[i] && !(fe[i] && has_region_fix(scene, static_cast<int>(i))) &&
          scene.bodies[i].kind == BodyKind::kRigid)
        throw InputError(scene.bodies[i].loc,
                         why + "gravity would pull rigid body '" + scene.bodies[i].name +
                             "', which nothing holds; fix it, drive it with 'move', or use "
                             "mode=dynamic");
}

double step_dividing(double interval, double step) {
  VPROTO_DEMAND(step > 0);
  return interval > 0 ? interval / std::ceil(interval / step - 1e-9) : step;
}

double run_time_step(const Scene& scene) {
  const SimulationSettings& st = scene.simulation;
  const std::vector<char> fe = finite_element_bodies(scene);
  const bool any_fe = std::find(fe.begin(), fe.end(), 1) != fe.end();
  const double interval = st.frames > 1 ? st.duration / (st.frames - 1) : st.duration;
  // with FE bodies the frame interval: Dynamics lowers it for the tolerance or contact
  const double asked = st.time_step ? *st.time_step
                       : any_fe     ? interval
                                    : std::min(1e-3, st.duration / 1000);
  return step_dividing(interval, asked);
}

Dynamics::Dynamics(const Scene& scene, double time_step, ContactOptions contact_options)
    : scene_(scene), time_step_(time_step) {
  VPROTO_DEMAND(time_step > 0);
  const std::size_t n = scene.bodies.size();
  states_.resize(n);
  inertias_.resize(n);
  fixed_.assign(n, false);
  moves_.assign(n, false);
  driven_.assign(n, -1);
  elastic_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    states_[i].position = scene.bodies[i].mass_properties.centroid;
    inertias_[i].mass = scene.bodies[i].mass;
    inertias_[i].inertia = scene.bodies[i].inertia;
  }
  for (const auto& f : scene.fixes) fixed_[f.body] = !f.region;
  for (std::size_t m = 0; m < scene.moves.size(); ++m)
    if (driven_[scene.moves[m].body] < 0) driven_[scene.moves[m].body] = static_cast<int>(m);
  for (const auto& v : scene.velocities) {
    states_[v.body].velocity = v.linear;
    states_[v.body].angular_velocity = v.angular;
    moves_[v.body] = true;
  }
  for (const auto& f : scene.forces) moves_[f.body] = true;
  for (const auto& t : scene.torques) moves_[t.body] = true;
  if (scene.gravity && scene.gravity->norm() > 0) moves_.assign(n, true);

  // the FE bodies: model, factor, and the map from nodes to surface vertices
  const std::vector<char> fe = finite_element_bodies(scene);
  elastic_pairs_ = elastic_contact_pairs(scene);
  const std::vector<std::pair<int, int>> elastic_elastic = elastic_elastic_pairs(scene);
  auto has_partner = [&](int body) {
    for (const auto& pr : elastic_pairs_)
      if (pr.first == body) return true;
    for (const auto& pr : elastic_elastic)
      if (pr.first == body || pr.second == body) return true;
    return false;
  };
  using Clock = std::chrono::steady_clock;
  for (std::size_t i = 0; i < n; ++i) {
    if (!fe[i]) continue;
    VPROTO_DEMAND(scene.bodies[i].meshed);
    auto e = std::make_unique<ElasticBody>();
    const auto t0 = Clock::now();
    // not clamped and not driven: the frame floats (moved by joints, forces and contact),
    // held to the body by its grips or, when it has none, by a frame grip of its own
    e->floating = !has_region_fix(scene, static_cast<int>(i)) && driven_[i] < 0 && !fixed_[i];
    e->model = make_elastic_model(scene, static_cast<int>(i), e->floating);
    // a floating body sleeps (moves rigidly, no FE work) until something loads its nodes
    e->awake = !e->floating || !e->model.loads.empty() || !contact_options.rigid_until_contact;
    assemble_seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
    elastic_[i] = std::move(e);
  }
  // contact between two elastic bodies is solved in one body's stage (the owner), the
  // other body taking the reactions as loads of its own step: a floating one owns a pair
  // with a held one (its frame's rows are the stage's own); of two floating ones, the one on
  // joints (whose mobility only the joints give), else the first, the other's frame then
  // answering the rows as a free or jointed rigid partner's does (step by step, the one its
  // other contacts support owns the pair: choose_owners)
  auto on_joints = [&](int body) {
    for (const auto& j : scene.joints)
      if (j.body == body || j.other == body) return true;
    return false;
  };
  for (const auto& [a, b] : elastic_elastic) {
    ElasticBody &ea = *elastic_[static_cast<std::size_t>(a)],
                &eb = *elastic_[static_cast<std::size_t>(b)];
    bool b_owns = eb.floating && !ea.floating;
    if (ea.floating && eb.floating) b_owns = on_joints(b) && !on_joints(a);
    elastic_elastic_.push_back({b_owns ? b : a, b_owns ? a : b});
  }
  // Floating bodies that can touch something deform quasi-statically in their frame (the
  // decoupled form of Eqs. 26-27: the frame carries the inertia, the deformation is the
  // equilibrium under the contact and region loads at each step). Newmark with contact on
  // a floating frame rang and gained energy after impacts in our tests; see docs.
  const bool quasistatic = scene.simulation.mode == SimulationMode::kQuasistatic;
  for (std::size_t i = 0; i < n; ++i) {
    ElasticBody* e = elastic_[i].get();
    if (e && quasistatic) e->quasi_static = true;  // every step an equilibrium
    if (!e || quasistatic) continue;
    if (!e->floating) {
      // a held body that a free or jointed rigid body can strike: Newmark's answer to
      // position-level contact rows gained energy from every impact in our tests (a steel
      // cube dropped on a clamped rubber pad left it at 10 times its energy); the
      // quasi-static body is the massless spring the struck body's inertia works against
      bool struck = false;
      for (const auto& [fe_body, rigid] : elastic_pairs_)
        struck = struck || (fe_body == static_cast<int>(i) && movable_partner(rigid));
      for (const auto& [owner, other] : elastic_elastic_)  // a floating elastic body's frame
        struck = struck || (other == static_cast<int>(i) && elastic_[owner]->floating);
      if (!struck) continue;
      e->quasi_static = true;
      notes_.push_back(scene.bodies[i].name +
                       " deforms quasi-statically (no elastic inertia: a free or jointed body "
                       "can strike it)");
      continue;
    }
    if (!has_partner(static_cast<int>(i)) && !e->model.frame_grip) continue;
    e->quasi_static = true;
    notes_.push_back(scene.bodies[i].name +
                     " deforms quasi-statically in its floating frame (the frame carries the "
                     "inertia)");
  }
  if (!scene.simulation.time_step) {
    const SimulationSettings& st = scene.simulation;
    // contact: a point moving at the largest speed the loads can give over the scene's
    // size crosses at most half the finest mesh size per step (a quarter for quasi-static
    // increments, the drive's travel per increment). (A quarter until the rows of
    // a part's edges on elastic triangles were taken anew where a step ends them: the
    // snap-fit's push over the edges is now 99.3 N at 0.26 ms and 100.4 N at 0.56 ms; it was
    // 106.4 N at 0.28 ms before, about 99.5 N converged.)
    if (!elastic_pairs_.empty() || !elastic_elastic.empty()) {
      geometry::Bounds all;
      for (const Body& b : scene.bodies) all.extend(geometry::bounds(b.surface));
      const double size = (all.hi - all.lo).norm();
      double speed = 0, finest = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < n; ++i) {
        if (elastic_[i] && has_partner(static_cast<int>(i)))
          finest = std::min(finest, scene.bodies[i].tet_mesh.mesh_size);
        double load = scene.gravity && !quasistatic ? scene.gravity->norm() : 0.0;
        for (const auto& f : scene.forces)
          if (f.body == static_cast<int>(i) && inertias_[i].mass > 0 && !quasistatic)
            load += f.force.norm() / inertias_[i].mass;
        // a spinning body's farthest point moves faster than its centre
        const geometry::Bounds box = geometry::bounds(scene.bodies[i].surface);
        const double radius = std::max((box.hi - scene.bodies[i].mass_properties.centroid).norm(),
                                       (box.lo - scene.bodies[i].mass_properties.centroid).norm());
        speed = std::max(speed, states_[i].velocity.norm() +
                                    states_[i].angular_velocity.norm() * radius +
                                    std::sqrt(2 * load * size));
      }
      for (const auto& m : scene.moves) speed = std::max(speed, m.by.norm() / m.over);
      // (quasi-static increments: a quarter, contracts.md)
      const double share = quasistatic ? 0.25 : 0.5;
      if (speed > 0 && std::isfinite(finest) && share * finest / speed < time_step_) {
        char why[200];
        std::snprintf(why, sizeof why,
                      "dt from contact: %.3g m/s (the fastest the loads can move a body over "
                      "the scene) crosses %s the finest mesh size (%.3g m) per step",
                      speed, quasistatic ? "a quarter of" : "half", finest);
        time_step_reason_ = why;
        time_step_ = share * finest / speed;
      }
    }
    // Newmark's period error (w h)^2 / 12 within the tolerance on each body's lowest mode
    // (floating bodies in contact deform quasi-statically when the step cannot resolve it)
    for (std::size_t i = 0; i < n; ++i) {
      const ElasticBody* e = elastic_[i].get();
      if (!e || e->model.held_nodes().empty() || e->quasi_static) continue;
      const auto t0 = Clock::now();
      double f1 = 0;
      try {
        f1 = natural_frequencies(e->model.fe, e->model.held_nodes(), 1)[0];
      } catch (const FactorMemoryError& err) {
        refuse_factor(scene.bodies[i], err);
      }
      factor_seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
      const double h = std::sqrt(12 * st.tolerance) / (2 * M_PI * f1);
      if (h < time_step_) {
        char why[160];
        std::snprintf(why, sizeof why,
                      "dt from tolerance %g: period error of %s's first mode (%.4g Hz) within it",
                      st.tolerance, scene.bodies[i].name.c_str(), f1);
        time_step_reason_ = why;
        time_step_ = h;
      }
    }
    const double interval = st.frames > 1 ? st.duration / (st.frames - 1) : st.duration;
    if (!time_step_reason_.empty()) time_step_ = step_dividing(interval, time_step_);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!elastic_[i]) continue;
    const Body& b = scene.bodies[i];
    ElasticBody* e = elastic_[i].get();
    double numerical_damping = scene.simulation.numerical_damping.value_or(0.0);
    if (!scene.simulation.numerical_damping && has_partner(static_cast<int>(i)) &&
        !e->quasi_static) {
      numerical_damping = kContactNumericalDamping;
      char note[160];
      std::snprintf(note, sizeof note,
                    "%s: numerical_damping %g (contact excites Newmark's undamped two-step "
                    "mode; set numerical_damping=0 to conserve energy exactly)",
                    b.name.c_str(), numerical_damping);
      notes_.push_back(note);
    }
    NewmarkOptions options = NewmarkOptions::with_numerical_damping(numerical_damping);
    options.solver = scene.simulation.solver;
    options.constraint_columns = has_partner(static_cast<int>(i));
    options.mesh = &b.tet_mesh;
    options.rayleigh_mass = scene.simulation.mass_damping;
    options.rayleigh_stiffness = scene.simulation.stiffness_damping;
    options.inertia = !e->quasi_static;
    try {
      e->solver = std::make_unique<ElasticDynamics>(e->model.fe, e->model.held_nodes(), time_step_,
                                                    options);
    } catch (const FactorMemoryError& err) {
      refuse_factor(b, err);
    }
    factor_seconds_ +=
        e->solver->factor_stats().analyze_seconds + e->solver->factor_stats().factor_seconds;
    e->grip_dof = dof_mask(e->model.fe.dofs, e->model.grip_nodes);
    e->locator = std::make_unique<TetLocator>(b.tet_mesh);
    e->surface_map = interpolation_matrix(b.tet_mesh, *e->locator, b.drawn().V);
    e->at_sharp_corner = elements_at_sharp_corners(b.tet_mesh, b.surface, 0.4 * b.thinnest_wall);
    e->corner_reads = corner_reads(b.surface, *e->locator, b.tet_mesh.mesh_size);
    moves_[i] = e->floating;  // a floating frame moves as a rigid body
    for (const auto& [fe_body, rigid] : elastic_pairs_)
      if (fe_body == static_cast<int>(i)) e->partners.push_back(rigid);
    // a body on its own frame grip takes the contact stage's path even with no partner:
    // its region loads are then balanced by its inertia there
    bool paired = false;
    for (const auto& [owner, other] : elastic_elastic_)
      paired = paired || owner == static_cast<int>(i) || other == static_cast<int>(i);
    if (!e->partners.empty() || e->model.frame_grip || paired) {
      e->touchable = true;
      e->surface = make_contact_surface(b.tet_mesh);
    }
    if (e->floating) {
      e->absolute_u = Eigen::VectorXd::Zero(e->model.fe.dofs);
      e->mean_axes = e->model.frame_grip;
      if (e->mean_axes) rigid_modes(static_cast<int>(i));
    }
    e->pending_load = Eigen::VectorXd::Zero(e->model.fe.dofs);
  }
  VPROTO_DEMAND(assign_stages());  // the owners chosen above form no cycle

  // the convex parts of the rigid bodies elastic bodies can touch
  {
    std::vector<char> wanted(n, 0);
    for (const auto& pr : elastic_pairs_) wanted[static_cast<std::size_t>(pr.second)] = 1;
    for (std::size_t i = 0; i < n; ++i) {
      if (!wanted[i]) continue;
      const Body& body = scene.bodies[i];
      std::vector<geometry::TriMesh> meshes = body.convex_parts_computed ? body.convex_parts
                                              : geometry::is_convex(body.surface)
                                                  ? std::vector<geometry::TriMesh>{body.surface}
                                                  : geometry::convex_parts(body.surface);
      for (geometry::TriMesh& m : meshes) {
        m.V.rowwise() -= body.mass_properties.centroid.transpose();
        rigid_parts_.push_back({static_cast<int>(i), geometry::make_polytope(m)});
      }
    }
  }
  joints_ = std::make_unique<JointSystem>(scene, fixed_);
  // a free rigid body an elastic body can touch moves: the contact pushes it
  for (const auto& [fe_body, rigid] : elastic_pairs_)
    if (movable_partner(rigid)) moves_[static_cast<std::size_t>(rigid)] = true;
  for (std::size_t i = 0; i < n; ++i)
    if (joints_->moves(static_cast<int>(i))) moves_[i] = false;  // stepped with the rows
  for (std::size_t i = 0; i < n; ++i)
    if (fixed_[i] || driven_[i] >= 0) {
      moves_[i] = false;
      states_[i].velocity.setZero();
      states_[i].angular_velocity.setZero();
    }
  for (std::size_t i = 0; i < n; ++i)
    if (driven_[i] >= 0) frame_offset(static_cast<int>(i), 0, &states_[i].velocity);
  // contact between rigid bodies that are not jointed: a free body can be pushed by one
  // that touches it, so every free rigid body moves
  const std::vector<char> touchable = contact_bodies(scene);
  contact_roles_.assign(n, ContactRole::kNone);
  for (std::size_t i = 0; i < n; ++i) {
    if (!touchable[i]) continue;
    contact_roles_[i] = fixed_[i]                             ? ContactRole::kStatic
                        : driven_[i] >= 0                     ? ContactRole::kKinematic
                        : joints_->moves(static_cast<int>(i)) ? ContactRole::kJointed
                                                              : ContactRole::kFree;
    if (contact_roles_[i] == ContactRole::kFree) moves_[i] = true;
  }
  if (std::find(touchable.begin(), touchable.end(), 1) != touchable.end()) {
    contact_ = std::make_unique<ContactSystem>(scene, contact_roles_, contact_options);
    contact_->check_start(states_);
  }
  for (std::size_t i = 0; i < n; ++i) {
    ElasticBody* e = elastic_[i].get();
    if (!e) continue;
    if (e->floating) {
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(e->model.fe.dofs);
      e->solver->start(0, zero, zero, e->awake ? elastic_load(static_cast<int>(i), 0) : zero);
      update_absolute(static_cast<int>(i));
      continue;
    }
    const HeldMotion held = held_motion(static_cast<int>(i), 0);
    Eigen::VectorXd v0 = held.v;
    if (driven_[i] >= 0 && e->model.fixed_nodes.empty()) {
      // a body its grips drive starts moving with them, whole (the drive carries the part
      // along; starting its free nodes at rest would jolt it, and with damping the grips
      // would feel the strain rate for long after)
      for (Eigen::Index k = 0; k < v0.size(); ++k) v0[k] = states_[i].velocity[k % 3];
    }
    e->solver->start(0, held.u, v0, e->model.load_at(0), &held);
  }
  check_overlaps();
  bool rigid_only = scene.moves.empty();
  for (const auto& e : elastic_) rigid_only = rigid_only && !e;
  if (rigid_only) watched_energy_ = kinetic_energy();
  cut_increments_ = quasistatic && (!elastic_pairs_.empty() || !elastic_elastic_.empty());
  halve_every_increment_ = contact_options.halve_every_increment;
}

Dynamics::~Dynamics() = default;

// The contact stage takes the owners of elastic pairs first, floating ones before held ones
// (a held owner is owned only by a floating body or by a held one before it), and a body
// only after every body that owns a pair with it: their stages load the other bodies (and
// jump the floating ones' frames) before those step. False when the owners form a cycle.
bool Dynamics::assign_stages() {
  const std::size_t n = elastic_.size();
  for (auto& e : elastic_)
    if (e) {
      e->elastic_partners.clear();
      e->floating_owners.clear();
    }
  for (const auto& [owner, other] : elastic_elastic_) {
    ElasticBody& eo = *elastic_[static_cast<std::size_t>(owner)];
    ElasticBody& ex = *elastic_[static_cast<std::size_t>(other)];
    eo.elastic_partners.push_back(other);
    if (eo.floating && ex.floating) ex.floating_owners.push_back(owner);
  }
  std::vector<int> by_kind;
  for (const bool floating : {true, false})
    for (std::size_t i = 0; i < n; ++i)
      if (elastic_[i] && !elastic_[i]->elastic_partners.empty() &&
          elastic_[i]->floating == floating)
        by_kind.push_back(static_cast<int>(i));
  for (std::size_t i = 0; i < n; ++i)
    if (elastic_[i] && elastic_[i]->elastic_partners.empty())
      by_kind.push_back(static_cast<int>(i));
  stage_order_.clear();
  std::vector<char> placed(n, 0);
  while (stage_order_.size() < by_kind.size()) {
    const std::size_t before_pass = stage_order_.size();
    for (const int i : by_kind) {
      if (placed[static_cast<std::size_t>(i)]) continue;
      bool ready = true;
      for (const auto& [owner, other] : elastic_elastic_)
        ready = ready && (other != i || placed[static_cast<std::size_t>(owner)]);
      if (!ready) continue;
      placed[static_cast<std::size_t>(i)] = 1;
      stage_order_.push_back(i);
    }
    if (stage_order_.size() == before_pass) return false;
  }
  return true;
}

// Of two floating elastic bodies in contact, the one that its other contacts support (they
// carried force in its last step) owns the pair when the other is free of them: its stage
// then solves the pair's rows with those contacts' rows, the free one's frame answering as
// a free rigid body's. (The other way round, the stage would take the supported body's frame
// as free where its contacts hold it: a cube on a cube resting on a plate crept sideways.)
// (A body on joints answers as a jointed partner.) When both press elsewhere the owner
// solves the pair with the other's supports (its pressed points on rigid bodies and held
// elastic bodies: can_support), so the pair goes to the one that presses on a body that
// cannot support (a floating elastic one) when the other presses on supports only. (When
// both do, the owner's stage takes the other's own rows' forces on floating partners as
// forces to come on it: elastic_contact_stage's `later` and `later_loads`.) A change that
// would make the owners a cycle is not made.
bool Dynamics::pair_pressed(int owner, int other) const {
  const auto& forces = elastic_[static_cast<std::size_t>(owner)]->last_pair_force;
  const auto it = forces.find(other);
  return it != forces.end() && it->second > 0;
}

std::vector<int> Dynamics::pressed_on(int body) const {
  std::vector<int> out;
  for (const auto& [partner, force] : elastic_[static_cast<std::size_t>(body)]->last_pair_force)
    if (force > 0) out.push_back(partner);
  for (const auto& [owner, other] : elastic_elastic_)  // rows its owners solved
    if (other == body && pair_pressed(owner, body)) out.push_back(owner);
  return out;
}

bool Dynamics::can_support(int body) const {
  // (a rigid body that moves: its mobility, or its mechanism's, in the rows)
  const ElasticBody* e = elastic_[static_cast<std::size_t>(body)].get();
  return !e || !e->floating;
}

bool Dynamics::floating(int body) const {
  const ElasticBody* e = elastic_[static_cast<std::size_t>(body)].get();
  return e && e->floating;
}

Dynamics::PartnerWrenches Dynamics::stage_wrenches(int body) const {
  const ElasticBody& e = *elastic_[static_cast<std::size_t>(body)];
  PartnerWrenches w = e.last_partner_wrench;
  if (e.last_own_wrench.squaredNorm() > 0) w[body] = e.last_own_wrench;
  return w;
}

Dynamics::NodeLoads Dynamics::stage_loads(int body) const {
  const ElasticBody& e = *elastic_[static_cast<std::size_t>(body)];
  NodeLoads out;
  for (const auto& [r, forces] : e.last_partner_forces)
    if (floating(r)) out[r] = forces;
  if (!e.last_own_forces.empty()) out[body] = e.last_own_forces;
  return out;
}

bool Dynamics::presses_apart(int body, int except, bool moving_only) const {
  for (const int partner : pressed_on(body))
    if (partner != except && (!moving_only || !can_support(partner))) return true;
  return false;
}

std::vector<int> Dynamics::stage_group(int body) const {
  auto at = [&](int q) -> const ElasticBody* {
    return elastic_[static_cast<std::size_t>(q)].get();
  };
  auto has = [](const std::vector<int>& v, int q) { return std::count(v.begin(), v.end(), q) > 0; };
  auto shared_rigid = [&](int r) { return !at(r) && movable_partner(r); };
  auto member = [&](int q) { return at(q) && at(q)->touchable; };
  if (!member(body)) return {body};
  // linked: they touch one movable rigid body, or one's stage solves their pair
  auto linked = [&](int a, int b) {
    const ElasticBody &ea = *at(a), &eb = *at(b);
    if (has(ea.elastic_partners, b) || has(eb.elastic_partners, a)) return true;
    return std::any_of(ea.partners.begin(), ea.partners.end(),
                       [&](int r) { return shared_rigid(r) && has(eb.partners, r); });
  };
  std::set<int> members{body};
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t q = 0; q < elastic_.size(); ++q) {
      const int qi = static_cast<int>(q);
      if (members.count(qi) || !member(qi)) continue;
      if (std::any_of(members.begin(), members.end(), [&](int m) { return linked(m, qi); }))
        grew = members.insert(qi).second || grew;
    }
  }
  // one solve is wanted where two of their stages move one body: a rigid one both touch, or
  // a floating elastic one whose contact with an owner that stage solves while its own stage
  // or another owner's solves its other rows (cubes pushed together on a plate: 566 Newton
  // iterations instead of 1,045 in the pushed blocks sample, no passes; two such blocks
  // pressed together at rest, below their friction, now sleep where stage by stage they crept
  // 8.5 um in 0.2 s; on a loose mat, which owns their contacts with it while one cube owns
  // their pair, stage by stage they crept 28 um in 0.3 s and took 24 s, grouped none and 1 s)
  bool wanted = false, paired = false;
  for (const int m : members) {
    const ElasticBody& e = *at(m);
    for (const int r : e.partners)
      if (shared_rigid(r))
        wanted = wanted || std::count_if(members.begin(), members.end(),
                                         [&](int q) { return has(at(q)->partners, r); }) >= 2;
    for (const int q : e.elastic_partners) paired = paired || members.count(q) > 0;
  }
  wanted = wanted || paired;
  if (!wanted) return {body};
  std::vector<int> group;
  for (const int q : stage_order_)
    if (members.count(q)) group.push_back(q);
  return group;
}

void Dynamics::choose_owners() {
  auto touching = [&](const std::pair<int, int>& pair) {
    return pair_pressed(pair.first, pair.second);
  };
  for (auto& pair : elastic_elastic_) {
    const auto [owner, other] = pair;
    ElasticBody& eo = *elastic_[static_cast<std::size_t>(owner)];
    const ElasticBody& ex = *elastic_[static_cast<std::size_t>(other)];
    if (!eo.floating || !ex.floating || !touching(pair)) continue;
    // the other one presses elsewhere and the owner does not; or both do, the other on a
    // body that moves (no support the owner's stage can hold) and the owner on fixed
    // bodies only (the other's stage can hold them), where the owner's supports, which the
    // other's stage would then solve as rows too, are few beside the other's own points (a
    // rubber mat on a table under a block: 150-430 points on the table against 20-50; the
    // block's stage and the mat's took turns owning the pair, the block's solving the mat's
    // supports too, 97 s against 19 s. The stage before takes the other's forces on bodies
    // that move as forces to come)
    constexpr std::size_t kFewSupports = 64;
    const bool few =
        eo.supports.size() <= std::max(kFewSupports, 4 * static_cast<std::size_t>(ex.last_points));
    const bool swap = presses_apart(other, owner) &&
                      (!presses_apart(owner, other) || (few && presses_apart(other, owner, true) &&
                                                        !presses_apart(owner, other, true)));
    if (!swap) continue;
    pair = {other, owner};
    if (!assign_stages()) {
      // a cycle: a pair that does not touch may turn round to break it
      bool broken = false;
      for (auto& q : elastic_elastic_) {
        if (&q == &pair || touching(q)) continue;
        std::swap(q.first, q.second);
        if (assign_stages()) {
          broken = true;
          break;
        }
        std::swap(q.first, q.second);
      }
      if (!broken) {
        pair = {owner, other};
        VPROTO_DEMAND(assign_stages());
        continue;
      }
    }
    // the old owner's memory of the pair goes: the new one starts it cold
    eo.last_partner_forces.erase(other);
    eo.last_partner_wrench.erase(other);
    eo.last_pair_force.erase(other);
    for (auto it = eo.warm.begin(); it != eo.warm.end();)
      it = it->first.first == -(2 + 2 * other) || it->first.first == -(3 + 2 * other)
               ? eo.warm.erase(it)
               : std::next(it);
  }
}

// the reference frame's displacement from where it started under the body's `move`
// statements, taken one after another
Eigen::Vector3d Dynamics::frame_offset(int body, double t, Eigen::Vector3d* velocity) const {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  if (velocity) velocity->setZero();
  double start = 0;
  for (const auto& m : scene_.moves) {
    if (m.body != body) continue;
    const double f = std::clamp((t - start) / m.over, 0.0, 1.0);
    d += f * m.by;
    if (velocity && t >= start && t < start + m.over) *velocity = m.by / m.over;
    start += m.over;
  }
  return d;
}

// clamped nodes stay put; gripped ones move with the frame (a translation, its velocity,
// no acceleration between the velocity changes of the moves)
HeldMotion Dynamics::held_motion(int body, double t) const {
  const ElasticBody& e = *elastic_[body];
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  const Eigen::Vector3d d = frame_offset(body, t, &v);
  HeldMotion held;
  held.u = held.v = held.a = Eigen::VectorXd::Zero(e.model.fe.dofs);
  for (Eigen::Index k = 0; k < e.model.fe.dofs; ++k)
    if (e.grip_dof[k]) {
      held.u[k] = d[k % 3];
      held.v[k] = v[k % 3];
    }
  return held;
}

double Dynamics::kinetic_energy() const {
  double e = 0;
  for (std::size_t i = 0; i < states_.size(); ++i)
    e += elastic_[i]
             ? elastic_[i]->solver->kinetic_energy() +
                   (elastic_[i]->floating ? sim::kinetic_energy(states_[i], inertias_[i]) : 0)
             : sim::kinetic_energy(states_[i], inertias_[i]);
  return e;
}

double Dynamics::sum_elastic(double (ElasticDynamics::*quantity)() const) const {
  double sum = 0;
  for (const auto& b : elastic_)
    if (b) sum += ((*b->solver).*quantity)();
  return sum;
}

double Dynamics::strain_energy() const { return sum_elastic(&ElasticDynamics::strain_energy); }

double Dynamics::external_work() const {
  return rigid_work_ + sum_elastic(&ElasticDynamics::external_work);
}

double Dynamics::damped_energy() const { return sum_elastic(&ElasticDynamics::damped_energy); }

double Dynamics::joint_drift() const { return joints_ ? joints_->drift(states_) : 0.0; }

double Dynamics::max_von_mises() const {
  double m = 0;
  for (const auto& b : elastic_)
    if (b) m = std::max(m, b->max_von_mises);
  return m;
}

bool Dynamics::holds(int body) const {
  const ElasticBody* e = elastic_[body].get();
  return e && !e->model.held_nodes().empty() && !e->model.frame_grip;
}

bool Dynamics::reads_corners(int body) const {
  const ElasticBody* e = elastic_[body].get();
  return e && !e->corner_reads.empty();
}

std::pair<double, double> Dynamics::corner_values(int body) const {
  const ElasticBody* e = elastic_[body].get();
  if (!e) return {0.0, 0.0};
  return {e->corner_now.von_mises, e->corner_now.strain};
}

Eigen::Vector3d Dynamics::reaction(int body) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const ElasticBody* e = elastic_[body].get();
  if (!e || e->model.held_nodes().empty() || !e->awake) return sum;
  const Eigen::VectorXd r = e->solver->reactions();
  for (Eigen::Index k = 0; k < r.size(); ++k) sum[k % 3] += r[k];
  // a floating body's reactions are in its frame's axes
  return e->floating ? (states_[body].rotation * sum).eval() : sum;
}

Eigen::Vector3d Dynamics::contact_force_on(int body) const {
  const ElasticBody* e = elastic_[static_cast<std::size_t>(body)].get();
  if (!e) return Eigen::Vector3d::Zero();
  // its own stage's rows, and the rows its owners' stages solved against it
  Eigen::Vector3d f = e->contact_force;
  for (const auto& [owner, other] : elastic_elastic_) {
    if (other != body) continue;
    const auto& given = elastic_[static_cast<std::size_t>(owner)]->last_partner_forces;
    const auto it = given.find(body);
    if (it != given.end())
      for (const auto& [node, g] : it->second) f += g;
  }
  return f;
}

std::vector<ElasticStatus> Dynamics::elastic_status() const {
  std::vector<ElasticStatus> out;
  for (std::size_t i = 0; i < elastic_.size(); ++i) {
    const ElasticBody* e = elastic_[i].get();
    if (!e) continue;
    const Body& b = scene_.bodies[i];
    ElasticStatus st;
    st.body = static_cast<int>(i);
    st.strain_energy = e->solver->strain_energy();
    st.kinetic_energy = e->solver->kinetic_energy();
    st.max_von_mises = e->max_von_mises;
    st.peak_von_mises = e->peaks.von_mises.value;
    st.peaks = e->peaks;
    st.max_principal_strain = max_principal_strain(b.tet_mesh, e->solver->displacement());
    const Eigen::VectorXd r = e->solver->reactions();
    for (Eigen::Index k = 0; k < r.size(); ++k) st.reaction[k % 3] += r[k];
    st.peak_reaction = e->peak_reaction;
    out.push_back(st);
  }
  return out;
}

void Dynamics::advance_to(double t) {
  const double span = t - time_;
  if (span <= 0) return;
  const long n = static_cast<long>(std::ceil(span / time_step_ - 1e-9));
  const double dt = span / static_cast<double>(std::max(1L, n));
  for (long k = 0; k < std::max(1L, n); ++k) step(dt);
  time_ = t;
}

void Dynamics::step(double dt) {
  if (!cut_increments_) {
    take_step(dt);
    finish_step(dt);
    return;
  }
  increment(dt, 0);
}

void Dynamics::increment(double dt, int cuts) {
  // A quasi-static increment is redone as two halves from the state before it when its
  // contact rows did not settle within the stage's passes (an apex passing a part's edge
  // within it: the rows on the lead face hold the surface out where the end configuration
  // has the edge past the face, and the released state finds the face again) or when a
  // contact let go within it (below), down to a 64th of the increment; what still does not
  // settle there is kept as solved (summary.json: cut_increments, unsettled_increments).
  // The paw of samples/paw_quasistatic.vp then peaks at 7.95 N going in and 3.56 N coming
  // out at its own increments (8.02 and 3.57 N at 25 times finer ones; 8.44 and 4.06 N
  // before), and the socket driven at a quarter of its mesh size per increment (1.13 mm)
  // follows its fine curve through the apexes' passing (174 N at 4.52 mm before, where the
  // fine increments slide at 17.4 N).
  constexpr int kMaxCuts = 6;
  // (a contact letting go: a body's contact force losing more than kEventChange of what it
  // was, when that was more than kEventFloor of the largest so far)
  constexpr double kEventChange = 0.5, kEventFloor = 1e-3;
  // the state before it (take_step leaves time_ and steps_ as they are)
  const Checkpoint saved = checkpoint();
  unsettled_ = false;
  last_cut_ = cuts >= kMaxCuts;
  take_step(dt);
  last_cut_ = false;
  // a contact letting go within the increment: the contact force on a body lost more than
  // half its size (an apex passing an edge: the paw's push falls from 8 N to 0.9 N within
  // one increment, and the sampled curve would miss its peak). (A force that grows is not
  // cut: points that close within an increment join its rows where it ends them, and a
  // press from zero would be halved six times for nothing.)
  bool event = false;
  for (std::size_t i = 0; i < elastic_.size(); ++i) {
    if (!elastic_[i]) continue;
    const double was = saved.elastic[i]->contact_force.norm(),
                 now = elastic_[i]->contact_force.norm();
    if (was > kEventFloor * largest_contact_force_ && now < (1 - kEventChange) * was) event = true;
    largest_contact_force_ = std::max(largest_contact_force_, now);
  }
  if (halve_every_increment_ && cuts == 0) event = true;
  if (unsettled_ && cuts >= kMaxCuts) {
    // no equilibrium found at a 64th of the increment, its stages passed 32 times there:
    // kept as solved and counted, and the first one said (the paw sample's hook at 30
    // degrees on its 0.1 in elements, pulled out: where the return face's apex passes the
    // catch's edge, 96 % of the force is on rows past the edge after 32 passes, or 64;
    // elements of 0.05 in settle)
    ++elastic_stats_.unsettled_increments;
    if (elastic_stats_.first_unsettled.empty()) {
      const Unsettled& u = unsettled_at_;
      const Body& b = scene_.bodies[static_cast<std::size_t>(std::max(u.body, 0))];
      const std::string partner =
          u.partner >= 0 ? "'" + scene_.bodies[static_cast<std::size_t>(u.partner)].name + "'"
                         : std::string("its partners");
      char t[560];
      std::snprintf(t, sizeof t,
                    "' with %s found no equilibrium in the quasi-static increment at t = %.6g "
                    "s, kept as solved: cut to a %dth of it (dt = %.3g s), its contact rows "
                    "still changed after %d passes (%.0f %% of the force moved between rows "
                    "or held past a surface's edge), where a part's edge or apex passes a "
                    "face between its nodes; the forces there are approximate: use a finer "
                    "mesh_size for '%s' (now %.3g m)",
                    partner.c_str(), time_, 1 << kMaxCuts, dt, u.passes, 100 * u.share,
                    b.name.c_str(), b.tet_mesh.mesh_size);
      elastic_stats_.first_unsettled = "contact of '" + b.name + t;
    }
  }
  if ((!unsettled_ && !event) || cuts >= kMaxCuts) {
    finish_step(dt);
    return;
  }
  // (the effort of the rejected increment stays counted; what it found does not)
  restore(saved);
  ++elastic_stats_.cut_increments;
  increment(0.5 * dt, cuts + 1);
  increment(0.5 * dt, cuts + 1);
}

// Elastic bodies that touch rigid bodies only and share a movable one (rubber jaws on a
// gripped block, pads under a beam) have their stages' rows solved as one problem
// (stage_group, elastic_contact_stage). Other stages solve their own rows; a movable rigid
// body that several of them press on (a floating elastic body among them, or another
// stage's elastic partner) answers each with the others' forces as loads: those of the
// stages before it in this step, and of the stages after it as they were in their last
// step. Where two of them hold it by friction, the lag stays in what each carries: two
// rubber jaws (tet10 of 5 mm, 1.7 ms steps) squeezing a steel block carried -5 % and 105 %
// of its weight (listed the other way round, 115 % and -15 %; the test's tet4 jaws at 1 ms,
// 22 % and 78 %), where the same jaws share it equally. So while two stages or more hold
// one movable rigid body, the stages are passed again from the step's start, each taking
// the forces that the stages after it gave in the pass before, until those agree with
// what they give to kAgree of the largest wrench on the body (torques over its radius of
// gyration): the forces of one solve of all their rows, its fixed point (the jaws: 50.01 %
// and 49.99 % either way round). The passes are a block Gauss-Seidel iteration over the
// stages, a partitioned coupling; where the body's mobility over a step outweighs the
// bodies' compliance it contracts slowly (0.75 a pass for the jaws at 1.7 ms steps), and
// the forces handed on are accelerated (Anderson's mixing, below): 2-3 passes a step more
// for the jaws, none in scenes whose stages slide on a shared body (the rubber blocks on a
// tray). The same holds for a floating elastic body that two stages move (its owner's, and
// its own through its rows on floating partners: two rubber cubes pushed together on a loose
// rubber mat, before such stages were one group), its deformation under the forces handed on going
// with them (mixed with the same coefficients); one that two stages press on without both holding
// it is passed again too, to a looser tolerance (kLoose, below).
void Dynamics::coupled_stages(double dt, const std::vector<RigidState>& before,
                              std::vector<Eigen::Vector3d>& forces,
                              std::vector<Eigen::Vector3d>& torques, std::vector<char>& done) {
  constexpr int kMaxPasses = 12;
  constexpr std::size_t kMemory = 6;
  constexpr double kAgree = 1e-6, kLoose = 1e-3;
  // (a movable rigid body two elastic bodies can touch, or a floating elastic body that
  // two stages can move: its owners' and, with floating partners of its own, its own)
  // (the stages of a group count once: one solve takes their rows together)
  std::map<int, int> partner_of;
  std::set<std::pair<int, int>> counted;  // (first stage of a group, body)
  for (std::size_t s = 0; s < elastic_.size(); ++s) {
    const ElasticBody* e = elastic_[s].get();
    if (!e || !e->touchable) continue;
    const int group = stage_group(static_cast<int>(s)).front();
    for (const int r : e->partners)
      if (movable_partner(r) && counted.insert({group, r}).second) ++partner_of[r];
    bool own = false;
    for (const int r : e->elastic_partners)
      if (floating(r)) {
        if (counted.insert({group, r}).second) ++partner_of[r];
        own = true;
      }
    if (own && e->floating && counted.insert({group, static_cast<int>(s)}).second)
      ++partner_of[static_cast<int>(s)];
  }
  if (std::none_of(partner_of.begin(), partner_of.end(),
                   [](const auto& p) { return p.second >= 2; })) {
    elastic_contact_stage(dt, before, forces, torques, done);
    return;
  }
  // The forces handed on: per stage, its wrenches on the rigid bodies that a stage before it
  // pressed on too (no stage takes the first one's on a body as a load), where two stages or
  // more held the body by friction. (Where all but one slide on it, the forces on it follow
  // from the rows and a lag is made up in the next step; where two hold it, what each
  // carries follows from the friction's history, and a lag stays in it: the jaws' split.)
  using Handed = std::map<std::pair<int, int>, Eigen::Matrix<double, 6, 1>>;  // (stage, body)
  // (a floating body's stage hands on its own frame's wrench by its own key)
  auto wrenches = [&](int body) { return stage_wrenches(body); };
  // (a floating elastic body that two stages press on, not both holding it by friction: its
  // forces handed on agree to kLoose. Taken from the last step, they lag it by a step's
  // change: two rubber blocks sliding together on a loose mat under a growing push, the
  // pusher's normal force on the mat swung between 0 and 2.7 times its weight from step to
  // step, and it hopped; to kAgree they settle no closer than the solves' own rounding
  // allows, 1e-6-1e-5, in twelve passes)
  std::set<std::pair<int, int>> loose;
  auto handed = [&] {
    std::map<int, std::vector<int>> pressing;  // by body: the stages, in their order
    std::map<int, int> holding;
    for (const int body : stage_order_) {
      const ElasticBody* e = elastic_[static_cast<std::size_t>(body)].get();
      if (!e || !e->touchable) continue;
      for (const auto& [r, w] : wrenches(body)) {
        if ((elastic_[static_cast<std::size_t>(r)] && !floating(r)) || w.squaredNorm() == 0)
          continue;
        pressing[r].push_back(body);
        // (its own frame: held where it sticks on a floating partner)
        bool holds = e->sticking_on.count(r) > 0;
        if (r == body)
          for (const int q : e->sticking_on) holds = holds || floating(q);
        holding[r] += holds ? 1 : 0;
      }
    }
    Handed out;
    loose.clear();
    for (const auto& [r, stages] : pressing)
      if (holding[r] >= 2 || (floating(r) && stages.size() >= 2))
        for (std::size_t k = 1; k < stages.size(); ++k) {
          out[{stages[k], r}] = wrenches(stages[k]).at(r);
          if (holding[r] < 2) loose.insert({stages[k], r});
        }
    return out;
  };
  // (a torque over the body's radius of gyration, to weigh with the forces)
  auto gyration = [&](int r) {
    const RigidInertia& in = inertias_[static_cast<std::size_t>(r)];
    return std::sqrt(0.5 * in.inertia.trace() / in.mass);
  };
  auto scaled = [&](int r, Eigen::Matrix<double, 6, 1> w) {
    w.tail<3>() /= gyration(r);
    return w;
  };
  const Checkpoint start = checkpoint();
  const std::vector<Eigen::Vector3d> forces0 = forces, torques0 = torques;
  // what the passes took: the last step's wrenches, then the accelerated ones
  Handed input;
  for (const int body : stage_order_)
    if (elastic_[static_cast<std::size_t>(body)])
      for (const auto& [r, w] : wrenches(body)) input[{body, r}] = w;
  // the passes' inputs x and residuals g(x) - x as vectors (the keys of the first pass
  // that handed forces on), for Anderson's least squares
  std::vector<std::pair<int, int>> keys;
  std::vector<Eigen::VectorXd> xs, gs;
  // and, where the body is a floating elastic one, the nodal forces the passes gave it
  // (the stage's on it, on its surface nodes, world axes), mixed with the same
  // coefficients: the deformation that goes with the accelerated wrenches
  std::vector<Eigen::VectorXd> gls;
  auto surface_size = [&](int r) {
    return static_cast<Eigen::Index>(3 *
                                     elastic_[static_cast<std::size_t>(r)]->surface.nodes.size());
  };
  auto loads_of = [&](int stage, int r) -> const std::vector<std::pair<int, Eigen::Vector3d>>* {
    const ElasticBody& e = *elastic_[static_cast<std::size_t>(stage)];
    if (r == stage) return &e.last_own_forces;
    const auto it = e.last_partner_forces.find(r);
    return it == e.last_partner_forces.end() ? nullptr : &it->second;
  };
  double last_worst = 0;
  int growing = 0;
  for (int pass = 0;; ++pass) {
    elastic_contact_stage(dt, before, forces, torques, done);
    const Handed out = handed();
    if (out.empty()) break;
    if (pass == 0) ++elastic_stats_.shared_steps;
    // the residual: what the stages gave less what the stages before them took
    // (over its tolerance, kAgree or kLoose)
    double largest = 0, worst = 0;
    for (const auto& [key, w] : out) {
      const auto it = input.find(key);
      const Eigen::Matrix<double, 6, 1> was =
          it == input.end() ? Eigen::Matrix<double, 6, 1>::Zero() : it->second;
      // (forces and torques over the body's radius of gyration)
      largest = std::max(largest, scaled(key.second, w).norm());
      worst = std::max(worst,
                       scaled(key.second, w - was).norm() / (loose.count(key) ? kLoose : kAgree));
    }
    if (worst <= largest) break;
    // (at the limit, or growing in three passes running: a row's state changing from pass
    // to pass; the last pass is kept)
    growing = pass > 0 && worst > last_worst ? growing + 1 : 0;
    last_worst = worst;
    if (pass + 1 == kMaxPasses || growing == 3) {
      ++elastic_stats_.shared_unsettled;
      break;
    }
    // Anderson's acceleration (type II, the last kMemory passes): the next input is
    // x + r - (dX + dR) gamma, gamma the least-squares fit of r by the residuals' changes dR
    // (Walker and Ni; preCICE's IQN-ILS). On a linear map of n unknowns it is exact in n + 1
    // passes; the jaws' normal and tangential forces contract at different rates, which
    // one relaxation factor (Aitken's) could not follow.
    std::vector<std::pair<int, int>> now_keys;
    for (const auto& [key, w] : out) now_keys.push_back(key);
    if (now_keys != keys) {  // (other forces handed on: the history restarts)
      keys = std::move(now_keys);
      xs.clear();
      gs.clear();
      gls.clear();
    }
    const auto n = static_cast<Eigen::Index>(6 * keys.size());
    Eigen::VectorXd x(n), g(n);
    for (std::size_t k = 0; k < keys.size(); ++k) {
      const auto it = input.find(keys[k]);
      const Eigen::Matrix<double, 6, 1> was =
          it == input.end() ? Eigen::Matrix<double, 6, 1>::Zero() : it->second;
      x.segment<6>(6 * static_cast<Eigen::Index>(k)) = scaled(keys[k].second, was);
      g.segment<6>(6 * static_cast<Eigen::Index>(k)) = scaled(keys[k].second, out.at(keys[k]));
    }
    Eigen::Index nl = 0;
    for (const auto& key : keys)
      if (floating(key.second)) nl += surface_size(key.second);
    Eigen::VectorXd gl = Eigen::VectorXd::Zero(nl);
    Eigen::Index at = 0;
    for (const auto& key : keys) {
      if (!floating(key.second)) continue;
      if (const auto* f = loads_of(key.first, key.second))
        for (const auto& [node, force] : *f) gl.segment<3>(at + 3 * node) += force;
      at += surface_size(key.second);
    }
    xs.push_back(x);
    gs.push_back(g);
    gls.push_back(gl);
    if (xs.size() > kMemory + 1) {
      xs.erase(xs.begin());
      gs.erase(gs.begin());
      gls.erase(gls.begin());
    }
    Eigen::VectorXd next_x = g, next_gl = gl;
    if (xs.size() > 1) {
      const auto cols = static_cast<Eigen::Index>(xs.size() - 1);
      Eigen::MatrixXd dr(n, cols), dg(n, cols);
      for (Eigen::Index c = 0; c < cols; ++c) {
        const auto q = static_cast<std::size_t>(c);
        dr.col(c) = (gs[q + 1] - xs[q + 1]) - (gs[q] - xs[q]);
        dg.col(c) = gs[q + 1] - gs[q];
      }
      const Eigen::VectorXd gamma = dr.colPivHouseholderQr().solve(g - x);
      next_x -= dg * gamma;
      for (Eigen::Index c = 0; c < cols; ++c) {
        const auto q = static_cast<std::size_t>(c);
        next_gl -= gamma[c] * (gls[q + 1] - gls[q]);
      }
    }
    // the next pass's: accelerated for the forces handed on, else as this pass gave them
    std::map<int, PartnerWrenches> next;
    for (const int body : stage_order_)
      if (elastic_[static_cast<std::size_t>(body)]) next[body] = wrenches(body);
    for (std::size_t k = 0; k < keys.size(); ++k) {
      Eigen::Matrix<double, 6, 1> w = next_x.segment<6>(6 * static_cast<Eigen::Index>(k));
      w.tail<3>() *= gyration(keys[k].second);
      next[keys[k].first][keys[k].second] = w;
    }
    // (the nodal forces on floating bodies: mixed for the wrenches handed on, else as this
    // pass gave them)
    std::map<int, NodeLoads> next_loads;
    for (const int body : stage_order_)
      if (elastic_[static_cast<std::size_t>(body)]) next_loads[body] = stage_loads(body);
    at = 0;
    for (const auto& key : keys) {
      if (!floating(key.second)) continue;
      auto& mixed = next_loads[key.first][key.second];
      mixed.clear();
      for (Eigen::Index k = 0; 3 * k < surface_size(key.second); ++k)
        if (const Eigen::Vector3d f = next_gl.segment<3>(at + 3 * k); f.squaredNorm() > 0)
          mixed.push_back({static_cast<int>(k), f});
      at += surface_size(key.second);
    }
    input.clear();
    for (const auto& [body, ws] : next)
      for (const auto& [r, w] : ws) input[{body, r}] = w;
    // again from the step's start, each stage warm-started from this pass's forces
    std::vector<std::map<std::pair<int, std::int64_t>, Eigen::Vector3d>> warm(elastic_.size());
    for (std::size_t i = 0; i < elastic_.size(); ++i)
      if (elastic_[i]) warm[i] = elastic_[i]->warm;
    restore(start);
    for (std::size_t i = 0; i < elastic_.size(); ++i)
      if (elastic_[i]) elastic_[i]->warm = std::move(warm[i]);
    forces = forces0;
    torques = torques0;
    std::fill(done.begin(), done.end(), 0);
    pass_wrenches_ = std::move(next);
    pass_loads_ = std::move(next_loads);
    ++elastic_stats_.shared_passes;
  }
  pass_wrenches_.reset();
  pass_loads_.reset();
}

Dynamics::Checkpoint Dynamics::checkpoint() const {
  Checkpoint c;
  c.states = states_;
  for (const auto& e : elastic_)
    c.elastic.push_back(e ? std::optional<ElasticBody::Saved>(e->save()) : std::nullopt);
  c.events = events_.size();
  c.records = elastic_stats_.step_records.size();
  c.touching = elastic_touching_;
  c.points = elastic_points_;
  c.force = elastic_force_;
  c.peak_force = elastic_peak_force_;
  c.rigid_work = rigid_work_;
  c.max_penetration = elastic_stats_.max_penetration;
  c.max_penetration_time = elastic_stats_.max_penetration_time;
  c.worst_residual = elastic_stats_.worst_residual;
  c.unconverged = elastic_stats_.unconverged;
  c.steps = elastic_stats_.steps;
  c.rows = elastic_stats_.rows;
  c.unsettled = unsettled_;
  if (contact_) c.contact = contact_->save();
  return c;
}

void Dynamics::restore(const Checkpoint& c) {
  states_ = c.states;
  for (std::size_t i = 0; i < elastic_.size(); ++i)
    if (elastic_[i]) elastic_[i]->restore(*c.elastic[i]);
  events_.resize(c.events);
  elastic_stats_.step_records.resize(c.records);
  elastic_touching_ = c.touching;
  elastic_points_ = c.points;
  elastic_force_ = c.force;
  elastic_peak_force_ = c.peak_force;
  rigid_work_ = c.rigid_work;
  elastic_stats_.max_penetration = c.max_penetration;
  elastic_stats_.max_penetration_time = c.max_penetration_time;
  elastic_stats_.worst_residual = c.worst_residual;
  elastic_stats_.unconverged = c.unconverged;
  elastic_stats_.steps = c.steps;
  elastic_stats_.rows = c.rows;
  unsettled_ = c.unsettled;
  if (contact_ && c.contact) contact_->restore(*c.contact);
}

void Dynamics::finish_step(double dt) {
  time_ += dt;
  ++steps_;
  check_overlaps();
  if (on_step_) on_step_(*this);
}

// Velocity Verlet with the contact impulse at the step's start (the elastic stage's velocity
// jump) leaves a body that contact holds at rest moving at the end of each step: a steel
// block lying on a rubber pad jumps up by g dt / 2 and falls back at g dt / 2, and reported
// that speed (4.9 mm/s at 1 ms steps; kinetic energy 370 times the pad's strain energy); one
// sliding on the pad went half a step's friction faster than it moved (mu g dt / 2). So a
// free rigid body that elastic stages held in the last step moves differently this step:
// - along the directions the rows held (a pressed point's normal, a sticking one's tangents
//   too), by its end velocity (Moreau-Jean's rule, theta = 1): x1 = x0 + dt v1, the loads'
//   push dt^2 / 2 farther than Verlet takes it (held_shift_: Q M^-1 times the loads, Q the
//   mass-weighted projection M^-1 J' (J M^-1 J')^+ J on them), so that held at rest it ends
//   its steps at rest; a jump still stops an impact there (a force over the step would
//   double to close the gap, and the body would bounce off);
// - along the others (a slide's direction), the rows' forces act over the step as its loads
//   do: their jump carries it half as far (held_travel_, (I + Q) / 2, in the stages'
//   Delassus blocks too; jump_lag), and it slides at its exact speed.
// Taken whole, the end-velocity rule threw the slide's friction onto its positions instead:
// the block pushed over the pad fell behind by mu g dt t / 2, 0.8 % of its travel at 0.1 s.
// A floating elastic body's frame moves the same way where its own rows held it on bodies
// that stay where they are or are driven (a rubber cube resting or sliding on a table: its
// frame at rest from its second step, where it slept after 0.03 s; sliding, at the velocity
// of its positions to 1e-6 m/s, 2 mm/s fast before), and so did every floating frame pressed
// together with it in the last step (two rubber blocks pushed together over a table: their
// kinetic energy that of their positions' velocities to 2e-10 from 0.1 s, 0.9 % high before,
// mu g dt / 2 too fast): its stage's Delassus blocks take the frame's travel, the
// deformation its jump's acceleration (FloatingSide::jump_mobility), and the other stages
// view it so (PartnerMotion::travel). (Bodies with rigid contacts move with their islands,
// by ContactSystem's midpoint rule; jointed ones with their joints; a group of frames of
// which one is not so held, as before, each by its jumps.)
void Dynamics::held_shifts(double dt, const std::vector<Eigen::Vector3d>& forces,
                           const std::vector<Eigen::Vector3d>& torques) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  const std::size_t n = states_.size();
  held_shift_.assign(n, Eigen::Matrix<double, 6, 1>::Zero());
  held_travel_.assign(n, Matrix6::Zero());
  std::map<int, Matrix6> held;
  for (const auto& e : elastic_)
    if (e && !e->resting)
      for (const auto& [r, rows] : e->last_held_rows)
        held.try_emplace(r, Matrix6::Zero()).first->second += rows;
  // a floating frame its own rows held on bodies that stay where they are or are driven,
  // with every floating frame it pressed on or that pressed on it in the last step, and
  // theirs in turn (a group), held so too: the group's frames then move alike, each stage's
  // view of the others (PartnerMotion::travel) as they move (two rubber blocks pushed
  // together over a table). A group with a frame not so held (a block stacked on another,
  // on a loose mat) moves as before, each frame by its jumps: rows between frames moved by
  // different rules would push their centre of mass aside
  auto frame_held = [&](int r) {
    const ElasticBody* e = elastic_[static_cast<std::size_t>(r)].get();
    return e && e->floating && !e->resting && moves_[static_cast<std::size_t>(r)] &&
           !joints_->moves(r) && held.count(r);
  };
  auto floating_group_held = [&](int r) {
    std::vector<int> frontier{r};
    std::set<int> seen{r};
    while (!frontier.empty()) {
      const int p = frontier.back();
      frontier.pop_back();
      if (!frame_held(p)) return false;
      std::vector<int> near = pressed_on(p);
      for (const auto& [q, w] : stage_wrenches(p)) near.push_back(q);
      for (std::size_t q = 0; q < n; ++q)
        if (static_cast<int>(q) != p && elastic_[q] && stage_wrenches(static_cast<int>(q)).count(p))
          near.push_back(static_cast<int>(q));
      for (const int q : near) {
        const ElasticBody* eq = elastic_[static_cast<std::size_t>(q)].get();
        if (q != p && eq && eq->floating && seen.insert(q).second) frontier.push_back(q);
      }
    }
    return true;
  };
  std::set<int> linked;  // free bodies with rigid contacts
  if (contact_)
    for (const ContactSystem::Link& l : contact_->links()) {
      linked.insert(l.a);
      linked.insert(l.b);
    }
  for (const auto& [r, rows] : held) {
    const auto k = static_cast<std::size_t>(r);
    if (!moves_[k] || joints_->moves(r) ||
        (elastic_[k] ? !floating_group_held(r)
                     : linked.count(r) || (contact_ && !contact_->supports(r).empty())))
      continue;
    // the held directions: the rows' span, an orthonormal basis of it
    const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(rows);
    const double largest = eigen.eigenvalues().maxCoeff();
    if (!(largest > 0)) continue;
    std::vector<int> kept;
    for (int q = 0; q < 6; ++q)
      if (eigen.eigenvalues()[q] > 1e-10 * largest) kept.push_back(q);
    Eigen::MatrixXd basis(6, static_cast<Eigen::Index>(kept.size()));
    for (std::size_t q = 0; q < kept.size(); ++q)
      basis.col(static_cast<Eigen::Index>(q)) = eigen.eigenvectors().col(kept[q]);
    const Eigen::Matrix3d rot = states_[k].rotation.toRotationMatrix();
    Matrix6 minv = Matrix6::Zero();
    minv.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / inertias_[k].mass;
    minv.bottomRightCorner<3, 3>() = rot * inertias_[k].inertia.inverse() * rot.transpose();
    const Eigen::MatrixXd minv_b = minv * basis;
    const Eigen::MatrixXd w = basis.transpose() * minv_b;
    Eigen::Matrix<double, 6, 1> load;
    load << forces[k], torques[k];
    const Matrix6 q = minv_b * w.ldlt().solve(basis.transpose());  // Q = M^-1 B W^-1 B'
    held_shift_[k] = 0.5 * dt * dt * q * minv * load;
    held_travel_[k] = 0.5 * (Matrix6::Identity() + q);
  }
}

Eigen::Matrix<double, 6, 1> Dynamics::jump_lag(int body, const RigidState& before,
                                               const RigidState& jumped, double dt) const {
  const auto k = static_cast<std::size_t>(body);
  if (held_travel_.size() <= k || held_travel_[k].isZero())
    return Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> jump;
  jump << jumped.velocity - before.velocity, jumped.angular_velocity - before.angular_velocity;
  return dt * (held_travel_[k] - Eigen::Matrix<double, 6, 6>::Identity()) * jump;
}

void Dynamics::take_step(double dt) {
  const double t_mid = time_ + 0.5 * dt, t_end = time_ + dt;
  // loads at the middle of the step (ramps), gravity at the centre of mass
  const std::size_t n = states_.size();
  std::vector<Eigen::Vector3d> forces(n, Eigen::Vector3d::Zero()),
      torques(n, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    if (!moves_[i] && !joints_->moves(static_cast<int>(i))) continue;
    const RigidState& s = states_[i];
    if (scene_.gravity) forces[i] += inertias_[i].mass * *scene_.gravity;
    for (const auto& f : scene_.forces) {
      if (f.body != static_cast<int>(i)) continue;
      const Eigen::Vector3d fi = ramp_factor(f.ramp, t_mid) * f.force;
      forces[i] += fi;
      if (f.at) {
        // the point of application moves with the body
        const Eigen::Vector3d lever =
            s.rotation * (*f.at - scene_.bodies[i].mass_properties.centroid);
        torques[i] += lever.cross(fi);
      }
    }
    for (const auto& tq : scene_.torques)
      if (tq.body == static_cast<int>(i)) torques[i] += ramp_factor(tq.ramp, t_mid) * tq.torque;
    // a region force turns a floating frame by its moment about the centroid
    if (elastic_[i] && elastic_[i]->floating)
      for (const ElasticModel::Load& l : elastic_[i]->model.loads)
        torques[i] += ramp_factor(l.ramp, t_mid) * (s.rotation * l.moment);
  }
  const std::vector<RigidState> before = states_;
  held_shifts(dt, forces, torques);
  // contact of elastic bodies first: it advances the FE bodies it concerns and adds the
  // contact forces on floating frames to their loads
  std::vector<char> fe_done(n, 0);
  coupled_stages(dt, before, forces, torques, fe_done);
  const std::vector<RigidState> kicked = states_;  // with the elastic contact's jumps
  // contact moves the free bodies that may touch something within the step (driven ones
  // at their velocity over the step); the others move freely
  std::vector<char> by_contact(n, 0);
  if (contact_) {
    for (std::size_t i = 0; i < n; ++i)
      if (driven_[i] >= 0) frame_offset(static_cast<int>(i), t_mid, &states_[i].velocity);
    // a jointed body answers contact as its joints let it: through its mechanism's
    // mobility, the joint rows held exactly
    for (std::size_t m = 0; m < joints_->mechanisms().size(); ++m) {
      const std::vector<int>& bodies = joints_->mechanisms()[m];
      if (std::any_of(bodies.begin(), bodies.end(), [&](int b) {
            return contact_roles_[static_cast<std::size_t>(b)] == ContactRole::kJointed;
          }))
        contact_->set_mechanism(
            bodies, joints_->mechanism_mobility(states_, inertias_, static_cast<int>(m)));
    }
    const std::size_t known = contact_->events().size();
    contact_->step(states_, inertias_, forces, torques, time_, dt, &by_contact);
    events_.insert(events_.end(), contact_->events().begin() + static_cast<long>(known),
                   contact_->events().end());
  }
  for (std::size_t i = 0; i < n; ++i) {
    RigidState& s = states_[i];
    if (driven_[i] >= 0) {
      // kinematic: the frame follows its moves exactly
      s.position = scene_.bodies[i].mass_properties.centroid +
                   frame_offset(static_cast<int>(i), t_end, &s.velocity);
      continue;
    }
    if (moves_[i] && !by_contact[i]) {
      step_rigid(s, inertias_[i], forces[i], torques[i], dt);
      if (!elastic_[i] || !elastic_[i]->resting)  // (a frame asleep stays put)
        shift_by(s, held_shift_[i] + jump_lag(static_cast<int>(i), before[i], kicked[i], dt));
    }
  }
  if (!joints_->empty()) {
    // a jointed body's contact impulse acts over the step, as a load its joints pass on
    std::vector<Eigen::Vector3d> joint_forces = forces, joint_torques = torques;
    for (std::size_t i = 0; i < n; ++i)
      if (contact_ && joints_->moves(static_cast<int>(i))) {
        const Eigen::Matrix<double, 6, 1>& impulse = contact_->jointed_impulse(static_cast<int>(i));
        joint_forces[i] += impulse.head<3>() / dt;
        joint_torques[i] += impulse.tail<3>() / dt;
        // out of the overlaps the contact found, from where it starts (first order in the
        // joint rows, which the joint step's projection then restores)
        const Eigen::Matrix<double, 6, 1>& push = contact_->jointed_correction(static_cast<int>(i));
        if (push.squaredNorm() > 0) {
          states_[i].position += push.head<3>();
          const double angle = push.tail<3>().norm();
          if (angle > 0)
            states_[i].rotation =
                (Eigen::Quaterniond(Eigen::AngleAxisd(angle, push.tail<3>() / angle)) *
                 states_[i].rotation)
                    .normalized();
        }
      }
    joints_->step(states_, inertias_, joint_forces, joint_torques, dt);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!moves_[i] && !joints_->moves(static_cast<int>(i))) continue;
    const RigidState& s = states_[i];
    // the loads are constant over the step: their work is force times displacement (right
    // across an impact within the step, where the velocity flips; issue 13): the contact
    // system's own tally for the bodies it advanced, else the step's mean velocity from
    // after the elastic contact's velocity jumps (a difference of positions would lose the
    // digits of a tiny step)
    const Eigen::Matrix<double, 6, 1> shifted =
        elastic_[i] && elastic_[i]->resting
            ? Eigen::Matrix<double, 6, 1>::Zero().eval()
            : (held_shift_[i] + jump_lag(static_cast<int>(i), before[i], kicked[i], dt)).eval();
    Eigen::Vector3d moved = 0.5 * dt * (kicked[i].velocity + s.velocity) + shifted.head<3>();
    Eigen::Vector3d turned =
        0.5 * dt * (kicked[i].angular_velocity + s.angular_velocity) + shifted.tail<3>();
    if (by_contact[i] && contact_roles_[i] == ContactRole::kFree) {
      moved = contact_->travel(static_cast<int>(i)).head<3>();
      turned = contact_->travel(static_cast<int>(i)).tail<3>();
    }
    rigid_work_ += forces[i].dot(moved) + torques[i].dot(turned);
    if (!s.position.allFinite() || !s.velocity.allFinite() || !s.angular_velocity.allFinite())
      throw SimulationError("the state of body '" + scene_.bodies[i].name +
                            "' became non-finite at t = " + std::to_string(t_end) + " s");
  }
  for (std::size_t i = 0; i < elastic_.size(); ++i) {
    ElasticBody* e = elastic_[i].get();
    if (!e) continue;
    ElasticDynamics& solver = *e->solver;
    if (!fe_done[i] && e->awake) {
      // one factor for the whole run: steps that differ from it only by rounding use it
      if (std::abs(dt - solver.time_step()) > 1e-9 * dt) solver.set_time_step(dt);
      try {
        if (e->floating) {
          solver.step(elastic_load(static_cast<int>(i), t_end));
        } else {
          const HeldMotion held = held_motion(static_cast<int>(i), t_end);
          solver.step(e->model.load_at(t_end), &held);
        }
      } catch (const SimulationError& err) {
        throw SimulationError("body '" + scene_.bodies[i].name + "': " + err.what());
      }
    }
    if (e->floating) {
      update_absolute(static_cast<int>(i));
    } else {
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      const Eigen::Vector3d d = frame_offset(static_cast<int>(i), t_end, &v);
      states_[i].position = scene_.bodies[i].mass_properties.centroid + d;
      states_[i].velocity = v;
    }
    if (!e->awake || solver.version() == e->stress_version) continue;  // unchanged
    e->stress_version = solver.version();
    const Body& b = scene_.bodies[i];
    const ElementStressStrain fields = element_stress_strain(
        b.tet_mesh, solver.displacement(), b.material.youngs_modulus, b.material.poisson_ratio);
    // the run's peaks, where and when, and the first step past the material's yield; also
    // away from contacts: two mesh sizes from every node a contact pressed in the step (a
    // sharp edge or corner pressing a face concentrates the stress over about two elements)
    const std::vector<Eigen::Vector3d> pressed = e->pressed_points(b);
    e->max_von_mises =
        track_material_peaks(b.tet_mesh, fields, pressed, ElasticBody::contact_reach(b),
                             e->at_sharp_corner, b.material.yield_strength, b.material.yield_strain,
                             t_end, &e->peaks)
            .first;
    // and the hot-spot values extrapolated to its sharp inside corners
    if (!e->corner_reads.empty()) {
      e->corner_now = corner_hot_spot(e->corner_reads, b.tet_mesh, solver.displacement(),
                                      b.material.youngs_modulus, b.material.poisson_ratio, pressed,
                                      ElasticBody::contact_reach(b));
      track_corner_peaks(e->corner_reads, e->corner_now, b.material.yield_strength,
                         b.material.yield_strain, t_end, &e->peaks);
      if (e->corner_now.strain_read < 0)  // every read under a contact: none to give
        e->corner_now.von_mises = e->corner_now.strain = std::numeric_limits<double>::quiet_NaN();
    }
    if (!e->model.held_nodes().empty()) {
      const Eigen::VectorXd r = solver.reactions();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (Eigen::Index k = 0; k < r.size(); ++k) sum[k % 3] += r[k];
      e->peak_reaction = std::max(e->peak_reaction, sum.norm());
    }
  }
  if (!joints_->empty()) max_joint_drift_ = std::max(max_joint_drift_, joints_->drift(states_));
  if (!std::isnan(watched_energy_)) {
    // the loads' work is all a rigid scene without drives can gain (contact and joints
    // only take energy away): half as much again means the steps have run away
    const double energy = kinetic_energy();
    const double supplied = watched_energy_ + std::max(external_work(), 0.0);
    peak_supplied_ = std::max(peak_supplied_, supplied);
    if (!std::isfinite(energy) || energy - supplied > 0.5 * peak_supplied_ + 1e-12) {
      char what[600];
      const int n_written = std::snprintf(
          what, sizeof what,
          "the motion gained energy no load supplied: %.3g J of kinetic energy at t = %.6g s "
          "against %.3g J given by the start and the loads; ",
          energy, t_end, supplied);
      // the likely cause: a body turning so fast that a step's rotation is not small (a
      // thin needle struck at an edge spins about its axis; contact is linearised at the
      // step's start)
      std::size_t fastest = n;
      double spin = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (moves_[i] && states_[i].angular_velocity.norm() > spin) {
          spin = states_[i].angular_velocity.norm();
          fastest = i;
        }
      const std::size_t room = sizeof what - static_cast<std::size_t>(n_written);
      if (fastest < n && spin * dt > 0.5)
        std::snprintf(what + n_written, room,
                      "body '%s' spins at %.3g rad/s, %.2g rad per step: the step (%.3g s) is "
                      "too long for it; lower dt to %.2g s (0.1 rad per step)",
                      scene_.bodies[fastest].name.c_str(), spin, spin * dt, dt, 0.1 / spin);
      else
        std::snprintf(what + n_written, room,
                      "the step (%.3g s) is too long for this scene's contacts or joints: lower "
                      "dt (try %.3g s)",
                      dt, dt / 10);
      throw SimulationError(what);
    }
  }
}

void Dynamics::check_overlaps() const {
  const std::size_t n = states_.size();
  std::vector<geometry::Bounds> boxes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const geometry::Bounds b0 = geometry::bounds(scene_.bodies[i].surface);
    if (elastic_[i]) {
      // the undeformed box grown by the largest nodal displacement
      const Eigen::VectorXd& u = *nodal_displacement(static_cast<int>(i));
      double reach = 0;
      for (Eigen::Index k = 0; k + 2 < u.size(); k += 3)
        reach = std::max(reach, u.segment<3>(k).norm());
      boxes[i].lo = b0.lo.array() - reach;
      boxes[i].hi = b0.hi.array() + reach;
      continue;
    }
    // the starting box's corners carried by the pose: a box that holds the body
    const Eigen::Vector3d c0 = scene_.bodies[i].mass_properties.centroid;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p((corner & 1) ? b0.hi.x() : b0.lo.x(),
                              (corner & 2) ? b0.hi.y() : b0.lo.y(),
                              (corner & 4) ? b0.hi.z() : b0.lo.z());
      const Eigen::Vector3d q = states_[i].position + states_[i].rotation * (p - c0);
      boxes[i].lo = boxes[i].lo.cwiseMin(q);
      boxes[i].hi = boxes[i].hi.cwiseMax(q);
    }
  }
  auto skipped = [&](std::size_t a, std::size_t b) {
    for (const auto& nc : scene_.nocontacts)
      if ((nc.body_a == static_cast<int>(a) && nc.body_b == static_cast<int>(b)) ||
          (nc.body_a == static_cast<int>(b) && nc.body_b == static_cast<int>(a)))
        return true;
    return false;
  };
  auto still = [&](std::size_t i) {
    return !moves_[i] && driven_[i] < 0 && !elastic_[i] && !joints_->moves(static_cast<int>(i));
  };
  auto by_contact = [&](std::size_t a, std::size_t b) {
    for (const auto& [e, r] : elastic_pairs_)
      if ((e == static_cast<int>(a) && r == static_cast<int>(b)) ||
          (e == static_cast<int>(b) && r == static_cast<int>(a)))
        return true;
    for (const auto& [e, r] : elastic_elastic_)
      if ((e == static_cast<int>(a) && r == static_cast<int>(b)) ||
          (e == static_cast<int>(b) && r == static_cast<int>(a)))
        return true;
    return contact_ && contact_roles_[a] != ContactRole::kNone &&
           contact_roles_[b] != ContactRole::kNone;
  };
  auto jointed = [&](std::size_t a, std::size_t b) {
    for (const auto& j : scene_.joints)
      if ((j.body == static_cast<int>(a) && j.other == static_cast<int>(b)) ||
          (j.body == static_cast<int>(b) && j.other == static_cast<int>(a)))
        return true;
    return false;
  };
  // the broad phase: pairs whose boxes overlap strictly (touching is not yet contact)
  for (const auto& [ia, ib] : geometry::AabbTree(boxes).overlapping_pairs()) {
    const auto a = static_cast<std::size_t>(ia), b = static_cast<std::size_t>(ib);
    if ((still(a) && still(b)) || skipped(a, b) || jointed(a, b) || by_contact(a, b)) continue;
    char t[32];
    std::snprintf(t, sizeof t, "%.6g", time_);
    throw SimulationError("bodies '" + scene_.bodies[a].name + "' and '" + scene_.bodies[b].name +
                          "' may touch at t = " + t +
                          " s (their bounding boxes overlap), and no contact stage handles "
                          "this pair in this version; clamp or drive one of them, separate "
                          "them, add 'nocontact " +
                          scene_.bodies[a].name + " " + scene_.bodies[b].name +
                          ";', or shorten the run");
  }
}

Frame Dynamics::frame(int index, const std::string& field) const {
  Frame f;
  f.index = index;
  f.time = time_;
  f.field = field;
  f.field_unit = field == "von_mises" ? "Pa" : field == "displacement" ? "m" : "";
  const bool elastic_field = field == "von_mises" || field == "strain" || field == "yield";
  for (std::size_t i = 0; i < states_.size(); ++i) {
    const Body& body = scene_.bodies[i];
    BodyFrame b;
    b.position = states_[i].position;
    b.rotation = states_[i].rotation;
    if (const ElasticBody* e = elastic_[i].get()) {
      const Eigen::VectorXd& u = *nodal_displacement(static_cast<int>(i));
      const Eigen::MatrixXd u_nodes =
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
              u.data(), body.tet_mesh.nodes.rows(), 3);
      const Eigen::MatrixX3d u_surface = e->surface_map * u_nodes;
      b.deformed = body.drawn().V + u_surface;
      // the deformation alone: in the floating frame's axes rotated to the world, or less
      // the drive's translation that the grips carry
      const Eigen::VectorXd& own = e->solver->displacement();
      Eigen::MatrixX3d own_surface =
          e->surface_map *
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
              own.data(), body.tet_mesh.nodes.rows(), 3);
      if (e->floating) {
        // (in mean axes: less the displacement's rigid part)
        const Eigen::Matrix<double, 6, 1> rigid = e->rigid_part(own);
        const Eigen::Vector3d c = body.mass_properties.centroid;
        for (Eigen::Index v = 0; v < own_surface.rows(); ++v)
          own_surface.row(v) -=
              ElasticBody::rigid_motion(rigid, body.drawn().V.row(v).transpose() - c).transpose();
        b.deformation = own_surface * states_[i].rotation.toRotationMatrix().transpose();
      } else {
        b.deformation = own_surface;
        if (driven_[i] >= 0)
          b.deformation.rowwise() -= frame_offset(static_cast<int>(i), time_, nullptr).transpose();
      }
      if (field == "displacement") b.field = u_surface.rowwise().norm();
      if (field == "von_mises") b.field = e->surface_map * nodal_von_mises(static_cast<int>(i));
      if (field == "strain") b.field = e->surface_map * nodal_strain(static_cast<int>(i));
      if (field == "yield") b.field = e->surface_map * nodal_yield_ratio(static_cast<int>(i));
      if (field == "von_mises" || field == "strain")  // (the yield map's scale is fixed)
        b.concentrated = flagged_points(
            e->surface_map,
            concentration_nodes(body.tet_mesh, e->pressed_points(body),
                                ElasticBody::contact_reach(body), e->at_sharp_corner));
    } else if (field == "displacement") {
      const geometry::TriMesh& drawn = body.drawn();
      b.field.resize(drawn.V.rows());
      for (Eigen::Index v = 0; v < drawn.V.rows(); ++v)
        b.field[v] = displacement(static_cast<int>(i), drawn.V.row(v).transpose()).norm();
    } else if (elastic_field && body.kind == BodyKind::kElastic) {
      b.field = Eigen::VectorXd::Zero(body.drawn().V.rows());  // moving rigidly: unstressed
    }
    f.bodies.push_back(std::move(b));
  }
  return f;
}

Eigen::Vector3d Dynamics::displacement(int body, const Eigen::Vector3d& point) const {
  if (const ElasticBody* e = elastic_[body].get()) {
    const std::array<double, 3> key{point.x(), point.y(), point.z()};
    auto found = e->located.find(key);
    if (found == e->located.end()) found = e->located.emplace(key, e->locator->locate(point)).first;
    const std::optional<MeshPoint>& at = found->second;
    if (!at) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    const Eigen::VectorXd& u = *nodal_displacement(body);
    const geometry::TetMesh& m = scene_.bodies[body].tet_mesh;
    const Eigen::VectorXd nv = shape_values(at->barycentric, m.elements.cols() == 10);
    Eigen::Vector3d out = Eigen::Vector3d::Zero();
    for (Eigen::Index k = 0; k < nv.size(); ++k)
      out += nv[k] * u.segment<3>(3 * m.elements(at->element, k));
    return out;
  }
  const RigidState& s = states_[body];
  const Eigen::Vector3d c0 = scene_.bodies[body].mass_properties.centroid;
  return s.position + s.rotation * (point - c0) - point;
}

const Eigen::VectorXd* Dynamics::nodal_displacement(int body) const {
  const ElasticBody* e = elastic_[body].get();
  if (!e) return nullptr;
  return e->floating ? &e->absolute_u : &e->solver->displacement();
}

std::vector<Eigen::Vector3d> Dynamics::ElasticBody::pressed_points(const Body& body) const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(last_forces.size());
  for (const auto& [node, f] : last_forces)
    out.push_back(
        body.tet_mesh.nodes.row(surface.nodes[static_cast<std::size_t>(node)]).transpose());
  return out;
}

const Eigen::VectorXd& Dynamics::ElasticBody::nodal_field(const Body& body, bool strain) const {
  if (nodal_fields_version != solver->version()) {
    const ElementStressStrain fields =
        nodal_stress_strain(body.tet_mesh, solver->displacement(), body.material.youngs_modulus,
                            body.material.poisson_ratio);
    nodal_stress = fields.von_mises;
    nodal_strain = fields.principal_strain;
    nodal_fields_version = solver->version();
  }
  return strain ? nodal_strain : nodal_stress;
}

Eigen::VectorXd Dynamics::nodal_von_mises(int body) const {
  const ElasticBody* e = elastic_[body].get();
  return e ? e->nodal_field(scene_.bodies[body], false) : Eigen::VectorXd();
}

Eigen::VectorXd Dynamics::nodal_strain(int body) const {
  const ElasticBody* e = elastic_[body].get();
  return e ? e->nodal_field(scene_.bodies[body], true) : Eigen::VectorXd();
}

Eigen::VectorXd Dynamics::nodal_yield_ratio(int body) const {
  const ElasticBody* e = elastic_[body].get();
  if (!e) return {};
  return yield_ratios(scene_.bodies[body].material, e->nodal_field(scene_.bodies[body], false),
                      e->nodal_field(scene_.bodies[body], true));
}

const SparseCholesky::Stats* Dynamics::factor_stats(int body) const {
  const ElasticBody* e = elastic_[body].get();
  return e ? &e->solver->factor_stats() : nullptr;
}

}  // namespace vproto::sim
