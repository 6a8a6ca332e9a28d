#include "vproto/ui_batch/animation_writer.h"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <sstream>

#include "vproto/materials/errors.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
// Frames waiting for the writer: up to 16, or 256 MB of them (a frame carries its elastic
// bodies' deformed surfaces and fields: 0.25 MB each on the snap-fit). With the writer at the
// lowest priority the step loop runs ahead through a landing that takes both cores and the
// frames are drawn when a core is free (the snap-fit rendered 10.67 -> 10.44 s against 4
// frames at nice 10, 8 alternating runs each).
constexpr std::size_t kMaxQueued = 16;
constexpr std::size_t kMaxQueuedBytes = std::size_t{256} << 20;

std::size_t bytes_of(const sim::Frame& frame) {
  std::size_t n = sizeof frame;
  for (const sim::BodyFrame& b : frame.bodies)
    n += sizeof b + sizeof(double) * static_cast<std::size_t>(
                                         b.deformed.size() + b.deformation.size() + b.field.size());
  return n;
}

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string numbered(const std::string& stem, int index, const std::string& ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%04d.", index);
  return stem + buf + ext;
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

bool on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / name;
    if (::access(p.c_str(), X_OK) == 0) return true;
  }
  return false;
}

AnimationWriter::AnimationWriter(const sim::Scene& scene, AnimationOptions options)
    : scene_(scene), options_(std::move(options)) {
  std::error_code ec;
  if (options_.render) fs::create_directories(options_.out_dir / "frames", ec);
  if (!ec && options_.mesh_format != "none")
    fs::create_directories(options_.out_dir / "meshes", ec);
  if (ec)
    throw InputError(SourceLoc{options_.out_dir.string(), 0, 0},
                     "cannot create the output folders: " + ec.message());
  worker_ = std::thread([this] { work(); });
}

AnimationWriter::~AnimationWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  changed_.notify_all();
  if (worker_.joinable()) worker_.join();
  if (video_pipe_) ::pclose(video_pipe_);
}

void AnimationWriter::push(sim::Frame frame) {
  std::unique_lock<std::mutex> lock(mutex_);
  const std::size_t bytes = bytes_of(frame);
  // (one frame goes in however large it is)
  changed_.wait(lock, [&] {
    return queue_.empty() ||
           (queue_.size() < kMaxQueued && queued_bytes_ + bytes <= kMaxQueuedBytes) || error_;
  });
  if (error_) return;  // reported by finish()
  queued_bytes_ += bytes;
  queue_.push_back(std::move(frame));
  changed_.notify_all();
}

void AnimationWriter::work() {
  try {
    // the OpenGL context lives and dies on this thread, at the lowest priority (and ffmpeg,
    // started from it, with it): frames take the cores the simulation leaves
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 19);
    std::unique_ptr<Renderer> renderer;
    if (options_.render) renderer = std::make_unique<Renderer>(scene_, options_.render_options);
    while (true) {
      sim::Frame frame;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait(lock, [this] { return !queue_.empty() || closing_; });
        if (queue_.empty()) return;
        frame = std::move(queue_.front());
        queue_.pop_front();
        queued_bytes_ -= bytes_of(frame);
      }
      changed_.notify_all();
      write_frame(renderer.get(), frame);
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = std::current_exception();
    queue_.clear();
    queued_bytes_ = 0;
    changed_.notify_all();
  }
}

