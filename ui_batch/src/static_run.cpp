// `vproto run` with mode=static: elastic equilibrium, shown as the load ramps from 0 to 1
// (the problem is linear, so every frame is the solution scaled by its load factor).
#include <sstream>

#include "cli_support.h"
#include "vproto/sim/run_history.h"
#include "vproto/sim/static_solve.h"
#include "vproto/sim/tet_locator.h"
#include "vproto/ui_batch/animation_writer.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch::detail {

namespace fs = std::filesystem;
using nlohmann::json;

int run_static(const Options& o, const sim::Scene& scene,
               const std::vector<sim::ElasticSolution>& solutions, double solve_seconds,
               const fs::path& out, Progress& progress, Clock::time_point start,
               double build_seconds, double mesh_seconds, std::ostream& err) {
  // each elastic body's surface vertices located once in its tet mesh
  struct SurfaceMap {
    const sim::ElasticSolution* solution = nullptr;
    Eigen::MatrixX3d u;              ///< displacement at each surface vertex
    Eigen::VectorXd von_mises;       ///< nodal-averaged stress at each surface vertex
    Eigen::VectorXd strain;          ///< the same for the largest principal strain
    Eigen::VectorXd yield;           ///< the nodes' yield ratios there (materials::yield_ratio)
    std::vector<char> concentrated;  ///< at a sharp inside corner: left out of the scale's top
  };
  std::vector<SurfaceMap> maps(scene.bodies.size());
  for (const auto& sol : solutions) {
    const sim::Body& b = scene.bodies[sol.body];
    const sim::TetLocator locator(b.tet_mesh);
    const Eigen::SparseMatrix<double> at_surface =
        sim::interpolation_matrix(b.tet_mesh, locator, b.drawn().V);
    const Eigen::MatrixXd u_nodes =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
            sol.displacement.data(), b.tet_mesh.nodes.rows(), 3);
    SurfaceMap& sm = maps[sol.body];
    sm.solution = &sol;
    sm.u = at_surface * u_nodes;
    sm.von_mises = at_surface * sol.nodal_von_mises;
    sm.strain = at_surface * sol.nodal_strain;
    sm.yield = at_surface * sim::yield_ratios(b.material, sol.nodal_von_mises, sol.nodal_strain);
    sm.concentrated = sim::flagged_points(at_surface, sol.concentrated_nodes);
  }

  const sim::SimulationSettings& st = scene.simulation;
  const std::string field = scene.render.field;
  AnimationOptions ao;
  ao.out_dir = out;
  ao.render = !o.no_render;
  ao.render_options.width = scene.render.width;
  ao.render_options.height = scene.render.height;
  ao.render_options.title = fs::path(o.file).filename().string() + " (static)";
  const sim::Frame rest = start_frame(scene);
  const geometry::Bounds bounds = frame_bounds(scene, rest);
  ao.camera =
      scene.render.camera == "custom"
          ? look_at(scene.render.eye, scene.render.target)
          : fit_camera(scene.render.camera, bounds,
                       static_cast<double>(ao.render_options.width) / ao.render_options.height);
  ao.ground_z = bounds.lo.z();
  ao.mesh_format = scene.output.format == "vtu" ? "none" : scene.output.format;
  ao.export_every = scene.output.every;
  // the colour map spans the final field, so the ramp brightens as the load grows; a
  // stress or strain map up to its value away from sharp inside corners (their peaks in
  // the top colour), as the dynamic frames' scale
  for (const auto& sm : maps) {
    if (!sm.solution) continue;
    if (field == "displacement") {
      ao.render_options.field_max =
          std::max(ao.render_options.field_max, sm.u.rowwise().norm().maxCoeff());
      continue;
    }
    const Eigen::VectorXd& f = field == "strain" ? sm.strain : sm.von_mises;
    double top = 0, own_top = 0;
    bool own = false;
    for (Eigen::Index v = 0; v < f.size(); ++v) {
      top = std::max(top, f[v]);
      if (!sm.concentrated[static_cast<std::size_t>(v)])
        own_top = std::max(own_top, f[v]), own = true;
    }
    ao.render_options.field_max =
        std::max(ao.render_options.field_max, own && own_top > 0 ? own_top : top);
  }
  if (!(ao.render_options.field_max > 0)) ao.render_options.field_max = 1;

  const int frames = st.frames;
  std::ostringstream history;
  history.precision(17);
  history << sim::history_header(scene);

  // probes: shape-function interpolation in elastic bodies, rigid ones stay put
  std::vector<Eigen::Vector3d> probe_u(scene.probes.size(), Eigen::Vector3d::Zero());
  for (std::size_t p = 0; p < scene.probes.size(); ++p) {
    const auto& pr = scene.probes[p];
    const SurfaceMap& sm = maps[pr.body];
    if (!sm.solution) continue;
    const sim::Body& b = scene.bodies[pr.body];
    const sim::TetLocator locator(b.tet_mesh);
    const auto at = locator.locate(pr.point);
    if (!at) throw InputError(pr.loc, "probe point is outside body '" + b.name + "'");
    const Eigen::MatrixXd u_nodes =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
            sm.solution->displacement.data(), b.tet_mesh.nodes.rows(), 3);
    probe_u[p] = locator.interpolate(*at, u_nodes).transpose();
  }

  double total_strain = 0, total_work = 0, peak_vm = 0;
  for (const auto& sol : solutions) {
    total_strain += sol.strain_energy;
    total_work += sol.external_work;
    peak_vm = std::max(peak_vm, sol.max_von_mises);
  }
  AnimationWriter writer(scene, ao);
  VtuSeries vtu(out);
  for (int k = 0; k < frames; ++k) {
    const double load = frames > 1 ? static_cast<double>(k) / (frames - 1) : 1.0;
    sim::Frame f = rest;
    f.index = k;
    f.time = load * st.duration;
    f.field = field;
    f.field_unit = field == "von_mises" ? "Pa" : field == "displacement" ? "m" : "";
    for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
      const SurfaceMap& sm = maps[i];
      if (!sm.solution) continue;
      f.bodies[i].deformed = scene.bodies[i].drawn().V + load * sm.u;
      if (field == "von_mises") f.bodies[i].field = load * sm.von_mises;
      if (field == "strain") f.bodies[i].field = load * sm.strain;
      if (field == "yield") f.bodies[i].field = load * sm.yield;
      if (field == "displacement") f.bodies[i].field = load * sm.u.rowwise().norm();
    }
    writer.push(std::move(f));
    // volume meshes with fields, for ParaView
    if (scene.output.format == "vtu" && k % std::max(1, scene.output.every) == 0) {
      for (const auto& sol : solutions) {
        const sim::Body& b = scene.bodies[sol.body];
        const Eigen::Index nodes = b.tet_mesh.nodes.rows();
        auto as_rows = [&](const Eigen::VectorXd& v) {
          return Eigen::MatrixX3d(
              load * Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
                         v.data(), nodes, 3));
        };
        // the nodal loads and held nodes go along, so a peer solver can be given the
        // very same problem (bench/calculix_compare.py)
        Eigen::MatrixXd held = Eigen::MatrixXd::Zero(nodes, 1);
        for (int v : sol.held_nodes) held(v, 0) = 1;
        std::vector<PointField> fields =
            vtu_fields(b, load * sol.nodal_von_mises, load * sol.nodal_strain);
        fields.emplace_back("load", as_rows(sol.load));
        fields.emplace_back("held", held);
        vtu.add(b, sol.body, k, f.time, as_rows(sol.displacement), fields);
      }
    }
    history << f.time << "," << k << ",0,0,0," << load * load * total_strain << ","
            << load * load * total_work << "," << load * peak_vm;
    for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
      const Eigen::Vector3d c = scene.bodies[i].mass_properties.centroid;
      history << "," << c.x() << "," << c.y() << "," << c.z();
    }
    for (const auto& u : probe_u)
      history << "," << load * u.x() << "," << load * u.y() << "," << load * u.z();
    history << "\n";
    progress.update("render", k + 1, frames);
  }
  writer.finish();
  vtu.finish();
  AnimationStats as = writer.stats();
  as.export_seconds += vtu.seconds();  // the volume meshes are exported too
  write_text_atomically(out / "history.csv", history.str());

  json probes = json::object();
  for (std::size_t p = 0; p < scene.probes.size(); ++p)
    probes[scene.probes[p].name] = {{"u", vec_json(probe_u[p])}};
  json bodies = json::array();
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const SurfaceMap& sm = maps[i];
    bodies.push_back({{"name", scene.bodies[i].name},
                      {"position", vec_json(scene.bodies[i].mass_properties.centroid)},
                      {"rotation", json::array({1.0, 0.0, 0.0, 0.0})},
                      {"max_von_mises", sm.solution ? sm.solution->max_von_mises : 0.0},
                      {"max_strain", sm.solution ? sm.solution->max_principal_strain : 0.0}});
    if (sm.solution) {
      bodies.back()["reaction"] = vec_json(sm.solution->reaction);
      // the load ramps from 0 to 1 over the duration: the peaks' load factors as times
      sim::MaterialPeaks peaks = sm.solution->peaks;
      for (sim::FieldPeak* f : {&peaks.von_mises, &peaks.strain, &peaks.bulk_von_mises,
                                &peaks.bulk_strain, &peaks.regular_von_mises, &peaks.regular_strain,
                                &peaks.corner_von_mises, &peaks.corner_strain})
        if (f->time >= 0) f->time *= st.duration;
      for (double* t : {&peaks.yielded_at, &peaks.bulk_yielded_at, &peaks.regular_yielded_at,
                        &peaks.corner_yielded_at})
        if (*t >= 0) *t *= st.duration;
      add_material_peaks(scene.bodies[i], peaks, &bodies.back());
      if (peaks.yielded_at >= 0 && !o.quiet)
        err << "warning: " << yield_sentence(scene.bodies[i], peaks) << "\n";
    }
  }
  RunReport run_report;
  run_report.mode = "static";
  run_report.note =
      "linear static equilibrium; frames ramp the load from 0 to 1 (t is the load factor "
      "times the duration)";
  run_report.steps = 1;
  run_report.sim_time = st.duration;
  run_report.build_seconds = build_seconds;
  run_report.simulate_seconds = solve_seconds;
  // the stages of the solve: assembly, the factor (analysis and numeric), the triangular
  // solves, and the figures taken from the answer
  run_report.mesh_seconds = mesh_seconds;
  double solves = 0, figures = 0;
  for (const auto& sol : solutions) {
    run_report.assemble_seconds += sol.assemble_seconds;
    run_report.factor_seconds += sol.factor.analyze_seconds + sol.factor.factor_seconds;
    solves += sol.solve_seconds;
    figures += sol.stress_seconds;
  }
  run_report.wall_extra = {{"solve", solves}, {"stresses", figures}};
  run_report.start = start;
  run_report.probes = probes;
  run_report.bodies = bodies;
  run_report.strain_energy = total_strain;
  run_report.solver = json::object();
  for (const auto& sol : solutions)
    run_report.solver[scene.bodies[sol.body].name] =
        solver_json(sol.factor, sol.displacement.size());
  run_report.external_work = total_work;
  write_summary(out, run_report, as);
  progress.stage("done: static solve, " + std::to_string(frames) + " frames -> " + o.out_dir);
  progress.finish();
  return 0;
}

}  // namespace vproto::ui_batch::detail
