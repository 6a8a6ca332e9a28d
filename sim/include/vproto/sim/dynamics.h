#pragma once
// The dynamic step loop (DESIGN.md "The step loop"): rigid bodies move freely under
// initial velocities, forces, torques and gravity, are held by `fix`, driven by `move`, or
// joined by `joint` (sim::JointSystem); rigid bodies that are not jointed touch each other
// through sim::ContactSystem (unilateral rows, impacts, friction). Elastic bodies that
// something holds, loads or can touch are advanced by the FE solver (Newmark on one kept
// factor):
//  - clamped (`fix ... region=`) or driven (`move` with a `grip`) bodies carry absolute
//    nodal displacements, their grips following the frame's `move`;
//  - gripped bodies that are not driven are floating (Eqs. 26-27): the reference frame is
//    a rigid body with the whole mass and inertia, moved by forces, gravity, joints and
//    contact; the nodal displacements live in that frame, the grips clamped to it, loaded
//    by the contact forces and the frame's acceleration. While nothing can touch such a
//    body it moves as a rigid body and no FE work is done;
//  - an elastic body that nothing holds but that can touch another carries absolute
//    displacements (translation only: it must not spin).
// Contact between an elastic body's deformed surface and a held or driven rigid body
// (surface nodes against the rigid parts and the parts' edges and vertices against the
// surface triangles, sim::ContactSurface) is a set of unilateral rows with Coulomb
// friction solved at the end of each step on the Delassus matrix of the bodies'
// responses: the FE body's compliance K^^-1 from its kept factor (columns for the
// touched nodes only, computed once and kept), plus the floating frame's mobility. No
// factorization is redone when contacts come and go. What the loop cannot honour is
// refused up front.

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "vproto/sim/contact.h"
#include "vproto/sim/contact_surface.h"
#include "vproto/sim/elastic_contact.h"
#include "vproto/sim/elastic_dynamics.h"
#include "vproto/sim/elastic_model.h"
#include "vproto/sim/frame.h"
#include "vproto/sim/joints.h"
#include "vproto/sim/rigid_body.h"
#include "vproto/sim/scene.h"

namespace vproto::sim {

/// Which bodies the FE solver advances in a dynamic run (1) and which move as rigid
/// bodies (0): decided from the statements alone, so only these are meshed.
std::vector<char> finite_element_bodies(const Scene& scene);

/// The time-step rule's start (s), written once for every caller: the scene's `dt`, else
/// the frame interval when FE bodies take part, else 1 ms (at most a thousandth of the
/// duration); rounded down to divide the frame interval, so frames fall on steps. Dynamics
/// lowers it further where contact or the tolerance ask (see Dynamics::time_step_reason).
double run_time_step(const Scene& scene);

/// The longest step (s) of at most `step` that divides `interval` into whole steps.
double step_dividing(double interval, double step);

/// Throws InputError at the first statement of `scene` this step loop cannot honour.
void check_dynamics_supported(const Scene& scene);

/// Throws InputError at the first statement a quasistatic run cannot honour: every frame
/// must be fixed or driven ('move' legs; clamped elastic bodies under force ramps), as
/// each step is an equilibrium with no inertia (joints, velocities, forces on frames
/// nothing holds are refused with the remedy). Call with check_dynamics_supported.
void check_quasistatic_supported(const Scene& scene);

/// What happened to one FE body so far.
struct ElasticStatus {
  int body = 0;
  double strain_energy = 0;         ///< J, now
  double kinetic_energy = 0;        ///< J, now
  double max_von_mises = 0;         ///< Pa, now, over element centroids
  double peak_von_mises = 0;        ///< Pa, over the run so far (at steps)
  double max_principal_strain = 0;  ///< now
  MaterialPeaks peaks;              ///< the run's largest stress and strain, where and when
  Eigen::Vector3d reaction = Eigen::Vector3d::Zero();  ///< N, holders on the body, now
  double peak_reaction = 0;                            ///< N, largest |reaction| so far
};

class Dynamics {
 public:
  /// The scene's bodies must have their mass properties, and the FE bodies their tet
  /// meshes. `time_step` > 0. When the scene gives no dt, an FE body's step is lowered to
  /// keep Newmark's period error (w_1 h)^2 / 12 of its lowest mode within the scene's
  /// tolerance (and rounded to divide the frame interval).
  Dynamics(const Scene& scene, double time_step, ContactOptions contact_options = {});
  ~Dynamics();

