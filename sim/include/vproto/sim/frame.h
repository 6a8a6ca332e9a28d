#pragma once
// What writers and the renderer need at one instant (DESIGN.md "Frame"), and the sink
// interface frames flow through out of the step loop.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace vproto::sim {

/// One body at one instant. The pose moves the body's reference frame from where it
/// started (its centroid, identity rotation) to `position`, `rotation`.
struct BodyFrame {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();            ///< m, reference origin
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< unit quaternion
  /// Elastic bodies: deformed surface vertices in world coordinates (#V by 3, same order as
  /// the body's surface); empty for rigid bodies, whose surface follows the pose.
  Eigen::MatrixX3d deformed;
  /// Elastic bodies: the part of `deformed` that is deformation (world axes, #V by 3),
  /// without the motion of the body's frame or of what holds it; for magnified drawing.
  Eigen::MatrixX3d deformation;
  /// A per-surface-vertex scalar field (#V), or empty.
  Eigen::VectorXd field;
  /// Elastic bodies with a stress or strain field: per surface vertex, whether the value
  /// there is a local concentration (under a contact or at a sharp inside corner,
  /// fe_elasticity.h's concentration_nodes) rather than the body's own field; empty: none
  /// known. The colour scale tops out at the largest value of the other vertices.
  std::vector<char> concentrated;
};

struct Frame {
  int index = 0;
  double time = 0;                ///< s
  std::vector<BodyFrame> bodies;  ///< one per scene body, in scene order
  std::string field;              ///< "none", "displacement" or "von_mises"
  std::string field_unit;         ///< SI unit of the field ("m", "Pa")
};

/// Receives frames from the step loop, in order. Implementations may work on another
/// thread; `finish` waits for everything to be written and reports errors.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void push(Frame frame) = 0;
  virtual void finish() = 0;
};

}  // namespace vproto::sim
