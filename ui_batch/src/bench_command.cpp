// `vproto bench [--quick] -o DIR`: work-precision and speed figures of the solvers this
// version has, measured in-process on fixed inputs; writes DIR/bench.json.
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <sstream>

#include "cli_support.h"
#include "vproto/geometry/convex_parts.h"
#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/geometry/tet_mesh.h"
#include "vproto/materials/material.h"
#include "vproto/sim/dynamics.h"
#include "vproto/sim/elastic_dynamics.h"
#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/linear_solver.h"
#include "vproto/sim/rigid_body.h"
#include "vproto/ui_batch/animation_writer.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/cli.h"
#include "vproto/ui_batch/mesh_io.h"
#include "vproto/ui_batch/renderer.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

// the 49-hole plate: CSG time and volume error against the exact polyhedral volume
geometry::CsgNode holed_plate(int segments, int rows = 7) {
  geometry::CsgNode tree;
  tree.op = geometry::BooleanOp::kDifference;
  tree.children.push_back(
      geometry::CsgNode::make_leaf(geometry::make_box({0.1, 0.1, 0.01}, false)));
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < rows; ++j)
      tree.children.push_back(geometry::CsgNode::make_leaf(geometry::transformed(
          geometry::make_cylinder(0.012, 0.004, 0.004, segments, false),
          Eigen::Affine3d(Eigen::Translation3d(0.01 + 0.08 / (rows - 1) * i,
                                               0.01 + 0.08 / (rows - 1) * j, -0.001)))));
  return tree;
}

// the best of `repeats` evaluations: seconds and the volume
std::pair<double, double> time_csg(const geometry::CsgNode& tree, int repeats) {
  double best = 1e300, volume = 0;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    const geometry::TriMesh out = geometry::evaluate_csg(tree);
    best = std::min(best, since(t0));
    volume = geometry::mass_properties(out).volume;
  }
  return {best, volume};
}

json bench_csg(int repeats) {
  const auto [best, volume] = time_csg(holed_plate(64), repeats);
  const double exact =
      0.1 * 0.1 * 0.01 - 49 * 0.01 * 0.5 * 64 * 0.004 * 0.004 * std::sin(2 * kPi / 64);
  return {{"case", "49-hole plate, one batched difference"},
          {"seconds", best},
          {"volume_relative_error", std::abs(volume - exact) / exact}};
}

// the plate's accuracy knob: the holes' segments, its volume against round holes (the
// faceting error, 1 - sin(2 pi / N) N / (2 pi) of each hole) and its cost
json bench_csg_segments(bool quick) {
  const double exact = 0.1 * 0.1 * 0.01 - 49 * 0.01 * kPi * 0.004 * 0.004;
  json rows = json::array();
  for (int segments : quick ? std::vector<int>{16, 32, 64} : std::vector<int>{16, 32, 64, 128}) {
    const auto [seconds, volume] = time_csg(holed_plate(segments), quick ? 1 : 2);
    rows.push_back({{"segments", segments},
                    {"seconds", seconds},
                    {"volume_relative_error", std::abs(volume - exact) / exact}});
  }
  return rows;
}

