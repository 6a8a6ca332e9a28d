#include "vproto/ui_batch/cli.h"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_support.h"
#include "vproto/materials/errors.h"
#include "vproto/modeler/compiler.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/modeler/parser.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/mesh_io.h"
#include "vproto/ui_batch/renderer.h"
#include "vproto/ui_batch/vtu_writer.h"

namespace vproto::ui_batch {
namespace {

using namespace detail;

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

// The assembly at its start, with the script's render settings (camera, size).
void render_preview(const sim::Scene& scene, const std::string& file) {
  if (fs::path(file).extension() != ".png")
    throw InputError(kCommandLine, "--render needs a .png file name, got '" + file + "'");
  RenderOptions ro;
  ro.width = scene.render.width;
  ro.height = scene.render.height;
  ro.title = "vproto preview";
  Renderer renderer(scene, ro);
  const sim::Frame frame = start_frame(scene);
  const geometry::Bounds b = frame_bounds(scene, frame);
  const Camera cam =
      scene.render.camera == "custom"
          ? look_at(scene.render.eye, scene.render.target)
          : fit_camera(scene.render.camera, b, static_cast<double>(ro.width) / ro.height);
  write_png(renderer.render(frame, cam, b.lo.z()), file);
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
  if (!o.render_file.empty()) {
    // checked before any work: the preview goes into an existing folder or into DIR
    const fs::path parent = fs::absolute(o.render_file).parent_path();
    std::error_code ec;
    if (parent != fs::absolute(o.out_dir) && !fs::is_directory(parent, ec))
      throw InputError(kCommandLine,
                       "--render: the folder of '" + o.render_file + "' does not exist");
    if (fs::path(o.render_file).extension() != ".png")
      throw InputError(kCommandLine,
                       "--render needs a .png file name, got '" + o.render_file + "'");
  }
  modeler::EvaluatedScript script = load(o, progress, err);
  const double parse_seconds = since(t0);

  const fs::path out(o.out_dir);
  modeler::CompileOptions copts;
  copts.cache_dir = out / ".vproto-cache";
  copts.convex_parts = o.convex;
  copts.tet_meshes = o.tets;
  copts.load_mesh = read_mesh;
  copts.progress = [&](const std::string& line, int done, int total) {
    progress.update(line, done, total);
  };
  const modeler::CompileReport report = modeler::compile_bodies(script, copts);
  if (!o.quiet)
    for (const std::string& w : report.warnings) err << w << "\n";

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
  for (const sim::Body& b : script.scene.bodies) {
    const fs::path file = out / (b.name + "." + o.format);
    progress.stage("write " + file.string());
    write_mesh(b.surface, b.name, format, file.string());
  }
  for (const sim::Body& b : script.scene.bodies) {
    if (!b.meshed) continue;
    const fs::path file = out / (b.name + ".vtu");
    progress.stage("write " + file.string());
    write_vtu(b.tet_mesh, file.string());
  }
  if (!o.render_file.empty()) {
    progress.stage("render " + o.render_file);
    render_preview(script.scene, o.render_file);
  }
  write_build_json(out, o, script, report, parse_seconds, since(t_export), t0);
  progress.stage("done: " + std::to_string(script.scene.bodies.size()) + " bodies -> " + o.out_dir);
  progress.finish();
  return 0;
}

}  // namespace

namespace {

// Under mpirun every rank computes the whole run (the FE solves are shared, everything
// else is repeated on the same data) and rank 0 alone writes DIR: another rank writes
// into a scratch folder of its own, removed when it ends, and renders nothing.
class RankScratch {
 public:
  explicit RankScratch(Options& o) {
    const int rank = sim::launched_rank();
    // (a sweep's ranks each run variants of their own into DIR)
    if (rank == 0 || o.out_dir.empty() || o.command == "sweep" || o.rank_writes) return;
    dir_ = fs::temp_directory_path() /
           ("vproto-rank" + std::to_string(rank) + "-" + std::to_string(::getpid()) + "-" +
            fs::path(o.out_dir).filename().string());
    o.out_dir = dir_.string();
    o.no_render = true;
    o.quiet = true;
    o.render_file.clear();
  }
  ~RankScratch() {
    std::error_code ignored;
    if (!dir_.empty()) fs::remove_all(dir_, ignored);
  }
  RankScratch(const RankScratch&) = delete;
  RankScratch& operator=(const RankScratch&) = delete;

 private:
  fs::path dir_;
};

int dispatch(Options o, std::ostream& err) {
  if (o.help) {
    err << kUsage;
    return 0;
  }
  const RankScratch scratch(o);
  if (o.command == "check") return command_check(o, err);
  if (o.command == "build") return command_build(o, err);
  if (o.command == "run") return command_run(o, err);
  if (o.command == "sweep") return command_sweep(o, err);
  return command_bench(o, err);
}

}  // namespace

namespace detail {

int guarded(std::ostream& err, const std::function<int()>& body) {
  try {
    return body();
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

int run_guarded(const Options& o, std::ostream& err) {
  return guarded(err, [&] { return dispatch(o, err); });
}

}  // namespace detail

int run_cli(const std::vector<std::string>& args, std::ostream& err) {
  return detail::guarded(err, [&] { return dispatch(detail::parse_args(args), err); });
}

}  // namespace vproto::ui_batch
