#include "vproto/sim/free_motion.h"

#include <cmath>
#include <cstdio>

#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

[[noreturn]] void unsupported(const SourceLoc& loc, const std::string& what) {
  throw InputError(loc, what +
                            " is not simulated in this version yet (it needs joints, contact "
                            "or the elastic solver); 'vproto run' handles free rigid bodies under "
                            "velocity, force, torque and gravity, with 'fix' for held bodies");
}

double ramp_factor(double ramp, double t) { return ramp > 0 ? std::min(t / ramp, 1.0) : 1.0; }

}  // namespace

void check_free_motion_supported(const Scene& scene) {
  if (!scene.joints.empty()) unsupported(scene.joints[0].loc, "joint");
  if (!scene.moves.empty()) unsupported(scene.moves[0].loc, "move");
  if (!scene.grips.empty()) unsupported(scene.grips[0].loc, "grip");
  for (const auto& f : scene.fixes)
    if (f.region) unsupported(f.loc, "fix with a region (a clamp on an elastic body)");
  for (const auto& f : scene.forces) {
    if (f.region) unsupported(f.loc, "force spread over a region");
    if (scene.bodies[f.body].kind == BodyKind::kElastic)
      unsupported(f.loc, "force on an elastic body");
  }
  for (const auto& t : scene.torques)
    if (scene.bodies[t.body].kind == BodyKind::kElastic)
      unsupported(t.loc, "torque on an elastic body");
  for (const auto& v : scene.velocities)
    if (scene.bodies[v.body].kind == BodyKind::kElastic && v.angular.norm() > 0)
      unsupported(v.loc, "spinning an elastic body (it would load it centrifugally)");
}

FreeMotion::FreeMotion(const Scene& scene, double time_step)
    : scene_(scene), time_step_(time_step) {
  VPROTO_DEMAND(time_step > 0);
  const std::size_t n = scene.bodies.size();
  states_.resize(n);
  inertias_.resize(n);
  fixed_.assign(n, false);
  moves_.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    states_[i].position = scene.bodies[i].mass_properties.centroid;
    inertias_[i].mass = scene.bodies[i].mass;
    inertias_[i].inertia = scene.bodies[i].inertia;
  }
  for (const auto& f : scene.fixes) fixed_[f.body] = true;
  for (const auto& v : scene.velocities) {
    states_[v.body].velocity = v.linear;
    states_[v.body].angular_velocity = v.angular;
    moves_[v.body] = true;
  }
  for (const auto& f : scene.forces) moves_[f.body] = true;
  for (const auto& t : scene.torques) moves_[t.body] = true;
  if (scene.gravity && scene.gravity->norm() > 0) moves_.assign(n, true);
  for (std::size_t i = 0; i < n; ++i)
    if (fixed_[i]) {
      moves_[i] = false;
      states_[i].velocity.setZero();
      states_[i].angular_velocity.setZero();
    }
  check_overlaps();
}

double FreeMotion::kinetic_energy() const {
  double e = 0;
  for (std::size_t i = 0; i < states_.size(); ++i)
    e += sim::kinetic_energy(states_[i], inertias_[i]);
  return e;
}

void FreeMotion::advance_to(double t) {
  const double span = t - time_;
  if (span <= 0) return;
  const long n = static_cast<long>(std::ceil(span / time_step_ - 1e-9));
  const double dt = span / static_cast<double>(std::max(1L, n));
  for (long k = 0; k < std::max(1L, n); ++k) step(dt);
  time_ = t;
}

void FreeMotion::step(double dt) {
  const double t_mid = time_ + 0.5 * dt;
  for (std::size_t i = 0; i < states_.size(); ++i) {
    if (!moves_[i]) continue;
    RigidState& s = states_[i];
    // loads at the middle of the step (ramps), gravity at the centre of mass
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
    if (scene_.gravity) force += inertias_[i].mass * *scene_.gravity;
    for (const auto& f : scene_.forces) {
      if (f.body != static_cast<int>(i)) continue;
      const Eigen::Vector3d fi = ramp_factor(f.ramp, t_mid) * f.force;
      force += fi;
      if (f.at) {
        // the point of application moves with the body
        const Eigen::Vector3d lever =
            s.rotation * (*f.at - scene_.bodies[i].mass_properties.centroid);
        torque += lever.cross(fi);
      }
    }
    for (const auto& tq : scene_.torques)
      if (tq.body == static_cast<int>(i)) torque += ramp_factor(tq.ramp, t_mid) * tq.torque;
    const Eigen::Vector3d v0 = s.velocity, w0 = s.angular_velocity;
    step_rigid(s, inertias_[i], force, torque, dt);
    external_work_ +=
        dt * (force.dot(0.5 * (v0 + s.velocity)) + torque.dot(0.5 * (w0 + s.angular_velocity)));
    if (!s.position.allFinite() || !s.velocity.allFinite() || !s.angular_velocity.allFinite())
      throw SimulationError("the state of body '" + scene_.bodies[i].name +
                            "' became non-finite at t = " + std::to_string(time_ + dt) + " s");
  }
  time_ += dt;
  ++steps_;
  check_overlaps();
  if (on_step_) on_step_(*this);
}

void FreeMotion::check_overlaps() const {
  const std::size_t n = states_.size();
  std::vector<geometry::Bounds> boxes(n);
  for (std::size_t i = 0; i < n; ++i) {
    // the starting box's corners carried by the pose: a box that holds the body
    const geometry::Bounds b0 = geometry::bounds(scene_.bodies[i].surface);
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
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      if ((!moves_[a] && !moves_[b]) || skipped(a, b)) continue;
      // strict overlap: boxes that only touch are not yet in contact
      const bool overlap = (boxes[a].lo.array() < boxes[b].hi.array()).all() &&
                           (boxes[b].lo.array() < boxes[a].hi.array()).all();
      if (overlap) {
        char t[32];
        std::snprintf(t, sizeof t, "%.6g", time_);
        throw SimulationError("bodies '" + scene_.bodies[a].name + "' and '" +
                              scene_.bodies[b].name + "' may touch at t = " + t +
                              " s (their bounding boxes overlap), and contact is not simulated in "
                              "this version yet; separate them, add 'nocontact " +
                              scene_.bodies[a].name + " " + scene_.bodies[b].name +
                              ";', or shorten the run");
      }
    }
}

Frame FreeMotion::frame(int index) const {
  Frame f;
  f.index = index;
  f.time = time_;
  f.field = "none";
  for (const auto& s : states_) {
    BodyFrame b;
    b.position = s.position;
    b.rotation = s.rotation;
    f.bodies.push_back(b);
  }
  return f;
}

Eigen::Vector3d FreeMotion::displacement(int body, const Eigen::Vector3d& point) const {
  const RigidState& s = states_[body];
  const Eigen::Vector3d c0 = scene_.bodies[body].mass_properties.centroid;
  return s.position + s.rotation * (point - c0) - point;
}

}  // namespace vproto::sim
