#include "vproto/modeler/evaluator.h"

#include <gtest/gtest.h>

#include "script_helpers.h"

namespace vproto::modeler {
namespace {

using testing::evaluate;
constexpr double kInch = 0.0254;
constexpr double kLbf = 4.4482216152605;

// the leaves of a body, in order
void leaves(const Feature& f, std::vector<const Feature*>& out) {
  if (f.is_leaf()) out.push_back(&f);
  for (const auto& c : f.children) leaves(c, out);
}
std::vector<const Feature*> leaves_of(const EvaluatedScript& s, int body = 0) {
  std::vector<const Feature*> out;
  leaves(s.body_trees.at(body), out);
  return out;
}

TEST(Evaluator, UnitsAndBareNumbers) {
  const auto s = evaluate(R"(
    units length=in;
    let a = 2 * 3;                 // a plain number
    let w = 1mm + 1;               // the bare 1 takes the default length: 1 in
    rigid body b (material=steel) { box([a, w, 2ft]); }
  )");
  const auto l = leaves_of(s);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0]->size.x(), 6 * kInch, 1e-15);
  EXPECT_NEAR(l[0]->size.y(), 0.001 + kInch, 1e-15);
  EXPECT_NEAR(l[0]->size.z(), 0.6096, 1e-15);
}

TEST(Evaluator, ExpressionsVectorsRangesComprehensions) {
  const auto s = evaluate(R"(
    let v = [for (k = [0:5]) k * 2];            // 0 2 4 6 8 10
    let r = [1 : 0.5 : 3];                      // 1 1.5 2 2.5 3
    let n = [for (i = [0:1]) for (j = [0:2]) i + j];  // flattened: 6 values
    let d = [1, 2, 3] * [4, 5, 6];              // dot product 32
    let c = len(v) > 5 && !false ? max(v) : -1; // 10
    let t = atan2(1mm, 1mm);                     // 45 degrees
    rigid body b (material=steel) {
      box([len(v), len(r), len(n)]);
      box([d, c, round(t / 1deg)]);
      box([v[5] - r[4], sqrt(16mm * 1mm) / 1mm, norm([3, 4])]);
      box([min(3, 1, 2), abs(-2), floor(2.7) + ceil(0.2)]);
    }
  )");
  const auto l = leaves_of(s);
  ASSERT_EQ(l.size(), 4u);
  EXPECT_EQ(l[0]->size, Eigen::Vector3d(6, 5, 6));
  EXPECT_EQ(l[1]->size, Eigen::Vector3d(32, 10, 45));
  EXPECT_TRUE(l[2]->size.isApprox(Eigen::Vector3d(7, 4, 5), 1e-14));
  EXPECT_EQ(l[3]->size, Eigen::Vector3d(1, 2, 3));
}

TEST(Evaluator, ModulesLoopsAndConditions) {
  const auto s = evaluate(R"(
    module peg(r, h=10mm, at=[0,0,0]) { translate(at) cylinder(h=h, r=r, segments=8); }
    rigid body b (material=steel) {
      for (i = [0:2]) if (i != 1) peg(1mm, at=[i * 10mm, 0, 0]); else peg(r=2mm, h=5mm);
    }
  )");
  const auto l = leaves_of(s);
  ASSERT_EQ(l.size(), 3u);
  EXPECT_DOUBLE_EQ(l[0]->r1, 0.001);
  EXPECT_DOUBLE_EQ(l[0]->height, 0.010);
  EXPECT_DOUBLE_EQ(l[1]->r1, 0.002);
  EXPECT_DOUBLE_EQ(l[1]->height, 0.005);
  EXPECT_NEAR(l[2]->transform.translation().x(), 0.020, 1e-15);
  EXPECT_EQ(l[2]->segments, 8);
}

TEST(Evaluator, TransformsCompose) {
  const auto s = evaluate(R"(
    rigid body b (material=steel) {
      translate([1, 0, 0]) rotate([0, 0, 90]) scale([2, 1, 1]) box([1, 1, 1]);
      rotate(90, axis=[1, 0, 0]) box(1);
      mirror([1, 0, 0]) box(1);
    }
  )");
  const auto l = leaves_of(s);
  const Eigen::Vector3d p =
      l[0]->transform *
      Eigen::Vector3d(1, 0, 0);  // -> scaled (2,0,0) -> rotated (0,2,0) -> (1,2,0)
  EXPECT_TRUE(p.isApprox(Eigen::Vector3d(1, 2, 0), 1e-14));
  const Eigen::Vector3d q = l[1]->transform * Eigen::Vector3d(0, 1, 0);
  EXPECT_TRUE(q.isApprox(Eigen::Vector3d(0, 0, 1), 1e-14));
  EXPECT_LT(l[2]->transform.linear().determinant(), 0);
}

