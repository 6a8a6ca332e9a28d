#include "vproto/sim/contact.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "vproto/geometry/aabb_tree.h"
#include "vproto/geometry/convex_parts.h"
#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

Eigen::Quaterniond rotation_by(const Eigen::Vector3d& angle) {
  const double a = angle.norm();
  if (a < 1e-300) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, angle / a));
}

std::pair<int, int> ordered(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

const ContactSetting* pair_setting(const Scene& s, int a, int b, bool want_friction) {
  const ContactSetting* global = nullptr;
  for (const auto& c : s.contacts) {
    const bool has = want_friction ? c.friction.has_value() : c.restitution.has_value();
    if (!has) continue;
    if ((c.body_a == a && c.body_b == b) || (c.body_a == b && c.body_b == a)) return &c;
    if (c.body_a == kGround && c.body_b == kGround) global = &c;
  }
  return global;
}

std::string seconds(double t) {
  char s[32];
  std::snprintf(s, sizeof s, "%.6g", t);
  return s;
}

}  // namespace

double pair_friction(const Scene& s, int a, int b) {
  if (const ContactSetting* c = pair_setting(s, a, b, true)) return *c->friction;
  return std::sqrt(s.bodies[a].material.friction.value_or(0) *
                   s.bodies[b].material.friction.value_or(0));
}

double pair_restitution(const Scene& s, int a, int b) {
  if (const ContactSetting* c = pair_setting(s, a, b, false)) return *c->restitution;
  return std::sqrt(s.bodies[a].material.restitution.value_or(0) *
                   s.bodies[b].material.restitution.value_or(0));
}

std::vector<char> contact_bodies(const Scene& s) {
  const std::size_t n = s.bodies.size();
  std::vector<char> capable(n, 0), fixed(n, 0), out(n, 0);
  for (std::size_t i = 0; i < n; ++i) capable[i] = s.bodies[i].kind == BodyKind::kRigid;
  for (const auto& j : s.joints) {
    capable[j.body] = 0;
    if (j.other != kGround) capable[j.other] = 0;
  }
  for (const auto& f : s.fixes) fixed[f.body] = fixed[f.body] || !f.region;
  std::set<std::pair<int, int>> skip;
  for (const auto& nc : s.nocontacts) skip.insert(ordered(nc.body_a, nc.body_b));
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      if (!capable[a] || !capable[b] || (fixed[a] && fixed[b])) continue;
      if (skip.count({static_cast<int>(a), static_cast<int>(b)})) continue;
      out[a] = out[b] = 1;
    }
  return out;
}

// One contact point: a point of A that stays outside a plane of B (Eq. 16), places and
// normal in the body frames, and the world quantities of the current solve.
struct ContactSystem::Point {
  int a = 0, b = 0;            ///< bodies
  int part_a = 0, part_b = 0;  ///< parts
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();  ///< body frames
  /// The normal (A towards B) in the frame of the body whose surface it belongs to: A's
  /// for a vertex of B on a face of A (and edge on edge, face on face), else B's.
  Eigen::Vector3d n_local = Eigen::Vector3d::UnitZ();
  bool normal_on_a = true;
  double gap = 0;              ///< m, at detection
  double mu = 0, e = 0;
  Eigen::Vector3d ra = Eigen::Vector3d::Zero(), rb = Eigen::Vector3d::Zero();  ///< world levers
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();  ///< columns n, t1, t2 (world)
  double w_nn = 0;         ///< Delassus block: normal diagonal and the tangent block's inverse
  Eigen::Matrix2d w_tt_inv = Eigen::Matrix2d::Zero();
  double w_t = 0;  ///< the tangent block's largest eigenvalue
  Eigen::Vector3d lambda = Eigen::Vector3d::Zero();  ///< impulse in the basis
  double target = 0;                                 ///< v_n+ >= target
  bool closed = false;
};

// Velocities and inverse masses of the bodies during one solve.
struct ContactSystem::Solver {
  std::vector<Eigen::Vector3d> v, w;
  std::vector<double> inv_mass;
  std::vector<Eigen::Matrix3d> inv_inertia;  ///< world axes