// The 49-hole plate in the tools a designer would otherwise use, where installed: OpenSCAD
// (2021's CGAL Nef polyhedra; the full sweep only, it takes tens of seconds) and Manifold
// (npm manifold-3d under Node). The same solid in millimetres: its time and its volume
// error against the exact polyhedral volume, beside vproto's.
json bench_csg_peers(bool quick, int segments) {
  json out = json::object();
  const double exact =
      100.0 * 100 * 10 - 49 * 10 * 0.5 * segments * 16 * std::sin(2 * kPi / segments);
  const fs::path work =
      fs::temp_directory_path() / ("vproto_bench_csg_" + std::to_string(::getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  auto run = [&](const std::string& command) {
    const auto t0 = Clock::now();
    const int code = std::system(("cd '" + work.string() + "' && " + command).c_str());
    return code == 0 ? since(t0) : -1.0;
  };
  const std::string seg = std::to_string(segments);
  if (!on_path("openscad")) {
    out["openscad"] = {{"skipped", "not installed: apt-get install openscad"}};
  } else if (quick) {
    out["openscad"] = {{"skipped", "the full sweep runs it (tens of seconds)"}};
  } else {
    std::ofstream(work / "plate.scad")
        << "difference() {\n  cube([100, 100, 10]);\n  for (i = [0:6], j = [0:6])\n"
           "    translate([10 + 80 / 6 * i, 10 + 80 / 6 * j, -1]) cylinder(h=12, r=4, $fn="
        << seg << ");\n}\n";
    const double seconds = run("openscad -o plate.stl plate.scad > openscad.log 2>&1");
    if (seconds < 0) {
      out["openscad"] = {{"error", "openscad failed"}};
    } else {
      const double volume =
          geometry::mass_properties(read_mesh((work / "plate.stl").string())).volume;
      out["openscad"] = {{"seconds", seconds},
                         {"volume_relative_error", std::abs(volume - exact) / exact}};
    }
  }
  // Manifold: a module folder from VPROTO_MANIFOLD_JS, else npm's global folder
  std::string module;
  for (const std::string& candidate :
       {std::string(std::getenv("VPROTO_MANIFOLD_JS") ? std::getenv("VPROTO_MANIFOLD_JS") : ""),
        std::string("/usr/lib/node_modules/manifold-3d/manifold.js"),
        std::string("/usr/local/lib/node_modules/manifold-3d/manifold.js")})
    if (!candidate.empty() && fs::exists(candidate)) {
      module = candidate;
      break;
    }
  if (!on_path("node") || module.empty()) {
    out["manifold"] = {{"skipped", "not installed: npm install -g manifold-3d (Node 18 or later)"}};
  } else {
    std::ofstream(work / "plate.mjs")
        << "import Module from '" << module
        << "';\nconst wasm = await Module();\nwasm.setup();\n"
           "const { Manifold } = wasm;\nlet best = Infinity, volume = 0;\n"
           "for (let r = 0; r < 3; ++r) {\n  const t0 = performance.now();\n"
           "  const holes = [];\n  for (let i = 0; i < 7; ++i)\n    for (let j = 0; j < 7; ++j)\n"
           "      holes.push(Manifold.cylinder(12, 4, 4, "
        << seg
        << ").translate([10 + 80 / 6 * i, "
           "10 + 80 / 6 * j, -1]));\n"
           "  const result = Manifold.cube([100, 100, 10]).subtract(Manifold.union(holes));\n"
           "  volume = result.volume();\n  best = Math.min(best, (performance.now() - t0) / "
           "1000);\n}\n"
           "console.log(JSON.stringify({ volume, seconds: best }));\n";
    if (run("node plate.mjs > manifold.json 2> manifold.log") < 0) {
      out["manifold"] = {{"error", "node plate.mjs failed"}};
    } else {
      try {
        const json r = json::parse(std::ifstream(work / "manifold.json"));
        out["manifold"] = {
            {"seconds", r["seconds"]},
            {"volume_relative_error", std::abs(r["volume"].get<double>() - exact) / exact},
            {"note", "best of 3 in one Node process (after the module loads)"}};
      } catch (const std::exception& e) {
        out["manifold"] = {{"error", std::string("unreadable output: ") + e.what()}};
      }
    }
  }
  fs::remove_all(work);
  return out;
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

// CalculiX (`ccx`) on the very mesh vproto solved: the same nodes and elements (vproto's
// tet10 node order is C3D10's), clamp and nodal loads; its run time (2 threads, as
// vproto's factorization), its tip error against the reference, the largest nodal
// difference from vproto's displacements, and (tet10) its first frequency. Empty when ccx
// is not installed.
json calculix_peer(const geometry::TetMesh& m, const std::vector<int>& clamp,
                   const Eigen::VectorXd& f, const Eigen::VectorXd& u, double e, double nu,
                   double rho, bool frequency) {
  if (!on_path("ccx")) return json();
  const fs::path work =
      fs::temp_directory_path() / ("vproto_bench_ccx_" + std::to_string(::getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  const bool quadratic = m.elements.cols() == 10;
  auto deck = [&](const std::string& name, const std::string& step) {
    std::ofstream d(work / (name + ".inp"));
    d.precision(17);
    d << "*NODE, NSET=NALL\n";
    for (Eigen::Index i = 0; i < m.nodes.rows(); ++i)
      d << i + 1 << ", " << m.nodes(i, 0) << ", " << m.nodes(i, 1) << ", " << m.nodes(i, 2) << "\n";
    d << "*ELEMENT, TYPE=" << (quadratic ? "C3D10" : "C3D4") << ", ELSET=EALL\n";
    for (Eigen::Index t = 0; t < m.elements.rows(); ++t) {
      d << t + 1;
      for (Eigen::Index k = 0; k < m.elements.cols(); ++k) d << ", " << m.elements(t, k) + 1;
      d << "\n";
    }
    d << "*NSET, NSET=HELD\n";
    for (int n : clamp) d << n + 1 << ",\n";
    d << "*MATERIAL, NAME=M\n*ELASTIC\n"
      << e << ", " << nu << "\n*DENSITY\n"
      << rho << "\n*SOLID SECTION, ELSET=EALL, MATERIAL=M\n*BOUNDARY\nHELD, 1, 3, 0.\n"
      << step;
  };
  std::ostringstream load;
  load.precision(17);
  load << "*STEP\n*STATIC\n*CLOAD\n";
  for (Eigen::Index k = 0; k < f.size(); ++k)
    if (f[k] != 0) load << k / 3 + 1 << ", " << k % 3 + 1 << ", " << f[k] << "\n";
  load << "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
  deck("static", load.str());
  auto run = [&](const std::string& name) {
    const auto t0 = Clock::now();
    const std::string command = "cd '" + work.string() +
                                "' && OMP_NUM_THREADS=2 CCX_NPROC_EQUATION_SOLVER=2 ccx -i " +
                                name + " > " + name + ".log 2>&1";
    const int code = std::system(command.c_str());
    return code == 0 ? since(t0) : -1.0;
  };
  json out;
  const double seconds = run("static");
  if (seconds < 0) {
    fs::remove_all(work);
    return json{{"error", "ccx failed on the static deck"}};
  }
  // its displacements: "node ux uy uz" lines after the displacement header
  Eigen::VectorXd uc = Eigen::VectorXd::Constant(u.size(), NAN);
  {
    std::ifstream dat(work / "static.dat");
    bool in_block = false;
    for (std::string line; std::getline(dat, line);) {
      if (line.find("displacements") != std::string::npos) {
        in_block = true;
        continue;
      }
      if (!in_block) continue;
      std::istringstream cells(line);
      long node = 0;
      double x = 0, y = 0, z = 0;
      if (cells >> node >> x >> y >> z && node >= 1 && 3 * node <= uc.size())
        uc.segment<3>(3 * (node - 1)) << x, y, z;
    }
  }
  const double scale = uc.cwiseAbs().maxCoeff();
  out["calculix_seconds"] = seconds;
  out["tip_relative_error"] = f.dot(uc) / 100 / 3.043e-4 - 1;  // as vproto's, load-weighted
  out["max_relative_difference"] = (u - uc).cwiseAbs().maxCoeff() / scale;
  if (frequency) {
    deck("frequency", "*STEP\n*FREQUENCY\n1\n*END STEP\n");
    const double fs_seconds = run("frequency");
    std::ifstream dat(work / "frequency.dat");
    double f1 = NAN;
    bool table = false;
    for (std::string line; std::getline(dat, line);) {
      if (line.find("E I G E N V A L U E") != std::string::npos) table = true;
      std::istringstream cells(line);
      long mode = 0;
      double eigen = 0, rad = 0, cycles = 0;
      if (table && cells >> mode >> eigen >> rad >> cycles && mode == 1) {
        f1 = cycles;
        break;
      }
    }
    out["frequency_seconds"] = fs_seconds;
    out["f1_hz"] = f1;
  }
  fs::remove_all(work);
  return out;
}

// The references.md cantilever (steel 1 x 0.05 x 0.05 m, clamped): static tip deflection
// and first frequency against mesh size (error against CalculiX C3D10 3.043e-4 m and the
// Euler-Bernoulli f1), and Newmark's period error against (w h)^2 / 12 and its energy
// fluctuation, per time step
// An elastic tet10 body of this surface, material and mesh size, meshed (for scenes built in
// code).
sim::Body elastic_body(const std::string& name, const geometry::TriMesh& surface,
                       const materials::Material& material, double mesh_size,
                       bool quadratic = true) {
  sim::Body b;
  b.name = name;
  b.kind = sim::BodyKind::kElastic;
  b.material = material;
  b.mesh_size = mesh_size;
  b.surface = surface;
  b.mass_properties = geometry::mass_properties(b.surface);
  b.mass = material.density * b.mass_properties.volume;
  b.inertia = material.density * b.mass_properties.unit_inertia;
  geometry::TetMeshOptions o;
  o.size = mesh_size;
  o.quadratic = quadratic;
  b.tet_mesh = geometry::make_tet_mesh(b.surface, o);
  b.meshed = true;
  return b;
}

// Newmark through the engine's own step rule (the `tolerance=` knob): the cantilever under
// a sudden 100 N tip load, simulated with no dt, so that the engine picks the step for the
// first mode's period error (w h)^2 / 12 within the tolerance. Measured against the same
// mesh's first frequency (subspace iteration): the first mode's period over eight swings
// about its rest value, and the energy balance KE + SE - f.u (zero for a load applied at once).
json bench_newmark_tolerance(bool quick) {
  const materials::Material& steel = *materials::find_builtin("steel");
  sim::Scene scene;
  scene.bodies.push_back(
      elastic_body("beam", geometry::make_box({1.0, 0.05, 0.05}, false), steel, 0.05));
  const geometry::TetMesh& mesh = scene.bodies[0].tet_mesh;
  const sim::Region root{{-1, -1, -1}, {1e-9, 1, 1}}, tip{{1 - 1e-9, -1, -1}, {1 + 1e-9, 1, 1}};
  scene.fixes.push_back({0, root, {}});
  sim::Force load;
  load.body = 0;
  load.force = {0, 0, -100};
  load.region = tip;
  scene.forces.push_back(load);
  const sim::FeMatrices fe =
      sim::assemble(mesh, steel.youngs_modulus, steel.poisson_ratio, steel.density);
  const auto clamp = sim::boundary_nodes_in(mesh, root.lo, root.hi);
  const Eigen::VectorXd f = sim::region_force(mesh, tip.lo, tip.hi, load.force);
  Eigen::MatrixXd modes;
  const double f1 = sim::natural_frequencies(fe, clamp, 1, &modes)[0];
  // the first mode's coordinate (M-orthogonal to the others, which the sudden load also
  // excites and which would shift the tip's crossings)
  auto modal = [&](const Eigen::VectorXd& u) {
    return modes.col(0).dot(sim::symmetric_times(fe.mass(), u));
  };
  const Eigen::VectorXd rest = sim::solve_static(fe, f, clamp);
  const double work_static = f.dot(rest), level = modal(rest);
  scene.simulation.duration = 8.25 / f1;
  scene.simulation.frames = 2;
  json rows = json::array();
  for (double tolerance : quick ? std::vector<double>{1e-2, 1e-3, 1e-4}
                                : std::vector<double>{1e-2, 1e-3, 1e-4, 1e-5}) {
    scene.simulation.tolerance = tolerance;
    const auto t0 = Clock::now();
    sim::Dynamics dyn(scene, sim::run_time_step(scene));
    const double dt = dyn.time_step();
    auto deflection = [&] { return modal(*dyn.nodal_displacement(0)); };
    std::vector<double> crossings;  // the mode passing its rest value, one way
    double previous = deflection(), worst = 0;
    while (dyn.time() < scene.simulation.duration - 0.5 * dt) {
      dyn.advance_to(dyn.time() + dt);
      const double now = deflection();
      if (previous > level && now <= level &&
          (crossings.empty() || dyn.time() - crossings.back() > 0.5 / f1))
        crossings.push_back(dyn.time() - dt * (level - now) / (previous - now));
      previous = now;
      const double balance =
          dyn.kinetic_energy() + dyn.strain_energy() - f.dot(*dyn.nodal_displacement(0));
      worst = std::max(worst, std::abs(balance) / work_static);
    }
    const double seconds = since(t0);
    const double period = crossings.size() > 1
                              ? (crossings.back() - crossings.front()) / (crossings.size() - 1)
                              : NAN;
    const double omega_h = 2 * kPi * f1 * dt;
    rows.push_back({{"tolerance", tolerance},
                    {"time_step", dt},
                    {"omega_h", omega_h},
                    {"time_step_reason", dyn.time_step_reason()},
                    {"dofs", fe.dofs},
                    {"seconds", seconds},
                    {"period_error", period * f1 - 1},
                    {"predicted_period_error", omega_h * omega_h / 12},
                    {"energy_error", worst}});
  }
  return rows;
}

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
      json row = {{"element", quadratic ? "tet10" : "tet4"},
                  {"mesh_size", h},
                  {"dofs", fe.dofs},
                  {"seconds", seconds},
                  {"tip_relative_error", tip / 3.043e-4 - 1}};
      const json peer = calculix_peer(m, clamp, f, u, e, nu, rho, quadratic);
      if (!peer.is_null()) row["calculix"] = peer;
      double f1_ccx = NAN, f1_ccx_seconds = NAN;
      if (peer.contains("f1_hz")) {
        f1_ccx = peer["f1_hz"].get<double>();
        f1_ccx_seconds = peer["frequency_seconds"].get<double>();
        row["calculix"].erase("f1_hz");
        row["calculix"].erase("frequency_seconds");
      }
      statics.push_back(row);
      if (!quadratic) continue;
      const auto t1 = Clock::now();
      const double f1 = sim::natural_frequencies(fe, clamp, 1)[0];
      json frow = {{"mesh_size", h},
                   {"dofs", fe.dofs},
                   {"seconds", since(t1)},
                   {"f1_hz", f1},
                   {"relative_error_vs_euler_bernoulli", f1 / f1_eb - 1}};
      if (std::isfinite(f1_ccx))
        frow["calculix"] = {{"f1_hz", f1_ccx},
                            {"seconds", f1_ccx_seconds},
                            {"relative_error_vs_euler_bernoulli", f1_ccx / f1_eb - 1},
                            {"relative_difference", f1 / f1_ccx - 1}};
      frequencies.push_back(frow);
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
          {"newmark", newmark},
          {"newmark_tolerance", bench_newmark_tolerance(quick)}};
}

// Contact (issue 4): the judged cases as figures (rebound height against e^2 h, the
// incline's acceleration against g (sin - mu cos), sticking drift, a stack's sinking and
// creep, jointed bodies struck and dragged against exact answers) and the speed of a pile
// of boxes settling in a bin, per number of boxes.
geometry::TriMesh box_mesh(const Eigen::Vector3d& size, const Eigen::Vector3d& centre,
                           const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity()) {
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  pose.linear() = rotation;
  pose.translation() = centre;
  return geometry::transformed(geometry::make_box(size, true), pose);
}

void hold(sim::Scene& scene, int body) {
  sim::Fix f;
  f.body = body;
  scene.fixes.push_back(f);
}

// A rubber-like material: E 10 MPa, nu 0.45, 1,100 kg/m^3.
materials::Material rubber_material() {
  materials::Material rubber;
  rubber.name = "rubber";
  rubber.youngs_modulus = 1e7;
  rubber.poisson_ratio = 0.45;
  rubber.density = 1100;
  return rubber;
}

void contact_setting(sim::Scene& scene, double mu, double e) {
  sim::ContactSetting c;
  c.friction = mu;
  c.restitution = e;
  scene.contacts.push_back(c);
}

// A bar on a revolute joint released horizontal: its period against the exact
// large-amplitude value 4 sqrt(I / (m g d)) K(sin 45 deg), and its energy drift, per step
json bench_pendulum(bool quick) {
  constexpr double g = 9.81;
  sim::Scene scene;
  scene.bodies.push_back(
      sim::make_rigid_body("bar", box_mesh({0.2, 0.01, 0.01}, {0.1, 0, 0}), 7850));
  sim::Joint hinge;
  hinge.type = sim::JointType::kRevolute;
  hinge.body = 0;
  hinge.axis = Eigen::Vector3d::UnitY();
  scene.joints.push_back(hinge);
  scene.gravity = Eigen::Vector3d(0, 0, -g);
  const sim::Body& bar = scene.bodies[0];
  const double m = bar.mass, d = 0.1;
  const double inertia = bar.inertia(1, 1) + m * d * d;  // about the hinge
  // K(k) by the arithmetic-geometric mean
  double a = 1, b = std::sqrt(1 - 0.5);  // k^2 = sin^2(45 deg)
  for (int k = 0; k < 30; ++k) {
    const double next = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = next;
  }
  const double exact = 4 * std::sqrt(inertia / (m * g * d)) * kPi / (2 * a);
  json rows = json::array();
  for (double dt : quick ? std::vector<double>{4e-3, 2e-3, 1e-3}
                         : std::vector<double>{4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4}) {
    sim::Dynamics dyn(scene, dt);
    const double e0 = dyn.kinetic_energy() + m * g * dyn.states()[0].position.z();
    std::vector<double> crossings;  // the centre passing x = 0 towards +x
    double previous = dyn.states()[0].position.x(), drift = 0;
    const auto t0 = Clock::now();
    while (dyn.time() < 4.5 * exact) {
      dyn.advance_to(dyn.time() + dt);
      const sim::RigidState& st = dyn.states()[0];
      const double x = st.position.x();
      if (previous < 0 && x >= 0) crossings.push_back(dyn.time() - dt * x / (x - previous));
      previous = x;
      drift = std::max(drift,
                       std::abs(dyn.kinetic_energy() + m * g * st.position.z() - e0) / (m * g * d));
    }
    const double seconds = since(t0);
    const double period = crossings.size() > 1
                              ? (crossings.back() - crossings.front()) / (crossings.size() - 1)
                              : NAN;
    rows.push_back({{"time_step", dt},
                    {"seconds", seconds},
                    {"period", period},
                    {"exact_period", exact},
                    {"period_error", period / exact - 1},
                    {"energy_drift", drift},
                    {"joint_drift", dyn.max_joint_drift()}});
  }
  return rows;
}

json bench_contact(bool quick) {
  constexpr double g = 9.81;
  const double steel = 7850;
  json out;
  // a ball dropped 0.5 m, e = 0.5, at a fine and a coarse step
  json bounce = json::array();
  for (double dt : {1e-3, 1e-2}) {
    sim::Scene scene;
    scene.bodies.push_back(
        sim::make_rigid_body("slab", box_mesh({1, 1, 0.1}, {0, 0, -0.05}), steel));
    hold(scene, 0);
    geometry::TriMesh ball = geometry::make_sphere(0.05, 24);
    ball.V.col(2).array() += 0.5 - ball.V.col(2).minCoeff();
    scene.bodies.push_back(sim::make_rigid_body("ball", ball, steel));
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    contact_setting(scene, 0.3, 0.5);
    sim::Dynamics dyn(scene, dt);
    const double rest = dyn.states()[1].position.z() - 0.5;
    double apex = 0, previous = 0;
    bool up = false;
    const auto t0 = Clock::now();
    while (dyn.time() < 1.5) {
      dyn.advance_to(dyn.time() + dt);
      const sim::RigidState& s = dyn.states()[1];
      up = up || s.velocity.z() > 0;
      if (up && previous > 0 && s.velocity.z() <= 0) {
        apex = s.position.z() + s.velocity.z() * s.velocity.z() / (2 * g) - rest;
        break;
      }
      previous = s.velocity.z();
    }
    bounce.push_back(
        {{"time_step", dt},
         {"rebound_relative_error", (apex / 0.5 - 0.25) / 0.25},
         {"impact_time_error", dyn.contact_events().empty()
                                   ? 1.0
                                   : dyn.contact_events()[0].time - std::sqrt(2 * 0.5 / g)},
         {"max_penetration", dyn.max_penetration()},
         {"seconds", since(t0)}});
  }
  out["bounce"] = bounce;
  // a finely faceted ball (64 segments, 2k vertices) resting on a slab: the cost of a
  // resting contact whose narrow phase sees thousands of faces (9 ms a step before the
  // touching depth skipped the edge pairs; issue 13)
  {
    sim::Scene scene;
    scene.bodies.push_back(
        sim::make_rigid_body("slab", box_mesh({2, 2, 0.1}, {0, 0, -0.05}), steel));
    hold(scene, 0);
    geometry::TriMesh ball = geometry::make_sphere(0.1, 64);
    ball.V.col(2).array() -= ball.V.col(2).minCoeff();
    scene.bodies.push_back(sim::make_rigid_body("ball", ball, steel));
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    sim::Dynamics dyn(scene, 1e-3);
    const double steps = quick ? 200 : 1000;
    const auto t0 = Clock::now();
    dyn.advance_to(steps * 1e-3);
    const double seconds = since(t0);
    out["sphere64_at_rest"] = {{"steps", steps},
                               {"seconds_per_step", seconds / steps},
                               {"unconverged_solves", dyn.contact()->stats().unconverged},
                               {"max_penetration", dyn.max_penetration()},
                               {"kinetic_energy_end", dyn.kinetic_energy()}};
  }
  // a block on a 30 degree incline (mu 0.3 slides) and on a 20 degree one (mu 0.5 holds)
  auto incline = [&](double theta, double mu, double* travel, double* drift) {
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).matrix();
    const Eigen::Vector3d normal = tilt * Eigen::Vector3d::UnitZ();
    sim::Scene scene;
    scene.bodies.push_back(
        sim::make_rigid_body("slope", box_mesh({3, 1, 0.2}, -0.1 * normal, tilt), steel));
    hold(scene, 0);
    scene.bodies.push_back(
        sim::make_rigid_body("block", box_mesh({0.1, 0.08, 0.05}, 0.025 * normal, tilt), steel));
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    contact_setting(scene, mu, 0);
    sim::Dynamics dyn(scene, 1e-3);
    const Eigen::Vector3d start = dyn.states()[1].position;
    dyn.advance_to(1.0);
    const Eigen::Vector3d moved = dyn.states()[1].position - start;
    *travel = moved.dot(tilt * Eigen::Vector3d::UnitX());
    *drift = moved.norm();
  };
  double travel = 0, drift = 0;
  incline(30 * kPi / 180, 0.3, &travel, &drift);
  const double a = g * (std::sin(kPi / 6) - 0.3 * std::cos(kPi / 6));
  out["incline_slide"] = {{"angle_deg", 30},
                          {"mu", 0.3},
                          {"acceleration", 2 * travel},
                          {"expected", a},
                          {"relative_error", (2 * travel - a) / a}};
  incline(20 * kPi / 180, 0.5, &travel, &drift);
  out["incline_stick"] = {{"angle_deg", 20}, {"mu", 0.5}, {"drift_over_1s", drift}};
  // five boxes falling 1 mm onto each other, then resting
  {
    sim::Scene scene;
    scene.bodies.push_back(
        sim::make_rigid_body("floor", box_mesh({2, 2, 0.2}, {0, 0, -0.1}), steel));
    hold(scene, 0);
    for (int k = 0; k < 5; ++k)
      scene.bodies.push_back(sim::make_rigid_body(
          "box", box_mesh({0.1, 0.1, 0.1}, {0.003 * k, 0, 0.101 * k + 0.051}), steel));
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    contact_setting(scene, 0.5, 0);
    sim::Dynamics dyn(scene, 1e-3);
    dyn.advance_to(1.0);
    const std::vector<sim::RigidState> settled = dyn.states();
    const double span = quick ? 2.0 : 10.0;
    const auto t0 = Clock::now();
    dyn.advance_to(1.0 + span);
    double creep = 0, sink = 0;
    for (int k = 1; k <= 5; ++k) {
      creep = std::max(creep, (dyn.states()[k].position - settled[k].position).norm());
      sink = std::max(sink, 0.1 * (k - 0.5) - dyn.states()[k].position.z());
    }
    out["stack_of_five"] = {{"rest_seconds", span},
                            {"creep", creep},
                            {"sinking", sink},
                            {"max_penetration", dyn.max_penetration()},
                            {"steps_per_second", span / 1e-3 / since(t0)}};
  }
  // jointed bodies in contact: the joint rows held exactly in the contact solve
  // (JointSystem::mechanism_mobility), against the exact answers of two cases
  {
    // a welded pair of 0.1 m cubes on a slider along x struck at both ends at once by free
    // 50 mm cubes (1 m/s and 0.5 m/s, e = 1, no friction, no gravity): Newton's law at both
    // contacts, the pair moving as one mass
    json rows = json::array();
    for (double dt : {1e-3, 1e-4}) {
      sim::Scene scene;
      scene.bodies.push_back(
          sim::make_rigid_body("a", box_mesh({0.1, 0.1, 0.1}, {0, 0, 0}), steel));
      scene.bodies.push_back(
          sim::make_rigid_body("b", box_mesh({0.1, 0.1, 0.1}, {0.1, 0, 0}), steel));
      scene.bodies.push_back(
          sim::make_rigid_body("right", box_mesh({0.05, 0.05, 0.05}, {0.175, 0, 0}), steel));
      scene.bodies.push_back(
          sim::make_rigid_body("left", box_mesh({0.05, 0.05, 0.05}, {-0.075, 0, 0}), steel));
      scene.joints.push_back({sim::JointType::kSlider,
                              0,
                              sim::kGround,
                              Eigen::Vector3d::UnitX(),
                              Eigen::Vector3d::Zero(),
                              {}});
      scene.joints.push_back(
          {sim::JointType::kFixed, 1, 0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero(), {}});
      scene.velocities.push_back({2, Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d::Zero(), {}});
      scene.velocities.push_back({3, Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero(), {}});
      contact_setting(scene, 0, 1);
      sim::Dynamics dyn(scene, dt);
      const double m1 = scene.bodies[2].mass, m2 = scene.bodies[3].mass;
      const double pair = 2 * (m1 * -1 + m2 * 0.5) / (m1 + m2 + 2 * scene.bodies[0].mass);
      const double energy = dyn.kinetic_energy();
      const auto t0 = Clock::now();
      dyn.advance_to(0.01);
      const double seconds = since(t0);
      const auto& st = dyn.states();
      const double error = std::max(
          {std::abs(st[0].velocity.x() - pair), std::abs(st[1].velocity.x() - pair),
           std::abs(st[2].velocity.x() - (pair + 1)), std::abs(st[3].velocity.x() - (pair - 0.5))});
      rows.push_back({{"time_step", dt},
                      {"velocity_error", error},
                      {"energy_relative_error", dyn.kinetic_energy() / energy - 1},
                      {"joint_drift", dyn.max_joint_drift()},
                      {"seconds", seconds}});
    }
    out["mechanism_struck_at_both_ends"] = rows;
    // a carriage on a slider along x carrying a block on a slider along z that rests on the
    // floor (mu 0.2), 40 N along x on the carriage: (F - mu m_b g) / (m_a + m_b)
    sim::Scene scene;
    scene.bodies.push_back(
        sim::make_rigid_body("floor", box_mesh({2, 2, 0.2}, {0, 0, -0.1}), steel));
    hold(scene, 0);
    scene.bodies.push_back(
        sim::make_rigid_body("carriage", box_mesh({0.1, 0.1, 0.1}, {0, 0, 0.2}), steel));
    scene.bodies.push_back(
        sim::make_rigid_body("block", box_mesh({0.1, 0.1, 0.1}, {0, 0, 0.05}), steel));
    scene.joints.push_back({sim::JointType::kSlider,
                            1,
                            sim::kGround,
                            Eigen::Vector3d::UnitX(),
                            Eigen::Vector3d::Zero(),
                            {}});
    scene.joints.push_back(
        {sim::JointType::kSlider, 2, 1, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero(), {}});
    scene.forces.push_back({1, Eigen::Vector3d(40, 0, 0), std::nullopt, std::nullopt, 0, {}});
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    contact_setting(scene, 0.2, 0);
    sim::Dynamics dyn(scene, 1e-3);
    const auto t0 = Clock::now();
    dyn.advance_to(1.0);
    const double seconds = since(t0);
    const double expected =
        (40 - 0.2 * scene.bodies[2].mass * g) / (scene.bodies[1].mass + scene.bodies[2].mass);
    out["carriage_drags_its_block"] = {
        {"acceleration", dyn.states()[2].velocity.x()},
        {"expected", expected},
        {"relative_error", dyn.states()[2].velocity.x() / expected - 1},
        {"steps_per_second", 1000 / seconds}};
  }
  // an elastic body struck by a mechanism: two steel cubes (20 mm) welded together on a
  // slider strike a clamped rubber block (E 10 MPa, tet10 at 5 mm) at 0.5 m/s, one behind
  // the other or side by side, against the bar they make: the largest difference of their
  // speeds over the steps (the rows on the mechanism answer through its mobility)
  {
    const materials::Material rubber = rubber_material();
    const sim::Body block =
        elastic_body("block", box_mesh({0.02, 0.05, 0.03}, {0.011, 0, 0}), rubber, 0.005);
    json rows = json::array();
    for (const bool side_by_side : {false, true}) {
      auto run = [&](bool pair, double* seconds) {
        sim::Scene scene;
        scene.bodies.push_back(block);
        sim::Fix clamp;
        clamp.body = 0;
        clamp.region = sim::Region{Eigen::Vector3d(0.0209, -1, -1), Eigen::Vector3d(1, 1, 1)};
        scene.fixes.push_back(clamp);
        const Eigen::Vector3d a =
            side_by_side ? Eigen::Vector3d(-0.01, -0.01, 0) : Eigen::Vector3d(-0.03, 0, 0);
        const Eigen::Vector3d b =
            side_by_side ? Eigen::Vector3d(-0.01, 0.01, 0) : Eigen::Vector3d(-0.01, 0, 0);
        if (pair) {
          scene.bodies.push_back(sim::make_rigid_body("a", box_mesh({0.02, 0.02, 0.02}, a), steel));
          scene.bodies.push_back(sim::make_rigid_body("b", box_mesh({0.02, 0.02, 0.02}, b), steel));
          scene.joints.push_back({sim::JointType::kFixed,
                                  2,
                                  1,
                                  Eigen::Vector3d::UnitZ(),
                                  Eigen::Vector3d::Zero(),
                                  {}});
          scene.velocities.push_back({2, Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero(), {}});
        } else {
          const Eigen::Vector3d size =
              side_by_side ? Eigen::Vector3d(0.02, 0.04, 0.02) : Eigen::Vector3d(0.04, 0.02, 0.02);
          scene.bodies.push_back(sim::make_rigid_body("bar", box_mesh(size, 0.5 * (a + b)), steel));
        }
        scene.joints.push_back({sim::JointType::kSlider,
                                1,
                                sim::kGround,
                                Eigen::Vector3d::UnitX(),
                                Eigen::Vector3d::Zero(),
                                {}});
        scene.velocities.push_back({1, Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero(), {}});
        sim::Dynamics dyn(scene, 2e-4);
        std::vector<double> speeds;
        dyn.on_step([&](const sim::Dynamics& d) { speeds.push_back(d.states()[1].velocity.x()); });
        const auto t0 = Clock::now();
        dyn.advance_to(0.02);
        *seconds = since(t0);
        return speeds;
      };
      double pair_seconds = 0, bar_seconds = 0;
      const std::vector<double> bar = run(false, &bar_seconds), pair = run(true, &pair_seconds);
      double difference = 0;
      for (std::size_t k = 0; k < std::min(bar.size(), pair.size()); ++k)
        difference = std::max(difference, std::abs(pair[k] - bar[k]));
      rows.push_back({{"arrangement", side_by_side ? "side by side" : "one behind the other"},
                      {"rebound_speed", bar.empty() ? 0.0 : -bar.back()},
                      {"largest_speed_difference", difference},
                      {"pair_seconds", pair_seconds},
                      {"bar_seconds", bar_seconds}});
    }
    out["welded_pair_strikes_rubber_as_its_bar"] = rows;
  }
  // two floating elastic bodies that both press on fixed bodies: rubber cubes (20 mm, tet10
  // at 10 mm) on a steel plate (mu 0.3), one pushed into the other by 0.06 N growing over
  // 50 ms. The pushing cube's stage solves the pair with the other's supports on the plate:
  // their acceleration from their positions at 0.2, 0.3 and 0.4 s (quick: 0.1, 0.15, 0.2)
  // against (F - 2 mu m g) / 2m, and the time per step. Then (not in quick) the same cubes on a
  // loose rubber mat (160 x 40 x 10 mm, tet4 at 10 mm) lying on the plate: three floating
  // elastic bodies, each pressing on the others, their rows solved as one problem (a fifth
  // slower while they slide than stage by stage with passes where two held one: one larger
  // dense system). (A tet10 mat: 975 points on the plate, 0.46 s a step in its dense Newton
  // solves.)
  for (const bool loose : {false, true}) {
    if (loose && quick) continue;
    const materials::Material rubber = rubber_material();
    sim::Scene scene;
    scene.bodies.push_back(
        elastic_body("pusher", box_mesh({0.02, 0.02, 0.02}, {-0.0105, 0, 0.01}), rubber, 0.01));
    scene.bodies.push_back(
        elastic_body("pushed", box_mesh({0.02, 0.02, 0.02}, {0.01, 0, 0.01}), rubber, 0.01));
    const double plate_top = loose ? -0.01 : 0.0;
    scene.bodies.push_back(
        sim::make_rigid_body("plate", box_mesh({0.2, 0.2, 0.02}, {0, 0, plate_top - 0.01}), steel));
    hold(scene, 2);
    if (loose)
      scene.bodies.push_back(elastic_body("mat", box_mesh({0.16, 0.04, 0.01}, {0.02, 0, -0.005}),
                                          rubber, 0.01, false));
    contact_setting(scene, 0.3, 0);
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    sim::Force push;
    push.body = 0;
    push.force = Eigen::Vector3d(0.06, 0, 0);
    push.ramp = 0.05;
    scene.forces.push_back(push);
    sim::Dynamics dyn(scene, 2e-4);
    const double m = scene.bodies[0].mass;
    const double expected = (0.06 - 2 * 0.3 * m * g) / (2 * m);
    const auto t0 = Clock::now();
    std::array<double, 3> x{};
    const double from = quick ? 0.1 : 0.2, span = quick ? 0.05 : 0.1;
    for (int k = 0; k < 3; ++k) {
      dyn.advance_to(from + span * k);
      x[static_cast<std::size_t>(k)] = dyn.states()[1].position.x();
    }
    const double seconds = since(t0);
    const double a = (x[2] - 2 * x[1] + x[0]) / (span * span);
    json row = {{"acceleration", a},
                {"expected", expected},
                {"relative_error", a / expected - 1},
                {"steps", dyn.steps()},
                {"seconds", seconds},
                {"ms_per_step", 1e3 * seconds / static_cast<double>(dyn.steps())}};
    if (loose) {
      const sim::ElasticContactStats& st = dyn.elastic_contact_stats();
      row["shared_steps"] = st.shared_steps;
      row["shared_passes"] = st.shared_passes;
      row["shared_unsettled"] = st.shared_unsettled;
    }
    out[loose ? "elastic_cubes_pushed_together_on_a_loose_mat"
              : "elastic_cubes_pushed_together_on_a_plate"] = row;
  }
  // a floating elastic body landing flat: a free rubber slab (160 x 40 x 10 mm, 70 g, tet10
  // at 10 mm; 5 mm in full) dropped 1 mm onto a steel plate off the plate's middle, its
  // bottom nodes closing at once, its frame on the element at its centroid. Measured in mean
  // axes its contact problem is symmetric; measured from that element it was indefinite, and
  // the landing threw the slab off (forces of 1.5e6 N for a 45 N impact). The peak contact
  // force against the impact's m v / dt, the tilt at the end, how far the slab's centre ends
  // from its half-thickness, and the steps its rest skipped
  {
    json landings = json::array();
    for (const double h : quick ? std::vector<double>{0.01} : std::vector<double>{0.01, 0.005}) {
      sim::Scene scene;
      scene.bodies.push_back(elastic_body("slab", box_mesh({0.16, 0.04, 0.01}, {0.02, 0, 0.006}),
                                          rubber_material(), h));
      scene.bodies.push_back(
          sim::make_rigid_body("plate", box_mesh({0.2, 0.2, 0.02}, {0, 0, -0.01}), steel));
      hold(scene, 1);
      contact_setting(scene, 0.3, 0);
      scene.gravity = Eigen::Vector3d(0, 0, -g);
      const double dt = 2e-4;
      sim::Dynamics dyn(scene, dt);
      double peak = 0, tilt = 0;
      dyn.on_step([&](const sim::Dynamics& d) {
        peak = std::max(peak, d.contact_force());
        tilt = std::max(tilt, Eigen::AngleAxisd(d.states()[0].rotation).angle());
      });
      const auto t0 = Clock::now();
      dyn.advance_to(0.05);
      const double seconds = since(t0);
      const double impact = scene.bodies[0].mass * std::sqrt(2 * g * 1e-3) / dt;
      landings.push_back({{"mesh_size", h},
                          {"nodes", scene.bodies[0].tet_mesh.nodes.rows()},
                          {"peak_contact_force", peak},
                          {"impact_force", impact},
                          {"peak_over_impact", peak / impact},
                          {"largest_tilt", tilt},
                          {"final_tilt", Eigen::AngleAxisd(dyn.states()[0].rotation).angle()},
                          {"centre_height_error", std::abs(dyn.states()[0].position.z() - 0.005)},
                          {"max_penetration", dyn.max_penetration()},
                          {"steps", dyn.steps()},
                          {"resting_steps", dyn.elastic_contact_stats().resting_steps},
                          {"seconds", seconds}});
    }
    out["soft_slab_lands_flat"] = landings;
  }
  // piles: n^3 boxes 0.1 m, randomly tilted, dropped into a bin
  json piles = json::array();
  for (int side : quick ? std::vector<int>{3, 4} : std::vector<int>{5, 7, 10}) {
    sim::Scene scene;
    const double pitch = 0.16, width = side * pitch + 0.02;
    scene.bodies.push_back(sim::make_rigid_body(
        "floor", box_mesh({width + 0.4, width + 0.4, 0.1}, {0, 0, -0.05}), steel));
    for (int s : {-1, 1}) {
      scene.bodies.push_back(sim::make_rigid_body(
          "wall", box_mesh({0.1, width + 0.4, 2.0}, {s * (width / 2 + 0.05), 0, 1.0}), steel));
      scene.bodies.push_back(sim::make_rigid_body(
          "wall", box_mesh({width, 0.1, 2.0}, {0, s * (width / 2 + 0.05), 1.0}), steel));
    }
    for (int k = 0; k < 5; ++k) hold(scene, k);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int l = 0; l < side; ++l)
      for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
          const Eigen::Matrix3d r = (Eigen::AngleAxisd(0.3 * u(rng), Eigen::Vector3d::UnitX()) *
                                     Eigen::AngleAxisd(0.3 * u(rng), Eigen::Vector3d::UnitY()))
                                        .matrix();
          const Eigen::Vector3d c(-width / 2 + 0.01 + pitch * (i + 0.5),
                                  -width / 2 + 0.01 + pitch * (j + 0.5), 0.1 + pitch * l);
          scene.bodies.push_back(
              sim::make_rigid_body("box", box_mesh({0.1, 0.1, 0.1}, c, r), steel));
        }
    scene.gravity = Eigen::Vector3d(0, 0, -g);
    contact_setting(scene, 0.5, 0.2);
    sim::Dynamics dyn(scene, 1e-3);
    const double duration = quick ? 0.5 : 1.5;
    const auto t0 = Clock::now();
    dyn.advance_to(duration);
    const double seconds = since(t0);
    const sim::ContactSystem::Stats& st = dyn.contact()->stats();
    piles.push_back(
        {{"boxes", side * side * side},
         {"sim_seconds", duration},
         {"steps", dyn.steps()},
         {"wall_seconds", seconds},
         {"steps_per_second", static_cast<double>(dyn.steps()) / seconds},
         {"contact_points", dyn.contact_points()},
         {"kinetic_energy_end", dyn.kinetic_energy()},
         {"max_penetration", dyn.max_penetration()},
         {"solves", st.solves},
         {"sweeps_per_solve", st.solves ? static_cast<double>(st.sweeps) / st.solves : 0.0},
         {"unconverged_solves", st.unconverged},
         {"impact_cuts", st.substeps}});
  }
  out["pile"] = piles;
  return out;
}

