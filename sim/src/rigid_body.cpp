#include "vproto/sim/rigid_body.h"

#include <Eigen/LU>
#include <algorithm>
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

[[nodiscard]] Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d c;
  c << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return c;
}

// P1 of the implicit midpoint rule for Euler's equations over h (see step_rigid), by Newton's
// method from P0 + h tau; false when it does not converge in 50 iterations (or the
// momentum is not finite). `iterations` counts the Newton steps (adds to it).
bool midpoint_momentum(const Eigen::Vector3d& p0, const Eigen::Vector3d& tau,
                       const Eigen::Matrix3d& j_inv, double h, Eigen::Vector3d* p1,
                       int* iterations) {
  *p1 = p0 + h * tau;  // the gyroscopic term only turns P: start from its length
  const double scale = std::max({p0.norm(), h * tau.norm(), 1e-300});
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d pm = 0.5 * (p0 + *p1);
    const Eigen::Vector3d w = j_inv * pm;
    const Eigen::Vector3d residual = *p1 - p0 - h * (pm.cross(w) + tau);
    ++*iterations;
    if (!residual.allFinite()) return false;
    if (residual.norm() <= 1e-15 * scale) return true;
    // d(pm x J^-1 pm)/dpm = -[w]x + [pm]x J^-1, and dpm/dp1 = 1/2
    const Eigen::Matrix3d jacobian =
        Eigen::Matrix3d::Identity() - 0.5 * h * (cross_matrix(pm) * j_inv - cross_matrix(w));
    const Eigen::Vector3d step = jacobian.partialPivLu().solve(residual);
    *p1 -= step;
    if (step.norm() <= 1e-15 * scale) return p1->allFinite();
  }
  return false;
}

// The rotation part of a step (see step_rigid): the body-frame momentum P1 and the turned
// orientation at the step's end; iterations counts the Newton steps.
void turn_rigid(const Eigen::Quaterniond& q0, const Eigen::Vector3d& p0, const Eigen::Vector3d& tau,
                const Eigen::Matrix3d& j_inv, double dt, Eigen::Vector3d* p_end,
                Eigen::Quaterniond* q_end, int* iterations) {
  // a spin too fast for one midpoint step (the rule may have no nearby solution) is taken in
  // 2, 4, ... equal parts, each a midpoint step
  for (int parts = 1; parts <= 1024; parts *= 2) {
    const double h = dt / parts;
    Eigen::Vector3d p = p0;
    Eigen::Quaterniond q = q0;
    bool converged = true;
    for (int k = 0; k < parts && converged; ++k) {
      Eigen::Vector3d p1;
      converged = midpoint_momentum(p, tau, j_inv, h, &p1, iterations);
      // the body-frame midpoint angular velocity turns the body: q1 = q0 exp(h w_mid)
      q = (q * exp_map(h * (j_inv * (0.5 * (p + p1))))).normalized();
      p = p1;
    }
    if (!converged) continue;
    *p_end = p;
    *q_end = q;
    return;
  }
  throw SimulationError("the rotation step did not converge: the time step " + std::to_string(dt) +
                        " s is too long for the spin; lower dt");
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
  // implicit midpoint: P1 = P0 + h ((Pm x J^-1 Pm) + tau_body), Pm = (P0 + P1) / 2. The rule
  // keeps |P| and P'J^-1 P (the kinetic energy) exactly for any h when tau = 0; it is solved by
  // Newton's method, which converges where a fixed point would not (a thin needle spinning
  // about its axis: h |J^-1| |P| far above 1)
  const Eigen::Matrix3d r0 = s.rotation.toRotationMatrix();
  const Eigen::Matrix3d j_inv = m.inertia.inverse();
  const Eigen::Vector3d p0 = m.inertia * (r0.transpose() * s.angular_velocity);
  Eigen::Vector3d p1;
  int iterations = 0;
  turn_rigid(s.rotation, p0, r0.transpose() * torque, j_inv, dt, &p1, &s.rotation, &iterations);
  s.angular_velocity = s.rotation.toRotationMatrix() * (j_inv * p1);
  return iterations;
}

Eigen::Vector3d spin_after(const RigidState& s, const RigidInertia& m,
                           const Eigen::Vector3d& torque, double dt) {
  const Eigen::Matrix3d r0 = s.rotation.toRotationMatrix();
  const Eigen::Matrix3d j_inv = m.inertia.inverse();
  const Eigen::Vector3d p0 = m.inertia * (r0.transpose() * s.angular_velocity);
  Eigen::Vector3d p1;
  Eigen::Quaterniond q1;
  int iterations = 0;
  turn_rigid(s.rotation, p0, r0.transpose() * torque, j_inv, dt, &p1, &q1, &iterations);
  return r0 * (j_inv * p1);
}

}  // namespace vproto::sim
