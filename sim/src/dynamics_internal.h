#pragma once
// What sim::Dynamics keeps per FE body; shared by its step loop (dynamics.cpp) and its
// elastic contact stage (dynamics_contact.cpp).

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include "vproto/geometry/aabb_tree.h"
#include "vproto/sim/contact_surface.h"
#include "vproto/sim/dynamics.h"
#include "vproto/sim/hot_spot.h"
#include "vproto/sim/tet_locator.h"

namespace vproto::sim {

/// Moves a rigid state by a displacement and a rotation vector (world), its spin turning
/// along.
inline void shift_by(RigidState& s, const Eigen::Matrix<double, 6, 1>& shift) {
  s.position += shift.head<3>();
  const double angle = shift.tail<3>().norm();
  if (angle == 0) return;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, shift.tail<3>() / angle));
  s.rotation = (q * s.rotation).normalized();
  s.angular_velocity = q * s.angular_velocity;
}

struct Dynamics::ElasticBody {
  ElasticModel model;
  std::unique_ptr<ElasticDynamics> solver;
  std::unique_ptr<TetLocator> locator;
  /// Points located in the reference mesh so far (probes ask every step for the same
  /// material points).
  mutable std::map<std::array<double, 3>, std::optional<MeshPoint>> located;
  Eigen::SparseMatrix<double> surface_map;  ///< surface vertices from nodal values
  std::vector<char> grip_dof;
  /// Per element: at a sharp inside corner of the body (elements_at_sharp_corners).
  std::vector<char> at_sharp_corner;
  /// Where the hot-spot stress of its sharp inside corners is read (hot_spot.h).
  std::vector<CornerRead> corner_reads;
  CornerHotSpot corner_now;  ///< their values at the last step with FE work
  MaterialPeaks peaks;       ///< the run's largest stress and strain so far (at steps)
  double peak_reaction = 0;
  double max_von_mises = 0;  ///< at the current step

