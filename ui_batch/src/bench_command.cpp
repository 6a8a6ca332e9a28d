// `vproto bench [--quick] -o DIR`: work-precision and speed figures of the solvers this
// version has, measured in-process on fixed inputs; writes DIR/bench.json.
#include <chrono>
#include <cmath>
#include <filesystem>

#include "cli_support.h"
#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/geometry/tet_mesh.h"
#include "vproto/materials/material.h"
#include "vproto/sim/elastic_dynamics.h"
#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/rigid_body.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/renderer.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

// the 49-hole plate: CSG time and volume error against the exact polyhedral volume
json bench_csg(int repeats) {
  geometry::CsgNode tree;
  tree.op = geometry::BooleanOp::kDifference;
  tree.children.push_back(
      geometry::CsgNode::make_leaf(geometry::make_box({0.1, 0.1, 0.01}, false)));
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 7; ++j)
      tree.children.push_back(geometry::CsgNode::make_leaf(
          geometry::transformed(geometry::make_cylinder(0.012, 0.004, 0.004, 64, false),
                                Eigen::Affine3d(Eigen::Translation3d(
                                    0.01 + 0.08 / 6 * i, 0.01 + 0.08 / 6 * j, -0.001)))));
  double best = 1e300, volume = 0;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    const geometry::TriMesh out = geometry::evaluate_csg(tree);
    best = std::min(best, since(t0));
    volume = geometry::mass_properties(out).volume;
  }
  const double exact =
      0.1 * 0.1 * 0.01 - 49 * 0.01 * 0.5 * 64 * 0.004 * 0.004 * std::sin(2 * kPi / 64);
  return {{"case", "49-hole plate, one batched difference"},
          {"seconds", best},
          {"volume_relative_error", std::abs(volume - exact) / exact}};
}

// frames per second at 1280 x 720, 2x2 anti-aliased, for spheres of n triangles
json bench_render(const std::vector<long>& sizes) {
  json rows = json::array();
  for (long n : sizes) {
    sim::Scene scene;
    sim::Body b;
    b.name = "ball";
    b.material = *materials::find_builtin("steel");
    b.surface = geometry::make_sphere(0.1, static_cast<int>(std::sqrt(static_cast<double>(n))));
    b.mass_properties = geometry::mass_properties(b.surface);
    scene.bodies.push_back(b);
    RenderOptions o;
    Renderer r(scene, o);
    const sim::Frame frame = start_frame(scene);
    const Camera cam = fit_camera("iso", frame_bounds(scene, frame), 1280.0 / 720);
    r.render(frame, cam, -0.1);  // warm up
    const int frames = n >= 1'000'000 ? 3 : 10;
    const auto t0 = Clock::now();
    for (int k = 0; k < frames; ++k) r.render(frame, cam, -0.1);
    const double s = since(t0) / frames;
    rows.push_back({{"triangles", r.triangles()}, {"seconds_per_frame", s}, {"fps", 1 / s}});
  }
  return rows;
}

// torque-free T-handle spun about its intermediate axis for 5 s: energy drift and the
// error of the final body-frame angular velocity against a 16x finer run, per time step
json bench_rigid(bool quick) {
  sim::RigidInertia in;
  in.mass = 1;
  in.inertia = Eigen::Vector3d(0.0125, 0.0065, 0.0170).asDiagonal();
  auto run = [&](double dt, double* energy_drift, double* seconds) {
    sim::RigidState s;
    s.angular_velocity = Eigen::Vector3d(0.01, 6, 0.01);
    const double e0 = sim::kinetic_energy(s, in);
    double drift = 0;
    const auto t0 = Clock::now();
    const long n = std::lround(5.0 / dt);
    for (long k = 0; k < n; ++k) {
      sim::step_rigid(s, in, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), dt);
      drift = std::max(drift, std::abs(sim::kinetic_energy(s, in) - e0) / e0);
    }
    if (seconds) *seconds = since(t0);
    if (energy_drift) *energy_drift = drift;
    return Eigen::Vector3d(s.rotation.toRotationMatrix().transpose() * s.angular_velocity);
  };
  const std::vector<double> steps = quick ? std::vector<double>{4e-3, 2e-3, 1e-3}
                                          : std::vector<double>{4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4};
  const Eigen::Vector3d reference = run(steps.back() / 16, nullptr, nullptr);
  json rows = json::array();
  for (double dt : steps) {
    double drift = 0, seconds = 0;
    const Eigen::Vector3d w = run(dt, &drift, &seconds);
    rows.push_back({{"time_step", dt},
                    {"seconds", seconds},
                    {"omega_error", (w - reference).norm() / reference.norm()},
                    {"energy_drift", drift}});
  }
  return rows;
}

