// `vproto run`: build, simulate with the step loop this version has (sim::Dynamics: free,
// fixed and driven rigid bodies; held and loaded elastic bodies by FE), and drive the
// animation writer. What the loop cannot honour is refused before any work.
#include <filesystem>
#include <optional>
#include <sstream>

#include "cli_support.h"
#include "vproto/sim/dynamics.h"
#include "vproto/sim/run_history.h"
#include "vproto/sim/static_solve.h"
#include "vproto/sim/tet_locator.h"
#include "vproto/ui_batch/animation_writer.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/plot.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

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
  if (o.solver) st.solver = sim::solver_choice_from(*o.solver);
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
    if (st.mode == sim::SimulationMode::kQuasistatic) sim::check_quasistatic_supported(scene);
    sim::check_dynamics_supported(scene);
  }
  const std::vector<char> fe_bodies = sim::finite_element_bodies(scene);
  const bool any_fe = std::find(fe_bodies.begin(), fe_bodies.end(), 1) != fe_bodies.end();
  if (!static_mode && scene.output.format == "vtu" && !any_fe)
    throw InputError(kCommandLine,
                     "vtu export writes the volume meshes of elastic bodies that are held or "
                     "loaded, and this scene has none; use --export stl or obj");
  // the step divides the frame interval, so every step has the same length and an
  // elastic body's factor serves the whole run (sim::run_time_step; sim::Dynamics lowers
  // it for contact and the tolerance)
  const double time_step = sim::run_time_step(scene);
  // a bound on the steps, before anything is meshed (dt 1e-9 s ran for an hour towards a
  // 100 GB history; issue 13)
  if (!static_mode)
    sim::check_step_count(st, time_step, st.time_step ? "the dt given" : "the default step",
                          o.dt ? kCommandLine : SourceLoc{o.file, 0, 0});
  const std::string field = scene.render.field;
  bool field_on_some_body = field == "none" || field == "displacement";
  for (const auto& b : scene.bodies) field_on_some_body |= b.kind == sim::BodyKind::kElastic;
  if (!field_on_some_body)
    throw InputError(SourceLoc{o.file, 0, 0},
                     "render field=" + field +
                         ", but no body has it: only elastic bodies carry stress and strain; "
                         "declare a body 'elastic' or use field=displacement or none");
  if (field == "yield")
    for (const auto& b : scene.bodies)
      if (b.kind == sim::BodyKind::kElastic && !materials::has_yield(b.material))
        throw InputError(b.loc,
                         "render field=yield shows each elastic body's stress and strain "
                         "as a fraction of its material's yield, and body '" +
                             b.name + "' is of material '" + b.material.name +
                             "', which gives neither; give that material a "
                             "yield_strength or a yield_strain, or use field=von_mises "
                             "or strain");

  // geometry: what the run builds (modeler::run_compile_options: tet meshes only for what
  // the FE solver advances, convex parts only for what can touch, meshes graded towards
  // contact partners)
  const fs::path out(o.out_dir);
  modeler::CompileOptions copts =
      modeler::run_compile_options(scene, static_mode, o.mesh_every_elastic_body);
  copts.cache_dir = o.cache_dir.empty() ? out / ".vproto-cache" : fs::path(o.cache_dir);
  copts.load_mesh = read_mesh;
  copts.progress = [&](const std::string& line, int done, int total) {
    progress.update(line, done, total);
  };
  copts.defer_cache = true;  // written with the outputs, once the input is accepted
  modeler::CompileReport report = modeler::compile_bodies(script, copts);
  const double build_seconds = since(t0);
  if (!o.quiet)
    for (const std::string& w : report.warnings) err << w << "\n";

  // Setting up the solve can still find bad input (a region that selects no node, a probe
  // outside its body): it is done before anything is written.
  for (const auto& p : scene.probes) {
    const sim::Body& b = scene.bodies[p.body];
    if (b.meshed && !sim::TetLocator(b.tet_mesh).locate(p.point))
      throw InputError(p.loc, "probe point is outside body '" + b.name + "'");
  }
  std::vector<sim::ElasticSolution> solutions;
  std::unique_ptr<sim::Dynamics> dynamics;
  const auto t_setup = Clock::now();
  if (static_mode) {
    progress.stage("solve: static equilibrium");
    solutions = sim::solve_static_scene(scene);
  } else {
    progress.stage(any_fe ? "assemble and factor" : "simulate");
    dynamics = std::make_unique<sim::Dynamics>(scene, time_step);
    // and on the step the engine chose (contact, tolerance)
    sim::check_step_count(st, dynamics->time_step(), dynamics->time_step_reason(),
                          SourceLoc{o.file, 0, 0});
  }
  const double setup_seconds = since(t_setup);

  const OutputFolder folder(out);  // locked and cleared of an earlier run's outputs
  modeler::commit_cache(report);
  write_build_json(out, o, script, report, parse_seconds, 0.0, t0);
  if (static_mode)
    return run_static(o, scene, solutions, setup_seconds, out, progress, t0, build_seconds,
                      report.tetmesh_seconds, err);

  const int frames = st.frames;
  auto frame_time = [&](int k) { return frames > 1 ? st.duration * k / (frames - 1) : 0.0; };
  sim::Dynamics& motion = *dynamics;
  // what the bodies start with (an initial `velocity`): dissipated energy is what is
  // missing from it plus the loads' work at the end
  const double start_energy = motion.kinetic_energy() + motion.strain_energy();

  // the camera is fitted once for the whole run, from the one simulation: scenes of rigid
  // bodies only keep their frames (poses, a few hundred bytes each) until the run ends and
  // are rendered then, fitted to where the bodies went; scenes with FE bodies stream their
  // frames to the renderer as the run goes, fitted to the bodies' bounds grown by their
  // drives' travel
  const bool fit_after_run = !any_fe;
  geometry::Bounds run_bounds = frame_bounds(scene, motion.frame(0, "none"));
  if (!fit_after_run)
    for (const auto& m : scene.moves) {
      geometry::Bounds moved = geometry::bounds(scene.bodies[m.body].surface);
      moved.lo += m.by;
      moved.hi += m.by;
      run_bounds.extend(moved);
    }
  AnimationOptions ao;
  ao.out_dir = out;
  ao.render = !o.no_render;
  ao.render_options.width = scene.render.width;
  ao.render_options.height = scene.render.height;
  ao.render_options.title = fs::path(o.file).filename().string();
  ao.render_options.deform_scale = scene.render.deform_scale;
  if (scene.render.deform_scale != 1) {
    char t[64];
    std::snprintf(t, sizeof t, " (deformation x%g)", scene.render.deform_scale);
    ao.render_options.title += t;
  }
  const double aspect = static_cast<double>(scene.render.width) / scene.render.height;
  auto fit_view = [&](const geometry::Bounds& bounds) {
    ao.camera = scene.render.camera == "custom" ? look_at(scene.render.eye, scene.render.target)
                                                : fit_camera(scene.render.camera, bounds, aspect);
    ao.ground_z = bounds.lo.z();
  };
  fit_view(run_bounds);
  ao.mesh_format = scene.output.format == "vtu" ? "none" : scene.output.format;
  ao.export_every = scene.output.every;
  // a fixed colour scale makes frames comparable; stress is not known ahead, so the
  // legend follows each frame's range (field_max = 0)

  // history.csv's rows and the force curves, step by step (sim::RunHistory)
  sim::RunHistory history(scene, motion);
  const int drive = history.drive();
  double simulate_seconds = 0;
  std::string failure;
  std::optional<AnimationWriter> writer;
  if (!fit_after_run) writer.emplace(scene, ao);
  std::vector<sim::Frame> kept_frames;  // rigid scenes: rendered once the run's bounds are known
  VtuSeries vtu(out);
  history.record(motion);
  motion.on_step([&](const sim::Dynamics& m) { history.record(m); });
  try {
    for (int k = 0; k < frames; ++k) {
      const auto ts = Clock::now();
      motion.advance_to(frame_time(k));
      simulate_seconds += since(ts);
      if (scene.output.format == "vtu" && k % std::max(1, scene.output.every) == 0)
        for (std::size_t i = 0; i < scene.bodies.size(); ++i)
          if (const Eigen::VectorXd* u = motion.nodal_displacement(static_cast<int>(i))) {
            const sim::Body& b = scene.bodies[i];
            const Eigen::MatrixX3d u_rows =
                Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
                    u->data(), b.tet_mesh.nodes.rows(), 3);
            vtu.add(b, static_cast<int>(i), k, motion.time(), u_rows,
                    vtu_fields(b, motion.nodal_von_mises(static_cast<int>(i)),
                               motion.nodal_strain(static_cast<int>(i))));
          }
      sim::Frame frame = motion.frame(k, field);
      if (fit_after_run) {
        run_bounds.extend(frame_bounds(scene, frame));
        kept_frames.push_back(std::move(frame));
      } else {
        writer->push(std::move(frame));
      }
      progress.update(fit_after_run ? "simulate" : "simulate and render", k + 1, frames);
    }
  } catch (const SimulationError& e) {
    failure = e.what();  // the frames made so far are kept
  }
  if (fit_after_run) {
    fit_view(run_bounds);
    writer.emplace(scene, ao);
    const int count = static_cast<int>(kept_frames.size());
    for (int k = 0; k < count; ++k) {
      writer->push(std::move(kept_frames[static_cast<std::size_t>(k)]));
      if (ao.render) progress.update("render", k + 1, count);
    }
  }
  writer->finish();
  vtu.finish();
  AnimationStats as = writer->stats();
  as.export_seconds += vtu.seconds();  // the volume meshes are exported too

  write_text_atomically(out / "history.csv", history.csv());
  if (motion.elastic_contact() && !motion.elastic_contact_stats().step_records.empty())
    write_text_atomically(out / "contact_steps.csv",
                          contact_steps_csv(scene, motion.elastic_contact_stats().step_records));
  json reaction_curves = json::object();
  for (const sim::ForceCurve& curve : history.reaction_curves()) {
    const std::string& name = scene.bodies[static_cast<std::size_t>(curve.body)].name;
    json c = {{"against", drive >= 0 ? "travel of " + scene.bodies[drive].name + " (mm)" : "t (s)"},
              {"force", drive >= 0 ? "reaction along the drive (N)" : "reaction magnitude (N)"},
              {"peak_push", curve.largest()},
              {"peak_pull", curve.smallest()}};
    if (drive >= 0) c["direction"] = vec_json(history.drive_direction());
    if (ao.render) {
      fs::create_directories(out / "plots");
      const std::string file = "plots/" + name + "_reaction.png";
      PlotOptions po;
      po.title = fs::path(o.file).filename().string() + ": force the holders apply to " + name;
      po.x_label =
          drive >= 0 ? "travel of " + scene.bodies[drive].name + " along the drive (mm)" : "t (s)";
      po.y_label = drive >= 0 ? "reaction along the drive (N)" : "reaction (N)";
      write_line_plot({{name, curve.x, curve.y}}, po, (out / file).string());
      c["plot"] = file;
    }
    reaction_curves[name] = c;
  }
  json insertion_curves = json::object();
  for (const sim::PushedBody& p : history.pushed()) {
    const std::string& name = scene.bodies[static_cast<std::size_t>(p.body)].name;
    const double peak = p.curve.largest();
    json c = {{"against", "travel of " + name + " along its push (mm)"},
              {"force", "contact force against the push (N)"},
              {"direction", vec_json(p.direction)},
              {"peak", peak}};
    if (ao.render) {
      fs::create_directories(out / "plots");
      const std::string file = "plots/" + name + "_insertion.png";
      PlotOptions po;
      po.title = fs::path(o.file).filename().string() + ": contact force on " + name;
      po.x_label = "travel of " + name + " along its push (mm)";
      po.y_label = "contact force against the push (N)";
      // drawn up to twice the push: an impact's spike (a landing stopped within a step)
      // would flatten the insertion itself; the title gives its peak
      PlotSeries drawn{name, p.curve.x, p.curve.y};
      const double cap = 2 * p.push;
      if (!p.curve.y.empty() && peak > cap) {
        for (double& y : drawn.y) y = std::min(y, cap);
        char note[96];
        std::snprintf(note, sizeof note, " (peak %.3g N off scale)", peak);
        po.title += note;
      }
      write_line_plot({drawn}, po, (out / file).string());
      c["plot"] = file;
    }
    insertion_curves[name] = c;
  }
  // the hot-spot strain at each FE body's sharp inside corners against time, beside its
  // material's yield strain: how near the yield a snap-fit arm's root comes, and when
  json corner_plots = json::object();
  if (ao.render)
    for (const sim::ForceCurve& curve : history.corner_strain_curves()) {
      const sim::Body& body = scene.bodies[static_cast<std::size_t>(curve.body)];
      fs::create_directories(out / "plots");
      const std::string file = "plots/" + body.name + "_corner_strain.png";
      PlotOptions po;
      po.title = fs::path(o.file).filename().string() + ": strain at the sharp inside corners of " +
                 body.name + " (hot-spot)";
      po.x_label = "t (s)";
      po.y_label = "largest principal strain (%)";
      PlotSeries strain{"hot-spot strain", curve.x, curve.y};
      for (double& y : strain.y) y *= 100;
      std::vector<PlotSeries> series{strain};
      if (body.material.yield_strain && !curve.x.empty())
        series.push_back({"yield_strain",
                          {curve.x.front(), curve.x.back()},
                          {100 * *body.material.yield_strain, 100 * *body.material.yield_strain},
                          Rgb{214, 39, 40}});
      write_line_plot(series, po, (out / file).string());
      corner_plots[body.name] = file;
    }
  json probes = json::object();
  for (const auto& p : scene.probes)
    probes[p.name] = {{"u", vec_json(motion.displacement(p.body, p.point))}};
  const std::vector<sim::ElasticStatus> elastic = motion.elastic_status();
  json bodies = json::array();
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const auto& s = motion.states()[i];
    const Eigen::Quaterniond q = s.rotation.normalized();
    json b = {{"name", scene.bodies[i].name},
              {"position", vec_json(s.position)},
              {"rotation", json::array({q.w(), q.x(), q.y(), q.z()})},
              {"max_von_mises", 0.0},
              {"max_strain", 0.0}};
    for (const auto& e : elastic)
      if (e.body == static_cast<int>(i)) {
        b["max_von_mises"] = e.max_von_mises;
        b["max_strain"] = e.max_principal_strain;
        add_material_peaks(scene.bodies[i], e.peaks, &b);
        if (corner_plots.contains(scene.bodies[i].name) && b.contains("sharp_corner_hot_spot"))
          b["sharp_corner_hot_spot"]["plot"] = corner_plots[scene.bodies[i].name];
        if (e.peaks.yielded_at >= 0 && !o.quiet)
          err << "warning: " << yield_sentence(scene.bodies[i], e.peaks) << "\n";
        b["reaction"] = vec_json(e.reaction);
        b["peak_reaction"] = e.peak_reaction;
        b["strain_energy"] = e.strain_energy;
      }
    bodies.push_back(b);
  }
  const char* modes[] = {"static", "quasistatic", "dynamic"};
  RunReport run_report;
  run_report.status = failure.empty() ? "ok" : "failed";
  run_report.mode = modes[static_cast<int>(st.mode)];
  run_report.reason = failure;
  run_report.time_step = motion.time_step();
  if (!motion.time_step_reason().empty()) run_report.time_step_reason = motion.time_step_reason();
  if (st.time_step && std::abs(motion.time_step() - *st.time_step) > 1e-9 * *st.time_step) {
    // say when the given dt was not the one used (issue 13: it was cut silently)
    run_report.extra["time_step_requested"] = *st.time_step;
    if (motion.time_step_reason().empty()) {
      char why[200];
      std::snprintf(why, sizeof why,
                    "the dt given, %.6g s, cut to divide the frame interval (%.6g s) into "
                    "whole steps",
                    *st.time_step, st.frames > 1 ? st.duration / (st.frames - 1) : st.duration);
      run_report.time_step_reason = why;
    }
  }
  run_report.steps = motion.steps();
  run_report.sim_time = motion.time();
  run_report.build_seconds = build_seconds;
  run_report.mesh_seconds = report.tetmesh_seconds;
  run_report.assemble_seconds = motion.assemble_seconds();
  run_report.factor_seconds = motion.factor_seconds();
  run_report.simulate_seconds = simulate_seconds;
  run_report.start = t0;
  run_report.probes = probes;
  run_report.bodies = bodies;
  run_report.kinetic_energy = motion.kinetic_energy();
  run_report.strain_energy = motion.strain_energy();
  run_report.external_work = motion.external_work();
  // whatever the work did not go into: Rayleigh and Newmark's numerical damping (and
  // round-off, about 1e-12 of the work, when nothing damps)
  if (!scene.joints.empty()) run_report.extra["max_joint_drift"] = motion.max_joint_drift();
  if (!reaction_curves.empty()) run_report.extra["reaction_curves"] = reaction_curves;
  if (!insertion_curves.empty()) run_report.extra["insertion_curves"] = insertion_curves;
  {
    // contact events (the first 10,000; a rattling pile can make far more)
    const std::vector<sim::ContactEvent>& ev = motion.contact_events();
    const std::size_t kept = std::min<std::size_t>(ev.size(), 10000);
    json events = json::array();
    for (std::size_t k = 0; k < kept; ++k)
      events.push_back({{"t", ev[k].time},
                        {"type", ev[k].added ? "contact_added" : "contact_removed"},
                        {"bodies", json::array({scene.bodies[ev[k].body_a].name,
                                                scene.bodies[ev[k].body_b].name})}});
    run_report.extra["events"] = events;
    if (kept < ev.size()) run_report.extra["events_total"] = ev.size();
    run_report.extra["peak_contact_force"] = motion.peak_contact_force();
    if (const sim::ContactSystem* c = motion.contact()) {
      const sim::ContactSystem::Stats& cs = c->stats();
      run_report.extra["contact"] = {{"max_penetration", motion.max_penetration()},
                                     {"distance_queries", cs.queries},
                                     {"solves", cs.solves},
                                     {"sweeps", cs.sweeps},
                                     {"impact_substeps", cs.substeps},
                                     {"unconverged_solves", cs.unconverged},
                                     {"worst_residual", cs.worst_residual}};
    }
  }
  if (motion.elastic_contact()) {
    const sim::ElasticContactStats& es = motion.elastic_contact_stats();
    run_report.contact_seconds = es.seconds;
    run_report.extra["elastic_contact"] = {
        {"max_penetration", es.max_penetration},
        {"max_penetration_time", es.max_penetration_time},
        {"steps_with_rows", es.steps},
        {"rows_per_step", es.steps ? static_cast<double>(es.rows) / es.steps : 0.0},
        {"max_points", es.max_points},
        {"delassus_size", 3 * es.max_points},
        {"sweeps", es.sweeps},
        {"newton_iterations", es.newton_iterations},
        {"unconverged_solves", es.unconverged},
        {"worst_residual", es.worst_residual},
        {"response_solves", es.response_solves},
        {"correction_solves", es.correction_solves},
        {"column_drops", es.column_drops},
        {"region_nodes", es.region_nodes},
        {"surface_nodes", es.surface_nodes},
        {"lazy_solves", es.lazy_solves},
        {"lazy_points", es.lazy_points},
        {"lazy_columns", es.lazy_columns},
        {"seconds", es.seconds},
        {"seconds_per_step", es.steps ? es.seconds / es.steps : 0.0},
        {"column_seconds", es.column_seconds},
        {"delassus_seconds", es.delassus_seconds},
        {"solve_seconds", es.solve_seconds},
        {"rigid_only_steps", es.skipped_steps},
        {"resting_steps", es.resting_steps},
        {"cut_increments", es.cut_increments},
        {"unsettled_increments", es.unsettled_increments},
        {"shared_steps", es.shared_steps},
        {"shared_passes", es.shared_passes},
        {"shared_unsettled", es.shared_unsettled},
        {"joint_solves", es.joint_solves},
        {"joint_rows", es.joint_rows},
        {"threads", es.threads}};
    if (!es.step_records.empty()) {
      // the dearest step: where a run's contact time goes (every step: contact_steps.csv)
      const auto slowest =
          std::max_element(es.step_records.begin(), es.step_records.end(),
                           [](const auto& a, const auto& b) { return a.seconds < b.seconds; });
      run_report.extra["elastic_contact"]["slowest_step"] = {
          {"t", slowest->time},
          {"body", scene.bodies[static_cast<std::size_t>(slowest->body)].name},
          {"points", slowest->points},
          {"pressed", slowest->pressed},
          {"passes", slowest->passes},
          {"seconds", slowest->seconds}};
      run_report.extra["elastic_contact"]["steps_file"] = "contact_steps.csv";
    }
    // quasi-static increments kept unsettled: said, with the first one's place and fix
    if (!es.first_unsettled.empty()) {
      run_report.extra["elastic_contact"]["first_unsettled"] = es.first_unsettled;
      if (!o.quiet)
        err << "warning: " << es.unsettled_increments
            << " quasi-static increment(s) kept unsettled; the first: " << es.first_unsettled
            << "\n";
    }
  }
  run_report.dissipated = start_energy + run_report.external_work - run_report.kinetic_energy -
                          run_report.strain_energy;
  if (any_fe) {
    run_report.note =
        st.mode == sim::SimulationMode::kQuasistatic
            ? "elastic bodies: linear elasticity, an equilibrium with contact at every increment "
              "on one factor (no inertia); reaction is the force the clamps and grips apply to "
              "the body"
            : "elastic bodies: linear elastodynamics, Newmark average acceleration on one "
              "factor; reaction is the force the clamps and grips apply to the body";
    for (const std::string& n : motion.notes()) run_report.note += "; " + n;
    run_report.solver = json::object();
    for (const auto& e : elastic) {
      run_report.solver[scene.bodies[e.body].name] =
          solver_json(*motion.factor_stats(e.body), motion.nodal_displacement(e.body)->size());
    }
  }
  write_summary(out, run_report, as);
  if (!failure.empty()) throw SimulationError(failure);
  progress.stage("done: " + std::to_string(frames) + " frames -> " + o.out_dir);
  progress.finish();
  return 0;
}

}  // namespace vproto::ui_batch::detail