// What each skip saves: the work with the skip and without it, and the check that the
// answer is the same either way.
json skip_row(const std::string& skip, const std::string& input, double with, double without,
              bool same, const std::string& check) {
  return {{"skip", skip},
          {"input", input},
          {"seconds_with", with},
          {"seconds_without", without},
          {"speedup", with > 0 ? without / with : NAN},
          {"same_result", same},
          {"check", check}};
}

// The named columns of a history.csv, row by row (a missing column gives no rows)
std::vector<std::vector<double>> history_columns(const fs::path& file,
                                                 const std::vector<std::string>& wanted) {
  std::ifstream csv(file);
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> names;
  for (std::stringstream head(line); std::getline(head, line, ',');) names.push_back(line);
  std::vector<std::size_t> at;
  for (const std::string& w : wanted) {
    const auto it = std::find(names.begin(), names.end(), w);
    if (it == names.end()) return {};
    at.push_back(static_cast<std::size_t>(it - names.begin()));
  }
  std::vector<std::vector<double>> rows;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stod(cell));
    std::vector<double> picked;
    for (std::size_t k : at)
      if (k < v.size()) picked.push_back(v[k]);
    if (picked.size() < at.size()) break;
    rows.push_back(std::move(picked));
  }
  return rows;
}

// Of history_columns' rows (the first column t, rows not empty), the one nearest time t
std::vector<double> nearest_row(const std::vector<std::vector<double>>& rows, double t) {
  std::size_t best = 0;
  for (std::size_t k = 0; k < rows.size(); ++k)
    if (std::abs(rows[k][0] - t) < std::abs(rows[best][0] - t)) best = k;
  return rows[best];
}