  /// Displacements live in the reference frame, which moves as a rigid body (Eqs. 26-27).
  bool floating = false;
  /// The FE state is advanced (a floating body sleeps, moving rigidly, until something
  /// can touch it or a region force loads it).
  bool awake = true;
  /// The deformation is solved as equilibrium at each step (no elastic inertia).
  bool quasi_static = false;
  /// Floating bodies that can touch: the loads of the frame's six unit accelerations on the
  /// nodes, M Phi (3N by 6, frame axes: translations, then rotations about the frame's
  /// origin), and the deformation they cause, K^^-1 M Phi (grips at rest in the frame),
  /// computed once when first needed. The deformation is solved in the accelerating frame
  /// (Eqs. 26-27): a node carries its share -M Phi a of the frame's acceleration, so a force
  /// that stops the frame loads the body through its inertia, not through its grip.
  Eigen::MatrixXd inertia_load, inertia_response;
  /// A floating body nothing clamps or grips (its frame rides on the element at its
  /// centroid, ElasticModel::frame_grip) measures its deformation in mean axes: the solver's
  /// displacement u (relative to that element) less its rigid part Phi c(u), c(u) =
  /// (Phi' M Phi)^-1 Phi' M u, so that the deformation neither moves the body's centre of
  /// mass nor turns it about it. Relative to one element the rigid part is large and
  /// arbitrary (a long soft slab turns about its middle element as two cantilevers), and
  /// the points' motions under contact forces were then not symmetric in the forces: the
  /// Delassus matrix of a slab landing flat had negative eigenvalues and its contact
  /// problem unbounded solutions. In mean axes it is C P K^^-1 P' C' plus the frame's
  /// mobility, symmetric and semi-definite (P = I - Phi c: the rigid part taken out).
  /// The solver's state keeps its own gauge; every reader of positions takes the part out.
  bool mean_axes = false;
  Eigen::Matrix<double, 6, 6> rigid_mass_inverse = Eigen::Matrix<double, 6, 6>::Zero();
  /// Phi' M K^^-1 M Phi: the rigid part (times Phi' M Phi) of the deformation of the
  /// frame's six unit accelerations (with inertia_response, when that is computed).
  Eigen::Matrix<double, 6, 6> inertia_coupling = Eigen::Matrix<double, 6, 6>::Zero();
  /// c(u): zero unless mean_axes.
  Eigen::Matrix<double, 6, 1> rigid_part(const Eigen::VectorXd& u) const {
    if (!mean_axes) return Eigen::Matrix<double, 6, 1>::Zero();
    return rigid_mass_inverse * (inertia_load.transpose() * u);
  }
  /// The rigid part of the deformation that nodal forces (surface node, force in frame
  /// axes) cause with the frame's acceleration a (frame axes) they give it: c(K^^-1 (f -
  /// M Phi a)) = (Phi' M Phi)^-1 (sum_k S_k' f_k - inertia_coupling a), S_k the node's rows
  /// of inertia_response.
  template <class Forces>
  Eigen::Matrix<double, 6, 1> rigid_part_of(const Forces& forces,
                                            const Eigen::Matrix<double, 6, 1>& a) const {
    Eigen::Matrix<double, 6, 1> load = -inertia_coupling * a;
    for (const auto& [node, f] : forces)
      load.noalias() +=
          inertia_response.middleRows<3>(3 * surface.nodes[static_cast<std::size_t>(node)])
              .transpose() *
          f;
    return rigid_mass_inverse * load;
  }
  /// At a surface point (surface nodes, -1 unused, and weights): its deformation per unit
  /// frame acceleration (inertia_response's rows, frame axes) and, in mean axes, its motion
  /// per rigid part (Phi's rows; zero otherwise). `mesh` and `centroid` are the body's.
  void point_frame_rows(const std::array<int, 3>& nodes, const std::array<double, 3>& weights,
                        const geometry::TetMesh& mesh, const Eigen::Vector3d& centroid,
                        Eigen::Matrix<double, 3, 6>* response,
                        Eigen::Matrix<double, 3, 6>* rigid) const {
    response->setZero();
    rigid->setZero();
    for (std::size_t a = 0; a < 3; ++a) {
      if (nodes[a] < 0) continue;
      const int node = surface.nodes[static_cast<std::size_t>(nodes[a])];
      response->noalias() += weights[a] * inertia_response.middleRows<3>(3 * node);
      if (mean_axes) *rigid += weights[a] * rigid_rows(mesh.nodes.row(node).transpose() - centroid);
    }
  }
  /// A rigid part's motion at a point r from the centroid (frame axes).
  static Eigen::Vector3d rigid_motion(const Eigen::Matrix<double, 6, 1>& c,
                                      const Eigen::Vector3d& r) {
    return c.head<3>() + c.tail<3>().cross(r);
  }
  /// Its rows Phi_r (3 x 6): the motion at r per rigid part.
  static Eigen::Matrix<double, 3, 6> rigid_rows(const Eigen::Vector3d& r) {
    Eigen::Matrix<double, 3, 6> m;
    m.leftCols<3>().setIdentity();
    m.rightCols<3>() << 0, r.z(), -r.y(), -r.z(), 0, r.x(), r.y(), -r.x(), 0;
    return m;
  }
  /// Absolute nodal displacements (3N) of a floating body: frame motion and deformation.
  Eigen::VectorXd absolute_u;

