#include "vproto/sim/rigid_body.h"

#include <cmath>
#include <string>

#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

// exp of a rotation vector as a unit quaternion
Eigen::Quaterniond exp_map(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) {
    Eigen::Quaterniond q(1, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z());
    return q.normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

}  // namespace

double kinetic_energy(const RigidState& s, const RigidInertia& m) {
  const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
  const Eigen::Vector3d w_body = r.transpose() * s.angular_velocity;
  return 0.5 * m.mass * s.velocity.squaredNorm() + 0.5 * w_body.dot(m.inertia * w_body);
}

Eigen::Vector3d angular_momentum(const RigidState& s, const RigidInertia& m) {
  const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
  return r * (m.inertia * (r.transpose() * s.angular_velocity));
}

int step_rigid(RigidState& s, const RigidInertia& m, const Eigen::Vector3d& force,
               const Eigen::Vector3d& torque, double dt) {
  // translation: velocity Verlet with a force constant over the step
  const Eigen::Vector3d a = force / m.mass;
  s.position += dt * s.velocity + 0.5 * dt * dt * a;
  s.velocity += dt * a;

  // rotation: body-frame momentum P, Euler's equations P' = P x (J^-1 P) + tau_body,
  // implicit midpoint: P1 = P0 + h ((Pm x J^-1 Pm) + tau_body), Pm = (P0 + P1) / 2
  const Eigen::Matrix3d r0 = s.rotation.toRotationMatrix();
  const Eigen::Matrix3d j_inv = m.inertia.inverse();
  const Eigen::Vector3d tau = r0.transpose() * torque;
  const Eigen::Vector3d p0 = m.inertia * (r0.transpose() * s.angular_velocity);
  Eigen::Vector3d p1 = p0 + dt * (p0.cross(j_inv * p0) + tau);
  int iterations = 0;
  for (; iterations < 100; ++iterations) {
    const Eigen::Vector3d pm = 0.5 * (p0 + p1);
    const Eigen::Vector3d next = p0 + dt * (pm.cross(j_inv * pm) + tau);
    const double change = (next - p1).norm();
    p1 = next;
    if (change <= 1e-15 * std::max(p1.norm(), 1e-300)) break;
  }
  if (iterations == 100 || !p1.allFinite())
    throw SimulationError("the rotation step did not converge: the time step " +
                          std::to_string(dt) + " s is too long for the spin; lower dt");
  const Eigen::Vector3d w_mid = j_inv * (0.5 * (p0 + p1));
  // body-frame midpoint angular velocity rotates the body: q1 = q0 exp(h w_mid)
  s.rotation = (s.rotation * exp_map(dt * w_mid)).normalized();
  s.angular_velocity = s.rotation.toRotationMatrix() * (j_inv * p1);
  return iterations + 1;
}

}  // namespace vproto::sim