// whether two history.csv files have the same columns and rows, every number within
// `relative` of the larger of the two (and of 1)
bool histories_agree(const fs::path& a, const fs::path& b, double relative) {
  std::ifstream fa(a), fb(b);
  std::string la, lb;
  if (!std::getline(fa, la) || !std::getline(fb, lb) || la != lb) return false;
  while (true) {
    const bool more_a = static_cast<bool>(std::getline(fa, la));
    const bool more_b = static_cast<bool>(std::getline(fb, lb));
    if (more_a != more_b) return false;
    if (!more_a) return true;
    std::stringstream ra(la), rb(lb);
    for (std::string ca, cb; std::getline(ra, ca, ',');) {
      if (!std::getline(rb, cb, ',')) return false;
      const double x = std::stod(ca), y = std::stod(cb);
      if (!(std::abs(x - y) <= relative * std::max({1.0, std::abs(x), std::abs(y)}))) return false;
    }
  }
}

// the seconds `vproto ARGS` takes in-process (its messages dropped)
double timed_cli(const std::vector<std::string>& args) {
  std::ostringstream quiet;
  const auto t0 = Clock::now();
  const int code = run_cli(args, quiet);
  if (code != 0) throw std::runtime_error("vproto " + args[0] + " failed: " + quiet.str());
  return since(t0);
}

