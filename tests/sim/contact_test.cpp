#include "vproto/sim/contact.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/dynamics.h"

namespace vproto::sim {
namespace {

constexpr double kG = 9.81;

Body rigid(const std::string& name, const geometry::TriMesh& surface) {
  return make_rigid_body(name, surface, 7850);  // steel
}

geometry::TriMesh box_at(const Eigen::Vector3d& size, const Eigen::Vector3d& centre,
                         const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity()) {
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  pose.linear() = rotation;
  pose.translation() = centre;
  return geometry::transformed(geometry::make_box(size, true), pose);
}

// a fixed 2 m x 2 m slab whose top face is z = 0
void add_ground(Scene& scene) {
  scene.bodies.push_back(rigid("ground", box_at({2, 2, 0.2}, {0, 0, -0.1})));
  Fix f;
  f.body = static_cast<int>(scene.bodies.size()) - 1;
  scene.fixes.push_back(f);
}

void set_contact(Scene& scene, double friction, double restitution) {
  ContactSetting c;
  c.friction = friction;
  c.restitution = restitution;
  scene.contacts.push_back(c);
}

TEST(Contact, DroppedBallBouncesToRestitutionSquaredOfItsHeight) {
  for (const double e : {0.5, 0.8}) {
    Scene scene;
    add_ground(scene);
    const double r = 0.05, drop = 0.5;
    geometry::TriMesh ball = geometry::make_sphere(r, 24);
    // lift the ball so that its lowest vertex is `drop` above the ground
    ball.V.col(2).array() += drop - ball.V.col(2).minCoeff();
    scene.bodies.push_back(rigid("ball", ball));
    scene.gravity = Eigen::Vector3d(0, 0, -kG);
    set_contact(scene, 0.3, e);
    Dynamics dyn(scene, 1e-3);
    const double z0 = dyn.states()[1].position.z();
    const double rest = z0 - drop;  // the centre's height when the ball touches
    // fall, bounce, and record the highest point of the first rebound
    double apex = -1, previous_vz = 0;
    bool bounced = false;
    while (dyn.time() < 2.0) {
      dyn.advance_to(dyn.time() + 1e-3);
      const RigidState& s = dyn.states()[1];
      if (s.velocity.z() > 0) bounced = true;
      if (bounced && previous_vz > 0 && s.velocity.z() <= 0) {
        // the apex of the parabola through this step
        apex = s.position.z() + s.velocity.z() * s.velocity.z() / (2 * kG) - rest;
        break;
      }
      previous_vz = s.velocity.z();
      ASSERT_GT(s.position.z(), rest - 1e-6) << "the ball sank into the ground";
    }
    ASSERT_GT(apex, 0) << "no rebound";
    EXPECT_NEAR(apex / drop, e * e, 0.01 * e * e) << "e = " << e;
    EXPECT_LT(dyn.max_penetration(), 1e-6);
    // the impact is an event, and the ball left the ground again
    ASSERT_GE(dyn.contact_events().size(), 2u);
    EXPECT_TRUE(dyn.contact_events()[0].added);
    EXPECT_NEAR(dyn.contact_events()[0].time, std::sqrt(2 * drop / kG), 1e-6);
    EXPECT_FALSE(dyn.contact_events()[1].added);
  }
}

// a block of `mu` on a fixed slab tilted by `theta` about y, starting at rest on it
struct Incline {
  Scene scene;
  Eigen::Vector3d down_slope;
  Incline(double theta, double mu) {
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).matrix();
    const Eigen::Vector3d normal = tilt * Eigen::Vector3d::UnitZ();
    down_slope = tilt * Eigen::Vector3d::UnitX();
    if (down_slope.z() > 0) down_slope = -down_slope;
    scene.bodies.push_back(rigid("slope", box_at({3, 1, 0.2}, -0.1 * normal, tilt)));
    Fix f;
    f.body = 0;
    scene.fixes.push_back(f);
    scene.bodies.push_back(rigid("block", box_at({0.1, 0.08, 0.05}, 0.025 * normal, tilt)));
    scene.gravity = Eigen::Vector3d(0, 0, -kG);
    set_contact(scene, mu, 0);
  }
};

TEST(Contact, BlockSlidesDownAnInclineAtTheCoulombAcceleration) {
  const double theta = 30 * M_PI / 180, mu = 0.3;
  Incline incline(theta, mu);
  Dynamics dyn(incline.scene, 1e-3);
  const Eigen::Vector3d start = dyn.states()[1].position;
  dyn.advance_to(1.0);
  const double travelled = (dyn.states()[1].position - start).dot(incline.down_slope);
  const double expected = kG * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(2 * travelled, expected, 0.01 * expected) << "a = 2 s / t^2 at t = 1 s";
  // it slides flat: no tumbling, no lift-off
  EXPECT_LT(dyn.states()[1].angular_velocity.norm(), 1e-6);
  EXPECT_LT(dyn.max_penetration(), 1e-6);
  EXPECT_GT(dyn.contact_points(), 0);
}

TEST(Contact, BlockStaysOnAnInclineSteeperFrictionHolds) {
  const double theta = 20 * M_PI / 180, mu = 0.5;  // tan 20 deg = 0.36
  Incline incline(theta, mu);
  Dynamics dyn(incline.scene, 1e-3);
  const Eigen::Vector3d start = dyn.states()[1].position;
  dyn.advance_to(1.0);
  EXPECT_LT((dyn.states()[1].position - start).norm(), 1e-6);
  // the ground carries its weight
  const double weight = incline.scene.bodies[1].mass * kG;
  EXPECT_NEAR(dyn.contact_force(), weight, 1e-6 * weight);
}

TEST(Contact, BoxAndStackOfFiveRestWithoutSinkingOrCreeping) {
  for (const int count : {1, 5}) {
    Scene scene;
    add_ground(scene);
    const double side = 0.1;
    for (int k = 0; k < count; ++k)
      // a millimetre apart: they fall onto each other and settle
      scene.bodies.push_back(rigid("box" + std::to_string(k),
                                   box_at(Eigen::Vector3d::Constant(side),
                                          {0.003 * k, 0, (side + 1e-3) * k + side / 2 + 1e-3})));
    scene.gravity = Eigen::Vector3d(0, 0, -kG);
    set_contact(scene, 0.5, 0);
    Dynamics dyn(scene, 1e-3);
    dyn.advance_to(1.0);  // settled
    std::vector<RigidState> settled = dyn.states();
    double worst_speed = 0;
    while (dyn.time() < 10.0 - 1e-9) {
      dyn.advance_to(dyn.time() + 0.01);
      for (int k = 1; k <= count; ++k)
        worst_speed = std::max(worst_speed, dyn.states()[k].velocity.norm());
    }
    for (int k = 1; k <= count; ++k) {
      const double creep = (dyn.states()[k].position - settled[k].position).norm();
      EXPECT_LT(creep, 1e-6) << count << " boxes, box " << k;
      // resting on the one below: centre at the height of the boxes under it
      EXPECT_NEAR(dyn.states()[k].position.z(), side * (k - 0.5), 1e-6) << count << " " << k;
    }
    EXPECT_LT(worst_speed, 1e-6) << count << " boxes";
    EXPECT_LT(dyn.max_penetration(), 1e-6) << count << " boxes";
    double weight = 0;
    for (int k = 1; k <= count; ++k) weight += scene.bodies[k].mass * kG;
    // each interface carries what is above it: the sum of pair forces
    double expected = 0;
    for (int k = 1; k <= count; ++k) expected += scene.bodies[k].mass * kG * (count - k + 1);
    EXPECT_NEAR(dyn.contact_force(), expected, 1e-6 * expected);
  }
}

// What the rigid contact carries from step to step (warm starts, touching pairs, events,
// supports, links) is saved and restored whole: three boxes dropped onto one another,
// stepped on from a saved state, restored and stepped again, take the same steps to the
// bit, and report the same events (a quasi-static increment redone in halves starts again
// from such a state: Dynamics::increment).
TEST(Contact, ARestoredStateStepsOnAsBefore) {
  Scene scene;
  add_ground(scene);
  const double side = 0.1;
  for (int k = 0; k < 3; ++k)
    scene.bodies.push_back(rigid("box" + std::to_string(k),
                                 box_at(Eigen::Vector3d::Constant(side),
                                        {0.003 * k, 0, (side + 1e-3) * k + side / 2 + 1e-3})));
  set_contact(scene, 0.5, 0);
  std::vector<ContactRole> roles = {ContactRole::kStatic, ContactRole::kFree, ContactRole::kFree,
                                    ContactRole::kFree};
  ContactSystem contact(scene, roles);
  std::vector<RigidState> states(scene.bodies.size());
  std::vector<RigidInertia> inertias(scene.bodies.size());
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    states[i].position = scene.bodies[i].mass_properties.centroid;
    inertias[i].mass = scene.bodies[i].mass;
    inertias[i].inertia = scene.bodies[i].inertia;
  }
  const std::vector<Eigen::Vector3d> torques(scene.bodies.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> forces(scene.bodies.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 1; i < scene.bodies.size(); ++i)
    forces[i] = Eigen::Vector3d(0.2, 0, -kG) * inertias[i].mass;  // and a push along x
  const double dt = 1e-3;
  std::vector<char> advanced;
  // (bodies the contact did not advance move freely)
  auto step = [&](std::vector<RigidState>& s, double t) {
    contact.step(s, inertias, forces, torques, t, dt, &advanced);
    for (std::size_t i = 1; i < s.size(); ++i)
      if (!advanced[i]) step_rigid(s[i], inertias[i], forces[i], torques[i], dt);
  };
  int k = 0;
  for (; k < 30; ++k) step(states, k * dt);  // the lowest box lands at about 14 ms
  const ContactSystem::Saved saved = contact.save();
  const std::vector<RigidState> at = states;
  std::vector<std::vector<RigidState>> runs(2);
  std::vector<std::vector<ContactEvent>> events(2);
  std::vector<std::vector<double>> force(2);
  for (int run = 0; run < 2; ++run) {
    if (run == 1) contact.restore(saved);
    std::vector<RigidState> s = at;
    for (int q = k; q < k + 60; ++q) {
      step(s, q * dt);
      force[run].push_back(contact.contact_force());
    }
    runs[run] = s;
    events[run] = contact.events();
  }
  ASSERT_GE(events[0].size(), 3u);  // the three boxes have landed
  ASSERT_EQ(events[1].size(), events[0].size());
  for (std::size_t q = 0; q < events[0].size(); ++q) {
    EXPECT_EQ(events[1][q].time, events[0][q].time);
    EXPECT_EQ(events[1][q].body_a, events[0][q].body_a);
    EXPECT_EQ(events[1][q].body_b, events[0][q].body_b);
  }
  EXPECT_EQ(force[1], force[0]);
  EXPECT_GT(force[0].back(), 1.0);  // the stack rests on the ground
  for (std::size_t i = 1; i < runs[0].size(); ++i) {
    EXPECT_EQ(runs[1][i].position, runs[0][i].position) << i;
    EXPECT_EQ(runs[1][i].velocity, runs[0][i].velocity) << i;
  }
}

// The supports a stack's boxes report (what an elastic stage holds a free partner with):
// the lowest box's points on the ground, and each box above its points on the box below,
// which its own supports hold by friction. The boxes drop 1 mm onto each other, and the
// settled stack keeps friction at a corner on the cone's edge (cancelled by the others):
// held all the same, as nothing slips. On a frictionless ground nothing holds the lowest box
// sideways, and the boxes on it have no supports.
TEST(Contact, AStacksBoxesAreSupportedDownToTheGroundWhileFrictionHoldsThem) {
  for (const double ground_mu : {0.5, 0.0}) {
    Scene scene;
    add_ground(scene);
    const double side = 0.1;
    for (int k = 0; k < 3; ++k)
      scene.bodies.push_back(rigid(
          "box" + std::to_string(k),
          box_at(Eigen::Vector3d::Constant(side), {0, 0, (side + 1e-3) * k + side / 2 + 1e-3})));
    scene.gravity = Eigen::Vector3d(0, 0, -kG);
    set_contact(scene, 0.5, 0);
    ContactSetting ground;  // (the ground and the lowest box)
    ground.body_a = 0;
    ground.body_b = 1;
    ground.friction = ground_mu;
    scene.contacts.push_back(ground);
    Dynamics dyn(scene, 1e-3);
    dyn.advance_to(1.0);  // settled
    for (int k = 1; k <= 3; ++k) {
      const std::vector<ContactSystem::Support>& supports = dyn.contact()->supports(k);
      if (ground_mu == 0 && k > 1) {
        EXPECT_TRUE(supports.empty()) << k;
        continue;
      }
      ASSERT_GE(supports.size(), 3u) << ground_mu << " box " << k;
      for (const ContactSystem::Support& sp : supports) {
        EXPECT_NEAR(sp.normal.z(), 1, 1e-9) << k;              // pushing the box up
        EXPECT_NEAR(sp.point.z(), side * (k - 1), 1e-6) << k;  // on the top of the one below
        EXPECT_EQ(sp.still, ground_mu > 0) << k;
      }
    }
  }
}

TEST(Contact, FastBoxStopsAtAThinWallEvenWithLargeSteps) {
  // 20 m/s at 10 ms steps: 0.2 m per step against a 1 cm wall
  Scene scene;
  scene.bodies.push_back(rigid("wall", box_at({0.01, 1, 1}, {0.505, 0, 0})));
  Fix f;
  f.body = 0;
  scene.fixes.push_back(f);
  scene.bodies.push_back(rigid("brick", box_at({0.1, 0.1, 0.1}, {-0.3, 0, 0})));
  InitialVelocity v;
  v.body = 1;
  v.linear = Eigen::Vector3d(20, 0, 0);
  scene.velocities.push_back(v);
  Dynamics dyn(scene, 1e-2);
  dyn.advance_to(0.2);
  // plastic impact (no restitution given): it stops against the wall's face at x = 0.5
  EXPECT_NEAR(dyn.states()[1].position.x(), 0.45, 1e-6);
  EXPECT_LT(dyn.states()[1].velocity.norm(), 1e-9);
  ASSERT_FALSE(dyn.contact_events().empty());
  EXPECT_NEAR(dyn.contact_events()[0].time, 0.75 / 20, 1e-9);  // located inside the step
  EXPECT_LT(dyn.max_penetration(), 1e-6);
}

TEST(Contact, DrivenPusherShovesABoxAlongTheFloor) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("pusher", box_at({0.05, 0.2, 0.1}, {-0.2, 0, 0.06})));
  scene.bodies.push_back(rigid("box", box_at({0.1, 0.1, 0.1}, {0, 0, 0.05})));
  Move m;
  m.body = 1;
  m.by = Eigen::Vector3d(0.5, 0, 0);
  m.over = 1.0;
  scene.moves.push_back(m);
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  set_contact(scene, 0.3, 0);
  Dynamics dyn(scene, 1e-3);
  dyn.advance_to(1.0);
  // the pusher's face (x = -0.175 + 0.5) reached the box at t = 0.25 s and drove it since
  EXPECT_NEAR(dyn.states()[2].position.x(), 0.325 + 0.05, 1e-6);
  EXPECT_NEAR(dyn.states()[2].velocity.x(), 0.5, 1e-6);
  EXPECT_NEAR(dyn.states()[2].position.z(), 0.05, 1e-6);
  // one contact between pusher and box, made once
  int push = 0;
  for (const auto& e : dyn.contact_events()) push += e.added && e.body_a == 1 && e.body_b == 2;
  EXPECT_EQ(push, 1);
  EXPECT_GT(dyn.contact_force(), scene.bodies[2].mass * kG);
}

