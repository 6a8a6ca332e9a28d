#pragma once
// The output side of the animation engine: a FrameSink that renders PNG frames and
// exports surface meshes on a worker thread while the simulation goes on, then encodes
// an MP4 with ffmpeg when it is on the PATH (cli.md "Frames").

#include <Eigen/Core>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "vproto/sim/frame.h"
#include "vproto/sim/scene.h"
#include "vproto/ui_batch/image.h"
#include "vproto/ui_batch/mesh_io.h"
#include "vproto/ui_batch/renderer.h"

namespace vproto::ui_batch {

struct AnimationOptions {
  std::filesystem::path out_dir;
  bool render = true;
  RenderOptions render_options;
  Camera camera;                     ///< fitted once for the whole run
  double ground_z = 0;               ///< m
  std::string mesh_format = "none";  ///< stl | obj | none
  int export_every = 1;
  bool make_video = true;
  double video_fps = 30;
};

/// Timings of the writer's own work, for summary.json.
struct AnimationStats {
  int frames_rendered = 0;
  int meshes_written = 0;
  double render_seconds = 0;
  double export_seconds = 0;
  double video_seconds = 0;
  bool video_written = false;
};

class AnimationWriter : public sim::FrameSink {
 public:
  /// Creates DIR/frames and DIR/meshes as needed; the scene must outlive the writer.
  AnimationWriter(const sim::Scene& scene, AnimationOptions options);
  ~AnimationWriter() override;

  /// Queues a frame; blocks while the queue is full so memory stays bounded.
  void push(sim::Frame frame) override;
  /// Waits for every queued frame, encodes the video, and rethrows the first error.
  void finish() override;

  const AnimationStats& stats() const { return stats_; }

 private:
  void work();
  void write_frame(Renderer* renderer, const sim::Frame& frame);

  const sim::Scene& scene_;
  AnimationOptions options_;
  AnimationStats stats_;
  std::deque<sim::Frame> queue_;
  std::size_t queued_bytes_ = 0;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool closing_ = false;
  bool finished_ = false;
  std::exception_ptr error_;
  Yuv420Frames yuv_;                 ///< the video's frames (the worker's only)
  std::FILE* video_pipe_ = nullptr;  ///< ffmpeg's stdin: frames are encoded as they come
  PngSequence png_;                  ///< the frames' PNGs (the worker's only)
  struct LastMesh {
    Eigen::MatrixX3d vertices;  ///< a body's mesh as last exported
    std::filesystem::path file;
  };
  std::vector<LastMesh> last_meshes_;  ///< by body (the worker's only)
  std::thread worker_;
};

/// True when an executable named `name` is on the PATH.
bool on_path(const std::string& name);

}  // namespace vproto::ui_batch