// the seconds `vproto run SCRIPT -o OUT --no-render --quiet` takes in-process
double timed_run(const fs::path& script, const fs::path& out) {
  return timed_cli({"run", script.string(), "-o", out.string(), "--no-render", "--quiet"});
}

std::string file_text(const fs::path& f) {
  std::stringstream s;
  s << std::ifstream(f, std::ios::binary).rdbuf();
  return s.str();
}

// The largest difference between two history.csv files with the same columns, each
// column's difference over the largest magnitude of its vector (the columns NAME_x, _y,
// _z together; all-zero columns and the counts skipped); the worst column's name goes to
// `worst`.
double history_difference(const fs::path& a, const fs::path& b, std::string* worst) {
  auto read = [](const fs::path& f, std::vector<std::string>* names) {
    std::ifstream csv(f);
    std::string line;
    std::getline(csv, line);
    for (std::stringstream head(line); std::getline(head, line, ',');) names->push_back(line);
    std::vector<std::vector<double>> rows;
    while (std::getline(csv, line)) {
      std::vector<double> v;
      std::stringstream row(line);
      for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stod(cell));
      rows.push_back(std::move(v));
    }
    return rows;
  };
  std::vector<std::string> na, nb;
  const auto ra = read(a, &na), rb = read(b, &nb);
  if (na != nb || ra.size() != rb.size() || ra.empty()) return INFINITY;
  // a vector's components (NAME_x/_y/_z, NAME_ux/uy/uz, ...) are measured against the
  // vector's largest component: a lateral component at round-off is no answer
  auto family = [](const std::string& n) {
    const char last = n.empty() ? ' ' : n.back();
    return n.size() > 2 && (last == 'x' || last == 'y' || last == 'z') ? n.substr(0, n.size() - 1)
                                                                       : n;
  };
  std::map<std::string, double> scale;
  for (std::size_t c = 0; c < na.size(); ++c)
    for (std::size_t r = 0; r < ra.size(); ++r) {
      if (c >= ra[r].size() || c >= rb[r].size()) return INFINITY;
      double& s = scale[family(na[c])];
      s = std::max({s, std::abs(ra[r][c]), std::abs(rb[r][c])});
    }
  double most = 0;
  for (std::size_t c = 0; c < na.size(); ++c) {
    // counts (steps, contact points) are not answers: a point more where a face grazes
    if (na[c] == "step" || na[c] == "contacts") continue;
    double diff = 0;
    for (std::size_t r = 0; r < ra.size(); ++r)
      diff = std::max(diff, std::abs(ra[r][c] - rb[r][c]));
    const double sc = scale[family(na[c])];
    if (sc > 0 && diff / sc > most) {
      most = diff / sc;
      if (worst) *worst = na[c];
    }
  }
  return most;
}

// Issue 12: the two solver backends on every FE sample (the same answers), the static
// solve of 157k dofs against CalculiX on the same mesh, and the same run on 1 and 2 MPI
// ranks.
json bench_solvers(bool quick, const fs::path& out_dir) {
  json out;
  out["petsc_built"] = sim::petsc_available();
  if (!sim::petsc_available()) return out;
  const std::string samples = VPROTO_SAMPLES_DIR;
  const fs::path work = out_dir / "solvers";
  fs::remove_all(work);
  fs::create_directories(work);
  struct Case {
    std::string sample, what;
    std::vector<std::string> options;
  };
  const std::vector<Case> cases = {
      {"cantilever.vp", "static, CG + p-multigrid", {"--set", quick ? "size=20mm" : "size=10mm"}},
      {"cantilever_vibration.vp",
       "Newmark, one kept factor",
       {"--duration", quick ? "20ms" : "100ms"}},
      {"paw_quasistatic.vp", "quasistatic with contact (compliance columns)", {}},
  };
  json agreement = json::array();
  for (const Case& c : cases) {
    json row = {{"sample", c.sample}, {"what", c.what}};
    fs::path dirs[2];
    const char* backends[2] = {"cholmod", "petsc"};
    for (int k = 0; k < 2; ++k) {
      dirs[k] = work / (fs::path(c.sample).stem().string() + "_" + backends[k]);
      std::vector<std::string> args = {"run",         samples + "/" + c.sample,
                                       "-o",          dirs[k].string(),
                                       "--solver",    backends[k],
                                       "--no-render", "--quiet"};
      args.insert(args.end(), c.options.begin(), c.options.end());
      row[std::string(backends[k]) + "_seconds"] = timed_cli(args);
      const json summary = json::parse(std::ifstream(dirs[k] / "summary.json"));
      if (summary.contains("solver") && !summary["solver"].empty())
        row[std::string(backends[k]) + "_method"] = summary["solver"].begin().value()["method"];
      if (k == 1 && summary["solver"].begin().value().contains("relative_tolerance"))
        row["petsc_relative_tolerance"] = summary["solver"].begin().value()["relative_tolerance"];
    }
    std::string worst;
    row["max_relative_difference"] =
        history_difference(dirs[0] / "history.csv", dirs[1] / "history.csv", &worst);
    row["worst_column"] = worst;
    agreement.push_back(row);
  }
  out["agreement"] = agreement;

  // a static tet10 solve of 157k dofs (the cantilever at 7 mm; 12.5 mm quick), by the
  // backend `auto` picks and by CHOLMOD, against CalculiX on the same mesh
  {
    const double h = quick ? 0.0125 : 0.007, e = 210e9, nu = 0.3, rho = 7850;
    geometry::TetMeshOptions mo;
    mo.size = h;
    const auto t0 = Clock::now();
    const geometry::TetMesh m =
        geometry::make_tet_mesh(geometry::make_box({1.0, 0.05, 0.05}, false), mo);
    const double mesh_s = since(t0);
    const auto t1 = Clock::now();
    const sim::FeMatrices fe = sim::assemble(m, e, nu, rho);
    const auto clamp = sim::boundary_nodes_in(m, {-1e-9, -1, -1}, {1e-9, 1, 1});
    const Eigen::VectorXd f =
        sim::region_force(m, {1 - 1e-9, -1, -1}, {1 + 1e-9, 1, 1}, {0, 0, -100});
    const double assemble_s = since(t1);
    json row = {{"mesh_size", h},
                {"dofs", fe.dofs},
                {"mesh_seconds", mesh_s},
                {"assemble_seconds", assemble_s}};
    Eigen::VectorXd u_auto;
    for (const char* name : {"auto", "cholmod"}) {
      sim::SolverSetup setup;
      setup.choice = sim::solver_choice_from(name);
      setup.coordinates = m.nodes;
      setup.elements = m.elements;
      setup.relative_tolerance = sim::relative_tolerance_for(h, std::sqrt(1 + 2 * 0.05 * 0.05));
      sim::SolverStats st;
      const auto t2 = Clock::now();
      const Eigen::VectorXd u = sim::solve_static(fe, f, clamp, &st, &setup);
      const double solve_s = since(t2);
      row[name] = {{"backend", st.backend},
                   {"method", st.method},
                   {"solve_seconds", solve_s},
                   {"static_seconds", assemble_s + solve_s},
                   {"tip_relative_error", f.dot(u) / 100 / 3.043e-4 - 1}};
      if (std::string(name) == "auto") u_auto = u;
    }
    const json peer = calculix_peer(m, clamp, f, u_auto, e, nu, rho, false);
    if (!peer.is_null() && peer.contains("calculix_seconds")) {
      row["calculix"] = peer;
      const double ccx = peer["calculix_seconds"].get<double>();
      row["auto_over_calculix"] = row["auto"]["static_seconds"].get<double>() / ccx;
      row["cholmod_over_calculix"] = row["cholmod"]["static_seconds"].get<double>() / ccx;
    }
    out["static_vs_calculix"] = row;
  }

  // the same static run on 1 and 2 ranks (whole processes), where mpirun is installed
  if (on_path("mpirun")) {
    std::string exe = fs::read_symlink("/proc/self/exe").string();
    // (an executable rebuilt while the bench runs reads as "PATH (deleted)")
    const std::string deleted = " (deleted)";
    if (exe.size() > deleted.size() &&
        exe.compare(exe.size() - deleted.size(), deleted.size(), deleted) == 0)
      exe.resize(exe.size() - deleted.size());
    const std::string size = quick ? "size=12.5mm" : "size=7mm";
    json rows = json::array();
    for (int ranks : {1, 2}) {
      const fs::path dir = work / ("ranks_" + std::to_string(ranks));
      // a clean environment: this process may itself be an MPI singleton (PETSc ran in
      // it above), whose variables would make mpirun's ranks join it
      const char* path = std::getenv("PATH");
      const std::string command = "env -i PATH='" + std::string(path ? path : "/usr/bin:/bin") +
                                  "' mpirun --allow-run-as-root --oversubscribe -np " +
                                  std::to_string(ranks) + " '" + exe + "' run '" + samples +
                                  "/cantilever.vp' -o '" + dir.string() + "' --set " + size +
                                  " --solver petsc --no-render --export none --quiet > '" +
                                  (work / "mpirun.log").string() + "' 2>&1";
      const auto t0 = Clock::now();
      const int code = std::system(command.c_str());
      const double wall = since(t0);
      json r = {{"ranks", ranks}, {"wall_seconds", wall}, {"exit", code}};
      if (code == 0) {
        const json summary = json::parse(std::ifstream(dir / "summary.json"));
        const json& solver = summary["solver"]["beam"];
        r["dofs"] = solver["dofs"];
        r["iterations"] = solver["iterations"];
        r["setup_seconds"] = solver["setup_seconds"];
        r["solve_seconds"] = summary["wall_time"]["solve"];
        r["tip_uz"] = summary["probes"]["tip"]["u"][2];
      }
      rows.push_back(r);
    }
    out["ranks"] = rows;
  }
  fs::remove_all(work);
  return out;
}