  /// Advances to time `t` (>= the current time) in equal steps of at most the time step.
  /// Throws SimulationError when bodies' bounds meet or the state stops being finite.
  void advance_to(double t);

  double time() const { return time_; }
  long steps() const { return steps_; }
  double time_step() const { return time_step_; }
  /// What a reader of the results should know about how bodies were modelled.
  const std::vector<std::string>& notes() const { return notes_; }
  /// Why the step is what it is (empty: as given).
  const std::string& time_step_reason() const { return time_step_reason_; }
  /// Reference frames; fixed bodies never change. An FE body's frame is its centroid
  /// carried by its `move` (grips follow it).
  const std::vector<RigidState>& states() const { return states_; }
  /// Kinetic energy of all bodies (rigid and elastic), J.
  double kinetic_energy() const;
  /// Strain energy of the elastic bodies, J.
  double strain_energy() const;
  /// Work done on the bodies by loads, gravity and holders, J.
  double external_work() const;
  /// Energy taken out by damping, J.
  double damped_energy() const;
  /// Largest violation of a joint row now (m or rad); 0 without joints.
  double joint_drift() const;
  /// The largest joint drift after any step so far.
  double max_joint_drift() const { return max_joint_drift_; }
  /// Contact: the events so far, the points carrying force and the total contact force
  /// of the last step (N), the largest pair force so far (N), the deepest penetration
  /// left after any step (m); none without contact.
  const std::vector<ContactEvent>& contact_events() const { return events_; }
  int contact_points() const {
    return (contact_ ? contact_->active_points() : 0) + elastic_points_;
  }
  double contact_force() const {
    return (contact_ ? contact_->contact_force() : 0.0) + elastic_force_;
  }
  double peak_contact_force() const {
    return std::max(contact_ ? contact_->peak_contact_force() : 0.0, elastic_peak_force_);
  }
  double max_penetration() const {
    return std::max(contact_ ? contact_->max_penetration() : 0.0, elastic_stats_.max_penetration);
  }
  /// The rigid contact solver's effort, or null when no rigid pair can touch.
  const ContactSystem* contact() const { return contact_.get(); }
  /// Whether an elastic body can touch another, and the effort of those solves.
  bool elastic_contact() const { return !elastic_pairs_.empty() || !elastic_elastic_.empty(); }
  const ElasticContactStats& elastic_contact_stats() const { return elastic_stats_; }
  /// Largest element von Mises stress over the elastic bodies now, Pa.
  double max_von_mises() const;
  /// Whether FE body `body` has clamped or gripped nodes, and the total force those holders
  /// apply to it now (N, world axes; zero for other bodies).
  bool holds(int body) const;
  Eigen::Vector3d reaction(int body) const;
  /// The force contacts applied to FE body `body` over the last step (N, world axes; zero
  /// for other bodies), those solved in another body's stage included: a snap-fit's
  /// insertion force when a push, not a drive, moves it.
  Eigen::Vector3d contact_force_on(int body) const;
  /// Whether FE body `body` has sharp inside corners whose hot-spot values are read
  /// (hot_spot.h), and those values in the present state: the largest von Mises stress (Pa)
  /// and largest principal strain over the reads away from the step's contacts (zero for
  /// other bodies, and before the body's first FE step; NaN while a contact is near every
  /// read).
  bool reads_corners(int body) const;
  std::pair<double, double> corner_values(int body) const;
  /// The FE bodies' state (empty when there are none).
  std::vector<ElasticStatus> elastic_status() const;