TEST(Contact, NonConvexBodyRestsOnItsConvexParts) {
  // an L of two boxes (not convex: split into parts) lying on its long leg
  Scene scene;
  add_ground(scene);
  geometry::TriMesh l = box_at({0.3, 0.1, 0.05}, {0, 0, 0.026});
  const geometry::TriMesh upright = box_at({0.05, 0.1, 0.2}, {0.125, 0, 0.151});
  const Eigen::Index nv = l.V.rows();
  l.V.conservativeResize(nv + upright.V.rows(), 3);
  l.V.bottomRows(upright.V.rows()) = upright.V;
  l.F.conservativeResize(l.F.rows() + upright.F.rows(), 3);
  l.F.bottomRows(upright.F.rows()) = upright.F.array() + static_cast<int>(nv);
  scene.bodies.push_back(rigid("ell", l));
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  set_contact(scene, 0.5, 0);
  Dynamics dyn(scene, 1e-3);
  const double z0 = dyn.states()[1].position.z();
  dyn.advance_to(1.0);
  // fell the 1 mm gap and rests, upright leg still up
  EXPECT_NEAR(dyn.states()[1].position.z(), z0 - 0.001, 1e-6);
  EXPECT_LT(dyn.states()[1].velocity.norm(), 1e-6);
  EXPECT_LT(dyn.max_penetration(), 1e-6);
}

