// `vproto run`: build, then drive the animation writer. Until the simulators land, only
// scenes in which nothing acts (no loads, drives, gravity or initial velocities) can run:
// every body stays exactly at rest, and the frames show that honestly.
#include <filesystem>
#include <sstream>

#include "cli_support.h"
#include "vproto/ui_batch/animation_writer.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The first statement that would make something move, or none.
std::optional<std::pair<std::string, SourceLoc>> first_action(const sim::Scene& s) {
  if (!s.forces.empty()) return std::make_pair(std::string("force"), s.forces[0].loc);
  if (!s.torques.empty()) return std::make_pair(std::string("torque"), s.torques[0].loc);
  if (!s.moves.empty()) return std::make_pair(std::string("move"), s.moves[0].loc);
  if (!s.velocities.empty()) return std::make_pair(std::string("velocity"), s.velocities[0].loc);
  if (s.gravity && s.gravity->norm() > 0) {
    // gravity moves every body that is not fixed to the ground
    for (std::size_t i = 0; i < s.bodies.size(); ++i) {
      bool held = false;
      for (const auto& f : s.fixes) held = held || (f.body == static_cast<int>(i) && !f.region);
      if (!held) return std::make_pair(std::string("gravity"), s.bodies[i].loc);
    }
  }
  return std::nullopt;
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

  // what this version can honestly run
  if (const auto action = first_action(scene))
    throw InputError(action->second,
                     "this scene has a " + action->first +
                         ", so its bodies move, and the dynamics simulator is not in this version "
                         "yet; 'vproto run' can only animate scenes in which nothing acts. Use "
                         "'vproto build' for the geometry");
  if (scene.output.format == "vtu")
    throw InputError(kCommandLine,
                     "vtu export needs the elastic bodies' volume meshes, which this "
                     "version does not make yet; use --export stl or obj");
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

  // nothing acts: every body rests at its start, exactly
  const int frames = st.frames;
  sim::Frame rest = start_frame(scene);
  rest.field = field;
  rest.field_unit = field == "von_mises" ? "Pa" : field == "displacement" ? "m" : "";
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const bool carries = field == "displacement" ||
                         (field == "von_mises" && scene.bodies[i].kind == sim::BodyKind::kElastic);
    if (carries) rest.bodies[i].field = Eigen::VectorXd::Zero(scene.bodies[i].surface.V.rows());
  }

  AnimationOptions ao;
  ao.out_dir = out;
  ao.render = !o.no_render;
  ao.render_options.width = scene.render.width;
  ao.render_options.height = scene.render.height;
  ao.render_options.title = fs::path(o.file).filename().string();
  const geometry::Bounds bounds = frame_bounds(scene, rest);  // the whole run: nothing moves
  const double aspect = static_cast<double>(scene.render.width) / scene.render.height;
  ao.camera = scene.render.camera == "custom" ? look_at(scene.render.eye, scene.render.target)
                                              : fit_camera(scene.render.camera, bounds, aspect);
  ao.ground_z = bounds.lo.z();
  ao.mesh_format = scene.output.format;
  ao.export_every = scene.output.every;

  const auto t_frames = Clock::now();
  std::ostringstream history;
  history
      << "t,step,contacts,contact_force,kinetic_energy,strain_energy,external_work,max_von_mises";
  for (const auto& b : scene.bodies)
    history << "," << b.name << "_x," << b.name << "_y," << b.name << "_z";
  for (const auto& p : scene.probes)
    history << "," << p.name << "_ux," << p.name << "_uy," << p.name << "_uz";
  history << "\n";
  history.precision(17);
  {
    AnimationWriter writer(scene, ao);
    for (int k = 0; k < frames; ++k) {
      sim::Frame f = rest;
      f.index = k;
      f.time = frames > 1 ? st.duration * k / (frames - 1) : 0.0;
      history << f.time << "," << k << ",0,0,0,0,0,0";
      for (const auto& b : rest.bodies)
        history << "," << b.position.x() << "," << b.position.y() << "," << b.position.z();
      for (std::size_t p = 0; p < scene.probes.size(); ++p) history << ",0,0,0";
      history << "\n";
      writer.push(std::move(f));
      progress.update("frames", k + 1, frames);
    }
    writer.finish();
    const AnimationStats& as = writer.stats();

    write_text_atomically(out / "history.csv", history.str());
    json probes = json::object();
    for (const auto& p : scene.probes) probes[p.name] = {{"u", json::array({0.0, 0.0, 0.0})}};
    json bodies = json::array();
    for (std::size_t i = 0; i < scene.bodies.size(); ++i)
      bodies.push_back({{"name", scene.bodies[i].name},
                        {"position", vec_json(rest.bodies[i].position)},
                        {"rotation", json::array({1.0, 0.0, 0.0, 0.0})},
                        {"max_von_mises", 0.0},
                        {"max_strain", 0.0}});
    const char* modes[] = {"static", "quasistatic", "dynamic"};
    const json summary = {
        {"status", "ok"},
        {"mode", modes[static_cast<int>(st.mode)]},
        {"note", "no loads, drives, gravity or initial velocities act: every body stays at rest"},
        {"steps", 0},
        {"sim_time", st.duration},
        {"frames", as.frames_rendered},
        {"meshes", as.meshes_written},
        {"video", as.video_written},
        {"wall_time",
         {{"build", build_seconds},
          {"mesh", 0.0},
          {"assemble", 0.0},
          {"factor", 0.0},
          {"simulate", 0.0},
          {"render", as.render_seconds},
          {"export", as.export_seconds},
          {"video", as.video_seconds},
          {"frames_total", since(t_frames)},
          {"total", since(t0)}}},
        {"events", json::array()},
        {"peak_contact_force", 0.0},
        {"probes", probes},
        {"bodies", bodies},
        {"energy",
         {{"kinetic", 0.0}, {"strain", 0.0}, {"external_work", 0.0}, {"dissipated", 0.0}}}};
    write_text_atomically(out / "summary.json", summary.dump(2) + "\n");
  }
  progress.stage("done: " + std::to_string(frames) + " frames -> " + o.out_dir);
  progress.finish();
  return 0;
}

}  // namespace vproto::ui_batch::detail
