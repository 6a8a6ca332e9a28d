// Evaluation of materials, bodies and the scene statements (spec "Materials", "Bodies",
// "Holding, driving and loading", "Simulation and output").
#include <cmath>
#include <set>

#include "evaluator_impl.h"

namespace vproto::modeler::detail {
namespace {

using units::Dimension;

std::string join(const std::vector<std::string>& list) {
  std::string out;
  for (const auto& x : list) out += (out.empty() ? "" : ", ") + x;
  return out;
}

// The named settings of a scene statement, checked against what it accepts.
std::map<std::string, const Arg*> settings(const Stmt& s, const std::vector<std::string>& allowed) {
  std::map<std::string, const Arg*> out;
  for (const Arg& a : s.args) {
    bool ok = false;
    for (const auto& n : allowed) ok = ok || n == a.name;
    if (!ok)
      throw InputError(
          a.loc, "'" + s.name + "' has no setting '" + a.name + "'" +
                     (allowed.empty() ? " (it takes none)" : " (it takes: " + join(allowed) + ")"));
    if (out.count(a.name)) throw InputError(a.loc, "'" + a.name + "' is given twice");
    out[a.name] = &a;
  }
  return out;
}

const Arg* get(const std::map<std::string, const Arg*>& m, const std::string& name) {
  auto it = m.find(name);
  return it == m.end() ? nullptr : it->second;
}

}  // namespace

void Evaluator::material_statement(const Stmt& s, const Scope& scope) {
  materials::Material m;
  m.name = s.name;
  m.source = "script " + s.loc.file + ":" + std::to_string(s.loc.line);
  std::set<std::string> seen;
  for (const Arg& a : s.args) {
    if (!seen.insert(a.name).second) throw InputError(a.loc, "'" + a.name + "' is given twice");
    const Value v = eval(*a.value, scope);
    const std::string what = "material " + s.name + ": " + a.name;
    if (a.name == "E") {
      m.youngs_modulus = quantity(v, Dimension::of_pressure(), a.loc, what);
    } else if (a.name == "nu") {
      m.poisson_ratio = quantity(v, {}, a.loc, what);
    } else if (a.name == "density") {
      m.density = quantity(v, Dimension::of_density(), a.loc, what);
    } else if (a.name == "yield_strength") {
      m.yield_strength = quantity(v, Dimension::of_pressure(), a.loc, what);
    } else if (a.name == "yield_strain") {
      m.yield_strain = quantity(v, {}, a.loc, what);
    } else if (a.name == "friction") {
      m.friction = quantity(v, {}, a.loc, what);
    } else if (a.name == "restitution") {
      m.restitution = quantity(v, {}, a.loc, what);
    } else {
      throw InputError(a.loc, "unknown material property '" + a.name +
                                  "' (properties: E, nu, density, yield_strength, yield_strain, "
                                  "friction, restitution)");
    }
  }
  for (const char* required : {"E", "nu", "density"})
    if (!seen.count(required))
      throw InputError(s.loc,
                       "material " + s.name + " needs " + required + " (required: E, nu, density)");
  const std::string problem = materials::validation_error(m);
  if (!problem.empty()) throw InputError(s.loc, "material " + s.name + ": " + problem);
  materials_[s.name] = m;
}

void Evaluator::body_statement(const Stmt& s, const Scope& scope) {
  if (out_.scene.find_body(s.name) >= 0)
    throw InputError(s.loc,
                     "a body named '" + s.name + "' is already defined at line " +
                         std::to_string(out_.scene.bodies[out_.scene.find_body(s.name)].loc.line));
  sim::Body body;
  body.name = s.name;
  body.kind = s.subkind == "elastic" ? sim::BodyKind::kElastic : sim::BodyKind::kRigid;
  body.loc = s.loc;
  bool has_material = false;
  body_segments_ = 0;
  std::set<std::string> seen;
  for (const Arg& a : s.args) {
    if (!seen.insert(a.name).second) throw InputError(a.loc, "'" + a.name + "' is given twice");
    if (a.name == "material") {
      const std::string name = a.value->kind == Expr::Kind::kIdent
                                   ? a.value->text
                                   : symbol(*a.value, scope, {}, "material");
      auto it = materials_.find(name);
      if (it == materials_.end()) {
        std::vector<std::string> known;
        for (const auto& m : materials_) known.push_back(m.first);
        throw InputError(a.value->loc, "unknown material '" + name + "' (known: " + join(known) +
                                           "; or define it with 'material " + name + " { ... }')");
      }
      body.material = it->second;
      has_material = true;
    } else if (a.name == "mesh_size") {
      body.mesh_size = positive(eval(*a.value, scope), Dimension::of_length(), a.loc, "mesh_size");
    } else if (a.name == "element") {
      body.element = symbol(*a.value, scope, {"tet4", "tet10"}, "element") == "tet4"
                         ? sim::ElementType::kTet4
                         : sim::ElementType::kTet10;
    } else if (a.name == "segments") {
      body_segments_ = count(eval(*a.value, scope), a.loc, "segments", 3, limits_.max_segments);
    } else {
      throw InputError(a.loc, "a body has no attribute '" + a.name +
                                  "' (attributes: material, mesh_size, element, segments)");
    }
    if (body.kind == sim::BodyKind::kRigid && (a.name == "mesh_size" || a.name == "element"))
      out_.warnings.push_back(a.loc.file + ":" + std::to_string(a.loc.line) + ":" +
                              std::to_string(a.loc.column) + ": warning: " + a.name +
                              " is ignored: body '" + s.name +
                              "' is rigid and gets no volume mesh");
  }
  if (!has_material)
    throw InputError(s.loc, "body '" + s.name +
                                "' needs a material: write (material=steel) or "
                                "another built-in or defined material");
  body_triangles_ = 0;
  std::vector<Feature> made = solids(s.children, scope, Eigen::Affine3d::Identity(), 0);
  body_segments_ = 0;
  if (made.empty())
    throw InputError(s.loc, "body '" + s.name +
                                "' has no solids: add a box(), cylinder(), ... "
                                "inside its { }");
  Feature root;
  root.kind = Feature::Kind::kUnion;
  root.loc = s.loc;
  root.children = std::move(made);
  out_.scene.bodies.push_back(std::move(body));
  out_.body_trees.push_back(std::move(root));
}

void Evaluator::body_ref(const std::string& name, const SourceLoc& loc,
                         std::function<void(int)> set, const std::string& need_elastic) {
  pending_.push_back({name, loc, std::move(set), need_elastic});
}

void Evaluator::resolve_body_references() {
  for (const auto& p : pending_) {
    const int index = out_.scene.find_body(p.name);
    if (index < 0) {
      std::vector<std::string> names;
      for (const auto& b : out_.scene.bodies) names.push_back(b.name);
      throw InputError(p.loc, "unknown body '" + p.name + "'" +
                                  (names.empty() ? " (the script defines no bodies)"
                                                 : " (bodies: " + join(names) + ")"));
    }
    if (!p.need_elastic.empty() && out_.scene.bodies[index].kind != sim::BodyKind::kElastic)
      throw InputError(p.loc, p.need_elastic + " applies to elastic bodies only; '" + p.name +
                                  "' is rigid (declare it 'elastic body')");
    p.set(index);
  }
}

void Evaluator::scene_statement(const Stmt& s, const Scope& scope) {
  sim::Scene& sc = out_.scene;
  const Dimension length = Dimension::of_length();
  auto value = [&](const Arg* a) { return eval(*a->value, scope); };
  auto body_at = [&](std::size_t i) -> const std::string& { return s.idents.at(i); };
  auto loc_at = [&](std::size_t i) -> const SourceLoc& { return s.ident_locs.at(i); };
  auto need_value = [&](const std::string& what) -> Value {
    if (!s.value) throw InputError(s.loc, "'" + s.name + "' needs " + what);
    return eval(*s.value, scope);
  };
  auto time_of = [&](const Arg* a, const std::string& what) {
    return quantity(value(a), Dimension::of_time(), a->loc, what);
  };
  auto unitless_direction = [&](const Arg* a, const std::string& what) {
    const Value v = value(a);
    if (!v.is_vector() || v.items->size() != 3)
      throw InputError(a->loc, what + " must be a vector [x, y, z]");
    Eigen::Vector3d d;
    for (int i = 0; i < 3; ++i) {
      if (!(*v.items)[i].is_number()) throw InputError(a->loc, what + " must hold numbers");
      d[i] = (*v.items)[i].number;
    }
    if (!(d.norm() > 0) || !d.allFinite()) throw InputError(a->loc, what + " must not be zero");
    return Eigen::Vector3d(d.normalized());
  };
  const std::string& kw = s.name;

  if (kw == "fix") {
    const auto m = settings(s, {"region"});
    sim::Fix f;
    f.loc = s.loc;
    if (const Arg* r = get(m, "region")) f.region = region(*r->value, scope, "fix region");
    const std::size_t i = sc.fixes.size();
    sc.fixes.push_back(f);
    body_ref(
        body_at(0), loc_at(0), [&sc, i](int b) { sc.fixes[i].body = b; },
        f.region ? "fix region=" : "");
  } else if (kw == "grip") {
    const auto m = settings(s, {"region"});
    const Arg* r = get(m, "region");
    if (!r)
      throw InputError(s.loc, "grip needs region=box([..], [..]): the nodes the gripper holds");
    sim::Grip g;
    g.loc = s.loc;
    g.region = region(*r->value, scope, "grip region");
    const std::size_t i = sc.grips.size();
    sc.grips.push_back(g);
    body_ref(
        body_at(0), loc_at(0), [&sc, i](int b) { sc.grips[i].body = b; }, "grip");
  } else if (kw == "joint") {
    const std::string& type = s.idents[0];
    sim::Joint j;
    j.loc = s.loc;
    if (type == "slider")
      j.type = sim::JointType::kSlider;
    else if (type == "revolute")
      j.type = sim::JointType::kRevolute;
    else if (type == "spherical")
      j.type = sim::JointType::kSpherical;
    else if (type == "fixed")
      j.type = sim::JointType::kFixed;
    else
      throw InputError(loc_at(0), "unknown joint type '" + type +
                                      "' (types: slider, revolute, spherical, fixed)");
    std::vector<std::string> allowed;
    if (j.type == sim::JointType::kSlider) allowed = {"axis"};
    if (j.type == sim::JointType::kRevolute) allowed = {"at", "axis"};
    if (j.type == sim::JointType::kSpherical) allowed = {"at"};
    const auto m = settings(s, allowed);
    for (const auto& need : allowed)
      if (!get(m, need)) throw InputError(s.loc, "joint " + type + " needs " + need + "=[x, y, z]");
    if (const Arg* a = get(m, "axis")) j.axis = unitless_direction(a, "joint axis");
    if (const Arg* a = get(m, "at")) j.at = vec3(value(a), length, a->loc, "joint at");
    const bool to_other = s.idents.size() == 4;
    if (j.type == sim::JointType::kFixed && !to_other)
      throw InputError(s.loc,
                       "joint fixed needs 'to OTHER' (to hold a body to the ground, write "
                       "'fix BODY;')");
    if (to_other && s.idents[1] == s.idents[3])
      throw InputError(loc_at(3), "a joint connects two different bodies");
    const std::size_t i = sc.joints.size();
    sc.joints.push_back(j);
    body_ref(body_at(1), loc_at(1), [&sc, i](int b) { sc.joints[i].body = b; });
    if (to_other) body_ref(body_at(3), loc_at(3), [&sc, i](int b) { sc.joints[i].other = b; });
  } else if (kw == "force") {
    const auto m = settings(s, {"at", "region", "ramp"});
    sim::Force f;
    f.loc = s.loc;
    // the value first: it throws when there is none, before s.value is read for its place
    const Value force = need_value("a force vector [fx, fy, fz]");
    f.force = vec3(force, Dimension::of_force(), s.value->loc, "force");
    if (get(m, "at") && get(m, "region"))
      throw InputError(get(m, "region")->loc, "force takes at= or region=, not both");
    if (const Arg* a = get(m, "at")) f.at = vec3(value(a), length, a->loc, "force at");
    if (const Arg* a = get(m, "region")) f.region = region(*a->value, scope, "force region");
    if (const Arg* a = get(m, "ramp")) {
      f.ramp = time_of(a, "ramp");
      if (f.ramp < 0) throw InputError(a->loc, "ramp must not be negative");
    }
    const std::size_t i = sc.forces.size();
    sc.forces.push_back(f);
    body_ref(
        body_at(0), loc_at(0), [&sc, i](int b) { sc.forces[i].body = b; },
        f.region ? "force region=" : "");
  } else if (kw == "torque") {
    const auto m = settings(s, {"ramp"});
    sim::Torque t;
    t.loc = s.loc;
    const Value v = need_value("a torque vector [mx, my, mz]");
    const Dimension torque_dim = Dimension::of_force() * Dimension::of_length();
    if (!v.is_vector() || v.items->size() != 3)
      throw InputError(s.value->loc, "torque must be a vector [mx, my, mz], got " + describe(v));
    for (int k = 0; k < 3; ++k) {
      const Value& c = (*v.items)[k];
      if (!c.is_number()) throw InputError(s.value->loc, "torque must hold numbers");
      if (c.dim.dimensionless())
        t.torque[k] = c.number * units_.force.scale * units_.length.scale;
      else if (c.dim == torque_dim)
        t.torque[k] = c.number;
      else
        throw InputError(s.value->loc,
                         "torque must be a force times a length (e.g. 2N*m), got " + describe(c));
    }
    if (const Arg* a = get(m, "ramp")) {
      t.ramp = time_of(a, "ramp");
      if (t.ramp < 0) throw InputError(a->loc, "ramp must not be negative");
    }
    const std::size_t i = sc.torques.size();
    sc.torques.push_back(t);
    body_ref(body_at(0), loc_at(0), [&sc, i](int b) { sc.torques[i].body = b; });
  } else if (kw == "move") {
    const auto m = settings(s, {"by", "over"});
    if (!get(m, "by") || !get(m, "over"))
      throw InputError(s.loc, "move needs by=[dx, dy, dz] and over=TIME");
    sim::Move mv;
    mv.loc = s.loc;
    mv.by = vec3(value(get(m, "by")), length, get(m, "by")->loc, "move by");
    mv.over =
        positive(value(get(m, "over")), Dimension::of_time(), get(m, "over")->loc, "move over");
    const std::size_t i = sc.moves.size();
    sc.moves.push_back(mv);
    body_ref(body_at(0), loc_at(0), [&sc, i](int b) { sc.moves[i].body = b; });
  } else if (kw == "gravity") {
    settings(s, {});
    if (sc.gravity) throw InputError(s.loc, "gravity is given twice");
    const Value gravity = need_value("an acceleration vector [gx, gy, gz]");
    sc.gravity = vec3(gravity, Dimension::of_acceleration(), s.value->loc, "gravity");
  } else if (kw == "velocity") {
    const auto m = settings(s, {"linear", "angular"});
    if (m.empty()) throw InputError(s.loc, "velocity needs linear=[..] and/or angular=[..]");
    sim::InitialVelocity v;
    v.loc = s.loc;
    if (const Arg* a = get(m, "linear"))
      v.linear = vec3(value(a), Dimension::of_velocity(), a->loc, "linear velocity");
    if (const Arg* a = get(m, "angular")) {
      const Value w = value(a);
      if (!w.is_vector() || w.items->size() != 3)
        throw InputError(a->loc, "angular velocity must be a vector [wx, wy, wz]");
      for (int k = 0; k < 3; ++k) {
        const Value& c = (*w.items)[k];
        // 1/s is read as rad/s
        if (c.is_number() && c.dim == Dimension{0, 0, -1, 0})
          v.angular[k] = c.number;
        else
          v.angular[k] = quantity(c, Dimension::of_angular_velocity(), a->loc, "angular velocity");
      }
    }
    const std::size_t i = sc.velocities.size();
    sc.velocities.push_back(v);
    body_ref(body_at(0), loc_at(0), [&sc, i](int b) { sc.velocities[i].body = b; });
  } else if (kw == "contact") {
    const auto m = settings(s, {"friction", "restitution"});
    if (m.empty()) throw InputError(s.loc, "contact needs friction=MU and/or restitution=E");
    sim::ContactSetting c;
    c.loc = s.loc;
    if (const Arg* a = get(m, "friction")) {
      c.friction = quantity(value(a), {}, a->loc, "friction");
      if (!(*c.friction >= 0)) throw InputError(a->loc, "friction must be zero or positive");
    }
    if (const Arg* a = get(m, "restitution")) {
      c.restitution = quantity(value(a), {}, a->loc, "restitution");
      if (!(*c.restitution >= 0 && *c.restitution <= 1))
        throw InputError(a->loc, "restitution must lie between 0 and 1");
    }
    const std::size_t i = sc.contacts.size();
    sc.contacts.push_back(c);
    if (s.idents.size() == 2) {
      if (s.idents[0] == s.idents[1])
        throw InputError(loc_at(1), "contact names a pair of two bodies");
      body_ref(body_at(0), loc_at(0), [&sc, i](int b) { sc.contacts[i].body_a = b; });
      body_ref(body_at(1), loc_at(1), [&sc, i](int b) { sc.contacts[i].body_b = b; });
    }
  } else if (kw == "nocontact") {
    settings(s, {});
    if (s.idents[0] == s.idents[1])
      throw InputError(loc_at(1), "nocontact names a pair of two bodies");
    sim::NoContact n;
    n.loc = s.loc;
    const std::size_t i = sc.nocontacts.size();
    sc.nocontacts.push_back(n);
    body_ref(body_at(0), loc_at(0), [&sc, i](int b) { sc.nocontacts[i].body_a = b; });
    body_ref(body_at(1), loc_at(1), [&sc, i](int b) { sc.nocontacts[i].body_b = b; });
  } else if (kw == "probe") {
    const auto m = settings(s, {"point"});
    if (!get(m, "point")) throw InputError(s.loc, "probe needs point=[x, y, z]");
    for (const auto& p : sc.probes)
      if (p.name == s.idents[0])
        throw InputError(loc_at(0), "a probe named '" + p.name + "' is already defined at line " +
                                        std::to_string(p.loc.line));
    sim::Probe p;
    p.loc = s.loc;
    p.name = s.idents[0];
    p.point = vec3(value(get(m, "point")), length, get(m, "point")->loc, "probe point");
    const std::size_t i = sc.probes.size();
    sc.probes.push_back(p);
    body_ref(body_at(1), loc_at(1), [&sc, i](int b) { sc.probes[i].body = b; });
  } else if (kw == "simulate") {
    if (sc.simulation.given) throw InputError(s.loc, "simulate(...) is given twice");
    const auto m = settings(s, {"mode", "duration", "dt", "frames", "tolerance", "mass_damping",
                                "stiffness_damping", "numerical_damping", "solver"});
    sim::SimulationSettings& st = sc.simulation;
    st.given = true;
    st.loc = s.loc;
    if (const Arg* a = get(m, "mode")) {
      const std::string mode =
          symbol(*a->value, scope, {"static", "quasistatic", "dynamic"}, "mode");
      st.mode = mode == "static"        ? sim::SimulationMode::kStatic
                : mode == "quasistatic" ? sim::SimulationMode::kQuasistatic
                                        : sim::SimulationMode::kDynamic;
    }
    if (const Arg* a = get(m, "solver")) {
      st.solver =
          sim::solver_choice_from(symbol(*a->value, scope, {"auto", "cholmod", "petsc"}, "solver"));
      if (st.solver == sim::SolverChoice::kPetsc && !sim::petsc_available())
        throw InputError(a->loc, sim::no_petsc_message("solver=petsc"));
    }
    if (const Arg* a = get(m, "duration"))
      st.duration = positive(value(a), Dimension::of_time(), a->loc, "duration");
    if (const Arg* a = get(m, "dt")) {
      st.time_step = positive(value(a), Dimension::of_time(), a->loc, "dt");
      if (*st.time_step > st.duration) throw InputError(a->loc, "dt is longer than the duration");
    }
    if (const Arg* a = get(m, "frames")) st.frames = count(value(a), a->loc, "frames", 1, 100000);
    if (const Arg* a = get(m, "tolerance")) {
      st.tolerance = quantity(value(a), {}, a->loc, "tolerance");
      if (!(st.tolerance > 0 && st.tolerance < 1))
        throw InputError(a->loc, "tolerance must lie between 0 and 1 (a relative error)");
    }
    // Rayleigh damping C = alpha M + beta K of elastic bodies, and Newmark's numerical
    // damping of high frequencies (gamma = 1/2 + a)
    if (const Arg* a = get(m, "mass_damping")) {
      st.mass_damping = quantity(value(a), Dimension{0, 0, -1, 0}, a->loc, "mass_damping");
      if (!(st.mass_damping >= 0))
        throw InputError(a->loc, "mass_damping must not be negative (it is alpha in 1/s)");
    }
    if (const Arg* a = get(m, "stiffness_damping")) {
      st.stiffness_damping = quantity(value(a), Dimension::of_time(), a->loc, "stiffness_damping");
      if (!(st.stiffness_damping >= 0))
        throw InputError(a->loc, "stiffness_damping must not be negative (it is beta in s)");
    }
    if (const Arg* a = get(m, "numerical_damping")) {
      const double damping = quantity(value(a), {}, a->loc, "numerical_damping");
      st.numerical_damping = damping;
      if (!(damping >= 0 && damping <= 0.5))
        throw InputError(a->loc,
                         "numerical_damping must lie between 0 (none: energy is conserved) and "
                         "0.5");
    }
  } else if (kw == "render") {
    const auto m = settings(s, {"size", "field", "camera", "deform_scale"});
    sim::RenderSettings& r = sc.render;
    if (const Arg* a = get(m, "size")) {
      const Value v = value(a);
      if (!v.is_vector() || v.items->size() != 2)
        throw InputError(a->loc, "render size must be [width, height] in pixels");
      r.width = count((*v.items)[0], a->loc, "render width", 16, 8192);
      r.height = count((*v.items)[1], a->loc, "render height", 16, 8192);
    }
    if (const Arg* a = get(m, "field"))
      r.field = symbol(*a->value, scope, {"none", "displacement", "von_mises", "strain", "yield"},
                       "field");
    if (const Arg* a = get(m, "deform_scale")) {
      r.deform_scale = quantity(value(a), {}, a->loc, "deform_scale");
      if (!(r.deform_scale >= 0 && r.deform_scale <= 1e6))
        throw InputError(a->loc,
                         "deform_scale must be a number from 0 (undeformed) to 1e6 (the "
                         "deformation drawn that many times larger); 1 is true scale");
    }
    if (const Arg* a = get(m, "camera")) {
      if (a->value->kind == Expr::Kind::kIdent && !scope.find(a->value->text)) {
        r.camera = symbol(*a->value, scope, {"iso", "front", "side", "top"}, "camera");
      } else {
        const Value v = value(a);
        if (!v.is_vector() || v.items->size() != 2)
          throw InputError(a->loc, "camera must be iso, front, side, top or [[eye], [target]]");
        r.camera = "custom";
        r.eye = vec3((*v.items)[0], length, a->loc, "camera eye");
        r.target = vec3((*v.items)[1], length, a->loc, "camera target");
        if ((r.eye - r.target).norm() == 0)
          throw InputError(a->loc, "camera eye and target must differ");
      }
    }
  } else if (kw == "export") {
    const auto m = settings(s, {"format", "every"});
    if (const Arg* a = get(m, "format"))
      sc.output.format = symbol(*a->value, scope, {"stl", "obj", "vtu", "none"}, "format");
    if (const Arg* a = get(m, "every"))
      sc.output.every = count(value(a), a->loc, "every", 1, 1000000);
  } else {
    throw InternalError("unknown scene statement " + kw);
  }
}

}  // namespace vproto::modeler::detail