TEST(Contact, NoContactPairsPassThroughEachOther) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("ghost", box_at({0.1, 0.1, 0.1}, {0, 0, 0.06})));
  scene.bodies.push_back(rigid("brick", box_at({0.1, 0.1, 0.1}, {0.5, 0, 0.06})));
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  NoContact nc;
  nc.body_a = 1;
  nc.body_b = 0;
  scene.nocontacts.push_back(nc);
  Dynamics dyn(scene, 1e-3);
  dyn.advance_to(0.5);
  // the ghost falls freely through the ground; the brick lands on it and stays
  EXPECT_NEAR(dyn.states()[1].position.z(), 0.06 - 0.5 * kG * 0.25, 1e-9);
  EXPECT_NEAR(dyn.states()[2].position.z(), 0.05, 1e-6);
  for (const auto& e : dyn.contact_events()) EXPECT_NE(e.body_b, 1);
}

TEST(Contact, StartingOverlapIsRefusedNamingBoth) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("brick", box_at({0.1, 0.1, 0.1}, {0, 0, 0.04})));
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  try {
    Dynamics dyn(scene, 1e-3);
    FAIL() << "an overlap at the start was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'ground' and 'brick' overlap"), std::string::npos)
        << e.what();
  }
}

TEST(Contact, PairSettingsOverrideTheMaterials) {
  Scene scene;
  scene.bodies.push_back(rigid("a", box_at({1, 1, 1}, {0, 0, 0})));
  scene.bodies.push_back(rigid("b", box_at({1, 1, 1}, {2, 0, 0})));
  scene.bodies[0].material.friction = 0.4;
  scene.bodies[1].material.friction = 0.1;
  EXPECT_NEAR(pair_friction(scene, 0, 1), 0.2, 1e-15);  // the geometric mean
  EXPECT_EQ(pair_restitution(scene, 0, 1), 0.0);
  set_contact(scene, 0.7, 0.5);
  EXPECT_EQ(pair_friction(scene, 0, 1), 0.7);
  ContactSetting pair;
  pair.body_a = 1;
  pair.body_b = 0;
  pair.restitution = 0.9;
  scene.contacts.push_back(pair);
  EXPECT_EQ(pair_restitution(scene, 0, 1), 0.9);
  EXPECT_EQ(pair_friction(scene, 0, 1), 0.7);
}

