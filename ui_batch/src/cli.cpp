#include "vproto/ui_batch/cli.h"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vproto/materials/errors.h"
#include "vproto/modeler/compiler.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/modeler/parser.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/mesh_io.h"

namespace vproto::ui_batch {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

constexpr char kUsage[] =
    "usage: vproto COMMAND [options]\n"
    "  vproto check FILE                 parse and validate; build nothing\n"
    "  vproto build FILE -o DIR [--format stl|obj] [--tets] [--convex]\n"
    "                                    one surface mesh per body and DIR/build.json\n"
    "  vproto run FILE -o DIR [...]      build, mesh, simulate and write the animation\n"
    "  vproto bench [--quick] -o DIR     benchmarks\n"
    "common options: --set NAME=EXPR (repeatable), --quiet, -h\n";

const SourceLoc kCommandLine{"vproto", 0, 0};

struct Options {
  std::string command;
  std::string file;
  std::string out_dir;
  std::string format = "stl";
  bool tets = false;
  bool convex = false;
  bool quiet = false;
  bool help = false;
  std::vector<modeler::ParamOverride> overrides;
};

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

Options parse_args(const std::vector<std::string>& args) {
  Options o;
  if (args.empty()) throw InputError(kCommandLine, "no command given\n" + std::string(kUsage));
  o.command = args[0];
  if (o.command == "-h" || o.command == "--help") {
    o.help = true;
    return o;
  }
  if (o.command != "check" && o.command != "build" && o.command != "run" && o.command != "bench")
    throw InputError(kCommandLine, "unknown command '" + o.command + "'\n" + kUsage);
  auto value_of = [&](std::size_t& i, const std::string& flag) -> std::string {
    if (i + 1 >= args.size()) throw InputError(kCommandLine, flag + " needs a value");
    return args[++i];
  };
  for (std::size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      o.help = true;
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

// Progress on stderr: on a terminal one bar that redraws itself (stage, percent, rate,
// time left); otherwise one line per stage, so logs stay readable.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet)
      : err_(err), quiet_(quiet), tty_(&err == &std::cerr && ::isatty(2)), start_(Clock::now()) {}
  ~Progress() { finish(); }

  void stage(const std::string& what) { update(what, -1, 0); }

  /// `done` of `total` work items finished (-1: a stage without a count).
  void update(const std::string& what, int done, int total) {
    if (quiet_) return;
    const double t = std::chrono::duration<double>(Clock::now() - start_).count();
    char head[32];
    std::snprintf(head, sizeof head, "[%7.2fs] ", t);
    if (!tty_) {
      err_ << "vproto: " << head << what << "\n" << std::flush;
      return;
    }
    std::string line = "vproto: " + std::string(head);
    if (done >= 0 && total > 0) {
      const double frac = static_cast<double>(done) / total;
      const int width = 20, filled = static_cast<int>(frac * width);
      line += "[" + std::string(filled, '#') + std::string(width - filled, '.') + "] ";
      char stats[96];
      const double rate = t > 0 ? done / t : 0;
      if (done > 0 && done < total)
        std::snprintf(stats, sizeof stats, "%3.0f%% %.1f/s ~%.0fs left ", 100 * frac, rate,
                      (total - done) / rate);
      else
        std::snprintf(stats, sizeof stats, "%3.0f%% ", 100 * frac);
      line += stats;
    }
    line += what;
    err_ << "\r\033[K" << line << std::flush;
    open_line_ = true;
  }

  void finish() {
    if (open_line_) err_ << "\n" << std::flush;
    open_line_ = false;
  }

 private:
  std::ostream& err_;
  bool quiet_;
  bool tty_;
  bool open_line_ = false;
  Clock::time_point start_;
};

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

json vec_json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

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

int command_check(const Options& o, std::ostream& err) {
  Progress progress(err, o.quiet);
  const modeler::EvaluatedScript script = load(o, progress, err);
  progress.stage("ok: " + std::to_string(script.scene.bodies.size()) + " bodies");
  return 0;
}

int command_build(const Options& o, std::ostream& err) {
  const auto t0 = Clock::now();
  Progress progress(err, o.quiet);
  if (o.tets)
    throw InputError(kCommandLine,
                     "--tets (tetrahedral meshes of elastic bodies) is not available "
                     "in this version yet; build without it");
  modeler::EvaluatedScript script = load(o, progress, err);
  const double parse_seconds = since(t0);

  const fs::path out(o.out_dir);
  modeler::CompileOptions copts;
  copts.cache_dir = out / ".vproto-cache";
  copts.convex_parts = o.convex;
  copts.load_mesh = read_mesh;
  copts.progress = [&](const std::string& line, int done, int total) {
    progress.update(line, done, total);
  };
  const modeler::CompileReport report = modeler::compile_bodies(script, copts);

  // every body compiled: now (and only now) write outputs
  const auto t_export = Clock::now();
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out))
    throw InputError(
        SourceLoc{o.out_dir, 0, 0},
        "cannot create the output folder: " + (ec ? ec.message() : std::string("not a folder")));
  if (::access(out.c_str(), W_OK) != 0)
    throw InputError(SourceLoc{o.out_dir, 0, 0}, "the output folder is not writable");
  const MeshFormat format = o.format == "obj" ? MeshFormat::kObj : MeshFormat::kStl;
  json bodies = json::array();
  for (std::size_t i = 0; i < script.scene.bodies.size(); ++i) {
    const sim::Body& b = script.scene.bodies[i];
    const fs::path file = out / (b.name + "." + o.format);
    progress.stage("write " + file.string());
    write_mesh(b.surface, b.name, format, file.string());
    const geometry::Bounds box = geometry::bounds(b.surface);
    json inertia = json::array();
    for (int r = 0; r < 3; ++r) inertia.push_back(vec_json(b.inertia.row(r).transpose()));
    bodies.push_back(
        {{"name", b.name},
         {"kind", b.kind == sim::BodyKind::kElastic ? "elastic" : "rigid"},
         {"material", b.material.name},
         {"volume", b.mass_properties.volume},
         {"area", b.mass_properties.area},
         {"mass", b.mass},
         {"centroid", vec_json(b.mass_properties.centroid)},
         {"inertia", inertia},
         {"bbox", json::array({vec_json(box.lo), vec_json(box.hi)})},
         {"triangles", b.surface.F.rows()},
         {"vertices", b.surface.V.rows()},
         {"convex_parts", b.convex_parts_computed ? static_cast<long>(b.convex_parts.size()) : 0L},
         {"nodes", 0},
         {"tets", 0},
         {"file", file.filename().string()},
         {"hash", report.bodies[i].hash},
         {"cached", report.bodies[i].from_cache},
         {"corefinements", report.bodies[i].corefinements}});
  }
  json params = json::object();
  for (const auto& [k, v] : script.params) params[k] = v;
  const double export_seconds = since(t_export);
  json doc = {{"units", "SI"},
              {"script", o.file},
              {"params", params},
              {"bodies", bodies},
              {"timings",
               {{"parse", parse_seconds},
                {"csg", report.csg_seconds},
                {"convex", report.convex_seconds},
                {"tetmesh", 0.0},
                {"export", export_seconds},
                {"total", since(t0)}}}};
  write_text_atomically(out / "build.json", doc.dump(2) + "\n");
  progress.stage("done: " + std::to_string(bodies.size()) + " bodies -> " + o.out_dir);
  progress.finish();
  return 0;
}

}  // namespace

int run_cli(const std::vector<std::string>& args, std::ostream& err) {
  try {
    const Options o = parse_args(args);
    if (o.help) {
      err << kUsage;
      return 0;
    }
    if (o.command == "check") return command_check(o, err);
    if (o.command == "build") return command_build(o, err);
    throw InputError(kCommandLine, "'" + o.command +
                                       "' is not available in this version yet: the "
                                       "simulator and benchmarks land with the next issues; use "
                                       "'vproto build' for now");
  } catch (const InputError& e) {
    err << e.what() << "\n";
    return 2;
  } catch (const SimulationError& e) {
    err << "vproto: simulation failed: " << e.what() << "\n";
    return 3;
  } catch (const std::bad_alloc&) {
    err << "vproto: internal error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    err << "vproto: internal error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace vproto::ui_batch
