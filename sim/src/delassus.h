#pragma once
// The Delassus matrix of contact rows assembled from the responses of the bodies on the
// rows' sides (DESIGN.md "One constraint language"). A row (three directions: normal, two
// tangents) acts on each body it touches through one side: on an elastic body's surface
// nodes (a point of its surface: nodes and weights) or on a rigid motion (a rigid body's,
// or a floating elastic body's frame: six velocities). The rows' relative motion under
// their forces lambda is W lambda with
//   W_rs = sum over the sides a of r and b of s on one response of  sign_a sign_b A_ab,
// A_ab the response of a's point to a unit force at b's: an elastic body's compliance from
// its kept factor's columns (only at the nodes rows touch), a rigid body's mobility, two
// bodies of one mechanism the coupling block of its mobility; and, where a floating elastic
// body's frame takes forces, the deformation its acceleration causes (a term of rank six per
// floating body, not symmetric), less its rigid part in mean axes. The same assembly serves
// every row kind (a body's points on a rigid part or on another elastic body, a floating
// partner's supports, links between free rigid bodies) and any number of elastic bodies:
// what a row is follows from its sides alone (SOFA's constraint corrections, Drake's cliques).

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "dynamics_internal.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/point_contact_solver.h"

namespace vproto::sim {

/// A row's side on an elastic body's surface nodes.
struct NodeSide {
  const Dynamics::ElasticBody* body = nullptr;
  int id = -1;      ///< the scene's body
  double sign = 1;  ///< +1: the row's force acts along its directions on this body, -1 against
  std::array<int, 3> nodes{-1, -1, -1};  ///< surface nodes (-1: none) and their weights
  std::array<double, 3> weights{0, 0, 0};
  /// The nodes' compliance columns (the body's `columns`; null where a node is none).
  std::array<const Dynamics::ElasticBody::NodeColumns*, 3> columns{};
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();  ///< the row's directions, body axes
};

/// A row's side on a rigid motion (a rigid body's or a floating elastic body's frame).
struct FrameSide {
  int id = -1;  ///< the scene's body
  double sign = 1;
  /// The row's three directions on the body's six velocities (world; rotations about the
  /// point the body's mobility is taken about).
  Eigen::Matrix<double, 3, 6> jac = Eigen::Matrix<double, 3, 6>::Zero();
};

/// The sides of one row: at most two on surface nodes and two on frames (a point on an
/// elastic partner of a floating body: both bodies' nodes and frames).
struct RowSides {
  std::array<NodeSide, 2> nodes;
  std::array<FrameSide, 2> frames;
  int node_count = 0, frame_count = 0;
  void add(const NodeSide& s) {
    VPROTO_DEMAND(node_count < 2);
    nodes[static_cast<std::size_t>(node_count++)] = s;
  }
  void add(const FrameSide& s) {
    VPROTO_DEMAND(frame_count < 2);
    frames[static_cast<std::size_t>(frame_count++)] = s;
  }
};

/// A floating elastic body some rows touch: its frame's rotation at the step's start
/// (transposed, on forces and torques: rt6) and its mesh's reference centroid, for the
/// deformation its frame's acceleration causes.
struct FloatingSide {
  int id = -1;
  const Dynamics::ElasticBody* body = nullptr;
  Eigen::Matrix<double, 6, 6> rt6 = Eigen::Matrix<double, 6, 6>::Identity();
  const geometry::TetMesh* mesh = nullptr;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  /// How its frame's velocity jumps under a unit wrench on it, times dt (its mobility times
  /// dt^2, as FrameMobility's): the acceleration that deforms it, where FrameMobility gives
  /// how far the frame travels instead (a frame its last step's rows held travels less far
  /// under a jump along its free directions: Dynamics::held_travel_); none: the same.
  std::optional<Eigen::Matrix<double, 6, 6>> jump_mobility;
};

/// How body q's frame moves under a unit wrench on body r's, times dt^2 (its mobility when q
/// is r, the coupling block of their mechanism's mobility when they are jointed together;
/// none when r's wrench does not move q).
using FrameMobility = std::function<std::optional<Eigen::Matrix<double, 6, 6>>(int q, int r)>;

/// W (3m x 3m, m = rows.size()) of the rows, over two threads when large. `floating` lists the
/// floating elastic bodies whose frames rows act on (through frame or node sides); dt the
/// step (the mobilities hold dt^2). Reads the bodies' compliance columns only.
void assemble_delassus(const std::vector<RowSides>& rows, const FrameMobility& mobility,
                       const std::vector<FloatingSide>& floating, double dt, Eigen::MatrixXd* w);

/// W of the rows formed column by column as the contact solver asks for them
/// (DelassusColumns): the diagonal blocks at once, a point's columns when first asked for,
/// the same values the dense assembly gives. For large problems of which few points press:
/// 72 m bytes a column formed, against 72 m^2 for W. `demand(bytes)` is told the bytes the
/// columns formed so far take before they are formed (it throws when they would not fit).
/// Keeps references to the rows.
class LazyDelassus final : public DelassusColumns {
 public:
  LazyDelassus(const std::vector<RowSides>& rows, const FrameMobility& mobility,
               const std::vector<FloatingSide>& floating, double dt,
               std::function<void(double)> demand);
  ~LazyDelassus() override;
  Eigen::Index points() const override;
  void prepare(const std::vector<Eigen::Index>& which) override;
  const double* column(Eigen::Index j) const override;
  const Eigen::Matrix3d& diagonal(Eigen::Index i) const override;
  /// The columns formed so far (of points()), and the seconds that took.
  Eigen::Index formed() const;
  double seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vproto::sim