// A steel arm (150 x 10 x 10 mm) hinged about y at (0, 0, 100 mm), lying along +x, over a
// free steel box (40 mm, centred at x = 100 mm) on the ground, under gravity.
Scene hinged_arm_over_a_box() {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("arm", box_at({0.15, 0.01, 0.01}, {0.075, 0, 0.1})));
  scene.bodies.push_back(rigid("box", box_at({0.04, 0.04, 0.04}, {0.1, 0, 0.02})));
  scene.joints.push_back(
      {JointType::kRevolute, 1, kGround, Eigen::Vector3d::UnitY(), Eigen::Vector3d(0, 0, 0.1), {}});
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  return scene;
}

// Joints and contact together: a steel arm (150 x 10 x 10 mm) on a revolute hinge at
// 100 mm falls under gravity onto a free steel box (40 mm) resting on the ground. The
// contact answers through the arm's joint-constrained mobility, so the arm comes to rest
// on the box's far top edge at the angle where its lower face (5 mm from its axis) passes
// through that edge, the hinge holds to rounding, the box stays on the ground, and the
// contact does not chatter (one event per pair).
TEST(Contact, AJointedArmFallsOntoAFreeBoxAndRestsOnItsEdge) {
  Scene scene = hinged_arm_over_a_box();
  set_contact(scene, 0.5, 0);  // (without friction the arm pushes the box away and slips off)
  check_dynamics_supported(scene);
  Dynamics d(scene, 1e-3);
  d.advance_to(1.0);
  ASSERT_EQ(d.contact_events().size(), 2u);  // box on ground, arm on box: no chatter
  for (const ContactEvent& e : d.contact_events()) EXPECT_TRUE(e.added);
  EXPECT_LT(d.max_joint_drift(), 1e-12);
  EXPECT_LT(d.kinetic_energy(), 1e-12);
  EXPECT_LT(d.max_penetration(), 1e-9);
  const RigidState& box = d.states()[2];
  EXPECT_NEAR(box.position.z(), 0.02, 1e-9);  // on the ground
  // the edge (box's far top edge) relative to the hinge, and the angle it fixes:
  // x sin(theta) - z' cos(theta) = ... with the face 5 mm below the axis
  const double ex = box.position.x() + 0.02, ez = 0.04 - 0.1;
  const double theta = std::atan2(-ez, ex) - std::asin(0.005 / std::hypot(ex, ez));
  const Eigen::AngleAxisd turned(d.states()[1].rotation);
  EXPECT_NEAR(turned.angle(), theta, 1e-4);
  EXPECT_NEAR(std::abs(turned.axis().y()), 1, 1e-9);
}

