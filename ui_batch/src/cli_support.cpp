#include "cli_support.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "vproto/materials/units.h"
#include "vproto/modeler/parser.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch::detail {

namespace fs = std::filesystem;

const char kUsage[] =
    "usage: vproto COMMAND [options]\n"
    "  vproto check FILE                 parse and validate; build nothing\n"
    "  vproto build FILE -o DIR [--format stl|obj] [--tets] [--convex]\n"
    "                                    one surface mesh per body and DIR/build.json\n"
    "  vproto run FILE -o DIR [...]      build, mesh, simulate and write the animation\n"
    "                                    (--solver auto|cholmod|petsc; under mpirun -np N\n"
    "                                    the ranks share the FE solves)\n"
    "  vproto sweep FILE -o DIR --set NAME=a,b,c [--set ...] [--output KEY ...] [run options]\n"
    "                                    one run per combination, a table and plots of\n"
    "                                    summary.json's figures against the parameters\n"
    "  vproto bench [--quick] -o DIR     benchmarks\n"
    "  vproto bench --stress [--quick] -o DIR   stress scenes, each checked\n"
    "common options: --set NAME=EXPR (repeatable), --quiet, -h\n";

const SourceLoc kCommandLine{"vproto", 0, 0};

namespace {

// A time such as 0.5s, 20ms or 1e-3 (seconds).
double parse_time(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  const std::string unit = end ? std::string(end) : "";
  const auto u = unit.empty()
                     ? std::optional<units::Unit>(units::Unit{1, units::Dimension::of_time()})
                     : units::parse_unit(unit);
  if (end == text.c_str() || !u || u->dimension != units::Dimension::of_time() || !(v > 0) ||
      !std::isfinite(v))
    throw InputError(kCommandLine,
                     flag + " needs a positive time such as 0.5s or 20ms, got '" + text + "'");
  return v * u->scale;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

}  // namespace

Options parse_args(const std::vector<std::string>& args) {
  Options o;
  if (args.empty()) throw InputError(kCommandLine, "no command given\n" + std::string(kUsage));
  o.command = args[0];
  if (o.command == "-h" || o.command == "--help") {
    o.help = true;
    return o;
  }
  if (o.command != "check" && o.command != "build" && o.command != "run" && o.command != "bench" &&
      o.command != "sweep")
    throw InputError(kCommandLine, "unknown command '" + o.command + "'\n" + kUsage);
  auto value_of = [&](std::size_t& i, const std::string& flag) -> std::string {
    if (i + 1 >= args.size()) throw InputError(kCommandLine, flag + " needs a value");
    return args[++i];
  };
  const bool runs = o.command == "run" || o.command == "sweep";  // the run options
  for (std::size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      o.help = true;
    } else if (a == "--quick" && o.command == "bench") {
      o.quick = true;
    } else if (a == "--stress" && o.command == "bench") {
      o.stress = true;
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (a == "-o") {
      o.out_dir = value_of(i, a);
    } else if (a == "--format") {
      o.format = value_of(i, a);
      if (o.format != "stl" && o.format != "obj")
        throw InputError(kCommandLine, "--format must be stl or obj, got '" + o.format + "'");
    } else if (a == "--tets") {
      o.tets = true;
    } else if (a == "--convex") {
      o.convex = true;
    } else if (a == "--render" && o.command == "build") {
      o.render_file = value_of(i, a);
    } else if (a == "--frames" && runs) {
      const std::string v = value_of(i, a);
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (*end != '\0' || n < 1 || n > 100000)
        throw InputError(kCommandLine,
                         "--frames must be a whole number from 1 to 100000, got '" + v + "'");
      o.frames = static_cast<int>(n);
    } else if (a == "--size" && runs) {
      const std::string v = value_of(i, a);
      int w = 0, h = 0;
      char tail = 0;
      if (std::sscanf(v.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 ||
          h > 8192)
        throw InputError(kCommandLine,
                         "--size must be WxH with each side 16 to 8192 pixels, got '" + v + "'");
      o.size = std::make_pair(w, h);
    } else if (a == "--no-render" && runs) {
      o.no_render = true;
    } else if (a == "--export" && runs) {
      o.export_format = value_of(i, a);
      if (*o.export_format != "stl" && *o.export_format != "obj" && *o.export_format != "vtu" &&
          *o.export_format != "none")
        throw InputError(kCommandLine,
                         "--export must be stl, obj, vtu or none, got '" + *o.export_format + "'");
    } else if (a == "--mode" && runs) {
      o.mode = value_of(i, a);
      if (*o.mode != "static" && *o.mode != "quasistatic" && *o.mode != "dynamic")
        throw InputError(kCommandLine,
                         "--mode must be static, quasistatic or dynamic, got '" + *o.mode + "'");
    } else if (a == "--solver" && runs) {
      o.solver = value_of(i, a);
      if (*o.solver != "auto" && *o.solver != "cholmod" && *o.solver != "petsc")
        throw InputError(kCommandLine,
                         "--solver must be auto, cholmod or petsc, got '" + *o.solver + "'");
      if (*o.solver == "petsc" && !sim::petsc_available())
        throw InputError(kCommandLine, sim::no_petsc_message("--solver petsc"));
    } else if (a == "--duration" && runs) {
      o.duration = parse_time(a, value_of(i, a));
    } else if (a == "--dt" && runs) {
      o.dt = parse_time(a, value_of(i, a));
    } else if (a == "--output" && o.command == "sweep") {
      o.outputs.push_back(value_of(i, a));
    } else if (a == "--set") {
      const std::string kv = value_of(i, a);
      const auto eq = kv.find('=');
      if (eq == std::string::npos || !is_identifier(kv.substr(0, eq)) || eq + 1 == kv.size())
        throw InputError(kCommandLine,
                         "--set needs NAME=EXPR (e.g. --set clearance=0.003in), got '" + kv + "'");
      o.overrides.push_back({kv.substr(0, eq), kv.substr(eq + 1)});
    } else if (!a.empty() && a[0] == '-') {
      throw InputError(kCommandLine,
                       "unknown option '" + a + "' for '" + o.command + "'\n" + kUsage);
    } else if (o.file.empty() && o.command != "bench") {
      o.file = a;
    } else {
      throw InputError(kCommandLine, "unexpected argument '" + a + "'\n" + kUsage);
    }
  }
  if (o.help) return o;
  if (o.command != "bench" && o.file.empty())
    throw InputError(kCommandLine, "'" + o.command + "' needs a script FILE\n" + kUsage);
  if ((o.command == "build" || o.command == "run" || o.command == "bench") && o.out_dir.empty())
    throw InputError(kCommandLine, "'" + o.command + "' needs an output folder: -o DIR");
  return o;
}

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

nlohmann::json vec_json(const Eigen::Vector3d& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

std::string read_script(const std::string& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw InputError(SourceLoc{file, 0, 0}, "cannot read the script: no such file");
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  if (!in && !in.eof()) throw InputError(SourceLoc{file, 0, 0}, "cannot read the script");
  std::string text = ss.str();
  if (text.size() > 64u << 20)
    throw InputError(SourceLoc{file, 0, 0}, "the script is larger than 64 MiB");
  return text;
}

modeler::EvaluatedScript load(const Options& o, Progress& progress, std::ostream& err) {
  const std::string text = read_script(o.file);
  progress.stage("parse " + o.file);
  const modeler::Program program = modeler::parse_program(text, o.file);
  const std::string dir = fs::path(o.file).parent_path().string();
  modeler::EvaluatedScript script =
      modeler::evaluate_program(program, o.overrides, dir.empty() ? "." : dir);
  if (!o.quiet)
    for (const auto& w : script.warnings) err << w << "\n";
  return script;
}

void write_build_json(const fs::path& out, const Options& o, const modeler::EvaluatedScript& script,
                      const modeler::CompileReport& report, double parse_seconds,
                      double export_seconds, Clock::time_point start) {
  using nlohmann::json;
  json bodies = json::array();
  for (std::size_t i = 0; i < script.scene.bodies.size(); ++i) {
    const sim::Body& b = script.scene.bodies[i];
    const geometry::Bounds box = geometry::bounds(b.surface);
    json inertia = json::array();
    for (int r = 0; r < 3; ++r) inertia.push_back(vec_json(b.inertia.row(r).transpose()));
    bodies.push_back(
        {{"name", b.name},
         {"kind", b.kind == sim::BodyKind::kElastic ? "elastic" : "rigid"},
         {"material", b.material.name},
         {"youngs_modulus", b.material.youngs_modulus},
         {"poisson_ratio", b.material.poisson_ratio},
         {"density", b.material.density},
         {"volume", b.mass_properties.volume},
         {"area", b.mass_properties.area},
         {"mass", b.mass},
         {"centroid", vec_json(b.mass_properties.centroid)},
         {"inertia", inertia},
         {"bbox", json::array({vec_json(box.lo), vec_json(box.hi)})},
         {"triangles", b.surface.F.rows()},
         {"vertices", b.surface.V.rows()},
         {"convex_parts", b.convex_parts_computed ? static_cast<long>(b.convex_parts.size()) : 0L},
         {"nodes", b.meshed ? b.tet_mesh.nodes.rows() : 0},
         {"tets", b.meshed ? b.tet_mesh.elements.rows() : 0},
         {"file", b.name + "." + o.format},
         {"hash", report.bodies[i].hash},
         {"cached", report.bodies[i].from_cache},
         {"corefinements", report.bodies[i].corefinements}});
    if (b.meshed)
      bodies.back()["tet_mesh"] = {{"element", b.tet_mesh.elements.cols() == 10 ? "tet10" : "tet4"},
                                   {"mesh_size", b.tet_mesh.mesh_size},
                                   {"min_dihedral_angle", b.tet_quality.min_dihedral_angle},
                                   {"max_radius_edge_ratio", b.tet_quality.max_radius_edge_ratio},
                                   {"min_tet_volume", b.tet_quality.min_volume},
                                   {"mesh_volume", b.tet_quality.volume},
                                   {"thinnest_wall", b.thinnest_wall},
                                   {"cached", report.bodies[i].tets_from_cache},
                                   {"file", b.name + ".vtu"}};
    if (b.meshed && b.tet_mesh.max_size > 0)
      bodies.back()["tet_mesh"]["grading"] = {
          {"finest_size", b.tet_mesh.mesh_size},
          {"coarsest_size", b.tet_mesh.max_size},
          {"growth", 0.5},
          {"fine_surface_triangles", b.tet_mesh.fine_faces},
          {"fine_zone",
           "surface parts thinner than 4 mesh sizes, and the parts within 2 mesh sizes "
           "of the bounding box of a body that can touch this one, swept by the drives"}};
  }
  json params = json::object();
  for (const auto& [k, v] : script.params) params[k] = v;
  json doc = {{"units", "SI"},
              {"script", o.file},
              {"params", params},
              {"bodies", bodies},
              {"timings",
               {{"parse", parse_seconds},
                {"csg", report.csg_seconds},
                {"convex", report.convex_seconds},
                {"tetmesh", report.tetmesh_seconds},
                {"export", export_seconds},
                {"total", since(start)}}}};
  // what the script and the build warned of (stderr too, unless --quiet): a sweep's runs,
  // quiet, keep them here
  json warnings = json::array();
  for (const std::string& w : script.warnings) warnings.push_back(w);
  for (const std::string& w : report.warnings) warnings.push_back(w);
  doc["warnings"] = warnings;
  write_text_atomically(out / "build.json", doc.dump(2) + "\n");
}

std::string contact_steps_csv(const sim::Scene& scene,
                              const std::vector<sim::ContactStepRecord>& records) {
  std::ostringstream out;
  out << "t,body,detected,points,node_points,pressed,sliding,passes,newton_iterations,sweeps,"
         "converged,new_columns,column_seconds,delassus_seconds,solve_seconds,seconds\n";
  out.precision(9);
  for (const sim::ContactStepRecord& r : records)
    out << r.time << ',' << scene.bodies.at(static_cast<std::size_t>(r.body)).name << ','
        << r.detected << ',' << r.points << ',' << r.node_points << ',' << r.pressed << ','
        << r.sliding << ',' << r.passes << ',' << r.newton_iterations << ',' << r.sweeps << ','
        << (r.converged ? 1 : 0) << ',' << r.new_columns << ',' << r.column_seconds << ','
        << r.delassus_seconds << ',' << r.solve_seconds << ',' << r.seconds << '\n';
  return out.str();
}

nlohmann::json solver_json(const sim::SolverStats& f, Eigen::Index dofs) {
  nlohmann::json j = {{"backend", f.backend},
                      {"method", f.method},
                      {"reason", f.reason},
                      {"ranks", f.ranks},
                      {"ordering", f.ordering},
                      {"factor_nonzeros", f.factor_nonzeros},
                      {"factor_flops", f.flops},
                      {"factorizations", f.factorizations},
                      {"setup_seconds", f.analyze_seconds + f.factor_seconds},
                      {"dofs", dofs}};
  if (!f.single_solve.empty()) j["single_solve"] = f.single_solve;
  if (f.relative_tolerance > 0) {
    j["relative_tolerance"] = f.relative_tolerance;
    j["iterations"] = f.iterations;
    j["relative_residual"] = f.relative_residual;
  }
  return j;
}

void write_summary(const fs::path& out, const RunReport& r, const AnimationStats& as) {
  using nlohmann::json;
  json summary = {{"status", r.status},
                  {"mode", r.mode},
                  {"steps", r.steps},
                  {"sim_time", r.sim_time},
                  {"frames", as.frames_rendered},
                  {"meshes", as.meshes_written},
                  {"video", as.video_written},
                  {"wall_time",
                   {{"build", r.build_seconds},
                    {"mesh", r.mesh_seconds},
                    {"assemble", r.assemble_seconds},
                    {"factor", r.factor_seconds},
                    {"simulate", r.simulate_seconds},
                    {"render", as.render_seconds},
                    {"export", as.export_seconds},
                    {"video", as.video_seconds},
                    {"total", since(r.start)}}},
                  {"events", json::array()},
                  {"peak_contact_force", 0.0},
                  {"probes", r.probes},
                  {"bodies", r.bodies},
                  {"energy",
                   {{"kinetic", r.kinetic_energy},
                    {"strain", r.strain_energy},
                    {"external_work", r.external_work},
                    {"dissipated", r.dissipated}}}};
  if (!r.solver.is_null()) summary["solver"] = r.solver;
  // every rank's peak memory (collective under mpirun: every rank writes a summary)
  const std::vector<double> memory = sim::peak_memory_per_rank();
  summary["memory"] = {{"ranks", memory.size()}, {"peak_bytes_per_rank", memory}};
  if (r.contact_seconds > 0) summary["wall_time"]["contact"] = r.contact_seconds;
  for (const auto& [key, value] : r.wall_extra.items()) summary["wall_time"][key] = value;
  for (const auto& [key, value] : r.extra.items()) summary[key] = value;
  if (r.time_step > 0) summary["time_step"] = r.time_step;
  if (!r.time_step_reason.empty()) summary["time_step_reason"] = r.time_step_reason;
  if (!r.note.empty()) summary["note"] = r.note;
  if (!r.reason.empty()) summary["reason"] = r.reason;
  write_text_atomically(out / "summary.json", summary.dump(2) + "\n");
}

void VtuSeries::add(const sim::Body& body, int body_index, int frame, double time,
                    const Eigen::MatrixX3d& u, const std::vector<PointField>& fields) {
  const auto started = Clock::now();
  fs::create_directories(dir_);
  char name[256];
  std::snprintf(name, sizeof name, "%s_%04d.vtu", body.name.c_str(), frame);
  std::vector<PointField> all{{"displacement", u}};
  all.insert(all.end(), fields.begin(), fields.end());
  write_vtu(body.tet_mesh, (dir_ / name).string(), body.tet_mesh.nodes + u, all);
  entries_.push_back({time, body_index, name});
  seconds_ += since(started);
}

void VtuSeries::finish() {
  if (entries_.empty()) return;
  const auto started = Clock::now();
  std::ostringstream pvd;
  pvd.precision(17);
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (const Entry& e : entries_)
    pvd << "<DataSet timestep=\"" << e.time << "\" part=\"" << e.part << "\" file=\"" << e.file
        << "\"/>\n";
  pvd << "</Collection>\n</VTKFile>\n";
  write_text_atomically(dir_ / "series.pvd", pvd.str());
  seconds_ += since(started);
}

void add_material_peaks(const sim::Body& body, const sim::MaterialPeaks& p, nlohmann::json* b) {
  using nlohmann::json;
  auto peak_json = [&](const char* name, const sim::FieldPeak& f, json* into) {
    (*into)[std::string("peak_") + name] = f.value;
    if (f.time < 0) return;
    (*into)[std::string("peak_") + name + "_time"] = f.time;
    (*into)[std::string("peak_") + name + "_at"] = vec_json(f.at);
    (*into)[std::string("peak_") + name + "_at_sharp_corner"] = f.at_sharp_corner;
  };
  peak_json("von_mises", p.von_mises, b);
  peak_json("strain", p.strain, b);
  json away = json::object();
  peak_json("von_mises", p.bulk_von_mises, &away);
  peak_json("strain", p.bulk_strain, &away);
  (*b)["away_from_contact"] = away;
  json regular = json::object();
  peak_json("von_mises", p.regular_von_mises, &regular);
  peak_json("strain", p.regular_strain, &regular);
  (*b)["away_from_contact_and_corners"] = regular;
  // the hot-spot values extrapolated to the sharp inside corners, where the body has any
  const bool corners = p.corner_von_mises.time >= 0 || p.corner_strain.time >= 0;
  if (corners) {
    json hot = {{"method",
                 "hot-spot: 1.67 x the surface value at 0.4 t from the edge - 0.67 x "
                 "that at 1.0 t, t the wall's thickness"}};
    peak_json("von_mises", p.corner_von_mises, &hot);
    peak_json("strain", p.corner_strain, &hot);
    (*b)["sharp_corner_hot_spot"] = hot;
  }
  const materials::Material& mat = body.material;
  if (!mat.yield_strength && !mat.yield_strain) return;
  json y = {{"away_from_contact", json::object()},
            {"away_from_contact_and_corners", json::object()}};
  if (corners) y["sharp_corner_hot_spot"] = json::object();
  auto ratios = [&](const sim::FieldPeak& stress, const sim::FieldPeak& strain, double when,
                    json* into) {
    if (when >= 0) (*into)["exceeded_at"] = when;
    if (mat.yield_strength) (*into)["stress_ratio"] = stress.value / *mat.yield_strength;
    if (mat.yield_strain) (*into)["strain_ratio"] = strain.value / *mat.yield_strain;
  };
  ratios(p.von_mises, p.strain, p.yielded_at, &y);
  ratios(p.bulk_von_mises, p.bulk_strain, p.bulk_yielded_at, &y["away_from_contact"]);
  ratios(p.regular_von_mises, p.regular_strain, p.regular_yielded_at,
         &y["away_from_contact_and_corners"]);
  if (corners)
    ratios(p.corner_von_mises, p.corner_strain, p.corner_yielded_at, &y["sharp_corner_hot_spot"]);
  if (mat.yield_strength) y["strength"] = *mat.yield_strength;
  if (mat.yield_strain) y["strain"] = *mat.yield_strain;
  (*b)["yield"] = y;
}

std::vector<PointField> vtu_fields(const sim::Body& body, const Eigen::VectorXd& von_mises,
                                   const Eigen::VectorXd& strain) {
  std::vector<PointField> fields{{"von_mises", von_mises}, {"strain", strain}};
  if (materials::has_yield(body.material))
    fields.emplace_back("yield_ratio", sim::yield_ratios(body.material, von_mises, strain));
  return fields;
}

std::string yield_sentence(const sim::Body& body, const sim::MaterialPeaks& p) {
  const materials::Material& mat = body.material;
  // where the yield is passed: in the body (away from contacts and sharp corners), only at a
  // sharp inside corner of it, or only under a contact
  enum class Where { kBody, kCorner, kContact };
  const Where where = p.regular_yielded_at >= 0 ? Where::kBody
                      : p.bulk_yielded_at >= 0  ? Where::kCorner
                                                : Where::kContact;
  const sim::FieldPeak& stress = where == Where::kBody     ? p.regular_von_mises
                                 : where == Where::kCorner ? p.bulk_von_mises
                                                           : p.von_mises;
  const sim::FieldPeak& strain = where == Where::kBody     ? p.regular_strain
                                 : where == Where::kCorner ? p.bulk_strain
                                                           : p.strain;
  const double when = where == Where::kBody     ? p.regular_yielded_at
                      : where == Where::kCorner ? p.bulk_yielded_at
                                                : p.yielded_at;
  auto place = [](const sim::FieldPeak& f) {
    char s[128];
    std::snprintf(s, sizeof s, "at (%.4g, %.4g, %.4g) m where the body starts, t = %.4g s",
                  f.at.x(), f.at.y(), f.at.z(), f.time);
    return std::string(s);
  };
  std::ostringstream out;
  out << "elastic body '" << body.name << "' passes its material's yield "
      << (where == Where::kCorner    ? "only at a sharp inside corner "
          : where == Where::kContact ? "under a contact "
                                     : "")
      << "at t = " << when << " s:";
  char s[160];
  if (mat.yield_strength) {
    std::snprintf(s, sizeof s, " von Mises stress up to %.3g MPa (%.2f x yield_strength %.3g MPa) ",
                  stress.value * 1e-6, stress.value / *mat.yield_strength,
                  *mat.yield_strength * 1e-6);
    out << s << place(stress) << ";";
  }
  if (mat.yield_strain) {
    std::snprintf(s, sizeof s, " principal strain up to %.3g (%.2f x yield_strain %.3g) ",
                  strain.value, strain.value / *mat.yield_strain, *mat.yield_strain);
    out << s << place(strain) << ";";
  }
  switch (where) {
    case Where::kBody:
      out << " linear elasticity does not hold there, so what the run gives after that time "
             "(forces, deflections, stresses) is not the part's: lower the strain there (for a "
             "snap-fit arm a smaller undercut or a longer or thinner arm) or choose a material "
             "that takes it";
      break;
    case Where::kCorner:
      out << " away from it and from the contacts the body stays below (summary.json "
             "bodies[].away_from_contact_and_corners). At a re-entrant edge with no fillet the "
             "linear-elastic stress is singular: it grows without bound as the mesh is "
             "refined, so the value says that the corner concentrates the stress, not how "
             "much.";
      if (p.corner_von_mises.time >= 0 || p.corner_strain.time >= 0) {
        // the structural value at the corner, extrapolated from its faces
        const double stress_ratio =
            mat.yield_strength ? p.corner_von_mises.value / *mat.yield_strength : 0;
        const double strain_ratio =
            mat.yield_strain ? p.corner_strain.value / *mat.yield_strain : 0;
        std::snprintf(s, sizeof s,
                      " Extrapolated to the corner from its faces (the hot-spot stress, "
                      "summary.json bodies[].sharp_corner_hot_spot) it is %.3g MPa, strain %.3g ",
                      p.corner_von_mises.value * 1e-6, p.corner_strain.value);
        out << s;
        std::snprintf(s, sizeof s, "(%.2f of the yield)", std::max(stress_ratio, strain_ratio));
        out << s;
        if (p.corner_yielded_at >= 0)
          out << ": past the yield even so, so a fillet alone will not keep the corner below "
                 "it; lower the strain there (for a snap-fit arm a smaller undercut or a longer "
                 "arm) or choose a material that takes it";
        else
          out << ", below it: round the corner with a fillet whose stress concentration "
                 "factor keeps the product below the yield (for a snap-fit arm's root a radius "
                 "of at least half the arm's thickness) and run again";
      } else {
        out << " Round the corner (for a snap-fit arm's root a fillet of at least half the "
               "arm's thickness) and run again";
      }
      break;
    case Where::kContact:
      out << " away from the contacts it stays below (summary.json "
             "bodies[].away_from_contact): an edge or corner pressing a face concentrates it "
             "under the contact at the scale of the elements (it grows as they are refined), a "
             "local yield the linear-elastic forces do not include; rounding the edge spreads "
             "it";
      break;
  }
  return out.str();
}

}  // namespace vproto::ui_batch::detail