  // contact
  bool touchable = false;
  ContactSurface surface;
  /// The broad phase over the surface's triangles: built at the first contact step, refitted
  /// to the deformed surface at the next ones.
  std::optional<geometry::AabbTree> surface_tree;
  /// Compliance K^^-1 of the kept factor: per surface node that contact rows touched, its
  /// three columns restricted to the dofs of the nodes that had columns when they were solved
  /// (itself and those before it: 3 column_row[k] + 3 rows and more, by 3), computed when the
  /// node first takes part in a contact and kept for the run. K^^-1 is symmetric, so the
  /// block of any two such nodes is in the columns solved later (`compliance`): no column is
  /// ever solved again or extended as contact spreads, and they hold about half of the
  /// square of their nodes' blocks. Stored by rows: a node's 3 x 3 block (what the Delassus
  /// blocks and the surface's motion read, node by node) is then 72 contiguous bytes.
  using NodeColumns = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  std::unordered_map<int, NodeColumns> columns;
  /// The surface nodes with columns, in the order they were solved: column_row[k] is node
  /// k's block of rows in the columns solved with or after it, or -1 (no columns).
  std::vector<int> column_row;
  std::vector<int> column_nodes;
  /// Per surface node, when contact rows last needed its columns (column_clock counts the
  /// times they were looked for): under their memory bound the longest unused go first.
  std::vector<long> column_use;
  long column_clock = 0;
  /// Whether surface node k has columns: then the motion of k under a force at any node
  /// with columns, and of those nodes under a force at k, can be read from them.
  bool has_columns(int k) const {
    return k >= 0 && static_cast<std::size_t>(k) < column_row.size() &&
           column_row[static_cast<std::size_t>(k)] >= 0;
  }
  /// Whether `ci` (the columns of a node) hold node k's block: k had columns when they were
  /// solved.
  bool holds(const NodeColumns& ci, int k) const {
    const int row = column_row[static_cast<std::size_t>(k)];
    return row >= 0 && 3 * static_cast<Eigen::Index>(row) < ci.rows();
  }
  /// The motion of node k under a unit force at node i, whose columns are `ci` (both with
  /// columns; `ck`: k's, or null to look them up): from i's columns when they hold k's
  /// block, else from k's, which were solved later and hold i's (transposed).
  Eigen::Matrix3d compliance(const NodeColumns& ci, int i, int k,
                             const NodeColumns* ck = nullptr) const {
    const auto row_k = static_cast<Eigen::Index>(column_row[static_cast<std::size_t>(k)]);
    if (3 * row_k < ci.rows()) return ci.block<3, 3>(3 * row_k, 0);
    if (!ck) ck = &columns.at(k);
    return ck
        ->block<3, 3>(3 * static_cast<Eigen::Index>(column_row[static_cast<std::size_t>(i)]), 0)
        .transpose();
  }
  /// Where node k's block of `ci` starts (its 9 values row by row), or null when `ci` does
  /// not hold it.
  const double* block_data(const NodeColumns& ci, int k) const {
    return holds(ci, k)
               ? ci.data() +
                     9 * static_cast<std::ptrdiff_t>(column_row[static_cast<std::size_t>(k)])
               : nullptr;
  }
  /// Last step's contact force (world) per (rigid part, point key).
  std::map<std::pair<int, std::int64_t>, Eigen::Vector3d> warm;  ///< by (part, point key)
  /// The surface nodes' world positions where the contact stage's last two steps started
  /// (start_x at start_time, the latest), for how the surface turns (normal prediction).
  Eigen::MatrixX3d start_x, last_start;
  double start_time = -1, last_start_time = -1;
  /// Keeps the positions where a step starts at `time` (once a step).
  void keep_start(double time, const Eigen::MatrixX3d& x) {
    if (time == start_time) return;
    last_start = std::move(start_x);
    last_start_time = start_time;
    start_x = x;
    start_time = time;
  }
  std::vector<int> partners;  ///< rigid bodies it can touch
  /// Elastic bodies it can touch whose contact with it this body's stage solves (rows on
  /// both bodies' compliances, and a floating partner's frame mobility) and leaves the
  /// reactions on them in their `pending_load` (a floating partner's frame takes a velocity
  /// jump too).
  std::vector<int> elastic_partners;
  /// Floating bodies whose stage solves their contact with this floating body.
  std::vector<int> floating_owners;
  /// Contact forces (nodal, frame axes) an owner's stage put on this body for this step.
  Eigen::VectorXd pending_load;
  /// Last step's contact forces on each elastic partner's surface nodes (its axes).
  std::map<int, std::vector<std::pair<int, Eigen::Vector3d>>> last_partner_forces;
  /// At rest: in equilibrium against its partners under constant loads, so its steps are
  /// skipped (frame and FE state kept) until a load or a partner changes (box2d's sleep).
  bool resting = false;
  int still_steps = 0;       ///< consecutive steps in which nothing moved
  long stress_version = -1;  ///< the solver state the stress figures were taken from
  /// The nodal von Mises stress, or the largest principal strain, of the solver's state,
  /// averaged over the elements at each node: both computed when a frame or an export asks
  /// for either and kept while the state stays (a body at rest keeps it frame after frame).
  const Eigen::VectorXd& nodal_field(const Body& body, bool strain) const;
  mutable Eigen::VectorXd nodal_stress, nodal_strain;
  /// Where the last step's contacts pressed: the pressed surface nodes in the reference mesh.
  std::vector<Eigen::Vector3d> pressed_points(const Body& body) const;
  /// m, how far a contact's concentration reaches into the body: two mesh sizes (a sharp
  /// edge or corner pressing a face concentrates the stress over about two elements).
  static double contact_reach(const Body& body) { return 2 * body.tet_mesh.mesh_size; }
  mutable long nodal_fields_version = -1;
  double last_motion = 0;  ///< largest surface-node displacement of the last step, m
  Eigen::Vector3d last_frame_position = Eigen::Vector3d::Zero();  ///< at the last step's start
  int last_points = 0;                    ///< contact points carrying force after the last step
  std::map<int, double> last_pair_force;  ///< per partner, N
  double force_change = 0;  ///< |change of the contact force on the frame| over the last step, N
  /// Last step's contact forces: per surface node (frame axes), and on the frame (world).
  std::vector<std::pair<int, Eigen::Vector3d>> last_forces;
  Eigen::Vector3d last_frame_force = Eigen::Vector3d::Zero();
  /// The force the contacts applied to the body over the last step (world, N).
  Eigen::Vector3d contact_force = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_frame_torque = Eigen::Vector3d::Zero();
  /// Last step's contact wrench on each movable rigid partner (force, torque about its
  /// centre at the step's start; world axes).
  std::map<int, Eigen::Matrix<double, 6, 1>> last_partner_wrench;
  /// A floating body's last-step contact wrench on its own frame from its rows on floating
  /// partners (force, torque about its centre at the step's start; world axes): the stages
  /// before it (its owners') take it as a force to come on this body, as they take the
  /// later stages' forces on rigid bodies. (Its rows on rigid and held elastic bodies they
  /// solve themselves, as its `supports`.)
  Eigen::Matrix<double, 6, 1> last_own_wrench = Eigen::Matrix<double, 6, 1>::Zero();
  /// Those rows' forces on its surface nodes (world axes), for the same stages' view of its
  /// deformation.
  std::vector<std::pair<int, Eigen::Vector3d>> last_own_forces;
  /// The partners its rows held by friction (a pressed row inside the Coulomb cone) in its
  /// last step.
  std::set<int> sticking_on;
  /// Per free rigid partner, the directions its last step's rows held it along: the sum of
  /// j j' over the rows' Jacobians j = (d, (p - c) x d) on the partner's (velocity, angular
  /// velocity), d a pressed point's normal, and a sticking one's tangents too (world axes,
  /// the lever from the partner's centre at the step's start). Dynamics::take_step moves such
  /// a partner by its end velocity along them (end_velocity_shift_).
  std::map<int, Eigen::Matrix<double, 6, 6>> last_held_rows;
  /// A floating body's last-step pressed points on rigid bodies, or on held elastic bodies
  /// (Dynamics::can_support; not floating ones):
  /// an owner's stage solves them with the pair's rows (the point on this body's surface,
  /// the holding body's plane there, the rigid part, or the elastic pair's code, and its
  /// body; a free body's mobility, an elastic one's compliance joining the rows), so that the
  /// pair's forces meet this body as its supports hold it, not as a free one.
  struct SupportRow {
    SurfaceContact c;
    int part = 0, body = 0;
    double time = 0;  ///< the step's start it was taken at (a driven body moves on since)
    /// The holding body's pose then (a free body carries the plane along since).
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    /// On a held elastic body: its surface nodes and weights at the point.
    std::array<int, 3> held_nodes{-1, -1, -1};
    std::array<double, 3> held_weights{0, 0, 0};
  };
  std::vector<SupportRow> supports;

