#pragma once
// Free rigid-body dynamics in Euler parameters (unit quaternions, the seed's Eq. 2):
// Newton-Euler with gyroscopic terms. The rotation is advanced with the implicit midpoint
// rule on the body-frame angular momentum (it conserves the kinetic energy and |L| of a
// torque-free body exactly, both being quadratic invariants) and a unit-quaternion update
// by the exponential of the midpoint angular velocity; translation is velocity Verlet.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vproto::sim {

/// State of one rigid body; world axes, SI.
struct RigidState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();            ///< centre of mass, m
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< body to world
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();            ///< m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();    ///< rad/s, world axes
};

/// Mass properties in the body frame (the body frame is the world frame at the start).
struct RigidInertia {
  double mass = 1;                                        ///< kg
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity();  ///< kg m^2 about the centre
};

/// Kinetic energy, J.
double kinetic_energy(const RigidState& s, const RigidInertia& m);

/// Angular momentum about the centre of mass, world axes, kg m^2/s.
Eigen::Vector3d angular_momentum(const RigidState& s, const RigidInertia& m);

/// Advances the state by `dt` under a constant world-frame force (at the centre of mass)
/// and torque over the step. Returns the number of Newton iterations the implicit midpoint
/// solve took (it converges to 1e-15 relative, in up to 1024 parts of the step for a spin too
/// fast for one, or throws SimulationError).
int step_rigid(RigidState& s, const RigidInertia& m, const Eigen::Vector3d& force,
               const Eigen::Vector3d& torque, double dt);

/// The angular velocity step_rigid would give the body at the step's end under `torque`
/// (world), in the axes the body has at the step's start: Euler's equations by the
/// implicit midpoint rule, so the gyroscopic term keeps the kinetic energy (an explicit
/// omega x J omega adds energy every step to a fast, thin spinner).
Eigen::Vector3d spin_after(const RigidState& s, const RigidInertia& m,
                           const Eigen::Vector3d& torque, double dt);

}  // namespace vproto::sim
