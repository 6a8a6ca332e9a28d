// `vproto run`: build, simulate with the step loop this version has (free rigid bodies:
// sim::FreeMotion), and drive the animation writer. What the loop cannot honour is
// refused before any work.
#include <filesystem>
#include <sstream>

#include "cli_support.h"
#include "vproto/sim/free_motion.h"
#include "vproto/sim/static_solve.h"
#include "vproto/ui_batch/animation_writer.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Per-surface-vertex field of one body in the current state: |u| for displacement,
// zero stress for a rigid-moving elastic body (nothing loads it elastically).
Eigen::VectorXd field_of(const sim::Scene& scene, const sim::FreeMotion& motion, int body,
                         const std::string& field) {
  const sim::Body& b = scene.bodies[body];
  if (field == "displacement") {
    Eigen::VectorXd u(b.surface.V.rows());
    for (Eigen::Index v = 0; v < b.surface.V.rows(); ++v)
      u[v] = motion.displacement(body, b.surface.V.row(v).transpose()).norm();
    return u;
  }
  if (field == "von_mises" && b.kind == sim::BodyKind::kElastic)
    return Eigen::VectorXd::Zero(b.surface.V.rows());
  return {};
}

}  // namespace

int command_run(const Options& o, std::ostream& err) {
  const auto t0 = Clock::now();
  Progress progress(err, o.quiet);
  modeler::EvaluatedScript script = load(o, progress, err);
  sim::Scene& scene = script.scene;
  const double parse_seconds = since(t0);

  // command-line overrides of simulate(), render() and export()
  sim::SimulationSettings& st = scene.simulation;
  if (o.mode)
    st.mode = *o.mode == "static"        ? sim::SimulationMode::kStatic
              : *o.mode == "quasistatic" ? sim::SimulationMode::kQuasistatic
                                         : sim::SimulationMode::kDynamic;
  if (o.duration) st.duration = *o.duration;
  if (o.dt) st.time_step = *o.dt;
  if (o.frames) st.frames = *o.frames;
  if (o.size) {
    scene.render.width = o.size->first;
    scene.render.height = o.size->second;
  }
  if (o.export_format) scene.output.format = *o.export_format;
  if (st.time_step && *st.time_step > st.duration)
    throw InputError(kCommandLine, "--dt is longer than the duration");

  // what this version can honestly run: static equilibrium of elastic bodies, or free
  // rigid motion
  const bool static_mode = st.mode == sim::SimulationMode::kStatic;
  if (static_mode) {
    sim::check_static_supported(scene);
  } else {
    sim::check_free_motion_supported(scene);
    if (scene.output.format == "vtu")
      throw InputError(kCommandLine,
                       "vtu export carries elastic fields, which this version computes in "
                       "mode=static only; use --export stl or obj, or --mode static");
  }
  const double time_step = st.time_step ? *st.time_step : std::min(1e-3, st.duration / 1000);
  const std::string field = scene.render.field;
  bool field_on_some_body = field == "none" || field == "displacement";
  for (const auto& b : scene.bodies) field_on_some_body |= b.kind == sim::BodyKind::kElastic;
  if (!field_on_some_body)
    throw InputError(SourceLoc{o.file, 0, 0},
                     "render field=von_mises, but no body has it: only elastic bodies carry "
                     "stress; declare a body 'elastic' or use field=displacement or none");

  // geometry
  modeler::CompileOptions copts;
  const fs::path out(o.out_dir);
  copts.cache_dir = out / ".vproto-cache";
  copts.load_mesh = read_mesh;
  copts.tet_meshes = static_mode;
  copts.progress = [&](const std::string& line, int done, int total) {
    progress.update(line, done, total);
  };
  const modeler::CompileReport report = modeler::compile_bodies(script, copts);
  const double build_seconds = since(t0);

  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out) || ::access(out.c_str(), W_OK) != 0)
    throw InputError(SourceLoc{o.out_dir, 0, 0}, "cannot write to the output folder" +
                                                     (ec ? ": " + ec.message() : std::string()));
  write_build_json(out, o, script, report, parse_seconds, 0.0, t0);
  if (static_mode) return run_static(o, scene, out, progress, t0, build_seconds);

  const int frames = st.frames;
  auto frame_time = [&](int k) { return frames > 1 ? st.duration * k / (frames - 1) : 0.0; };
  const std::string unit = field == "von_mises" ? "Pa" : field == "displacement" ? "m" : "";

  // a first pass finds where the bodies go, so the camera is fitted once for the whole run
  geometry::Bounds run_bounds;
  {
    sim::FreeMotion probe_motion(scene, time_step);
    try {
      for (int k = 0; k < frames; ++k) {
        probe_motion.advance_to(frame_time(k));
        run_bounds.extend(frame_bounds(scene, probe_motion.frame(k)));
      }
    } catch (const SimulationError&) {
      run_bounds.extend(frame_bounds(scene, probe_motion.frame(0)));  // reported by the real pass
    }
  }
  AnimationOptions ao;
  ao.out_dir = out;
  ao.render = !o.no_render;
  ao.render_options.width = scene.render.width;
  ao.render_options.height = scene.render.height;
  ao.render_options.title = fs::path(o.file).filename().string();
  const double aspect = static_cast<double>(scene.render.width) / scene.render.height;
  ao.camera = scene.render.camera == "custom" ? look_at(scene.render.eye, scene.render.target)
                                              : fit_camera(scene.render.camera, run_bounds, aspect);
  ao.ground_z = run_bounds.lo.z();
  ao.mesh_format = scene.output.format;
  ao.export_every = scene.output.every;

  std::ostringstream history;
  history << history_header(scene);
  history.precision(17);
  auto history_row = [&](const sim::FreeMotion& m) {
    history << m.time() << "," << m.steps() << ",0,0," << m.kinetic_energy() << ",0,"
            << m.external_work() << ",0";
    for (const auto& s : m.states())
      history << "," << s.position.x() << "," << s.position.y() << "," << s.position.z();
    for (const auto& p : scene.probes) {
      const Eigen::Vector3d u = m.displacement(p.body, p.point);
      history << "," << u.x() << "," << u.y() << "," << u.z();
    }
    history << "\n";
  };

  sim::FreeMotion motion(scene, time_step);
  double simulate_seconds = 0;
  std::string failure;
  AnimationWriter writer(scene, ao);
  history_row(motion);
  motion.on_step(history_row);
  try {
    for (int k = 0; k < frames; ++k) {
      const auto ts = Clock::now();
      motion.advance_to(frame_time(k));
      simulate_seconds += since(ts);
      sim::Frame f = motion.frame(k);
      f.field = field;
      f.field_unit = unit;
      if (field != "none")
        for (std::size_t i = 0; i < scene.bodies.size(); ++i)
          f.bodies[i].field = field_of(scene, motion, static_cast<int>(i), field);
      writer.push(std::move(f));
      progress.update("simulate and render", k + 1, frames);
    }
  } catch (const SimulationError& e) {
    failure = e.what();  // the frames made so far are kept
  }
  writer.finish();
  const AnimationStats& as = writer.stats();

  write_text_atomically(out / "history.csv", history.str());
  json probes = json::object();
  for (const auto& p : scene.probes)
    probes[p.name] = {{"u", vec_json(motion.displacement(p.body, p.point))}};
  json bodies = json::array();
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const auto& s = motion.states()[i];
    const Eigen::Quaterniond q = s.rotation.normalized();
    bodies.push_back({{"name", scene.bodies[i].name},
                      {"position", vec_json(s.position)},
                      {"rotation", json::array({q.w(), q.x(), q.y(), q.z()})},
                      {"max_von_mises", 0.0},
                      {"max_strain", 0.0}});
  }
  const char* modes[] = {"static", "quasistatic", "dynamic"};
  RunReport run_report;
  run_report.status = failure.empty() ? "ok" : "failed";
  run_report.mode = modes[static_cast<int>(st.mode)];
  run_report.reason = failure;
  run_report.time_step = time_step;
  run_report.steps = motion.steps();
  run_report.sim_time = motion.time();
  run_report.build_seconds = build_seconds;
  run_report.simulate_seconds = simulate_seconds;
  run_report.start = t0;
  run_report.probes = probes;
  run_report.bodies = bodies;
  run_report.kinetic_energy = motion.kinetic_energy();
  run_report.external_work = motion.external_work();
  write_summary(out, run_report, as);
  if (!failure.empty()) throw SimulationError(failure);
  progress.stage("done: " + std::to_string(frames) + " frames -> " + o.out_dir);
  progress.finish();
  return 0;
}

}  // namespace vproto::ui_batch::detail