  /// The frame at the current time: poses, and deformed surfaces of FE bodies; the field
  /// ("none", "displacement", "von_mises", "strain" or "yield") per surface vertex.
  Frame frame(int index, const std::string& field) const;
  /// Displacement of the material point that started at `point` on `body`, m.
  Eigen::Vector3d displacement(int body, const Eigen::Vector3d& point) const;
  /// An FE body's nodal displacements (3N, world axes) and nodal-averaged von Mises
  /// stress (N), or null for a body the FE solver does not advance.
  const Eigen::VectorXd* nodal_displacement(int body) const;
  Eigen::VectorXd nodal_von_mises(int body) const;
  /// The largest principal strain at each node of an FE body's mesh, averaged over the
  /// elements around it (empty for rigid bodies).
  Eigen::VectorXd nodal_strain(int body) const;
  /// Each node's way to its material's yield (materials::yield_ratio of its nodal von
  /// Mises stress and strain; 1 = at the yield), or empty for rigid bodies.
  Eigen::VectorXd nodal_yield_ratio(int body) const;
  /// Factorization figures of an FE body (ordering, nnz(L), times).
  const SparseCholesky::Stats* factor_stats(int body) const;
  /// Seconds spent assembling and factoring at construction.
  double assemble_seconds() const { return assemble_seconds_; }
  double factor_seconds() const { return factor_seconds_; }

  /// Called after every step (for history rows).
  void on_step(std::function<void(const Dynamics&)> callback) { on_step_ = std::move(callback); }

  /// What it keeps per FE body (sim/src/dynamics_internal.h: its compliance columns and
  /// frame, which the contact rows' assembly in sim/src/delassus.cpp reads too).
  struct ElasticBody;

