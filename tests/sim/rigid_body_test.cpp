#include "vproto/sim/rigid_body.h"

#include <gtest/gtest.h>

namespace vproto::sim {
namespace {

// a 0.1 x 0.2 x 0.3 m steel box: three distinct principal moments
RigidInertia box_inertia() {
  const double a = 0.1, b = 0.2, c = 0.3, m = 7850 * a * b * c;
  RigidInertia in;
  in.mass = m;
  in.inertia =
      Eigen::Vector3d(m / 12 * (b * b + c * c), m / 12 * (a * a + c * c), m / 12 * (a * a + b * b))
          .asDiagonal();
  return in;
}

TEST(RigidBody, IntermediateAxisFlipsWhileEnergyAndMomentumHold) {
  const RigidInertia in = box_inertia();  // y is the intermediate axis
  RigidState s;
  s.angular_velocity = Eigen::Vector3d(1e-3, 10.0, 1e-3);  // spun about y, slightly off
  const double e0 = kinetic_energy(s, in);
  const Eigen::Vector3d l0 = angular_momentum(s, in);
  double min_y_body = 1e9, max_energy_error = 0, max_l_error = 0;
  for (int step = 0; step < 5000; ++step) {  // 5 s at dt = 1 ms
    step_rigid(s, in, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1e-3);
    const Eigen::Vector3d w_body = s.rotation.toRotationMatrix().transpose() * s.angular_velocity;
    min_y_body = std::min(min_y_body, w_body.y());
    max_energy_error = std::max(max_energy_error, std::abs(kinetic_energy(s, in) - e0) / e0);
    max_l_error = std::max(max_l_error, (angular_momentum(s, in) - l0).norm() / l0.norm());
    EXPECT_NEAR(s.rotation.norm(), 1.0, 1e-14);
  }
  EXPECT_LT(min_y_body, -9.0);  // the spin about y reversed in the body: the flip
  EXPECT_LT(max_energy_error, 1e-6);
  EXPECT_LT(max_l_error, 1e-3);
}

TEST(RigidBody, MajorAxisSpinIsStable) {
  const RigidInertia in = box_inertia();  // x has the largest moment
  RigidState s;
  s.angular_velocity = Eigen::Vector3d(10.0, 1e-3, 1e-3);
  for (int step = 0; step < 5000; ++step)
    step_rigid(s, in, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1e-3);
  const Eigen::Vector3d w_body = s.rotation.toRotationMatrix().transpose() * s.angular_velocity;
  EXPECT_GT(w_body.x(), 9.99);
}

// a 1 m x 1 mm square steel needle along x: axial moment 1/500,000 of the transverse ones
RigidInertia needle_inertia() {
  const double m = 7850 * 1e-6, a = 1e-3;
  RigidInertia in;
  in.mass = m;
  in.inertia = Eigen::Vector3d(m * a * a / 6, m / 12, m / 12).asDiagonal();
  return in;
}

// Struck on an edge, a needle spins about its axis at thousands of rad/s: h |J^-1| |P| is
// far above 1, where the old fixed-point solve of the midpoint rule diverged ("the rotation
// step did not converge") and an explicit gyroscopic term multiplied the energy each step.
TEST(RigidBody, AFastThinSpinnerKeepsItsEnergyAndMomentumAtALongStep) {
  const RigidInertia in = needle_inertia();
  RigidState s;
  s.angular_velocity = Eigen::Vector3d(2500, 3, -2);  // spinning about its axis, tumbling
  const double e0 = kinetic_energy(s, in);
  const Eigen::Vector3d l0 = angular_momentum(s, in);
  for (int step = 0; step < 1000; ++step) {
    step_rigid(s, in, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1e-3);
    ASSERT_NEAR(kinetic_energy(s, in), e0, 1e-10 * e0) << "step " << step;
    ASSERT_NEAR(angular_momentum(s, in).norm(), l0.norm(), 1e-10 * l0.norm()) << "step " << step;
  }
  // and the free spin the contact stage starts from keeps the energy the same way
  const Eigen::Vector3d w1 = spin_after(s, in, Eigen::Vector3d::Zero(), 1e-3);
  RigidState at_end = s;
  at_end.angular_velocity = w1;  // in the start's axes
  EXPECT_NEAR(kinetic_energy(at_end, in), e0, 1e-10 * e0);
}

TEST(RigidBody, ConstantForceGivesTheExactParabola) {
  RigidInertia in;
  in.mass = 2.0;
  RigidState s;
  s.velocity = Eigen::Vector3d(1, 0, 3);
  const Eigen::Vector3d g(0, 0, -9.81);
  for (int step = 0; step < 1000; ++step)
    step_rigid(s, in, in.mass * g, Eigen::Vector3d::Zero(), 1e-3);
  const Eigen::Vector3d expected = Eigen::Vector3d(1, 0, 3) * 1.0 + 0.5 * g;
  EXPECT_LT((s.position - expected).norm(), 1e-12);
  EXPECT_LT((s.velocity - (Eigen::Vector3d(1, 0, 3) + g)).norm(), 1e-12);
}

TEST(RigidBody, ConstantTorqueOnASymmetricBody) {
  RigidInertia in;
  in.inertia = 0.5 * Eigen::Matrix3d::Identity();
  RigidState s;
  const double tau = 0.2, t = 2.0;
  for (int step = 0; step < 2000; ++step)
    step_rigid(s, in, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, tau), 1e-3);
  EXPECT_NEAR(s.angular_velocity.z(), tau * t / 0.5, 1e-12);
  // angle = tau t^2 / (2 I) = 0.8 rad about z
  const Eigen::AngleAxisd aa(s.rotation);
  EXPECT_NEAR(aa.angle(), tau * t * t / (2 * 0.5), 1e-6);
  EXPECT_NEAR(std::abs(aa.axis().z()), 1.0, 1e-12);
}

}  // namespace
}  // namespace vproto::sim