  Eigen::Vector3d point_velocity(int body, const Eigen::Vector3d& r) const {
    return v[body] + w[body].cross(r);
  }
  Eigen::Vector3d relative_velocity(const Point& p) const {
    return point_velocity(p.b, p.rb) - point_velocity(p.a, p.ra);
  }
  void apply(const Point& p, const Eigen::Vector3d& impulse) {
    v[p.b] += inv_mass[p.b] * impulse;
    w[p.b] += inv_inertia[p.b] * p.rb.cross(impulse);
    v[p.a] -= inv_mass[p.a] * impulse;
    w[p.a] -= inv_inertia[p.a] * p.ra.cross(impulse);
  }
  // K = sum over the two bodies of m^-1 I - [r]x I^-1 [r]x, in the contact basis
  void prepare(Point& p) const {
    auto k_of = [&](int body, const Eigen::Vector3d& r) {
      Eigen::Matrix3d rx;
      rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
      return (inv_mass[body] * Eigen::Matrix3d::Identity() - rx * inv_inertia[body] * rx).eval();
    };
    const Eigen::Matrix3d k = p.basis.transpose() * (k_of(p.a, p.ra) + k_of(p.b, p.rb)) * p.basis;
    p.w_nn = k(0, 0);
    const Eigen::Matrix2d k_tt = k.block<2, 2>(1, 1);
    p.w_tt_inv = k_tt.inverse();
    // the block's largest eigenvalue
    const double mean = 0.5 * k_tt.trace(), dev = 0.5 * (k_tt(0, 0) - k_tt(1, 1));
    p.w_t = mean + std::sqrt(dev * dev + k_tt(0, 1) * k_tt(1, 0));
  }
  // Projected Gauss-Seidel on the point blocks: the normal impulse stays compressive
  // (lambda_n >= 0, complementary to v_n+ - target), the tangential one in Coulomb's
  // disc. Returns the sweeps taken; `residual` gets the last sweep's largest change of a
  // contact velocity.
  int solve(std::vector<Point*>& points, int max_sweeps, double tolerance, double* residual) {
    for (Point* p : points) {
      prepare(*p);
      if (p->lambda.squaredNorm() > 0) apply(*p, p->basis * p->lambda);
    }
    int sweep = 0;
    *residual = 0;
    while (sweep < max_sweeps) {
      ++sweep;
      double change = 0;
      for (Point* pp : points) {
        Point& p = *pp;
        const Eigen::Vector3d n = p.basis.col(0);
        const double vn = n.dot(relative_velocity(p));
        const double ln = std::max(0.0, p.lambda[0] + (p.target - vn) / p.w_nn);
        double dn = ln - p.lambda[0];
        if (dn != 0) {
          apply(p, dn * n);
          p.lambda[0] = ln;
        }
        change = std::max(change, std::abs(dn) * p.w_nn);
        if (p.mu <= 0) continue;
        const Eigen::Vector3d vr = relative_velocity(p);
        const Eigen::Vector2d vt(p.basis.col(1).dot(vr), p.basis.col(2).dot(vr));
        // sticking: the exact solve of the tangent block; sliding: a step along -v_t
        // projected on the disc, whose fixed point has the friction opposite the slip
        // (projecting the exact solve would bias it by the block's anisotropy)
        Eigen::Vector2d lt = p.lambda.tail<2>() - p.w_tt_inv * vt;
        const double limit = p.mu * ln;
        if (lt.norm() > limit) {
          lt = p.lambda.tail<2>() - vt / p.w_t;
          if (lt.norm() > limit) lt *= limit / lt.norm();
        }
        const Eigen::Vector2d dt = lt - p.lambda.tail<2>();
        if (dt.squaredNorm() > 0) {
          apply(p, p.basis.rightCols<2>() * dt);
          p.lambda.tail<2>() = lt;
        }
        change = std::max(change, dt.norm() * p.w_t);
      }
      *residual = change;
      if (change <= tolerance) break;
    }
    return sweep;
  }
};