json bench_skips(bool quick, const fs::path& out_dir) {
  json rows = json::array();
  {
    // bounding boxes and one batched difference, against every hole through its own Boolean
    const geometry::CsgNode plate = holed_plate(quick ? 16 : 64);
    auto t0 = Clock::now();
    const geometry::TriMesh a = geometry::evaluate_csg(plate);
    const double with = since(t0);
    t0 = Clock::now();
    const geometry::TriMesh b = geometry::evaluate_csg_unskipped(plate);
    const double without = since(t0);
    const double va = geometry::mass_properties(a).volume, vb = geometry::mass_properties(b).volume;
    rows.push_back(
        skip_row("CSG: bounding boxes, one batched difference",
                 std::string("49-hole plate, ") + (quick ? "16" : "64") + " segments per hole",
                 with, without, std::abs(va - vb) <= 1e-12 * vb, "volumes equal to 1e-12"));
    // convex parts only for bodies that can touch: the split a plate nothing touches skips
    // (the quick sweep splits a plate of 3 x 3 holes)
    const geometry::TriMesh split_plate = quick ? geometry::evaluate_csg(holed_plate(16, 3)) : a;
    const double split_volume = geometry::mass_properties(split_plate).volume;
    t0 = Clock::now();
    const std::vector<geometry::TriMesh> parts = geometry::convex_parts(split_plate);
    const double split = since(t0);
    double sum = 0;
    for (const auto& part : parts) sum += geometry::mass_properties(part).volume;
    rows.push_back(skip_row("convex parts only for bodies that can touch",
                            quick ? "a plate of 3 x 3 holes, 16 segments" : "the same plate", 0,
                            split, std::abs(sum - split_volume) <= 1e-9 * split_volume,
                            std::to_string(parts.size()) +
                                " parts, their volumes summing to the plate's (what is skipped)"));
  }
  const fs::path samples(VPROTO_SAMPLES_DIR);
  if (fs::exists(samples / "snapfit.vp") && fs::exists(samples / "pendulum.vp")) {
    // the compile cache after --set: only the bodies the change reaches are rebuilt
    // (a holed plate and a block beside it; the change reaches the block only)
    const fs::path warm = out_dir / "skips" / "warm", cold = out_dir / "skips" / "cold";
    fs::remove_all(warm);
    fs::remove_all(cold);
    fs::create_directories(out_dir / "skips");
    const fs::path script = out_dir / "skips" / "plate_and_block.vp";
    std::ofstream(script) << "param block = 0.02;\n"
                             "rigid body plate (material=steel, segments=32) {\n"
                             "  difference() {\n    box([0.1, 0.1, 0.01]);\n"
                             "    for (i = [0:6]) for (j = [0:6])\n"
                             "      translate([0.01 + 0.08 / 6 * i, 0.01 + 0.08 / 6 * j, -0.001])\n"
                             "        cylinder(h=0.012, r=0.004);\n  }\n}\n"
                             "rigid body block (material=steel) { translate([0.2, 0, 0]) "
                             "box(block); }\n";
    // (the quick sweep builds the surfaces only; the full one their convex parts too)
    auto build = [&](const fs::path& dir, bool set) {
      std::vector<std::string> args = {"build", script.string(), "-o", dir.string(), "--quiet"};
      if (!quick) args.push_back("--convex");
      if (set) args.insert(args.end(), {"--set", "block=0.03"});
      return timed_cli(args);
    };
    build(warm, false);
    const double with = build(warm, true), without = build(cold, true);
    const std::string a = file_text(warm / "plate.stl"), b = file_text(cold / "plate.stl");
    const std::string ba = file_text(warm / "block.stl"), bb = file_text(cold / "block.stl");
    rows.push_back(skip_row(
        "compile cache after --set",
        std::string("49-hole plate (32 segments") + (quick ? ")" : ", convex parts)") +
            " and a block; --set block=0.03",
        with, without, !a.empty() && a == b && ba == bb, "plate.stl and block.stl byte for byte"));
    // no rendering with --no-render
    const fs::path drawn = out_dir / "skips" / "drawn", bare = out_dir / "skips" / "bare";
    fs::remove_all(drawn);
    fs::remove_all(bare);
    const std::string pendulum = (samples / "pendulum.vp").string();
    const double rendered = timed_cli({"run", pendulum, "-o", drawn.string(), "--quiet"});
    const double plain =
        timed_cli({"run", pendulum, "-o", bare.string(), "--no-render", "--quiet"});
    rows.push_back(skip_row("no rendering with --no-render", "samples/pendulum.vp", plain, rendered,
                            file_text(drawn / "history.csv") == file_text(bare / "history.csv"),
                            "history.csv byte for byte"));
    // no mesh for elastic bodies nothing loads: an ABS bracket no force, clamp or contact
    // reaches, beside a steel ball bouncing on a floor; the skip off meshes it anyway
    const fs::path lean = out_dir / "skips" / "lean", meshed = out_dir / "skips" / "meshed";
    const fs::path beside = out_dir / "skips" / "bracket_beside_a_ball.vp";
    std::ofstream(beside)
        << "elastic body bracket (material=abs, mesh_size=" << (quick ? "0.006" : "0.003")
        << ") { difference() { box([0.2, 0.1, 0.02]); translate([0.1, 0.05, -1]) "
           "cylinder(r=0.02, h=3); } }\n"
           "rigid body floor (material=steel) { translate([0.3, 0, -0.1]) box([0.3, 0.3, 0.1]); }\n"
           "rigid body ball (material=steel) { translate([0.45, 0.15, 0.3]) sphere(r=0.02); }\n"
           "fix floor;\nnocontact bracket ball;\nnocontact bracket floor;\n"
           "contact restitution=0.5;\ngravity [0, 0, -9.81];\n"
           "simulate(duration=0.5s, frames=2);\n";
    auto run_beside = [&](const fs::path& dir, bool every) {
      Options run;
      run.command = "run";
      run.file = beside.string();
      run.out_dir = dir.string();
      run.no_render = true;
      run.quiet = true;
      run.mesh_every_elastic_body = every;
      fs::remove_all(dir);
      std::ostringstream quiet;
      const auto t0 = Clock::now();
      if (command_run(run, quiet) != 0)
        throw std::runtime_error("vproto run " + beside.string() + " failed: " + quiet.str());
      return since(t0);
    };
    const double unmeshed = run_beside(lean, false), all = run_beside(meshed, true);
    const auto tets = [](const fs::path& dir) {
      const json b = json::parse(std::ifstream(dir / "build.json"));
      return b["bodies"][0].value("tets", 0L);
    };
    rows.push_back(skip_row(
        "no mesh for elastic bodies nothing loads",
        "an ABS bracket (" + std::to_string(tets(meshed)) +
            " tets when meshed) beside a ball bouncing on a floor, 0.5 s",
        unmeshed, all,
        // (1e-9: the narrow phase gives the ball's landing points in another order, 1e-11 apart,
        // in the two runs of one process, and the contact solver, converged to its tolerance,
        // passes that on as a lateral drift of 1e-10 m by the run's end)
        tets(lean) == 0 && histories_agree(lean / "history.csv", meshed / "history.csv", 1e-9),
        "history.csv, every figure to 1e-9 relative; no tets in the lean run"));
    fs::remove_all(out_dir / "skips");
  }
  {
    // one factorization per run: the cantilever's Newmark steps on the kept factor, and the
    // same steps forming and factoring the step matrix each time (its ordering kept either
    // way, so this understates what a tool that analyses every step would spend)
    const materials::Material& steel = *materials::find_builtin("steel");
    geometry::TetMeshOptions o;
    o.size = quick ? 0.025 : 0.0125;
    o.quadratic = true;
    const geometry::TetMesh m =
        geometry::make_tet_mesh(geometry::make_box({1.0, 0.05, 0.05}, false), o);
    const sim::FeMatrices fe =
        sim::assemble(m, steel.youngs_modulus, steel.poisson_ratio, steel.density);
    const auto clamp = sim::boundary_nodes_in(m, {-1e-9, -1, -1}, {1e-9, 1, 1});
    const Eigen::VectorXd f =
        sim::region_force(m, {1 - 1e-9, -1, -1}, {1 + 1e-9, 1, 1}, {0, 0, -100});
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(fe.dofs);
    const int steps = 100;
    auto run = [&](bool refactor, Eigen::VectorXd* u) {
      const auto t0 = Clock::now();
      sim::ElasticDynamics dyn(fe, clamp, 2e-4);
      dyn.start(0, zero, zero, f);
      for (int k = 0; k < steps; ++k) {
        if (refactor) dyn.refactor();
        dyn.step(f);
      }
      *u = dyn.displacement();
      return since(t0);
    };
    Eigen::VectorXd kept, again;
    const double with = run(false, &kept), without = run(true, &again);
    rows.push_back(
        skip_row("one factorization per run",
                 "cantilever, tet10, " + std::to_string(fe.dofs) + " dofs, " +
                     std::to_string(steps) + " Newmark steps under a sudden tip load",
                 with, without,
                 (kept - again).lpNorm<Eigen::Infinity>() <= 1e-12 * kept.lpNorm<Eigen::Infinity>(),
                 "the displacements after the last step to 1e-12 of their largest"));
  }
  {
    // islands: boxes dropped from staggered heights onto a fixed floor, each its own island
    // (the floor links nothing); as one island, every box's landing cuts every box's step
    // and every solve takes all the points
    const int side = quick ? 4 : 6;
    sim::Scene scene;
    scene.bodies.push_back(
        sim::make_rigid_body("floor", box_mesh({2, 2, 0.1}, {0, 0, -0.05}), 7850));
    hold(scene, 0);
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j)
        scene.bodies.push_back(sim::make_rigid_body(
            "box",
            box_mesh({0.1, 0.1, 0.1},
                     {-0.5 + 0.2 * i, -0.5 + 0.2 * j, 0.1 + 0.013 * (i * side + j)}),
            7850));
    scene.gravity = Eigen::Vector3d(0, 0, -9.81);
    contact_setting(scene, 0.5, 0.3);
    auto run = [&](bool islands, std::vector<Eigen::Vector3d>* at) {
      sim::ContactOptions o;
      o.islands = islands;
      const auto t0 = Clock::now();
      sim::Dynamics dyn(scene, 1e-3, o);
      dyn.advance_to(0.8);
      for (const auto& st : dyn.states()) at->push_back(st.position);
      return since(t0);
    };
    std::vector<Eigen::Vector3d> apart, together;
    const double with = run(true, &apart), without = run(false, &together);
    double worst = 0;
    for (std::size_t k = 0; k < apart.size(); ++k)
      worst = std::max(worst, (apart[k] - together[k]).norm());
    rows.push_back(skip_row(
        "islands",
        std::to_string(side * side) + " boxes dropped from staggered heights onto a floor, 0.8 s",
        with, without, worst <= 1e-9, "every box's resting position to 1e-9 m"));
  }
  {
    // rigid until contact: a floating elastic block falling 0.2 m onto a floor; without
    // the skip its FE state is advanced from the first step
    const materials::Material& abs = *materials::find_builtin("abs");
    sim::Scene scene;
    scene.bodies.push_back(
        elastic_body("block", box_mesh({0.1, 0.1, 0.05}, {0, 0, 0.225}), abs, 0.0125));
    scene.bodies.push_back(
        sim::make_rigid_body("floor", box_mesh({0.4, 0.4, 0.1}, {0, 0, -0.05}), 7850));
    hold(scene, 1);
    scene.gravity = Eigen::Vector3d(0, 0, -9.81);
    scene.simulation.duration = 0.3;
    scene.simulation.frames = 7;
    auto run = [&](bool skip, Eigen::Vector3d* at, long* skipped) {
      sim::ContactOptions co;
      co.rigid_until_contact = skip;
      const auto t0 = Clock::now();
      sim::Dynamics dyn(scene, sim::run_time_step(scene), co);
      dyn.advance_to(scene.simulation.duration);
      *at = dyn.states()[0].position;
      *skipped = dyn.elastic_contact_stats().skipped_steps;
      return since(t0);
    };
    Eigen::Vector3d skipping, full;
    long skipped = 0, none = 0;
    const double with = run(true, &skipping, &skipped), without = run(false, &full, &none);
    rows.push_back(
        skip_row("rigid until contact",
                 "an elastic ABS block (tet10, 12.5 mm) falling 0.2 m onto a floor, 0.3 s; " +
                     std::to_string(skipped) + " steps without FE",
                 with, without, skipped > 0 && none == 0 && (skipping - full).norm() <= 1e-9,
                 "the block's resting position to 1e-9 m"));
  }
  return rows;
}