// A block on a slider (along x, held up by its joint) pushed by 10 N strikes a free box on
// frictionless ground and pushes it along: contact and joint rows share the load, so the
// pair's momentum is the push's impulse F t, and they go on together (plastic contact).
TEST(Contact, ASliderPushesAFreeBoxAlong) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("pusher", box_at({0.05, 0.05, 0.05}, {0, 0, 0.03})));
  scene.bodies.push_back(rigid("box", box_at({0.05, 0.05, 0.05}, {0.051, 0, 0.025})));
  scene.joints.push_back(
      {JointType::kSlider, 1, kGround, Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero(), {}});
  scene.forces.push_back({1, Eigen::Vector3d(10, 0, 0), std::nullopt, std::nullopt, 0, {}});
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  set_contact(scene, 0, 0);
  check_dynamics_supported(scene);
  Dynamics d(scene, 1e-3);
  d.advance_to(0.3);
  const double m1 = scene.bodies[1].mass, m2 = scene.bodies[2].mass;
  const RigidState &pusher = d.states()[1], &box = d.states()[2];
  EXPECT_NEAR(m1 * pusher.velocity.x() + m2 * box.velocity.x(), 10 * 0.3, 1e-9 * 3);
  EXPECT_NEAR(pusher.velocity.x(), box.velocity.x(), 1e-9);         // together
  EXPECT_NEAR(box.position.x() - pusher.position.x(), 0.05, 1e-9);  // face to face
  EXPECT_NEAR(box.position.z(), 0.025, 1e-9);                       // on the ground
  EXPECT_NEAR(pusher.position.z(), 0.03, 1e-12);                    // on its slider
  EXPECT_LT(d.max_joint_drift(), 1e-12);
}

