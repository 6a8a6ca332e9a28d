#include "vproto/modeler/compiler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "../geometry/test_volumes.h"
#include "script_helpers.h"
#include "vproto/geometry/csg.h"
#include "vproto/geometry/primitives.h"
#include "vproto/sim/contact.h"

namespace vproto::modeler {
namespace {

using testing::faceted_sphere_volume;
using testing::ngon_area;
using testing::ngon_frustum_volume;
constexpr double kInch = 0.0254;

double volume_of(const EvaluatedScript& s, int body) {
  return s.scene.bodies.at(body).mass_properties.volume;
}

TEST(Compiler, EveryPrimitiveTransformAndBooleanInMillimetres) {
  const auto s = testing::build(R"(
    units length=mm;
    rigid body plate (material=aluminum) {
      difference() {
        box([40, 30, 10]);
        for (i = [0:2]) translate([10 + 10 * i, 15, -1]) cylinder(h=12, d=6, segments=16);
        translate([13.5, 0, 5]) rotate([0, 0, 0]) box([3, 30, 5]);    // a slot flush with 3 faces
      }
      translate([0, 0, 10]) wedge([40, 30, 10]);                       // a ramp on top
    }
    rigid body knob (material=abs) {
      translate([100, 0, 0]) {
        sphere(r=5, segments=20);
        translate([0, 0, 4]) cylinder(h=6, r1=3, r2=2, segments=20);
      }
    }
    rigid body star (material=abs) {
      translate([0, 100, 0]) mirror([1, 0, 0]) scale([2, 1, 1])
        prism(points=[for (k = [0:9]) (k % 2 == 0 ? 5 : 2) * [cos(36 * k), sin(36 * k)]], h=3);
    }
    rigid body lens (material=polycarbonate) {
      translate([0, -100, 0]) intersection() {
        translate([0, 0, -3]) sphere(r=5, segments=24);
        translate([0, 0, 3]) sphere(r=5, segments=24);
        box([20, 20, 20], center=true);
      }
    }
  )");
  const double mm3 = 1e-9;
  // plate: box - 3 holes - slot between two holes + the ramp on top
  const double hole = 10 * ngon_area(3, 16);
  const double slot = 3 * 30 * 5;
  const double plate = 40 * 30 * 10 - 3 * hole - slot + 40 * 30 * 10 / 2.0;
  EXPECT_NEAR(volume_of(s, 0), plate * mm3, 1e-9 * plate * mm3);
  EXPECT_EQ(geometry::solid_validation_error(s.scene.bodies[0].surface), "");

  // star: area of the 10-point star times height, doubled by the scale
  double area = 0;
  for (int k = 0; k < 10; ++k) {
    const double r0 = k % 2 == 0 ? 5 : 2, r1 = (k + 1) % 2 == 0 ? 5 : 2;
    area += 0.5 * r0 * r1 * std::sin(36 * testing::kPi / 180);
  }
  EXPECT_NEAR(volume_of(s, 2), 2 * 3 * area * mm3, 1e-9 * 6 * area * mm3);
  EXPECT_GT(volume_of(s, 1), faceted_sphere_volume(5, 20) * mm3);
  EXPECT_GT(volume_of(s, 3), 0);
  for (const auto& b : s.scene.bodies) {
    EXPECT_EQ(geometry::solid_validation_error(b.surface), "") << b.name;
    EXPECT_NEAR(b.mass, b.material.density * b.mass_properties.volume, 1e-15);
  }
}

// fillet(r, h): the square [0, r]^2 less the quarter disc about (r, r), along +z; united
// into an L's inside corner it leaves no re-entrant edge sharper than the mesher's 30
// degrees, and adds its own volume: r^2 h less the quarter polygon of the arc.
TEST(Compiler, AFilletRoundsAnInsideCorner) {
  const auto s = testing::build(R"(
    units length=mm;
    rigid body round (material=steel) { fillet(r=4, h=10, segments=32); }
    rigid body l (material=steel) {
      box([30, 10, 10]);
      translate([0, 0, 10]) box([10, 10, 30]);
      translate([10, 10, 10]) rotate([90, 0, 0]) fillet(r=4, h=10, segments=32);
    }
  )");
  const double mm3 = 1e-9, r = 4, h = 10;
  // the arc's 8 chords cut the quarter disc: its polygon with the centre has 8 triangles
  const double quarter = 8 * 0.5 * r * r * std::sin(testing::kPi / 16);
  const double fillet = (r * r - quarter) * h;
  EXPECT_NEAR(volume_of(s, 0), fillet * mm3, 1e-9 * fillet * mm3);
  EXPECT_NEAR(volume_of(s, 1), (3000 + 3000 + fillet) * mm3, 1e-9 * 6000 * mm3);
  for (const auto& b : s.scene.bodies) EXPECT_EQ(geometry::solid_validation_error(b.surface), "");
  EXPECT_TRUE(geometry::reentrant_edges(s.scene.bodies[1].surface, 30).empty());
  // without it the L has its corner
  const auto bare = testing::build(R"(
    units length=mm;
    rigid body l (material=steel) { box([30, 10, 10]); translate([0, 0, 10]) box([10, 10, 30]); }
  )");
  EXPECT_FALSE(geometry::reentrant_edges(bare.scene.bodies[0].surface, 30).empty());
}

TEST(Compiler, InchesAndTheSnapFitPaw) {
  const auto s = testing::build(R"(
    units length=in;
    param depth = 0.1;
    rigid body paw (material=hdpe) {
      box([0.5, 0.5, 2]);
      translate([0, 0, 0.1]) rotate([0, 180, 0]) wedge([depth, 0.5, depth]);  // hook flush with the paw
      translate([0.25, 0.25, 2]) cylinder(h=1, r=0.25, segments=32);
    }
  )");
  const double in3 = kInch * kInch * kInch;
  const double v = 0.5 * 0.5 * 2 + 0.1 * 0.5 * 0.1 / 2 + ngon_frustum_volume(1, 0.25, 0.25, 32);
  EXPECT_NEAR(volume_of(s, 0), v * in3, 1e-9 * v * in3);
  const auto& mp = s.scene.bodies[0].mass_properties;
  EXPECT_GT(mp.unit_inertia(0, 0), 0);
  EXPECT_TRUE(mp.unit_inertia.isApprox(mp.unit_inertia.transpose(), 1e-14));
}

TEST(Compiler, FloatNoiseAndCoincidentOperands) {
  const auto s = testing::build(R"(
    rigid body same_union (material=steel) { union() { box(1); box(1); } }
    rigid body same_inter (material=steel) { intersection() { box(1); box(1); } }
    rigid body inside (material=steel) { difference() { box(3); translate([1, 1, 1]) box(1); } }
    // ring 2 of 5 lies at z = cos(90 deg): exactly on the cutting plane
    rigid body hemi (material=steel) { difference() { sphere(1, segments=9); translate([-2, -2, 0]) box(4); } }
    // 0.1 + 0.2 != 0.3 in floating point; three 30-degree turns are not exactly 90
    rigid body noise (material=steel) {
      translate([0.1 + 0.2, 0, 0]) box(1);
      translate([0.3 - 1, 0, 0]) box(1);
      translate([0, 0, 1]) rotate([0, 0, 30]) rotate([0, 0, 30]) rotate([0, 0, 30]) box(1);
    }
  )");
  EXPECT_NEAR(volume_of(s, 0), 1, 1e-14);
  EXPECT_NEAR(volume_of(s, 1), 1, 1e-14);
  EXPECT_NEAR(volume_of(s, 2), 26, 1e-13);
  EXPECT_NEAR(volume_of(s, 3), faceted_sphere_volume(1, 9) / 2, 1e-12);
  EXPECT_NEAR(volume_of(s, 4), 3, 1e-12);
  for (const auto& b : s.scene.bodies)
    EXPECT_EQ(geometry::solid_validation_error(b.surface), "") << b.name;
}

TEST(Compiler, SolidsMeetingAtAPointAreRejectedWithTheReason) {
  testing::expect_input_error(
      "rigid body tips (material=steel) {\n"
      "  cylinder(h=2, r1=1, r2=0, segments=7);\n"
      "  translate([0, 0, 2]) cylinder(h=1, r1=0, r2=1, segments=7);\n}\n",
      1, 1, "touch at a single point", true);
}

TEST(Compiler, ImportedMeshesAreCheckedAndOriented) {
  const auto s = testing::build(R"(
    rigid body a (material=steel) { import("tetra.stl"); }
    rigid body b (material=steel) { translate([5, 0, 0]) scale(2) import("tetra.obj"); }
  )");
  EXPECT_NEAR(volume_of(s, 0), 1.0 / 6, 1e-15);
  EXPECT_NEAR(volume_of(s, 1), 8.0 / 6, 1e-14);  // inward faces were turned outward
}

TEST(Compiler, RebuildRecomputesOnlyChangedBodies) {
  const std::string src = R"(
    param hole = 2mm;
    rigid body a (material=steel) { difference() { box(0.01); cylinder(h=0.03, r=hole, center=true); } }
    rigid body b (material=steel) { difference() { box(0.01); sphere(r=3mm); } }
  )";
  const std::filesystem::path cache = std::filesystem::temp_directory_path() / "vproto_cache_test";
  std::filesystem::remove_all(cache);
  CompileReport r1, r2, r3;
  const auto s1 = testing::build(src, {}, cache.string(), &r1);
  EXPECT_FALSE(r1.bodies[0].from_cache);
  EXPECT_FALSE(r1.bodies[1].from_cache);
  const auto s2 = testing::build(src, {}, cache.string(), &r2);
  EXPECT_TRUE(r2.bodies[0].from_cache);
  EXPECT_TRUE(r2.bodies[1].from_cache);
  EXPECT_EQ(volume_of(s1, 0), volume_of(s2, 0));
  const auto s3 = testing::build(src, {{"hole", "3mm"}}, cache.string(), &r3);
  EXPECT_FALSE(r3.bodies[0].from_cache);  // its subtree changed
  EXPECT_TRUE(r3.bodies[1].from_cache);
  EXPECT_LT(volume_of(s3, 0), volume_of(s1, 0));
  // a damaged cache entry is rebuilt, not trusted: cut short, or of the right size with
  // one coordinate changed (issue 13: that one was trusted and gave a wrong volume)
  for (const auto& e : std::filesystem::directory_iterator(cache))
    std::filesystem::resize_file(e.path(), 20);
  CompileReport r4;
  const auto s4 = testing::build(src, {}, cache.string(), &r4);
  EXPECT_FALSE(r4.bodies[0].from_cache);
  EXPECT_EQ(volume_of(s4, 0), volume_of(s1, 0));
  for (const auto& e : std::filesystem::directory_iterator(cache)) {
    std::fstream f(e.path(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(8 + 3 * 8 + 5);  // into the first vertex's x
    f.put('\x7f');
  }
  CompileReport r5;
  const auto s5 = testing::build(src, {}, cache.string(), &r5);
  EXPECT_FALSE(r5.bodies[0].from_cache);
  EXPECT_FALSE(r5.bodies[1].from_cache);
  EXPECT_EQ(volume_of(s5, 0), volume_of(s1, 0));
  std::filesystem::remove_all(cache);
}

// An elastic body's volume mesh comes from the cache when its surface and every meshing
// option are those of an entry, bit for bit the mesh made anew; a changed size or grading
// box meshes again, and a damaged entry is meshed again, not trusted.
TEST(Compiler, VolumeMeshesAreCachedUnderTheirSurfaceAndOptions) {
  const std::string src = R"(
    param size = 2mm;
    elastic body pad (material=abs, mesh_size=size, element=tet4) {
      difference() { box([0.02, 0.01, 0.006]); translate([0, 0, 0.003]) cylinder(h=0.01, r=3mm); }
    }
  )";
  const std::filesystem::path cache = std::filesystem::temp_directory_path() / "vproto_tets_test";
  std::filesystem::remove_all(cache);
  auto compile = [&](const std::vector<ParamOverride>& overrides, bool graded,
                     CompileReport* report) {
    EvaluatedScript script = testing::evaluate(src, overrides);
    CompileOptions options;
    options.cache_dir = cache;
    options.tet_meshes = true;
    if (graded) {  // towards a partner (a copy of the pad, not meshed)
      script.scene.bodies.push_back(script.scene.bodies[0]);
      script.body_trees.push_back(script.body_trees[0]);
      options.contact_partners = {{1}, {}};
      options.tet_mesh_bodies = {1, 0};
    }
    *report = compile_bodies(script, options);
    return script.scene.bodies[0].tet_mesh;
  };
  CompileReport r1, r2, r3, r4, r5;
  const geometry::TetMesh m1 = compile({}, false, &r1);
  EXPECT_FALSE(r1.bodies[0].tets_from_cache);
  ASSERT_GT(m1.elements.rows(), 100);
  const geometry::TetMesh m2 = compile({}, false, &r2);
  EXPECT_TRUE(r2.bodies[0].tets_from_cache);
  EXPECT_EQ(m2.nodes, m1.nodes);
  EXPECT_EQ(m2.elements, m1.elements);
  EXPECT_EQ(m2.mesh_size, m1.mesh_size);
  // another size: meshed anew, finer
  const geometry::TetMesh m3 = compile({{"size", "1.5mm"}}, false, &r3);
  EXPECT_FALSE(r3.bodies[0].tets_from_cache);
  EXPECT_GT(m3.elements.rows(), m1.elements.rows());
  // graded towards a partner: other options, meshed anew
  const geometry::TetMesh m4 = compile({}, true, &r4);
  EXPECT_FALSE(r4.bodies[0].tets_from_cache);
  EXPECT_GT(m4.max_size, 0);
  // one element's corner changed in every volume-mesh entry: meshed again, the same mesh
  for (const auto& e : std::filesystem::directory_iterator(cache))
    if (e.path().extension() == ".tets") {
      std::fstream f(e.path(), std::ios::in | std::ios::out | std::ios::binary);
      f.seekg(-12, std::ios::end);  // the last element's last corner, before the checksum
      const char byte = static_cast<char>(f.get());
      f.seekp(-12, std::ios::end);
      f.put(static_cast<char>(byte ^ 1));
    }
  const geometry::TetMesh m5 = compile({}, false, &r5);
  EXPECT_FALSE(r5.bodies[0].tets_from_cache);
  EXPECT_EQ(m5.elements, m1.elements);
  std::filesystem::remove_all(cache);
}

TEST(Compiler, HashDependsOnGeometryOnly) {
  const auto a = testing::evaluate("rigid body a (material=steel) { box(1); }");
  const auto b = testing::evaluate("elastic body a (material=abs) { box(1); }");
  const auto c = testing::evaluate("rigid body a (material=steel) { box([1, 1, 1.0000001]); }");
  EXPECT_EQ(feature_hash(a.body_trees[0]), feature_hash(b.body_trees[0]));
  EXPECT_NE(feature_hash(a.body_trees[0]), feature_hash(c.body_trees[0]));
}

// The default mesh size: about 10 elements across the thinnest wall, no finer than about
// 1e5 tetrahedra, and never coarser than the wall itself (issue 13: a plate thinner than
// about 8 mm got a default larger than its thickness and could not be meshed).
TEST(Compiler, DefaultMeshSizeFitsThinPlates) {
  const auto plate = [](double t) { return geometry::make_box({0.3, 0.3, t}, true); };
  for (const double t : {0.002, 0.005, 0.008}) {
    const double h = default_mesh_size(plate(t));
    EXPECT_LE(h, t) << t;
    EXPECT_GE(h, t / 10) << t;
  }
  // a chunky body: 10 across its 0.1 m
  EXPECT_NEAR(default_mesh_size(geometry::make_box({0.1, 0.1, 0.1}, true)), 0.01, 1e-9);
}

// What a run builds (run_compile_options): a static run meshes every elastic body; a
// dynamic one meshes only what the FE solver advances, splits only what can touch, and
// grades a held elastic body's mesh towards its contact partners, each partner's box swept
// over the travel of both bodies' drives (here the clip's two legs, 3 mm down then 1 mm up,
// seen from the clip: the catch moves between 0 and +3 mm); an elastic body that nothing
// holds touches anywhere and keeps a uniform mesh, and one that nothing loads or touches is
// not meshed at all unless the vtu export asks for every elastic body.
TEST(Compiler, ARunMeshesAndGradesWhatItsSolverNeeds) {
  const auto s = testing::evaluate(R"(
    units length=mm;
    elastic body clip (material=abs, mesh_size=1) { box([10, 10, 10]); }
    rigid body catch (material=steel) { translate([0, 0, -20]) box([10, 10, 5]); }
    elastic body ball (material=abs) { translate([50, 0, 0]) box([5, 5, 5]); }
    rigid body far (material=steel) { translate([100, 0, 0]) box(1); }
    fix catch;
    grip clip region=box([-1, -1, 9], [11, 11, 11]);
    move clip by=[0, 0, -3] over=1s;
    move clip by=[0, 0, 1] over=1s;
    gravity [0, 0, -9.81];
    simulate(duration=2s, frames=3);
  )");
  const sim::Scene& scene = s.scene;
  const CompileOptions st = run_compile_options(scene, true);
  EXPECT_TRUE(st.tet_meshes);
  EXPECT_TRUE(st.tet_mesh_bodies.empty());
  EXPECT_TRUE(st.contact_partners.empty());

  const CompileOptions dyn = run_compile_options(scene, false);
  EXPECT_FALSE(dyn.tet_meshes);
  ASSERT_EQ(dyn.tet_mesh_bodies.size(), 4u);
  EXPECT_EQ(dyn.tet_mesh_bodies[0], 1);  // the gripped, driven clip: FE
  EXPECT_EQ(dyn.tet_mesh_bodies[1], 0);  // rigid bodies never
  EXPECT_EQ(dyn.tet_mesh_bodies[2], 1);  // a free elastic body that can touch: FE (floating)
  EXPECT_EQ(dyn.tet_mesh_bodies[3], 0);
  EXPECT_EQ(dyn.convex_part_bodies, sim::contact_bodies(scene));
  ASSERT_EQ(dyn.contact_partners.size(), 4u);
  ASSERT_EQ(dyn.contact_travel.size(), 4u);
  // the clip can touch the catch (and the other bodies the falling box might reach)
  const auto& partners = dyn.contact_partners[0];
  const auto catch_at = std::find(partners.begin(), partners.end(), 1);
  ASSERT_NE(catch_at, partners.end());
  const geometry::Bounds& travel = dyn.contact_travel[0][catch_at - partners.begin()];
  EXPECT_NEAR(travel.lo.z(), 0, 1e-12);
  EXPECT_NEAR(travel.hi.z(), 0.003, 1e-12);
  EXPECT_NEAR(travel.lo.x(), 0, 1e-12);
  EXPECT_NEAR(travel.hi.x(), 0, 1e-12);
  EXPECT_TRUE(dyn.contact_partners[2].empty());  // nothing holds the box: uniform
  EXPECT_TRUE(dyn.contact_partners[1].empty());  // rigid bodies are not meshed

  const auto lone = testing::evaluate(
      "elastic body lone (material=abs) { box(1); }\nsimulate(duration=1s, frames=2);\n");
  EXPECT_EQ(run_compile_options(lone.scene, false).tet_mesh_bodies, std::vector<char>{0});
  EXPECT_EQ(run_compile_options(lone.scene, false, true).tet_mesh_bodies, std::vector<char>{1});
}

}  // namespace

}  // namespace vproto::modeler