TEST(Evaluator, PrimitivesAndBooleans) {
  const auto s = evaluate(R"(
    units length=mm;
    facets 24;
    rigid body b (material=steel, segments=12) {
      difference() {
        box([10, 10, 10], center=true);
        cylinder(h=20, d=4, center=true);
        sphere(d=3, segments=6);
      }
      intersection() { wedge([1, 2, 3]); prism(points=[[0,0],[1,0],[0,1]], h=2); }
      union() { cylinder(5, 2, 1); cylinder(h=5, r1=0, r2=1); }
    }
    rigid body c (material=steel) { cylinder(h=1, r=1); }
  )");
  const Feature& root = s.body_trees[0];
  ASSERT_EQ(root.children.size(), 3u);
  EXPECT_EQ(root.children[0].kind, Feature::Kind::kDifference);
  EXPECT_EQ(root.children[0].children.size(), 3u);
  EXPECT_EQ(root.children[1].kind, Feature::Kind::kIntersection);
  const auto l = leaves_of(s);
  EXPECT_TRUE(l[0]->center);
  EXPECT_DOUBLE_EQ(l[1]->r1, 0.002);
  EXPECT_EQ(l[1]->segments, 12);  // body attribute beats facets
  EXPECT_EQ(l[2]->segments, 6);   // the primitive's own beats both
  EXPECT_EQ(l[4]->kind, Feature::Kind::kPrism);
  EXPECT_DOUBLE_EQ(l[5]->r1, 0.002);  // cylinder(h, r1, r2)
  EXPECT_DOUBLE_EQ(l[5]->r2, 0.001);
  EXPECT_DOUBLE_EQ(l[6]->r1, 0.0);
  EXPECT_EQ(leaves_of(s, 1)[0]->segments, 24);  // facets
}

TEST(Evaluator, ParamsAndOverrides) {
  const std::string src = R"(
    units length=in;
    param gap = 0.002in;
    param n = 3;
    rigid body b (material=steel) { for (i = [1:n]) translate([i, 0, 0]) box([gap, 1, 1]); }
  )";
  auto s = evaluate(src);
  EXPECT_EQ(leaves_of(s).size(), 3u);
  EXPECT_NEAR(leaves_of(s)[0]->size.x(), 0.002 * kInch, 1e-15);
  s = evaluate(src, {{"gap", "0.003in"}, {"n", "2"}});
  EXPECT_EQ(leaves_of(s).size(), 2u);
  EXPECT_NEAR(leaves_of(s)[0]->size.x(), 0.003 * kInch, 1e-15);
  // a bare override takes the script's default units
  s = evaluate(src, {{"gap", "0.5"}});
  EXPECT_NEAR(leaves_of(s)[0]->size.x(), 0.5 * kInch, 1e-15);
  EXPECT_EQ(s.params.count("gap"), 1u);
}

TEST(Evaluator, MaterialsAndBodies) {
  const auto s = evaluate(R"(
    material hdpe { E = 1GPa; nu = 0.4; density = 0.96g/cm^3; friction = 0.2; }
    material soft { E = 1000psi; nu = 0.45; density = 0.03lb/in^3; }
    elastic body a (material=hdpe, mesh_size=2mm, element=tet4) { box(1); }
    rigid body b (material=soft) { box(1); }
    rigid body c (material=pom) { box(1); }
  )");
  ASSERT_EQ(s.scene.bodies.size(), 3u);
  const sim::Body& a = s.scene.bodies[0];
  EXPECT_EQ(a.kind, sim::BodyKind::kElastic);
  EXPECT_DOUBLE_EQ(a.material.youngs_modulus, 1e9);  // redefined built-in
  EXPECT_NEAR(a.material.density, 960, 1e-9);
  EXPECT_DOUBLE_EQ(*a.material.friction, 0.2);
  EXPECT_DOUBLE_EQ(a.mesh_size, 0.002);
  EXPECT_EQ(a.element, sim::ElementType::kTet4);
  EXPECT_NEAR(s.scene.bodies[1].material.youngs_modulus, 6894757.293168, 1e-3);
  EXPECT_NEAR(s.scene.bodies[1].material.density, 0.03 * 0.45359237 / std::pow(kInch, 3), 1e-6);
  EXPECT_EQ(s.scene.bodies[2].material.name, "pom");
  EXPECT_EQ(s.scene.bodies[2].element, sim::ElementType::kTet10);
}

