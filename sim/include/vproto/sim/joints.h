#pragma once
// Joints between rigid bodies (or a body and the ground) as the seed builds them
// (Fig. 2): sets of scalar constraint rows, each a point-to-plane row (Eq. 16: a point of
// one body stays on a plane of the other, n'(r_C - r_P) = 0) or a perpendicularity row
// (a direction of one body stays at right angles to a direction of the other).
//   spherical: three point-to-plane rows through the joint point (the other body's axes);
//   revolute:  spherical + two rows keeping the axis square to two of the other's
//              directions;
//   slider:    two point-to-plane rows (the axis' point stays on two planes through the
//              axis) + three rows locking the rotation;
//   fixed:     three point rows + three rotation rows.
// The constrained bodies step with the multipliers of the DAE (Eqs. 8-11) as impulses, by
// RATTLE: half a kick; the rows' reaction along their directions at the start, found by
// simplified Newton steps so that the positions the half-step velocity carries the bodies
// to satisfy every row to 1e-13 m; half a kick at the end, and the velocities made
// consistent with the rows there (J u = 0). Symplectic and second order: a pendulum
// released horizontal keeps its energy to 1e-5 of m g d over 10 s at dt 1 ms, and joint
// drift stays far below 1e-9 m whatever the step count.

#include <vector>

#include "vproto/sim/rigid_body.h"
#include "vproto/sim/scene.h"

namespace vproto::sim {

/// How bodies of inverse mass `minv` (6 per body) answer loads with the rows `j` held:
/// M^-1 - M^-1 J' (J M^-1 J')^+ J M^-1, a least-norm solve for redundant rows. With
/// `velocity`, it is projected on what the rows allow as well (its part along their
/// reactions changed so that J v = `target`, or 0).
Eigen::MatrixXd held_inverse_mass(const Eigen::MatrixXd& minv, const Eigen::MatrixXd& j,
                                  Eigen::VectorXd* velocity = nullptr,
                                  const Eigen::VectorXd* target = nullptr);

class JointSystem {
 public:
  /// The scene's joints; bodies held by `fix` count as ground.
  JointSystem(const Scene& scene, const std::vector<bool>& fixed);

  bool empty() const { return rows_.empty(); }
  /// Whether the body is moved by this system (it has a joint and is not fixed).
  bool moves(int body) const { return body >= 0 && member_[body]; }

  /// Advances every member body by dt under world forces and torques (per body, at the
  /// centre of mass). Throws SimulationError when the rows cannot be satisfied.
  void step(std::vector<RigidState>& states, const std::vector<RigidInertia>& inertias,
            const std::vector<Eigen::Vector3d>& forces, const std::vector<Eigen::Vector3d>& torques,
            double dt) const;

  /// The member bodies that joints tie together, directly or through one another (bodies
  /// held still count as ground): one list per mechanism, in body order.
  const std::vector<std::vector<int>>& mechanisms() const { return mechanisms_; }
  /// The mechanism `body` belongs to (an index into mechanisms()), or -1.
  int mechanism_of(int body) const { return body >= 0 ? mechanism_[body] : -1; }
  /// Where `body` is in its mechanism's list (its block in mechanism_mobility).
  int slot(int body) const;

  /// How a mechanism answers loads with every joint row held: the 6k x 6k inverse mass
  /// P = M^-1 - M^-1 J' (J M^-1 J')^+ J M^-1 of its k bodies (world axes, per body the
  /// 6-vector (force, torque) at its centre of mass to (acceleration, angular
  /// acceleration)). Block (i, j) is how body i answers a load on body j: the joint rows
  /// solved exactly, as equality rows of the one constraint solve, their reactions
  /// eliminated (a contact on a chain's link moves the whole chain).
  Eigen::MatrixXd mechanism_mobility(const std::vector<RigidState>& states,
                                     const std::vector<RigidInertia>& inertias,
                                     int mechanism) const;

  /// The diagonal block of mechanism_mobility for `body`: how a jointed reference frame
  /// answers contact forces on it alone, the rest of its mechanism moving as the joints
  /// make it.
  Eigen::Matrix<double, 6, 6> mobility(const std::vector<RigidState>& states,
                                       const std::vector<RigidInertia>& inertias, int body) const;

  /// Largest violation of any row now, m (or rad for the direction rows).
  double drift(const std::vector<RigidState>& states) const;

 private:
  struct Row {
    bool perpendicular = false;                    ///< direction row (else point-to-plane)
    int a = 0, b = kGround;                        ///< b may be the ground
    Eigen::Vector3d pa = Eigen::Vector3d::Zero();  ///< point in a's frame (point rows)
    Eigen::Vector3d pb = Eigen::Vector3d::Zero();  ///< the same point in b's frame
    Eigen::Vector3d da = Eigen::Vector3d::Zero();  ///< a's direction (perpendicular rows)
    Eigen::Vector3d db = Eigen::Vector3d::Zero();  ///< b's direction, or its plane normal
  };
  double value(const Row& row, const std::vector<RigidState>& states) const;
  /// The row's Jacobian block on one of its bodies (side a, else b): its rate per unit of
  /// that body's (velocity, angular velocity).
  Eigen::Matrix<double, 1, 6> jacobian(const Row& row, const std::vector<RigidState>& states,
                                       bool side_a) const;
  void add_point_rows(int a, int b, const Eigen::Vector3d& world_point,
                      const std::vector<Eigen::Vector3d>& normals);
  void add_perpendicular_row(int a, int b, const Eigen::Vector3d& da, const Eigen::Vector3d& db);

  const Scene& scene_;
  std::vector<Row> rows_;
  std::vector<char> member_;
  std::vector<int> mechanism_;  ///< per body, or -1
  std::vector<std::vector<int>> mechanisms_;
  std::vector<bool> fixed_;
};

}  // namespace vproto::sim