ContactSystem::ContactSystem(const Scene& scene, std::vector<ContactRole> roles,
                             ContactOptions options)
    : scene_(scene), roles_(std::move(roles)), options_(options) {
  const std::size_t n = scene.bodies.size();
  VPROTO_DEMAND(roles_.size() == n);
  for (const auto& nc : scene.nocontacts) skip_.insert(ordered(nc.body_a, nc.body_b));
  // bodies that may touch another: a free one, or a static or kinematic one a free or
  // kinematic body may reach
  std::vector<char> wanted(n, 0);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      const ContactRole ra = roles_[a], rb = roles_[b];
      if (ra == ContactRole::kNone || rb == ContactRole::kNone) continue;
      if (ra == ContactRole::kStatic && rb == ContactRole::kStatic) continue;
      if (skip_.count({static_cast<int>(a), static_cast<int>(b)})) continue;
      wanted[a] = wanted[b] = 1;
    }
  radius_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!wanted[i]) continue;
    const Body& body = scene.bodies[i];
    std::vector<geometry::TriMesh> meshes;
    if (body.convex_parts_computed) {
      meshes = body.convex_parts;
    } else if (geometry::is_convex(body.surface)) {
      meshes = {body.surface};
    } else {
      meshes = geometry::convex_parts(body.surface);
    }
    const Eigen::Vector3d c = body.mass_properties.centroid;
    for (geometry::TriMesh& m : meshes) {
      m.V.rowwise() -= c.transpose();
      Part part;
      part.body = static_cast<int>(i);
      part.local = geometry::make_polytope(m);
      for (const auto& v : part.local.vertices) radius_[i] = std::max(radius_[i], v.norm());
      parts_.push_back(std::move(part));
    }
  }
}

void ContactSystem::touch_error(int a, int b, double t) const {
  throw SimulationError("bodies '" + scene_.bodies[a].name + "' and '" + scene_.bodies[b].name +
                        "' touch at t = " + seconds(t) + " s, and this contact cannot be resolved");
}

std::vector<ContactSystem::Point> ContactSystem::detect(const std::vector<RigidState>& states,
                                                        const std::vector<double>& reach,
                                                        const std::vector<char>& in_step) const {
  std::vector<geometry::ConvexPolytope> world(parts_.size());
  std::vector<geometry::Bounds> boxes(parts_.size());
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    const int body = parts_[k].body;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = states[body].rotation.toRotationMatrix();
    pose.translation() = states[body].position;
    world[k] = geometry::transformed(parts_[k].local, pose);
    geometry::Bounds& box = boxes[k];
    for (const auto& v : world[k].vertices) {
      box.lo = box.lo.cwiseMin(v);
      box.hi = box.hi.cwiseMax(v);
    }
    box.lo.array() -= reach[body];
    box.hi.array() += reach[body];
  }
  std::vector<Point> points;
  for (auto [i, j] : geometry::AabbTree(boxes).overlapping_pairs()) {
    int a = parts_[i].body, b = parts_[j].body;
    if (a == b) continue;
    if (!in_step[a] && !in_step[b]) continue;  // neither is advanced here
    if (roles_[a] != ContactRole::kFree && roles_[b] != ContactRole::kFree) continue;
    if (skip_.count(ordered(a, b))) continue;
    if (a > b) {
      std::swap(a, b);
      std::swap(i, j);
    }
    const geometry::ConvexDistance d = geometry::gjk_distance(world[i], world[j]);
    ++stats_.queries;
    if (!d.overlap && d.distance > reach[a] + reach[b]) continue;
    const geometry::ContactManifold m = geometry::contact_manifold(world[i], world[j], d);
    const Eigen::Matrix3d rot_a = states[a].rotation.toRotationMatrix(),
                          rot_b = states[b].rotation.toRotationMatrix();
    const double mu = pair_friction(scene_, a, b), e = pair_restitution(scene_, a, b);
    for (const auto& c : m.points) {
      Point p;
      p.a = a;
      p.b = b;
      p.part_a = i;
      p.part_b = j;
      p.pa = rot_a.transpose() * (c.on_a - states[a].position);
      p.pb = rot_b.transpose() * (c.on_b - states[b].position);
      p.normal_on_a = m.feature != geometry::ContactFeature::kFaceVertex;
      p.n_local = (p.normal_on_a ? rot_a : rot_b).transpose() * m.normal;
      p.gap = c.gap;
      p.mu = mu;
      p.e = e;
      points.push_back(p);
    }
  }
  return points;
}