 private:
  struct RigidPart {
    int body = 0;
    geometry::ConvexPolytope local;  ///< body frame (origin at the centroid)
  };
  /// One step of dt: take_step and finish_step, or (quasistatic runs) an increment that is
  /// redone in halves while its contact rows do not settle.
  void step(double dt);
  void increment(double dt, int cuts);
  /// held_shift_ for a step of dt, from the loads at its start.
  void held_shifts(double dt, const std::vector<Eigen::Vector3d>& forces,
                   const std::vector<Eigen::Vector3d>& torques);
  /// What held_travel_ takes from the step of a body whose velocity the elastic stages
  /// jumped from `before` to `jumped` (displacement, rotation vector): the half of the jump
  /// along its free directions that a force over the step would not have carried it.
  Eigen::Matrix<double, 6, 1> jump_lag(int body, const RigidState& before, const RigidState& jumped,
                                       double dt) const;
  /// Advances every body over [time_, time_ + dt] (time_ stays).
  void take_step(double dt);
  /// What take_step changes (states, FE bodies, events, the figures of the run's result):
  /// a step or a stage pass redone starts again from it.
  struct Checkpoint;
  Checkpoint checkpoint() const;
  void restore(const Checkpoint& saved);
  /// elastic_contact_stage, passed again while several stages press on one movable rigid
  /// body until their forces on it agree.
  void coupled_stages(double dt, const std::vector<RigidState>& before,
                      std::vector<Eigen::Vector3d>& forces, std::vector<Eigen::Vector3d>& torques,
                      std::vector<char>& done);
  /// Moves time_ on, checks overlaps and reports the step.
  void finish_step(double dt);
  /// Contact of the elastic bodies over the step [time_, time_ + dt] from the states
  /// `before`: advances the FE bodies it concerns (marking them in `done`) and adds the
  /// contact forces on floating frames to `forces` and `torques`.
  void elastic_contact_stage(double dt, const std::vector<RigidState>& before,
                             std::vector<Eigen::Vector3d>& forces,
                             std::vector<Eigen::Vector3d>& torques, std::vector<char>& done);
  /// The bodies' elastic partners, floating owners and the contact stage's order from the
  /// owners of elastic_elastic_; false when the owners form a cycle.
  bool assign_stages();
  /// Hands a pair of floating elastic bodies to the one its other contacts support.
  void choose_owners();
  /// The bodies whose contact stages are solved together with `body`'s, in the stages'
  /// order: it alone, unless it is one of the elastic bodies linked through the movable
  /// rigid bodies they can touch and the elastic pairs their stages solve, where two of them
  /// can touch one movable rigid body (rubber jaws on a gripped block; blocks pushed
  /// together on a tray) or two of them touch each other (blocks pushed together on a fixed
  /// plate, or on a loose mat whose stage solves both blocks' rows on it).
  std::vector<int> stage_group(int body) const;
  /// Whether the pair's rows carried force in the owner's last step.
  bool pair_pressed(int owner, int other) const;
  /// The bodies elastic body `body` pressed on in the last step: its own stage's rows and
  /// the rows its owners' stages solved against it, that carried force.
  std::vector<int> pressed_on(int body) const;
  /// A rigid body that contact does not move (fixed, or driven by `move`): what a floating
  /// elastic body presses on there is a support its owners' stages can hold.
  bool holds_still(int body) const {
    return !elastic_[static_cast<std::size_t>(body)] &&
           (fixed_[static_cast<std::size_t>(body)] || driven_[static_cast<std::size_t>(body)] >= 0);
  }
  /// A body whose contacts with a floating elastic body its owners' stages can solve as
  /// supports: a rigid body (one that moves: its mobility, or its mechanism's, joins their
  /// rows), or a held elastic body (its compliance does). Not a floating elastic body (its
  /// frame moves with its own contacts).
  bool can_support(int body) const;
  /// Whether it pressed on a body other than `except` (with `moving_only`, on one that
  /// cannot support it: not can_support).
  bool presses_apart(int body, int except, bool moving_only = false) const;
  /// Computes a floating body's inertia_load and the inverse of its rigid mass (no solve).
  void rigid_modes(int body);
  /// Computes a floating body's inertia_response and inertia_coupling (6 solves, once).
  void frame_inertia(int body);
  /// A rigid partner of an elastic body that contact moves (free or jointed: neither
  /// fixed nor driven).
  bool movable_partner(int body) const { return !fixed_[body] && driven_[body] < 0; }
  /// The FE loads of body i at time t in its own frame (floating bodies: rotated into the
  /// frame, with the frame's acceleration as an inertial load).
  Eigen::VectorXd elastic_load(int body, double t) const;
  /// World positions of the surface nodes of FE body i for displacements u and a frame pose.
  Eigen::MatrixX3d surface_positions(int body, const Eigen::VectorXd& u,
                                     const RigidState& frame) const;
  /// The absolute nodal displacements of a floating body from its frame and u.
  void update_absolute(int body);
  void check_overlaps() const;
  double sum_elastic(double (ElasticDynamics::*quantity)() const) const;
  HeldMotion held_motion(int body, double t) const;
  Eigen::Vector3d frame_offset(int body, double t, Eigen::Vector3d* velocity) const;