  /// What a step changes in this body (with its solver's state): a quasi-static increment
  /// redone in two halves starts again from it. (The compliance columns, the region and the
  /// broad phase are kept: they hold for any state.)
  struct Saved {
    ElasticDynamics::State solver;
    bool awake = true, resting = false;
    int still_steps = 0, last_points = 0;
    MaterialPeaks peaks;
    double peak_reaction = 0, max_von_mises = 0, last_motion = 0, force_change = 0, start_time = -1,
           last_start_time = -1;
    Eigen::VectorXd absolute_u, pending_load;
    std::map<std::pair<int, std::int64_t>, Eigen::Vector3d> warm;
    Eigen::MatrixX3d start_x, last_start;
    std::map<int, std::vector<std::pair<int, Eigen::Vector3d>>> last_partner_forces;
    Eigen::Vector3d last_frame_position, last_frame_force, contact_force, last_frame_torque;
    std::map<int, double> last_pair_force;
    std::vector<std::pair<int, Eigen::Vector3d>> last_forces;
    std::map<int, Eigen::Matrix<double, 6, 1>> last_partner_wrench;
    Eigen::Matrix<double, 6, 1> last_own_wrench;
    std::vector<std::pair<int, Eigen::Vector3d>> last_own_forces;
    std::set<int> sticking_on;
    std::map<int, Eigen::Matrix<double, 6, 6>> last_held_rows;
    std::vector<SupportRow> supports;
  };
  /// Copies what a step changes from `from` to `to` (a body and its Saved, either way: the
  /// members have the same names).
  template <class To, class From>
  static void copy_step_state(To& to, const From& from) {
    to.awake = from.awake;
    to.resting = from.resting;
    to.still_steps = from.still_steps;
    to.last_points = from.last_points;
    to.peaks = from.peaks;
    to.peak_reaction = from.peak_reaction;
    to.max_von_mises = from.max_von_mises;
    to.last_motion = from.last_motion;
    to.force_change = from.force_change;
    to.start_time = from.start_time;
    to.last_start_time = from.last_start_time;
    to.absolute_u = from.absolute_u;
    to.pending_load = from.pending_load;
    to.warm = from.warm;
    to.start_x = from.start_x;
    to.last_start = from.last_start;
    to.last_partner_forces = from.last_partner_forces;
    to.last_frame_position = from.last_frame_position;
    to.last_frame_force = from.last_frame_force;
    to.contact_force = from.contact_force;
    to.last_frame_torque = from.last_frame_torque;
    to.last_pair_force = from.last_pair_force;
    to.last_forces = from.last_forces;
    to.last_partner_wrench = from.last_partner_wrench;
    to.last_own_wrench = from.last_own_wrench;
    to.last_own_forces = from.last_own_forces;
    to.sticking_on = from.sticking_on;
    to.last_held_rows = from.last_held_rows;
    to.supports = from.supports;
  }
  Saved save() const {
    Saved s;
    s.solver = solver->state();
    copy_step_state(s, *this);
    return s;
  }
  void restore(const Saved& s) {
    solver->restore(s.solver);
    copy_step_state(*this, s);
    stress_version = -1;  // (the solver's version moved on: figures taken again)
  }
};

struct Dynamics::Checkpoint {
  std::vector<RigidState> states;
  std::vector<std::optional<ElasticBody::Saved>> elastic;
  std::size_t events = 0, records = 0;
  std::set<std::pair<int, int>> touching;
  int points = 0;
  double force = 0, peak_force = 0, rigid_work = 0;
  double max_penetration = 0, max_penetration_time = 0, worst_residual = 0;
  long unconverged = 0, steps = 0, rows = 0;
  bool unsettled = false;
  std::optional<ContactSystem::Saved> contact;  ///< the rigid contact's, when the scene has one
};

}  // namespace vproto::sim