void ContactSystem::check_start(const std::vector<RigidState>& states) const {
  const std::vector<double> reach(states.size(), 0.0);
  const std::vector<char> all(states.size(), 1);
  for (const Point& p : detect(states, reach, all)) {
    const double allowed = 1e-6;  // m: faces placed on one another meet to rounding
    if (p.gap < -allowed) {
      char depth[32];
      std::snprintf(depth, sizeof depth, "%.3g", -p.gap);
      throw InputError(scene_.bodies[p.b].loc,
                       "bodies '" + scene_.bodies[p.a].name + "' and '" + scene_.bodies[p.b].name +
                           "' overlap by " + depth +
                           " m at the start; move them apart (they may touch), or add "
                           "'nocontact " +
                           scene_.bodies[p.a].name + " " + scene_.bodies[p.b].name + ";'");
    }
  }
}

void ContactSystem::step(std::vector<RigidState>& states, const std::vector<RigidInertia>& inertias,
                         const std::vector<Eigen::Vector3d>& forces,
                         const std::vector<Eigen::Vector3d>& torques, double t, double dt,
                         std::vector<char>* advanced) {
  const std::size_t n = states.size();
  advanced->assign(n, 0);
  active_points_ = 0;
  contact_force_ = 0;
  if (parts_.empty()) return;
  // how far each body can travel within `h`, plus a small margin that keeps resting
  // contacts in view
  auto reach_over = [&](double h) {
    std::vector<double> r(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const RigidState& s = states[i];
      const double margin = 1e-3 * radius_[i];
      if (roles_[i] == ContactRole::kFree)
        r[i] = (s.velocity.norm() + s.angular_velocity.norm() * radius_[i]) * h +
               0.5 * forces[i].norm() / inertias[i].mass * h * h + margin;
      else if (roles_[i] == ContactRole::kKinematic)
        r[i] = s.velocity.norm() * h + margin;
      else
        r[i] = margin;
    }
    return r;
  };
  std::vector<char> all(n, 0);
  for (std::size_t i = 0; i < n; ++i) all[i] = roles_[i] != ContactRole::kNone;
  std::vector<Point> points = detect(states, reach_over(dt), all);
  if (points.empty()) {
    warm_.clear();
    if (!touching_.empty()) {
      for (const auto& [pair, on] : touching_)
        events_.push_back({t, false, pair.first, pair.second});
      touching_.clear();
    }
    return;
  }
  // the island this system advances: the free bodies of the points
  std::vector<char>& island = *advanced;
  for (const Point& p : points)
    for (int b : {p.a, p.b})
      if (roles_[b] == ContactRole::kFree) island[b] = 1;
  for (const Point& p : points)
    for (int b : {p.a, p.b})
      if (roles_[b] == ContactRole::kNone) touch_error(p.a, p.b, t);

  Solver solver;
  solver.v.resize(n);
  solver.w.resize(n);
  solver.inv_mass.assign(n, 0.0);
  solver.inv_inertia.assign(n, Eigen::Matrix3d::Zero());
  std::map<std::pair<int, int>, Eigen::Vector3d> pair_impulse;  // over the step, on b
  auto add_impulse = [&](const Point& p) {
    auto [it, fresh] = pair_impulse.try_emplace({p.a, p.b}, Eigen::Vector3d::Zero());
    it->second += p.basis * p.lambda;
  };

  double remaining = dt, now = t;
  for (int substep = 0; remaining > 0; ++substep) {
    if (substep > 0) points = detect(states, reach_over(remaining), island);
    // drop points of free bodies outside the island (found late; the next step has them)
    points.erase(std::remove_if(points.begin(), points.end(),
                                [&](const Point& p) {
                                  return (roles_[p.a] == ContactRole::kFree && !island[p.a]) ||
                                         (roles_[p.b] == ContactRole::kFree && !island[p.b]);
                                }),
                 points.end());
    for (std::size_t i = 0; i < n; ++i) {
      solver.v[i] = states[i].velocity;
      solver.w[i] = states[i].angular_velocity;
      if (island[i]) {
        const Eigen::Matrix3d r = states[i].rotation.toRotationMatrix();
        solver.inv_mass[i] = 1 / inertias[i].mass;
        solver.inv_inertia[i] = r * inertias[i].inertia.inverse() * r.transpose();
      }
    }
    // world quantities; relative free acceleration along the normal for the time of
    // first contact and the impact threshold
    double velocity_scale = 0;
    for (Point& p : points) {
      const Eigen::Matrix3d rot_a = states[p.a].rotation.toRotationMatrix(),
                            rot_b = states[p.b].rotation.toRotationMatrix();
      p.ra = rot_a * p.pa;
      p.rb = rot_b * p.pb;
      const Eigen::Vector3d nrm = (p.normal_on_a ? rot_a : rot_b) * p.n_local;
      const Eigen::Vector3d helper =
          std::abs(nrm.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      const Eigen::Vector3d t1 = nrm.cross(helper).normalized();
      p.basis.col(0) = nrm;
      p.basis.col(1) = t1;
      p.basis.col(2) = nrm.cross(t1);
      p.gap = nrm.dot(states[p.b].position + p.rb - states[p.a].position - p.ra);
    }
    auto free_acceleration_vector = [&](const Point& p) {
      Eigen::Vector3d acc = Eigen::Vector3d::Zero();
      if (island[p.b]) acc += forces[p.b] / inertias[p.b].mass;
      if (island[p.a]) acc -= forces[p.a] / inertias[p.a].mass;
      return acc;
    };
    auto free_acceleration = [&](const Point& p) {
      return p.basis.col(0).dot(free_acceleration_vector(p));
    };
    // the velocity scale of the substep: relative speeds and what the loads add in it
    for (const Point& p : points)
      velocity_scale = std::max({velocity_scale, solver.relative_velocity(p).norm(),
                                 free_acceleration_vector(p).norm() * remaining});
    // closed: touching to rounding, or closing within a negligible part of the step
    for (Point& p : points) {
      const double vn = p.basis.col(0).dot(solver.relative_velocity(p));
      const double tol = 1e-9 * std::max(radius_[p.a], radius_[p.b]);
      p.closed = p.gap <= tol || (vn < 0 && p.gap <= -vn * 1e-6 * dt);
    }

    // 1. impacts: an instantaneous impulse with Newton's restitution on the closed points
    // that approach faster than the step's loads could bring them
    std::vector<Point*> closed;
    bool impact = false;
    for (Point& p : points) {
      if (!p.closed) continue;
      const double vn = p.basis.col(0).dot(solver.relative_velocity(p));
      const double threshold = 2 * std::abs(free_acceleration(p)) * dt + 1e-12;
      p.target = vn < -threshold ? -p.e * vn : 0.0;
      p.lambda.setZero();
      impact = impact || vn < -threshold;
      closed.push_back(&p);
    }
    if (impact) {
      double residual = 0;
      stats_.sweeps += solver.solve(closed, options_.max_sweeps,
                                    options_.tolerance * std::max(velocity_scale, 1e-300), &residual);
      ++stats_.solves;
      for (const Point* p : closed) add_impulse(*p);
      for (std::size_t i = 0; i < n; ++i)
        if (island[i]) {
          states[i].velocity = solver.v[i];
          states[i].angular_velocity = solver.w[i];
        }
    }

    // 2. the time of first contact of the open points: the gap closing under the
    // current velocity and the free acceleration, g + v t + a t^2 / 2 = 0
    double h = remaining;
    if (substep < options_.max_substeps) {
      for (const Point& p : points) {
        if (p.closed) continue;
        const double g = p.gap, vn = p.basis.col(0).dot(solver.relative_velocity(p)),
                     an = free_acceleration(p);
        double tau = std::numeric_limits<double>::infinity();
        if (std::abs(an) < 1e-300) {
          if (vn < 0) tau = -g / vn;
        } else {
          const double disc = vn * vn - 2 * an * g;
          if (disc >= 0) {
            // the smaller positive root, in the form that keeps its digits
            const double q = -0.5 * (vn + std::copysign(std::sqrt(disc), vn));
            const double r1 = q / (0.5 * an), r2 = q != 0 ? g / q : -1;
            for (double r : {r1, r2})
              if (r > 0) tau = std::min(tau, r);
          }
        }
        // only impacts are located: a point that closes slower than the step's loads
        // could stop it is left to the rows of the smooth step (-gap / h)
        const double speed = -(vn + an * tau);
        if (tau < h && speed > 2 * std::abs(an) * dt + 1e-12) h = std::max(tau, 1e-6 * dt);
      }
    }
    if (h < remaining) ++stats_.substeps;

    // 3. the smooth part of the substep: Moreau's midpoint with the unilateral rows
    std::vector<Point*> rows;
    for (Point& p : points) {
      p.target = p.closed ? 0.0 : -p.gap / h;
      // warm start from the last step's force at the nearest point of the same parts
      p.lambda.setZero();
      const auto it = warm_.find({p.part_a, p.part_b});
      if (it != warm_.end()) {
        double best = 1e-2 * radius_[p.a];
        for (const auto& [place, force] : it->second) {
          const double dist = (place - p.pa).norm();
          if (dist < best) {
            best = dist;
            Eigen::Vector3d l = p.basis.transpose() * (force * h);
            l[0] = std::max(0.0, l[0]);
            const double tn = l.tail<2>().norm(), limit = p.mu * l[0];
            if (tn > limit) l.tail<2>() *= tn > 0 ? limit / tn : 0.0;
            p.lambda = l;
          }
        }
      }
      rows.push_back(&p);
    }
    std::vector<Eigen::Vector3d> v0(n), w0(n);
    for (std::size_t i = 0; i < n; ++i) {
      v0[i] = states[i].velocity;
      w0[i] = states[i].angular_velocity;
      if (!island[i]) continue;
      const RigidState& s = states[i];
      const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
      const Eigen::Matrix3d inertia = r * inertias[i].inertia * r.transpose();
      solver.v[i] = s.velocity + h * forces[i] / inertias[i].mass;
      solver.w[i] = s.angular_velocity +
                    h * solver.inv_inertia[i] *
                        (torques[i] - s.angular_velocity.cross(inertia * s.angular_velocity));
    }
    for (std::size_t i = 0; i < n; ++i)
      if (!island[i]) {
        solver.v[i] = states[i].velocity;
        solver.w[i] = states[i].angular_velocity;
      }
    {
      double residual = 0;
      const double tol = options_.tolerance * std::max(velocity_scale, 1e-300);
      stats_.sweeps += solver.solve(rows, options_.max_sweeps, tol, &residual);
      ++stats_.solves;
      if (residual > tol) {
        ++stats_.unconverged;
        stats_.worst_residual = std::max(stats_.worst_residual, residual);
      }
    }
    warm_.clear();
    for (const Point* p : rows) {
      warm_[{p->part_a, p->part_b}].push_back({p->pa, p->basis * p->lambda / h});
      add_impulse(*p);
    }
    for (std::size_t i = 0; i < n; ++i) {
      RigidState& s = states[i];
      if (island[i]) {
        s.velocity = solver.v[i];
        s.angular_velocity = solver.w[i];
        s.position += 0.5 * h * (v0[i] + s.velocity);
        s.rotation = (rotation_by(0.5 * h * s.angular_velocity) *
                      rotation_by(0.5 * h * w0[i]) * s.rotation)
                         .normalized();
      } else if (roles_[i] == ContactRole::kKinematic) {
        s.position += h * s.velocity;  // the caller sets the exact place after the step
      }
    }

    // 4. positions out of any penetration: mass-weighted pushes along the normals
    // (nonlinear Gauss-Seidel, push only), velocities untouched
    auto gap_now = [&](const Point& p) {
      const Eigen::Vector3d nrm = states[p.normal_on_a ? p.a : p.b].rotation * p.n_local;
      return nrm.dot(states[p.b].position + states[p.b].rotation * p.pb -
                     states[p.a].position - states[p.a].rotation * p.pa);
    };
    std::vector<double> pushed(points.size(), 0.0);
    double worst = 0;
    for (int pass = 0; pass < 100; ++pass) {
      worst = 0;
      for (std::size_t k = 0; k < points.size(); ++k) {
        const Point& p = points[k];
        const double g = gap_now(p);
        worst = std::max(worst, -g);
        if (g >= 0 && pushed[k] == 0) continue;
        const double tol = 1e-10 * std::max(radius_[p.a], radius_[p.b]);
        if (std::abs(g) <= tol && g >= -tol) continue;
        const Eigen::Vector3d nrm = p.basis.col(0);
        const Eigen::Vector3d ca = p.ra.cross(nrm), cb = p.rb.cross(nrm);
        const double w = solver.inv_mass[p.a] + solver.inv_mass[p.b] +
                         ca.dot(solver.inv_inertia[p.a] * ca) + cb.dot(solver.inv_inertia[p.b] * cb);
        if (w <= 0) continue;
        const double delta = std::max(-g / w, -pushed[k]);
        pushed[k] += delta;
        for (int side : {p.a, p.b}) {
          if (!island[side]) continue;
          const double sign = side == p.b ? 1.0 : -1.0;
          const Eigen::Vector3d c = side == p.b ? cb : ca;
          states[side].position += sign * delta * solver.inv_mass[side] * nrm;
          states[side].rotation =
              (rotation_by(sign * delta * (solver.inv_inertia[side] * c)) * states[side].rotation)
                  .normalized();
        }
      }
      double tol = 1e-10;
      for (const Point& p : points) tol = std::min(tol, 1e-10 * std::max(radius_[p.a], radius_[p.b]));
      if (worst <= std::max(tol, 1e-15)) break;
    }
    double left = 0;
    for (const Point& p : points) left = std::max(left, -gap_now(p));
    max_penetration_ = std::max(max_penetration_, left);

    // 5. events: pairs touching now (a compressive force, or closed to rounding)
    now += h;
    remaining = remaining - h <= 1e-12 * dt ? 0.0 : remaining - h;
    std::map<std::pair<int, int>, char> touching;
    int active = 0;
    for (const Point& p : points) {
      const bool pressed = p.lambda[0] > 0;
      active += pressed;
      if (pressed || gap_now(p) <= 1e-9 * std::max(radius_[p.a], radius_[p.b]))
        touching[{p.a, p.b}] = 1;
    }
    active_points_ = active;
    for (const auto& [pair, on] : touching)
      if (!touching_.count(pair)) events_.push_back({now, true, pair.first, pair.second});
    for (const auto& [pair, on] : touching_)
      if (!touching.count(pair)) events_.push_back({now, false, pair.first, pair.second});
    touching_ = std::move(touching);
    for (std::size_t i = 0; i < n; ++i)
      if (island[i] && (!states[i].position.allFinite() || !states[i].velocity.allFinite() ||
                        !states[i].angular_velocity.allFinite()))
        throw SimulationError("the state of body '" + scene_.bodies[i].name +
                              "' became non-finite in contact at t = " + seconds(now) + " s");
  }
  for (const auto& [pair, impulse] : pair_impulse) {
    const double f = impulse.norm() / dt;
    contact_force_ += f;
    peak_contact_force_ = std::max(peak_contact_force_, f);
  }
}

}  // namespace vproto::sim