// The references.md cantilever (steel 1 x 0.05 x 0.05 m, clamped): static tip deflection
// and first frequency against mesh size (error against CalculiX C3D10 3.043e-4 m and the
// Euler-Bernoulli f1), and Newmark's period error against (w h)^2 / 12 and its energy
// fluctuation, per time step
json bench_elastic(bool quick) {
  const double e = 210e9, nu = 0.3, rho = 7850;
  const double f1_eb =
      1.8751 * 1.8751 / (2 * kPi) * std::sqrt(e * std::pow(0.05, 4) / 12 / (rho * 0.05 * 0.05));
  auto beam = [](double size, bool quadratic) {
    geometry::TetMeshOptions o;
    o.size = size;
    o.quadratic = quadratic;
    return geometry::make_tet_mesh(geometry::make_box({1.0, 0.05, 0.05}, false), o);
  };
  json statics = json::array(), frequencies = json::array();
  const std::vector<double> sizes =
      quick ? std::vector<double>{0.025, 0.0125} : std::vector<double>{0.025, 0.0125, 0.00833};
  for (bool quadratic : {false, true})
    for (double h : sizes) {
      const geometry::TetMesh m = beam(h, quadratic);
      const auto t0 = Clock::now();
      const sim::FeMatrices fe = sim::assemble(m, e, nu, rho);
      const auto clamp = sim::boundary_nodes_in(m, {-1e-9, -1, -1}, {1e-9, 1, 1});
      const Eigen::VectorXd f =
          sim::region_force(m, {1 - 1e-9, -1, -1}, {1 + 1e-9, 1, 1}, {0, 0, -100});
      const Eigen::VectorXd u = sim::solve_static(fe, f, clamp);
      const double seconds = since(t0);
      const double tip = f.dot(u) / 100;  // the load-weighted mean end deflection
      statics.push_back({{"element", quadratic ? "tet10" : "tet4"},
                         {"mesh_size", h},
                         {"dofs", fe.dofs},
                         {"seconds", seconds},
                         {"tip_relative_error", tip / 3.043e-4 - 1}});
      if (!quadratic) continue;
      const auto t1 = Clock::now();
      const double f1 = sim::natural_frequencies(fe, clamp, 1)[0];
      frequencies.push_back({{"mesh_size", h},
                             {"dofs", fe.dofs},
                             {"seconds", since(t1)},
                             {"f1_hz", f1},
                             {"relative_error_vs_euler_bernoulli", f1 / f1_eb - 1}});
    }
  // Newmark on a coarse tet10 beam released from its first mode
  const geometry::TetMesh m = beam(0.05, true);
  const sim::FeMatrices fe = sim::assemble(m, e, nu, rho);
  const auto clamp = sim::boundary_nodes_in(m, {-1e-9, -1, -1}, {1e-9, 1, 1});
  Eigen::MatrixXd modes;
  const double f1 = sim::natural_frequencies(fe, clamp, 1, &modes)[0];
  const double omega = 2 * kPi * f1;
  json newmark = json::array();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(fe.dofs);
  for (double wh : {0.05, 0.1, 0.2, 0.4}) {
    const double dt = wh / omega;
    sim::ElasticDynamics dyn(fe, clamp, dt);
    dyn.start(0, modes.col(0), zero, zero);
    const double e0 = dyn.kinetic_energy() + dyn.strain_energy();
    auto q = [&] { return modes.col(0).dot(sim::symmetric_times(fe.mass(), dyn.displacement())); };
    std::vector<double> crossings;
    double previous = q(), worst = 0;
    const long steps = std::lround((quick ? 4 : 8) * 2 * kPi / wh);
    const auto t0 = Clock::now();
    for (long k = 0; k < steps; ++k) {
      dyn.step(zero);
      const double now = q();
      if (previous > 0 && now <= 0) crossings.push_back(dyn.time() - dt * now / (now - previous));
      previous = now;
      worst = std::max(worst, std::abs(dyn.kinetic_energy() + dyn.strain_energy() - e0) / e0);
    }
    const double seconds = since(t0);
    const double period =
        crossings.size() > 1 ? (crossings.back() - crossings.front()) / (crossings.size() - 1) : 0;
    newmark.push_back({{"omega_h", wh},
                       {"dofs", fe.dofs},
                       {"steps", steps},
                       {"seconds_per_step", seconds / static_cast<double>(steps)},
                       {"period_error", period * f1 - 1},
                       {"predicted_period_error", wh * wh / 12},
                       {"energy_fluctuation", worst}});
  }
  return {{"static_cantilever", statics},
          {"first_frequency", frequencies},
          {"euler_bernoulli_f1_hz", f1_eb},
          {"newmark", newmark}};
}

}  // namespace

int command_bench(const Options& o, std::ostream& err) {
  const auto t0 = Clock::now();
  Progress progress(err, o.quiet);
  const fs::path out(o.out_dir);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || ::access(out.c_str(), W_OK) != 0)
    throw InputError(SourceLoc{o.out_dir, 0, 0}, "cannot write to the output folder");
  const bool quick = o.quick;
  progress.stage("csg: 49-hole plate");
  const json csg = bench_csg(quick ? 1 : 3);
  progress.stage("render: frames per second at 1280x720");
  const json render = bench_render(quick ? std::vector<long>{10'000, 100'000}
                                         : std::vector<long>{10'000, 100'000, 1'000'000});
  progress.stage("rigid: torque-free tumbling, work against precision");
  const json rigid = bench_rigid(quick);
  progress.stage("elastic: cantilever statics, frequency and Newmark, work against precision");
  const json elastic = bench_elastic(quick);
  const json doc = {{"quick", quick}, {"csg", csg},         {"render", render},
                    {"rigid", rigid}, {"elastic", elastic}, {"total_seconds", since(t0)}};
  write_text_atomically(out / "bench.json", doc.dump(2) + "\n");
  if (!o.quiet) err << doc.dump(2) << "\n";
  return 0;
}

}  // namespace vproto::ui_batch::detail