// One snap-fit paw pushed over its catch (samples/paw_quasistatic.vp, quasistatic, the
// in-stroke to 0.9 in) over the mesh size (at the engine's increments) and the increment (at
// 0.1 in): the push where the lead face rides over the catch's edge (0.26 in of travel,
// interpolated between increments, so it converges with them), the lateral force while
// the apex slides on the catch's face (mean over 0.40-0.60 in) and the sampled peak,
// against CalculiX C3D10 with contact on the same meshes (bench/calculix_paw.py's run,
// kept in docs/paw_calculix.json: 191-442 s per run, too slow to repeat here).
json bench_paw(bool quick, const fs::path& out_dir) {
  const fs::path sample = fs::path(VPROTO_SAMPLES_DIR) / "paw_quasistatic.vp";
  const fs::path stored = fs::path(VPROTO_SAMPLES_DIR).parent_path() / "docs" / "paw_calculix.json";
  if (!fs::exists(sample))
    return {{"skipped", "samples/paw_quasistatic.vp not found at " + sample.string()}};
  json reference = json::array();
  if (fs::exists(stored)) {
    // Python's json writes NaN (a figure a run did not reach): read it as null
    std::string text = file_text(stored);
    for (std::size_t at = text.find("NaN"); at != std::string::npos; at = text.find("NaN", at))
      text.replace(at, 3, "null");
    reference = json::parse(text)["results"];
  }
  constexpr double inch = 0.0254, mu = 0.3;
  auto calculix = [&](double mesh) -> json {
    for (const json& r : reference)
      if (std::abs(r["mesh_in"].get<double>() - mesh) < 1e-9 &&
          std::abs(r["mu"].get<double>() - mu) < 1e-9)
        return r["calculix"];
    return nullptr;
  };
  const json finest = calculix(0.05);
  json rows = json::array();
  auto run = [&](double mesh, double increment_scale) {
    Options o;
    o.command = "run";
    o.file = sample.string();
    o.out_dir = (out_dir / "paw").string();
    o.frames = 2;
    o.no_render = true;
    o.quiet = true;
    o.duration = 0.9 / 1.1;  // the in-stroke to 0.9 in
    char m[32];
    std::snprintf(m, sizeof m, "%gin", mesh);
    o.overrides = {{"mesh", m}, {"mu", "0.3"}};
    std::ostringstream quiet;
    auto once = [&] {
      fs::remove_all(o.out_dir);
      const auto t0 = Clock::now();
      if (command_run(o, quiet) != 0) throw std::runtime_error("paw: " + quiet.str());
      return since(t0);
    };
    if (increment_scale != 1) {
      // the engine's own increment at this mesh, scaled
      once();
      const json first = json::parse(std::ifstream(fs::path(o.out_dir) / "summary.json"));
      o.dt = first["time_step"].get<double>() * increment_scale;
    }
    const double seconds = once();
    const json summary = json::parse(std::ifstream(fs::path(o.out_dir) / "summary.json"));
    // (travel m, lateral N, push N) per increment, from the holder's reaction on the paw
    std::vector<std::array<double, 3>> curve;
    for (const auto& r :
         history_columns(fs::path(o.out_dir) / "history.csv", {"t", "paw_rx", "paw_rz"}))
      curve.push_back({r[0] * 1.1 * inch, r[1], -r[2]});
    fs::remove_all(o.out_dir);
    auto at = [&](double travel, std::size_t k) {
      for (std::size_t i = 1; i < curve.size(); ++i)
        if (curve[i][0] >= travel) {
          const double w = (travel - curve[i - 1][0]) / (curve[i][0] - curve[i - 1][0]);
          return curve[i - 1][k] + w * (curve[i][k] - curve[i - 1][k]);
        }
      return std::nan("");
    };
    double peak = 0, sliding = 0;
    int sliding_rows = 0;
    for (const auto& c : curve) {
      if (c[0] <= 0.38 * inch) peak = std::max(peak, c[2]);
      if (c[0] >= 0.40 * inch && c[0] <= 0.60 * inch) {
        sliding += c[1];
        ++sliding_rows;
      }
    }
    sliding = sliding_rows ? sliding / sliding_rows : NAN;
    const double push = at(0.26 * inch, 2);
    json row = {
        {"mesh_in", mesh},
        {"mu", mu},
        {"increment_in", summary["time_step"].get<double>() * 1.1},
        {"increments", summary["steps"]},
        // (halved where a contact let go or its rows did not settle; kept unsettled)
        {"cut_increments", summary["elastic_contact"].value("cut_increments", 0L)},
        {"unsettled_increments", summary["elastic_contact"].value("unsettled_increments", 0L)},
        {"dofs", summary["solver"]["paw"]["dofs"]},
        {"seconds", seconds},
        {"push_at_0.26in_N", push},
        {"sliding_lateral_N", sliding},
        {"peak_push_N", peak}};
    // (a figure CalculiX's run did not reach is null: its difference is left out too)
    auto figure = [](const json& r, const char* key) -> std::optional<double> {
      if (r.is_null() || !r.contains(key) || !r[key].is_number()) return std::nullopt;
      return r[key].get<double>();
    };
    const json same = calculix(mesh);
    if (!same.is_null()) {
      row["calculix_push_at_0.26in_N"] = same.value("lead_push_at_0.26in_N", json());
      row["calculix_sliding_lateral_N"] = same.value("sliding_lateral_N", json());
      if (const auto f = figure(same, "lead_push_at_0.26in_N"))
        row["push_difference"] = push / *f - 1;
      if (const auto f = figure(same, "sliding_lateral_N"))
        row["sliding_difference"] = sliding / *f - 1;
      row["calculix_seconds"] = same.value("seconds", json());
    }
    if (const auto f = figure(finest, "sliding_lateral_N"))
      row["sliding_error_vs_calculix_0.05in"] = sliding / *f - 1;
    rows.push_back(row);
  };
  for (double mesh : quick ? std::vector<double>{0.1, 0.07} : std::vector<double>{0.1, 0.07, 0.05})
    run(mesh, 1);
  json by_mesh = json::array();
  std::swap(rows, by_mesh);
  run(0.1, 1);
  for (double scale :
       quick ? std::vector<double>{0.5, 0.25} : std::vector<double>{0.5, 0.25, 0.125, 0.0625})
    run(0.1, scale);
  return {{"mesh_sweep", by_mesh},
          {"increment_sweep", rows},
          {"reference", fs::exists(stored) ? "CalculiX 2.20 C3D10, node-to-face penalty contact, "
                                             "stored by bench/calculix_paw.py in "
                                             "docs/paw_calculix.json"
                                           : "docs/paw_calculix.json not found"}};
}