// A pendulum (steel bar 10 x 10 x 200 mm, hinged at one end) released horizontal swings
// down onto a fixed stop below it: its far lower corner lands on the stop's top face and
// it rests there under gravity without passing into it, the hinge holding to rounding.
TEST(Contact, APendulumSwingsOntoAFixedStopAndRestsOnIt) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("bar", box_at({0.2, 0.01, 0.01}, {0.1, 0, 0.5})));
  scene.bodies.push_back(rigid("stop", box_at({0.1, 0.1, 0.1}, {0.1, 0, 0.3})));
  scene.fixes.push_back({2, std::nullopt, {}});
  scene.joints.push_back(
      {JointType::kRevolute, 1, kGround, Eigen::Vector3d::UnitY(), Eigen::Vector3d(0, 0, 0.5), {}});
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  set_contact(scene, 0.3, 0);
  check_dynamics_supported(scene);
  Dynamics d(scene, 1e-3);
  d.advance_to(1.0);
  ASSERT_EQ(d.contact_events().size(), 1u);  // lands once, stays
  EXPECT_TRUE(d.contact_events()[0].added);
  EXPECT_LT(d.max_joint_drift(), 1e-12);
  EXPECT_LT(d.max_penetration(), 1e-6);
  EXPECT_LT(d.kinetic_energy(), 1e-9);
  // turned down by theta, its corner (0.2 along, 5 mm below its axis) on the top face
  // 0.15 below the hinge: 0.2 sin(theta) + 0.005 cos(theta) = 0.15
  const double theta = std::asin(0.15 / std::hypot(0.2, 0.005)) - std::atan2(0.005, 0.2);
  const Eigen::AngleAxisd turned(d.states()[1].rotation);
  EXPECT_NEAR(turned.angle(), theta, 1e-5) << turned.angle();
}