void AnimationWriter::write_frame(Renderer* renderer, const sim::Frame& frame) {
  if (renderer) {
    const auto t0 = Clock::now();
    const Image img = renderer->render(frame, options_.camera, options_.ground_z);
    png_.write(img, (options_.out_dir / "frames" / numbered("frame", frame.index, "png")).string());
    if (options_.make_video && !video_pipe_ && stats_.frames_rendered == 0 && on_path("ffmpeg")) {
      // ffmpeg encodes beside the run from raw YUV 4:2:0 frames on its stdin (converted
      // here, sides rounded up to even: see Yuv420Frames)
      const std::string cmd =
          "ffmpeg -nostdin -y -loglevel error -f rawvideo -pix_fmt yuv420p -s " +
          std::to_string(img.width + img.width % 2) + "x" +
          std::to_string(img.height + img.height % 2) + " -framerate " +
          std::to_string(options_.video_fps) + " -i - " +
          "-c:v libx264 -preset superfast -pix_fmt yuv420p -f mp4 " +
          shell_quote((options_.out_dir / ".animation.tmp.mp4").string()) + " >/dev/null 2>&1";
      video_pipe_ = ::popen(cmd.c_str(), "w");
    }
    if (video_pipe_) {
      const std::vector<std::uint8_t>& yuv = yuv_.convert(img);
      if (std::fwrite(yuv.data(), 1, yuv.size(), video_pipe_) != yuv.size()) {
        ::pclose(video_pipe_);  // ffmpeg failed: the run goes on without a video
        video_pipe_ = nullptr;
        options_.make_video = false;
      }
    }
    stats_.render_seconds += since(t0);
    ++stats_.frames_rendered;
  }
  if (options_.mesh_format != "none" && frame.index % std::max(1, options_.export_every) == 0) {
    const auto t0 = Clock::now();
    const MeshFormat format = options_.mesh_format == "obj" ? MeshFormat::kObj : MeshFormat::kStl;
    for (std::size_t i = 0; i < scene_.bodies.size() && i < frame.bodies.size(); ++i) {
      const sim::Body& body = scene_.bodies[i];
      const sim::BodyFrame& b = frame.bodies[i];
      geometry::TriMesh mesh;
      if (b.deformed.rows() > 0) {
        mesh.V = b.deformed;
        mesh.F = body.drawn().F;
      } else {
        const Eigen::Affine3d t = Eigen::Translation3d(b.position) * b.rotation.normalized() *
                                  Eigen::Translation3d(-body.mass_properties.centroid);
        mesh = geometry::transformed(body.drawn(), t);
      }
      const fs::path file =
          options_.out_dir / "meshes" / numbered(body.name, frame.index, options_.mesh_format);
      // a body where the last frame had it (fixed, or at rest) gets that frame's file again
      // (assimp took 2.5 ms a mesh, on the thread that renders)
      if (last_meshes_.size() < scene_.bodies.size()) last_meshes_.resize(scene_.bodies.size());
      LastMesh& last = last_meshes_[i];
      if (!last.file.empty() && last.vertices.rows() == mesh.V.rows() && last.vertices == mesh.V) {
        write_atomically(file, [&](const fs::path& tmp) {
          std::error_code ec;
          fs::copy_file(last.file, tmp, fs::copy_options::overwrite_existing, ec);
          if (ec) throw InputError("cannot write '" + file.string() + "': " + ec.message());
        });
      } else {
        write_mesh(mesh, body.name, format, file.string());
        last.vertices = mesh.V;
      }
      last.file = file;
      ++stats_.meshes_written;
    }
    stats_.export_seconds += since(t0);
  }
}

void AnimationWriter::finish() {
  if (finished_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  changed_.notify_all();
  if (worker_.joinable()) worker_.join();
  finished_ = true;
  if (error_) std::rethrow_exception(error_);
  // the MP4, when ffmpeg was there; skipped silently otherwise (cli.md)
  if (video_pipe_) {
    const auto t0 = Clock::now();
    const fs::path tmp = options_.out_dir / ".animation.tmp.mp4";
    std::error_code ec;
    if (::pclose(video_pipe_) == 0) {
      fs::rename(tmp, options_.out_dir / "animation.mp4", ec);
      stats_.video_written = !ec;
    }
    video_pipe_ = nullptr;
    fs::remove(tmp, ec);
    stats_.video_seconds = since(t0);
  }
}

}  // namespace vproto::ui_batch