// The seed's case end to end, as the README's first command runs it (script to 120 frames
// at 1280x720 and the video): the time split, the contact effort per step and the figures
// a reader checks (insertion hump against Bayer's mating force, the grip at rest), against
// the 10 s target. Skipped with a line when the sample is not where the build put it.
// Elastic bodies that share a movable rigid body, their rows solved as one problem
// (Dynamics::stage_group): a steel beam resting on two clamped rubber pads (20 mm, graded
// tet4 of 5 mm, mu 0.5) under a push that grows to 0.3 N over 50 ms, which the pads'
// friction holds; alike, they carry half of it each (the error: the larger share's
// distance from a half). Then (not in quick) samples/block_on_beam_on_rubber_feet.vp: the
// feet's and the block's rows as one problem, its contact stage's time and Newton
// iterations; and two rubber blocks pushed together on a fixed table (below).
// out_dir / name, emptied: a bench's scripts and runs
fs::path fresh_subdir(const fs::path& out_dir, const std::string& name) {
  const fs::path dir = out_dir / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

json bench_joint(bool quick, const fs::path& out_dir) {
  const fs::path dir = fresh_subdir(out_dir, "joint");
  const fs::path script = dir / "pads_under_a_beam.vp";
  std::ofstream(script)
      << "units length=mm;\n"
         "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; }\n"
         "elastic body left (material=rubber, mesh_size=5mm, element=tet4) {\n"
         "  translate([-50, -10, -10]) box([20, 20, 10]);\n}\n"
         "elastic body right (material=rubber, mesh_size=5mm, element=tet4) {\n"
         "  translate([30, -10, -10]) box([20, 20, 10]);\n}\n"
         "rigid body beam (material=steel) { translate([-50, -10, 0]) box([100, 20, 10]); }\n"
         "fix left region=box([-60, -20, -10.1], [-20, 20, -9.9]);\n"
         "fix right region=box([20, -20, -10.1], [60, 20, -9.9]);\n"
         "gravity [0, 0, -9.81m/s^2];\n"
         "contact left beam friction=0.5;\ncontact right beam friction=0.5;\n"
         "nocontact left right;\nforce beam [0.3N, 0, 0] ramp=0.05s;\n"
         "simulate(mode=dynamic, duration=0.1s, frames=2, dt=1.5ms);\n";
  auto contact_of = [](const fs::path& run) {
    std::ifstream in(run / "summary.json");
    return json::parse(in).value("elastic_contact", json::object());
  };
  json out;
  {
    const fs::path run = dir / "pads";
    const double seconds = timed_run(script, run);
    const auto rows = history_columns(run / "history.csv", {"left_rx", "right_rx"});
    const json ec = contact_of(run);
    const double left = rows.empty() ? 0.0 : rows.back()[0],
                 right = rows.empty() ? 0.0 : rows.back()[1];
    const double total = left + right;
    out["pads_under_a_beam_share_a_push"] = {
        {"left_share", total != 0 ? left / total : 0.0},
        {"right_share", total != 0 ? right / total : 0.0},
        {"error", total != 0 ? std::max(left / total, right / total) - 0.5 : 1.0},
        {"seconds", seconds},
        {"contact_seconds", ec.value("seconds", 0.0)},
        {"newton_iterations", ec.value("newton_iterations", 0L)},
        {"joint_solves", ec.value("joint_solves", 0L)},
        {"shared_passes", ec.value("shared_passes", 0L)}};
  }
  // a sample run without rendering into dir / `name`: its time, or none where the sample
  // is not where the build put it
  auto run_sample = [&](const std::string& sample, const std::string& name) {
    const fs::path file = fs::path(VPROTO_SAMPLES_DIR) / sample;
    std::optional<double> seconds;
    if (fs::exists(file)) seconds = timed_run(file, dir / name);
    return seconds;
  };
  if (const auto seconds =
          quick ? std::nullopt : run_sample("block_on_beam_on_rubber_feet.vp", "block_on_beam")) {
    const json ec = contact_of(dir / "block_on_beam");
    out["block_on_beam_on_rubber_feet"] = {{"seconds", *seconds},
                                           {"contact_seconds", ec.value("seconds", 0.0)},
                                           {"newton_iterations", ec.value("newton_iterations", 0L)},
                                           {"joint_solves", ec.value("joint_solves", 0L)},
                                           {"joint_rows", ec.value("joint_rows", 0L)},
                                           {"shared_passes", ec.value("shared_passes", 0L)}};
  }
  // two rubber blocks pushed together on a fixed table, samples/rubber_blocks_pushed.vp
  // (0.15 N, mu 0.5): the pair's rows and the pushed block's on the table as one problem;
  // the acceleration they slide on with, from the history's positions at 50, 100 and
  // 150 ms, against (F - 2 mu m g) / 2m
  if (const auto seconds =
          quick ? std::nullopt : run_sample("rubber_blocks_pushed.vp", "blocks_pushed")) {
    const fs::path run = dir / "blocks_pushed";
    const json ec = contact_of(run);
    const json b = json::parse(std::ifstream(run / "build.json"));
    const double m = b["bodies"][1].value("mass", 0.0), g = 9.81, mu = 0.5, f = 0.15;
    const double expected = (f - 2 * mu * m * g) / (2 * m);
    const auto rows = history_columns(run / "history.csv", {"t", "pusher_x", "pushed_x"});
    auto at = [&](double t) { return nearest_row(rows, t); };
    double error = 1;
    if (rows.size() > 3) {
      const auto x0 = at(0.05), x1 = at(0.10), x2 = at(0.15);
      const double h = x1[0] - x0[0];
      error = 0;
      for (std::size_t c : {1u, 2u})
        error =
            std::max(error, std::abs((x2[c] - 2 * x1[c] + x0[c]) / (h * h) - expected) / expected);
    }
    out["blocks_pushed_on_a_table"] = {{"seconds", *seconds},
                                       {"contact_seconds", ec.value("seconds", 0.0)},
                                       {"acceleration_error", error},
                                       {"newton_iterations", ec.value("newton_iterations", 0L)},
                                       {"joint_solves", ec.value("joint_solves", 0L)},
                                       {"shared_passes", ec.value("shared_passes", 0L)}};
  }
  // two rubber blocks on a loose rubber mat on the table (those of
  // samples/rubber_blocks_pushed_on_loose_mat.vp), touching, one pushed against the other
  // with 0.06 N, below their friction (0.086 N), at 1.9 ms steps: the mat's stage solves
  // both blocks' rows on it, the pusher's their pair, as one problem. They should stay
  // put: `creep` is the most any of the three moved from 0.2 s to 0.4 s (m); and sleep
  // (`resting_steps`)
  if (!quick) {
    const fs::path mat_script = dir / "blocks_pressed_on_a_loose_mat.vp";
    std::ofstream(mat_script)
        << "units length=mm;\n"
           "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; friction = 0.5; }\n"
           "rigid body table (material=steel) { translate([-60, -40, -20]) box([160, 80, 10]); }\n"
           "elastic body mat (material=rubber, mesh_size=10mm, element=tet4) {\n"
           "  translate([-40, -20, -10]) box([120, 40, 10]); }\n"
           "elastic body pusher (material=rubber, mesh_size=10mm, element=tet4) {\n"
           "  translate([-20, -10, 0]) box([20, 20, 20]); }\n"
           "elastic body pushed (material=rubber, mesh_size=10mm, element=tet4) {\n"
           "  translate([0, -10, 0]) box([20, 20, 20]); }\n"
           "fix table;\ngravity [0, 0, -9.81m/s^2];\ncontact table mat friction=0.3;\n"
           "force pusher [0.06N, 0, 0] ramp=0.05s;\n"
           "simulate(mode=dynamic, duration=0.4s, frames=36);\n";
    const fs::path run = dir / "blocks_pressed_on_mat";
    const double seconds = timed_run(mat_script, run);
    const json ec = contact_of(run);
    const std::vector<std::string> columns{"t",        "mat_x",    "mat_y",    "mat_z",
                                           "pusher_x", "pusher_y", "pusher_z", "pushed_x",
                                           "pushed_y", "pushed_z"};
    const auto rows = history_columns(run / "history.csv", columns);
    auto at = [&](double t) { return nearest_row(rows, t); };
    double creep = 1;
    if (rows.size() > 3) {
      const auto x0 = at(0.2), x1 = at(0.4);
      creep = 0;
      for (std::size_t c = 1; c < columns.size(); ++c)
        creep = std::max(creep, std::abs(x1[c] - x0[c]));
    }
    out["blocks_pressed_on_a_loose_mat"] = {
        {"seconds", seconds},
        {"contact_seconds", ec.value("seconds", 0.0)},
        {"creep", creep},
        {"resting_steps", ec.value("resting_steps", 0L)},
        {"newton_iterations", ec.value("newton_iterations", 0L)},
        {"joint_solves", ec.value("joint_solves", 0L)},
        {"shared_passes", ec.value("shared_passes", 0L)}};
  }
  return out;
}

// A steel block (20 x 20 x 10 mm) lying on a clamped rubber pad (60 x 60 x 10 mm, friction
// 0.3), pushed along with a force growing at 3 N/s to 0.3 N at 0.1 s, 0.5 ms steps: held by
// friction until 31 ms, then sliding. How still the held block is (`held_kinetic_energy`,
// the most from 5 to 28 ms: it tilts a little on the pad as the push grows) and how fast it
// slides at 0.15 s, sqrt(2 E / m) from the kinetic energy, against the exact slide's speed
// (`sliding_speed_error`). (Both were the step's artifacts of a velocity Verlet step with the
// pad's impulse at its start: 1.0e-7 J, and 1.4e-3, half a step's friction fast; now
// 1.9e-12 J and 1.2e-4.)
json bench_held_on_rubber(const fs::path& out_dir) {
  const fs::path dir = fresh_subdir(out_dir, "held_on_rubber");
  const fs::path script = dir / "block_on_pad.vp";
  std::ofstream(script)
      << "units length=mm;\n"
         "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; }\n"
         "elastic body pad (material=rubber, mesh_size=5mm, element=tet4) {\n"
         "  translate([-30, -30, -10]) box([60, 60, 10]); }\n"
         "rigid body block (material=steel) { translate([-10, -10, 0]) box([20, 20, 10]); }\n"
         "fix pad region=box([-31, -31, -10.1], [31, 31, -9.9]);\n"
         "gravity [0, 0, -9.81m/s^2];\ncontact pad block friction=0.3;\n"
         "force block [0.3N, 0, 0] ramp=0.1s;\n"
         "simulate(mode=dynamic, duration=0.15s, dt=0.5ms, frames=4);\n";
  const fs::path run = dir / "run";
  const double seconds = timed_run(script, run);
  const json b = json::parse(std::ifstream(run / "build.json"));
  const double m = b["bodies"][1].value("mass", 0.0), g = 9.81, mu = 0.3, k = 3.0;
  const double ts = mu * m * g / k, v1 = k * (0.1 - ts) * (0.1 - ts) / (2 * m);
  const double speed = v1 + (0.3 - mu * m * g) / m * 0.05;  // at 0.15 s
  const auto rows = history_columns(run / "history.csv", {"t", "kinetic_energy"});
  double held = 0, error = 1;
  for (const auto& row : rows)
    if (row[0] > 0.005 && row[0] < ts - 0.002) held = std::max(held, row[1]);
  if (!rows.empty() && m > 0) error = std::sqrt(2 * rows.back()[1] / m) / speed - 1;
  return {{"seconds", seconds},
          {"held_kinetic_energy", held},
          {"sliding_speed", speed},
          {"sliding_speed_error", error}};
}

json bench_snapfit(const fs::path& out_dir, std::ostream& err) {
  const fs::path sample = fs::path(VPROTO_SAMPLES_DIR) / "snapfit.vp";
  if (!fs::exists(sample))
    return {{"skipped", "samples/snapfit.vp not found at " + sample.string() +
                            " (run vproto bench from the build tree of a source checkout)"}};
  Options run;
  run.command = "run";
  run.file = sample.string();
  run.out_dir = (out_dir / "snapfit").string();
  run.frames = 120;
  run.quiet = true;
  fs::remove_all(run.out_dir);
  const auto t0 = Clock::now();
  command_run(run, err);
  const double seconds = since(t0);
  const json s = json::parse(std::ifstream(fs::path(run.out_dir) / "summary.json"));
  const json& e = s["elastic_contact"];
  // the insertion hump: the contact force against the push over the first 10 mm
  double z0 = std::nan(""), hump = 0;
  for (const auto& r :
       history_columns(fs::path(run.out_dir) / "history.csv", {"socket_z", "socket_cz"})) {
    if (std::isnan(z0)) z0 = r[0];
    if (z0 - r[0] < 0.010) hump = std::max(hump, r[1]);
  }
  // Bayer: the two paws' mating force, W = 2 P (mu + tan a) / (1 - mu tan a)
  const double in = 0.0254,
               p = 0.25e9 * std::pow(0.5 * in, 4) * (0.099 * in) / (4 * std::pow(2 * in, 3));
  const double mating = 2 * p * 1.3 / 0.7;
  return {{"seconds", seconds},
          {"target_seconds", 10.0},
          {"ratio_to_target", seconds / 10.0},
          {"wall_time", s["wall_time"]},
          {"steps", s["steps"]},
          {"steps_with_rows", e["steps_with_rows"]},
          {"rows_per_step", e["rows_per_step"]},
          {"delassus_size", e["delassus_size"]},
          {"contact_seconds_per_step", e["seconds_per_step"]},
          {"column_seconds", e["column_seconds"]},
          {"delassus_seconds", e["delassus_seconds"]},
          {"solve_seconds", e["solve_seconds"]},
          {"unconverged_solves", e["unconverged_solves"]},
          {"factorizations", s["solver"]["socket"]["factorizations"]},
          {"insertion_hump", hump},
          {"bayer_mating_force", mating},
          {"insertion_hump_vs_bayer", hump / mating - 1},
          {"grip_reaction_at_rest", s["bodies"][0]["reaction"][2]},
          {"push", -50 * 4.4482216152605},
          {"max_penetration", e["max_penetration"]},
          {"newton_iterations", e["newton_iterations"]},
          {"response_solves", e["response_solves"]},
          {"region_nodes", e["region_nodes"]},
          {"surface_nodes", e["surface_nodes"]}};
}

}  // namespace

int command_bench(const Options& o, std::ostream& err) {
  if (o.stress) return command_stress(o, err);
  const auto t0 = Clock::now();
  Progress progress(err, o.quiet);
  const fs::path out(o.out_dir);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || ::access(out.c_str(), W_OK) != 0)
    throw InputError(SourceLoc{o.out_dir, 0, 0}, "cannot write to the output folder");
  const bool quick = o.quick;
  progress.stage("csg: 49-hole plate");
  json csg = bench_csg(quick ? 1 : 3);
  progress.stage("csg: the holes' segments, work against precision");
  csg["segments_sweep"] = bench_csg_segments(quick);
  progress.stage("csg: the same plate in OpenSCAD and Manifold, where installed");
  csg["peers"] = bench_csg_peers(quick, 64);
  progress.stage("render: frames per second at 1280x720");
  const json render = bench_render(quick ? std::vector<long>{10'000, 100'000}
                                         : std::vector<long>{10'000, 100'000, 1'000'000});
  progress.stage("rigid: torque-free tumbling, work against precision");
  const json rigid = bench_rigid(quick);
  progress.stage("joints: a pendulum's period, work against precision");
  const json pendulum = bench_pendulum(quick);
  progress.stage("elastic: cantilever statics, frequency and Newmark, work against precision");
  const json elastic = bench_elastic(quick);
  progress.stage("contact: bounce, incline, stack, piles of boxes");
  json contact = bench_contact(quick);
  progress.stage("contact: elastic bodies sharing a rigid body, their rows as one problem");
  contact["joint"] = bench_joint(quick, out);
  progress.stage("contact: a steel block held, then pushed along, on a rubber pad");
  contact["held_on_rubber"] = bench_held_on_rubber(out);
  progress.stage("skips: each with and without");
  const json skips = bench_skips(quick, out);
  progress.stage("snap-fit paw: insertion forces over the mesh size and the increment");
  const json paw = bench_paw(quick, out);
  progress.stage("solvers: CHOLMOD and PETSc on the FE samples, against CalculiX, 1 and 2 ranks");
  const json solvers = bench_solvers(quick, out);
  json doc = {{"quick", quick},    {"csg", csg},           {"render", render},
              {"rigid", rigid},    {"elastic", elastic},   {"contact", contact},
              {"skips", skips},    {"pendulum", pendulum}, {"paw", paw},
              {"solvers", solvers}};
  if (!quick) {
    progress.stage("snap-fit: the seed's case end to end (120 frames, video)");
    doc["snapfit"] = bench_snapfit(out, err);
  }
  doc["total_seconds"] = since(t0);
  doc["machine"] = machine_description();
  doc["commit"] = source_commit();
  write_text_atomically(out / "bench.json", doc.dump(2) + "\n");
  progress.stage("report: DIR/report.html");
  write_bench_report(doc, out);
  if (!o.quiet) err << doc.dump(2) << "\n";
  return 0;
}

}  // namespace vproto::ui_batch::detail