// The same pendulum without friction bounces off the stop by Newton's law although its
// island (a jointed body) is not cut at the impact: released horizontal, its centre drops
// by d to the stop and climbs back by e^2 d (the impacts of jointed bodies were plastic).
TEST(Contact, APendulumStrikingAStopReboundsByNewtonsLaw) {
  for (const double e : {1.0, 0.5}) {
    Scene scene;
    add_ground(scene);
    scene.bodies.push_back(rigid("bar", box_at({0.2, 0.01, 0.01}, {0.1, 0, 0.5})));
    scene.bodies.push_back(rigid("stop", box_at({0.1, 0.1, 0.1}, {0.1, 0, 0.3})));
    scene.fixes.push_back({2, std::nullopt, {}});
    scene.joints.push_back({JointType::kRevolute,
                            1,
                            kGround,
                            Eigen::Vector3d::UnitY(),
                            Eigen::Vector3d(0, 0, 0.5),
                            {}});
    scene.gravity = Eigen::Vector3d(0, 0, -kG);
    set_contact(scene, 0, e);
    check_dynamics_supported(scene);
    Dynamics d(scene, 1e-3);
    double lowest = 0.5, climbed = 0;
    bool struck = false;
    for (int k = 1; k <= 400; ++k) {
      d.advance_to(1e-3 * k);
      const double z = d.states()[1].position.z();
      if (!struck && z > lowest) struck = true;  // turned back at the stop
      if (struck)
        climbed = std::max(climbed, z);
      else
        lowest = z;
    }
    ASSERT_TRUE(struck) << "e = " << e;
    EXPECT_NEAR((climbed - lowest) / (0.5 - lowest), e * e, 0.01) << "e = " << e;
    EXPECT_LT(d.max_joint_drift(), 1e-12);
    EXPECT_LT(d.max_penetration(), 1e-6);
  }
}

// Without friction the hinged arm pushes the free box away and slips off its edge onto the
// ground: each pair's parting is one event (issue 13: contact_removed came twice).
TEST(Contact, APartingPairIsOneEvent) {
  Scene scene = hinged_arm_over_a_box();
  Dynamics d(scene, 1e-3);
  d.advance_to(1.0);
  std::map<std::pair<int, int>, int> state;  // +1 touching, 0 apart
  int removed = 0;
  for (const ContactEvent& e : d.contact_events()) {
    const auto pair = std::make_pair(std::min(e.body_a, e.body_b), std::max(e.body_a, e.body_b));
    EXPECT_NE(state[pair], e.added ? 1 : 0) << "t = " << e.time;  // alternates per pair
    state[pair] = e.added ? 1 : 0;
    removed += !e.added;
  }
  EXPECT_GE(removed, 1);  // the arm left the box
  EXPECT_EQ(state[std::make_pair(1, 2)], 0);
  EXPECT_EQ(state[std::make_pair(0, 1)], 1);  // on the ground
}

// A run that gains energy no load supplies is stopped with its cause and remedy, not
// written on to 1e258 J (issue 13). Restitution 1.5 (which the script refuses; set here
// directly) makes every bounce add energy.
TEST(Contact, ARunThatGainsEnergyStopsWithACauseAndARemedy) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("ball", box_at({0.1, 0.1, 0.1}, {0, 0, 0.2})));
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  set_contact(scene, 0, 1.5);
  Dynamics d(scene, 1e-3);
  try {
    d.advance_to(5.0);
    ADD_FAILURE() << "no error; kinetic energy " << d.kinetic_energy();
  } catch (const SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("gained energy no load supplied"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("lower dt"), std::string::npos) << e.what();
  }
  // the same with restitution 1 keeps its energy and runs to the end
  scene.contacts.clear();
  set_contact(scene, 0, 1.0);
  Dynamics kept(scene, 1e-3);
  EXPECT_NO_THROW(kept.advance_to(5.0));
  // its energy balance holds across the impacts: the kinetic energy is gravity's work
  // (issue 13: the work was summed with the step's mean velocity, wrong where it flips)
  EXPECT_NEAR(kept.kinetic_energy(), kept.external_work(), 1e-9 * scene.bodies[1].mass * kG);
}

