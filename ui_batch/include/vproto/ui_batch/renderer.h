#pragma once
// Off-screen rendering of an assembly with OSMesa (software OpenGL: no display, no GPU):
// shaded bodies with sharp CAD edges kept sharp, feature lines, a ground grid with a soft
// shadow, 2x2 supersampled anti-aliasing, a colour-mapped field with a legend, and a
// caption. One Renderer owns one OSMesa context; use it from one thread at a time.

#include <memory>
#include <string>
#include <vector>

#include "vproto/geometry/tri_mesh.h"
#include "vproto/sim/frame.h"
#include "vproto/sim/scene.h"
#include "vproto/ui_batch/image.h"

namespace vproto::ui_batch {

struct Camera {
  Eigen::Vector3d eye = Eigen::Vector3d(1, -1, 1);
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  bool orthographic = false;
  double fov_y = 0.5235987755982988;  ///< rad, perspective
  double ortho_height = 1;            ///< m, the view's height when orthographic
};

/// A camera preset (`iso`, `front`, `side`, `top`) aimed so the whole of `bounds` fits in
/// an image of the given aspect ratio (width / height) with a margin.
Camera fit_camera(const std::string& preset, const geometry::Bounds& bounds, double aspect);

/// A camera at `eye` looking at `target`, with the near/far range fitted to `bounds`.
Camera look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

struct RenderOptions {
  int width = 1280;
  int height = 720;
  bool feature_edges = true;
  bool ground = true;   ///< grid and shadow under the assembly
  bool legend = true;   ///< colour bar when a field is shown
  bool caption = true;  ///< time and title
  int supersample = 2;  ///< 1 = no anti-aliasing
  std::string title;
  /// Field range for the colour map; when min >= max it is taken from the frame.
  double field_min = 0, field_max = 0;
  /// Elastic deformation drawn this many times larger (BodyFrame::deformation).
  double deform_scale = 1;
};

class Renderer {
 public:
  /// Prepares render meshes (normals split at sharp edges, feature lines) for the scene's
  /// bodies. Throws InputError for an impossible size, SimulationError when OSMesa fails.
  Renderer(const sim::Scene& scene, const RenderOptions& options);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders one frame as seen by `camera`; `ground_z` is the height of the ground grid.
  Image render(const sim::Frame& frame, const Camera& camera, double ground_z);

  /// Triangles drawn per frame (for benchmarks).
  long triangles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The frame of a scene at its start: every body at its starting pose, no field.
sim::Frame start_frame(const sim::Scene& scene);

/// Bounds of every body's surface in `frame`.
geometry::Bounds frame_bounds(const sim::Scene& scene, const sim::Frame& frame);

}  // namespace vproto::ui_batch