TEST(Evaluator, SceneStatements) {
  const auto s = evaluate(R"(
    units length=in force=lbf;
    // statements may name bodies defined further down
    fix base;
    grip sock region=box([-1, -1, 4], [1, 1, 5]);
    fix sock region=box([-1, -1, -1], [1, 1, 0]);
    joint slider sock axis=[0, 0, 2];
    joint revolute arm to base at=[0, 0, 1] axis=[1, 0, 0];
    joint spherical arm at=[1, 2, 3];
    force sock [0, 0, -50] ramp=0.05s;
    force sock [1, 0, 0] region=box([0, 0, 0], [1, 1, 1]);
    torque arm [0, 0, 2];
    move arm by=[0, 0, -1] over=0.5s;
    gravity [0, 0, -386.1];
    velocity arm linear=[1, 0, 0] angular=[0, 0, 90deg/s];
    contact friction=0.3;
    contact sock base restitution=0.2;
    nocontact arm base;
    probe tip sock point=[0, 0, -1];
    simulate(mode=quasistatic, duration=2s, dt=1ms, frames=30, tolerance=1e-4);
    render(size=[640, 480], field=von_mises, camera=[[10, 10, 10], [0, 0, 0]]);
    export(format=obj, every=2);
    elastic body sock (material=hdpe) { box(2); }
    rigid body base (material=steel) { box(1); }
    rigid body arm (material=steel) { box(1); }
  )");
  const sim::Scene& sc = s.scene;
  ASSERT_EQ(sc.fixes.size(), 2u);
  EXPECT_EQ(sc.fixes[0].body, 1);
  EXPECT_FALSE(sc.fixes[0].region);
  EXPECT_EQ(sc.grips.at(0).body, 0);
  EXPECT_NEAR(sc.grips[0].region.hi.z(), 5 * kInch, 1e-15);
  ASSERT_EQ(sc.joints.size(), 3u);
  EXPECT_EQ(sc.joints[0].type, sim::JointType::kSlider);
  EXPECT_EQ(sc.joints[0].axis, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(sc.joints[0].other, sim::kGround);
  EXPECT_EQ(sc.joints[1].body, 2);
  EXPECT_EQ(sc.joints[1].other, 1);
  EXPECT_NEAR(sc.joints[2].at.z(), 3 * kInch, 1e-15);
  EXPECT_NEAR(sc.forces.at(0).force.z(), -50 * kLbf, 1e-12);
  EXPECT_DOUBLE_EQ(sc.forces[0].ramp, 0.05);
  EXPECT_TRUE(sc.forces[1].region);
  EXPECT_NEAR(sc.torques.at(0).torque.z(), 2 * kLbf * kInch, 1e-14);
  EXPECT_NEAR(sc.moves.at(0).by.z(), -kInch, 1e-15);
  EXPECT_NEAR(sc.gravity->z(), -386.1 * kInch, 1e-12);
  EXPECT_NEAR(sc.velocities.at(0).angular.z(), 3.14159265358979 / 2, 1e-12);
  EXPECT_NEAR(sc.velocities[0].linear.x(), kInch, 1e-15);
  ASSERT_EQ(sc.contacts.size(), 2u);
  EXPECT_EQ(sc.contacts[0].body_a, sim::kGround);
  EXPECT_DOUBLE_EQ(*sc.contacts[0].friction, 0.3);
  EXPECT_EQ(sc.contacts[1].body_b, 1);
  EXPECT_EQ(sc.nocontacts.at(0).body_a, 2);
  EXPECT_EQ(sc.probes.at(0).name, "tip");
  EXPECT_EQ(sc.simulation.mode, sim::SimulationMode::kQuasistatic);
  EXPECT_DOUBLE_EQ(*sc.simulation.time_step, 0.001);
  EXPECT_EQ(sc.simulation.frames, 30);
  EXPECT_DOUBLE_EQ(sc.simulation.tolerance, 1e-4);
  EXPECT_EQ(sc.render.width, 640);
  EXPECT_EQ(sc.render.field, "von_mises");
  EXPECT_EQ(sc.render.camera, "custom");
  EXPECT_NEAR(sc.render.eye.x(), 10 * kInch, 1e-15);
  EXPECT_EQ(sc.output.format, "obj");
  EXPECT_EQ(sc.output.every, 2);
}

TEST(Evaluator, WarnsAboutMeshSettingsOnRigidBodies) {
  const auto s = evaluate("rigid body b (material=steel, mesh_size=1mm) { box(1); }");
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("t.vp:1:31: warning: mesh_size is ignored"), std::string::npos);
}

}  // namespace
}  // namespace vproto::modeler