// A pair welded together on a slider along x (a, to ground; b fixed to a, 0.1 m steel
// cubes) struck at once on both ends by free hammers (50 mm steel cubes) already touching,
// 1 m/s from +x and 0.5 m/s from -x, no gravity, e = 1, no friction. The contacts answer
// through the mechanism's mobility and are solved together: Newton's law at both contacts
// with the pair moving as one mass gives the pair 2 (m1 u1 + m2 u2) / (m1 + m2 + M) and
// each hammer its speed relative to the pair reversed, the energy kept. (With each body
// answering alone, the others held still, the pair stood like a wall: both hammers came
// back at their own speed, and the joints then moved the pair with their impulses.)
TEST(Contact, AWeldedPairOnASliderStruckAtBothEndsMovesAsOneMass) {
  Scene scene;
  scene.bodies.push_back(rigid("a", box_at({0.1, 0.1, 0.1}, {0, 0, 0})));
  scene.bodies.push_back(rigid("b", box_at({0.1, 0.1, 0.1}, {0.1, 0, 0})));
  scene.bodies.push_back(rigid("right", box_at({0.05, 0.05, 0.05}, {0.175, 0, 0})));
  scene.bodies.push_back(rigid("left", box_at({0.05, 0.05, 0.05}, {-0.075, 0, 0})));
  scene.joints.push_back(
      {JointType::kSlider, 0, kGround, Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero(), {}});
  scene.joints.push_back(
      {JointType::kFixed, 1, 0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero(), {}});
  scene.velocities.push_back({2, Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d::Zero(), {}});
  scene.velocities.push_back({3, Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero(), {}});
  set_contact(scene, 0, 1);
  check_dynamics_supported(scene);
  Dynamics d(scene, 1e-4);
  const double m1 = scene.bodies[2].mass, m2 = scene.bodies[3].mass;
  const double mass = scene.bodies[0].mass + scene.bodies[1].mass;
  const double energy = d.kinetic_energy();
  d.advance_to(5e-3);
  const double pair = 2 * (m1 * -1 + m2 * 0.5) / (m1 + m2 + mass);
  const auto& s = d.states();
  EXPECT_NEAR(s[0].velocity.x(), pair, 1e-9);
  EXPECT_NEAR(s[1].velocity.x(), pair, 1e-9);
  EXPECT_NEAR(s[2].velocity.x(), pair + 1, 1e-9);    // -1 relative to the pair, reversed
  EXPECT_NEAR(s[3].velocity.x(), pair - 0.5, 1e-9);  // 0.5 relative, reversed
  EXPECT_NEAR(d.kinetic_energy(), energy, 1e-9 * energy);
  EXPECT_LT(d.max_joint_drift(), 1e-12);
  EXPECT_LT(d.max_penetration(), 1e-9);
}

// The second link of a chain rests on the floor with friction: a carriage (a) on a slider
// along x carries a block (b) on a slider along z, which sits on the ground under gravity;
// 40 N along x on the carriage drags the block with it. The block's friction, mu m_b g,
// holds back the whole chain: (F - mu m_b g) / (m_a + m_b), and the block stays on the
// ground. (With the block answering alone, its carriage held still, friction had no way to
// act along x.)
TEST(Contact, ACarriageDragsItsBlockAgainstFriction) {
  Scene scene;
  add_ground(scene);
  scene.bodies.push_back(rigid("carriage", box_at({0.1, 0.1, 0.1}, {0, 0, 0.2})));
  scene.bodies.push_back(rigid("block", box_at({0.1, 0.1, 0.1}, {0, 0, 0.05})));
  scene.joints.push_back(
      {JointType::kSlider, 1, kGround, Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero(), {}});
  scene.joints.push_back(
      {JointType::kSlider, 2, 1, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero(), {}});
  scene.forces.push_back({1, Eigen::Vector3d(40, 0, 0), std::nullopt, std::nullopt, 0, {}});
  scene.gravity = Eigen::Vector3d(0, 0, -kG);
  const double mu = 0.2;
  set_contact(scene, mu, 0);
  check_dynamics_supported(scene);
  Dynamics d(scene, 1e-3);
  d.advance_to(0.2);
  const double ma = scene.bodies[1].mass, mb = scene.bodies[2].mass;
  const double a = (40 - mu * mb * kG) / (ma + mb);
  const auto& s = d.states();
  EXPECT_NEAR(s[1].velocity.x(), a * 0.2, 1e-9);
  EXPECT_NEAR(s[2].velocity.x(), a * 0.2, 1e-9);
  EXPECT_NEAR(s[2].position.x(), 0.5 * a * 0.2 * 0.2, 1e-9);
  EXPECT_NEAR(s[2].position.z(), 0.05, 1e-9);  // on the ground
  EXPECT_NEAR(s[2].velocity.z(), 0, 1e-9);
  EXPECT_LT(d.max_joint_drift(), 1e-12);
}

}  // namespace
}  // namespace vproto::sim
