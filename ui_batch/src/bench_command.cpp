// `vproto bench [--quick] -o DIR`: work-precision and speed figures of the solvers this
// version has, measured in-process on fixed inputs; writes DIR/bench.json.
#include <chrono>
#include <cmath>
#include <filesystem>

#include "cli_support.h"
#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/materials/material.h"
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
  const json doc = {{"quick", quick},
                    {"csg", csg},
                    {"render", render},
                    {"rigid", rigid},
                    {"total_seconds", since(t0)}};
  write_text_atomically(out / "bench.json", doc.dump(2) + "\n");
  if (!o.quiet) err << doc.dump(2) << "\n";
  return 0;
}

}  // namespace vproto::ui_batch::detail