  const Scene& scene_;
  double time_step_;
  std::string time_step_reason_;
  std::vector<std::string> notes_;
  double time_ = 0;
  long steps_ = 0;
  double rigid_work_ = 0;
  /// Rigid scenes without drives: the kinetic energy at the start, to catch a run that gains
  /// energy no load supplied (a blow-up); NaN when not watched.
  double watched_energy_ = std::numeric_limits<double>::quiet_NaN();
  double peak_supplied_ = 0;  ///< the most energy the start and the loads have given
  double max_joint_drift_ = 0;
  double assemble_seconds_ = 0, factor_seconds_ = 0;
  std::vector<RigidState> states_;
  std::vector<RigidInertia> inertias_;
  std::vector<bool> fixed_;
  std::vector<bool> moves_;                            ///< integrated as a free rigid body
  std::vector<int> driven_;                            ///< index into scene.moves, or -1
  std::vector<std::unique_ptr<ElasticBody>> elastic_;  ///< per body, null unless FE
  /// Per body, how much farther than velocity Verlet takes it this step (displacement,
  /// rotation vector): for a free rigid body that an elastic contact stage held in the last
  /// step (ElasticBody::last_held_rows), the loads' dt^2 / 2 push along the held directions,
  /// so that it moves along them by its end velocity (Moreau-Jean's rule, theta = 1) and one
  /// held at rest ends its steps at rest; zero for the others (Dynamics::take_step).
  std::vector<Eigen::Matrix<double, 6, 1>> held_shift_;
  /// For those bodies, how far (over dt) a velocity jump carries them this step: the whole
  /// jump along the held directions, half of it along the others (the rows' friction there a
  /// force over the step, as Verlet takes the loads); (I + Q) / 2, Q the mass-weighted
  /// projection on the held directions. Empty entries (zero) for the others.
  std::vector<Eigen::Matrix<double, 6, 6>> held_travel_;
  std::unique_ptr<JointSystem> joints_;
  std::unique_ptr<ContactSystem> contact_;  ///< null when no two bodies can touch
  std::vector<ContactRole> contact_roles_;
  std::vector<std::pair<int, int>> elastic_pairs_;  ///< (elastic, rigid) that can touch
  /// (owner, other) elastic bodies that can touch, solved in the owner's contact stage
  std::vector<std::pair<int, int>> elastic_elastic_;
  std::vector<int> stage_order_;        ///< elastic bodies in the contact stage's order
  std::vector<RigidPart> rigid_parts_;  ///< of the rigid bodies in those pairs
  std::vector<ContactEvent> events_;    ///< rigid and elastic contact, in order
  std::set<std::pair<int, int>> elastic_touching_;
  int elastic_points_ = 0;
  double elastic_force_ = 0, elastic_peak_force_ = 0;
  ElasticContactStats elastic_stats_;
  /// Compliance columns solved in the run, and how many of them the steps' records
  /// (ContactStepRecord::new_columns) have counted: a step without rows can solve some too
  /// (for points about to touch), which the next record counts.
  long column_solves_ = 0, recorded_columns_ = 0;
  std::function<void(const Dynamics&)> on_step_;
  /// Quasistatic runs without rigid contact: increments are cut while their contact rows
  /// do not settle (`unsettled_`, set by the contact stage).
  bool cut_increments_ = false;
  bool halve_every_increment_ = false;  ///< ContactOptions::halve_every_increment
  bool unsettled_ = false;
  /// A quasi-static increment at its last cut: its stages may pass more times (a 64th of an
  /// increment in which an apex passes an edge still finds its rows changing after 8).
  bool last_cut_ = false;
  /// Where the contact stage last found its rows unsettled: the body, the partner whose
  /// rows carried the most force, how much of the force changed or was held past an edge,
  /// and after how many passes (for the warning of an increment kept unsettled).
  struct Unsettled {
    int body = -1, partner = -1;
    double share = 0;
    int passes = 0;
  } unsettled_at_;
  double largest_contact_force_ = 0;  ///< N, on one elastic body, over the run so far
  /// A stage pass redone (coupled_stages): each stage's wrenches on its movable rigid
  /// partners from the pass before, which the stages before it take in place of their last
  /// step's (elastic_contact_stage's `later`).
  using PartnerWrenches = std::map<int, Eigen::Matrix<double, 6, 1>>;
  std::optional<std::map<int, PartnerWrenches>> pass_wrenches_;
  /// And its forces on floating partners' surface nodes (world axes; on its own by its own
  /// key: ElasticBody::last_own_forces), which the stages before it take into their view of
  /// those bodies' deformation.
  using NodeLoads = std::map<int, std::vector<std::pair<int, Eigen::Vector3d>>>;
  std::optional<std::map<int, NodeLoads>> pass_loads_;
  /// A stage's last-step wrenches on its movable partners, and a floating body's on its own
  /// frame from its rows on floating partners by its own key (ElasticBody::last_own_wrench).
  PartnerWrenches stage_wrenches(int body) const;
  /// A stage's last-step forces on floating partners' surface nodes (world axes), and a
  /// floating body's own (ElasticBody::last_own_forces) by its own key.
  NodeLoads stage_loads(int body) const;
  bool floating(int body) const;
};

}  // namespace vproto::sim
