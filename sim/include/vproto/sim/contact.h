#pragma once
// Contact between rigid bodies (DESIGN.md "One constraint language"): the seed's
// point-to-surface rows (Eq. 16) made unilateral. Each step:
//  1. broad phase: the convex parts' boxes grown by how far each body can travel in the
//     step (geometry::AabbTree); pairs that cannot meet within the step cost nothing;
//  2. narrow phase: GJK distance and the contact features (geometry::contact_manifold):
//     every contact point is a pair of material points that must stay on the outer side
//     of the touching face, n'(p_B - p_A) >= 0, the normal n carried by the body whose
//     face it is;
//  3. impacts: points that are closed and approaching get a velocity jump with Newton's
//     restitution (v_n+ >= -e v_n-) and Coulomb friction, as an instantaneous impulse;
//  4. the time of first contact: a step that would carry an open point through its plane
//     is cut at the instant the gap closes (from the gap, its rate and the free
//     acceleration), so impacts happen where the surfaces meet, not deep inside;
//  5. the smooth part of the step (Moreau's midpoint scheme, exact for constant loads on a
//     free body): the unilateral rows (lambda >= 0, v_n+ >= 0 on closed points) with
//     Coulomb's cone |lambda_t| <= mu lambda_n, solved as a complementarity problem by the
//     one contact solver that elastic bodies' rows use too (point_contact_solver.h), over
//     the island's body velocities: projected Gauss-Seidel on the point blocks, warm-started
//     from the previous step's forces, finished on a small island by Newton's method (the
//     active-set method of Eq. 18 in semismooth form: every point's state settled
//     together); a row is active while its reaction is compressive and drops out when it
//     would pull;
//  6. positions projected out of any penetration (mass-weighted, push only), velocities
//     untouched, so resting contact neither sinks nor gains energy.
// Every pair that starts or stops touching is an event.

#include <map>
#include <set>
#include <string>
#include <vector>

#include "vproto/geometry/convex_distance.h"
#include "vproto/sim/point_contact_solver.h"
#include "vproto/sim/rigid_body.h"
#include "vproto/sim/scene.h"

namespace vproto::sim {

/// How a body takes part in contact.
enum class ContactRole : char {
  kNone,       ///< not handled here (elastic FE bodies)
  kFree,       ///< a rigid body moved by loads and contact
  kStatic,     ///< fixed: infinite mass, at rest
  kKinematic,  ///< driven by `move`: infinite mass, its own velocity
  /// Held by joints (sim::JointSystem moves it): contact answers through the mobility of
  /// its mechanism that the caller gives each step (set_mechanism: the inverse mass of all
  /// the bodies its joints tie together, with the joint rows held); an impact jumps the
  /// mechanism's velocities, the smooth step's contact impulse is handed back
  /// (jointed_impulse) for the joints to apply as a load over the step, as Moreau's
  /// midpoint rule has it.
  kJointed,
};

struct ContactEvent {
  double time = 0;  ///< s
  bool added = true;
  int body_a = 0, body_b = 0;
};

struct ContactOptions {
  /// Gauss-Seidel sweeps per solve (it stops earlier when converged): at most
  /// `max_sweeps`, and for a large island the share sweep_budget / points, but never
  /// fewer than `min_sweeps`.
  int max_sweeps = 200;
  int min_sweeps = 30;
  long sweep_budget = 20000;
  /// A solve has converged when no sweep changes a contact velocity by more than this
  /// fraction of the velocity scale of the step (m/s).
  double tolerance = 1e-10;
  int max_substeps = 16;  ///< cuts at times of first contact per step
  /// Islands of at most this many rows (3 per point) that Gauss-Seidel does not settle in 20
  /// sweeps are finished by Newton's method (Eq. 18's active sets, every point's state settled
  /// together); larger ones by the sweeps alone.
  int active_set_rows = 60;
  /// Each island of bodies linked by contact solved and cut at its impacts on its own;
  /// false: all touching bodies as one island (`vproto bench` measures what islands save).
  bool islands = true;
  /// A floating elastic body with no load of its own moves as a rigid body, with no FE
  /// work, until something can touch it within a step; false: FE from the first step.
  bool rigid_until_contact = true;
  /// (Tests) every quasistatic increment is redone once as two halves from the state before
  /// it, as one whose contact lets go is: the run is then the run at half the increment.
  bool halve_every_increment = false;
};

/// Settings of one pair: the pair's `contact A B`, else the scene's `contact`, else the
/// geometric mean of the two materials' values (a missing value counts as 0).
double pair_friction(const Scene& scene, int a, int b);
double pair_restitution(const Scene& scene, int a, int b);

/// Which bodies can touch another in a dynamic run (rigid, with a partner that is not
/// excluded by `nocontact`, not joined to it by a joint, and not also held still): only
/// these need their convex parts.
std::vector<char> contact_bodies(const Scene& scene);

class ContactSystem {
 public:
  /// `roles` per body. Bodies with a role other than kNone need their convex parts (when
  /// the scene has not computed them, they are computed here).
  ContactSystem(const Scene& scene, std::vector<ContactRole> roles, ContactOptions options = {});

  /// Whether some pair of bodies can touch at all.
  bool empty() const { return parts_.empty(); }

  /// Advances over [t, t + dt] every free body that may touch something within the step
  /// (they are flagged in `advanced`; the caller moves the others). Kinematic bodies move
  /// with their velocity in `states`. `forces` and `torques` are world loads at the
  /// centre of mass, constant over the step. Throws SimulationError when a body this
  /// system does not handle would be touched, or the contact cannot be resolved.
  void step(std::vector<RigidState>& states, const std::vector<RigidInertia>& inertias,
            const std::vector<Eigen::Vector3d>& forces, const std::vector<Eigen::Vector3d>& torques,
            double t, double dt, std::vector<char>* advanced);

  /// A mechanism of jointed bodies (sim::JointSystem::mechanisms: `bodies` in body order)
  /// and its mobility for the next step, 6k x 6k (JointSystem::mechanism_mobility: block
  /// (i, j) takes a (force, torque) on body j at its centre of mass to body i's
  /// (acceleration, angular acceleration), world axes). Contact on any of its kJointed
  /// bodies answers through it: the joint rows held exactly, so a contact on one link moves
  /// the whole chain, and two contacts on one mechanism are solved together (one island).
  void set_mechanism(const std::vector<int>& bodies, const Eigen::MatrixXd& mobility);

  /// The last step's smooth contact impulse on a kJointed body (world: impulse, and its
  /// moment about the centre of mass), N s.
  const Eigen::Matrix<double, 6, 1>& jointed_impulse(int body) const {
    return now_.jointed_impulse.at(static_cast<std::size_t>(body));
  }

  /// The last step's position correction of a mechanism's body out of overlaps (world: its
  /// centre's displacement, and its rotation vector), to be applied where the step starts
  /// (its joints then carry it over the step and put it back on their rows).
  const Eigen::Matrix<double, 6, 1>& jointed_correction(int body) const {
    return now_.jointed_correction.at(static_cast<std::size_t>(body));
  }

  /// How far the last step carried a body it advanced (world: its centre's displacement,
  /// and its rotation vector), summed from the increments (no difference of positions, so
  /// the loads' work over a tiny step keeps its digits).
  const Eigen::Matrix<double, 6, 1>& travel(int body) const {
    return now_.travel.at(static_cast<std::size_t>(body));
  }

  /// Checks the starting state: bodies that overlap by more than the contact tolerance
  /// throw SimulationError naming them (a scene must start without interference).
  void check_start(const std::vector<RigidState>& states) const;

  /// Contact points carrying force after the last step.
  int active_points() const { return now_.active_points; }
  /// Sum over touching pairs of |total contact force| averaged over the last step, N.
  double contact_force() const { return now_.contact_force; }
  /// Largest pair force of any step so far, N.
  double peak_contact_force() const { return now_.peak_contact_force; }
  /// Deepest penetration left after any step so far, m.
  double max_penetration() const { return now_.max_penetration; }
  const std::vector<ContactEvent>& events() const { return events_; }
  /// Effort figures: solves, Gauss-Seidel sweeps, cuts at times of first contact,
  /// narrow-phase queries, and the largest residual a solve stopped at (m/s).
  struct Stats {
    long solves = 0, sweeps = 0, substeps = 0, queries = 0, unconverged = 0;
    double worst_residual = 0;
  };
  const Stats& stats() const { return stats_; }

  /// A pressed point of a free body on a fixed or driven one at the end of the last step:
  /// where it is (world), the direction the holding body pushes the free one along, the
  /// friction force on the free one (N, world; its sliding part when it slid), and the
  /// holding body's velocity there.
  struct Support {
    Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d friction = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< the holding body's, at the point
    bool sticking = false;
    /// Held by friction at the step's end: sticking, or on the friction cone's edge with a
    /// slip below a millionth of the step's velocity scale (a resting stack's redundant
    /// corners can keep friction there that cancels out). Never without friction.
    bool still = false;
    int body = -1;  ///< the holding body
  };
  /// The last step's supports of a free body (what holds it up: the elastic contact stage
  /// lets a free rigid partner answer with them held).
  const std::vector<Support>& supports(int body) const {
    return now_.supports.at(static_cast<std::size_t>(body));
  }
  /// A point where two free bodies touched (pressed, or nearly closed) at the end of the
  /// last step: its places on a and on b (world), the normal of a's force on b, and the parts
  /// it is between.
  struct Link {
    int a = 0, b = 0, part_a = 0, part_b = 0;
    Eigen::Vector3d on_a = Eigen::Vector3d::Zero(), on_b = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  };
  /// The last step's links (an elastic body's contact stage solves those between the free
  /// rigid bodies it touches, blocks stacked on a rubber pad, with its own rows).
  const std::vector<Link>& links() const { return now_.links; }

  /// What the system carries from one step to the next (its events apart): the warm
  /// starts, the touching pairs, the supports and links, the last step's figures.
  struct Carried {
    /// per body: the last step's contact impulse and overlap correction on a jointed body,
    /// and how far the step carried a body it advanced (jointed_impulse() ...)
    std::vector<Eigen::Matrix<double, 6, 1>> jointed_impulse, jointed_correction, travel;
    std::vector<std::vector<Support>> supports;  ///< per body, of the last step
    std::vector<Link> links;                     ///< of the last step
    /// Contact forces of the last step per pair of parts (for warm starts): the points'
    /// places on A (body frame) and their force, world axes.
    std::map<std::pair<int, int>, std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>> warm;
    std::map<std::pair<int, int>, char> touching;  ///< body pairs touching now
    int active_points = 0;
    double contact_force = 0, peak_contact_force = 0, max_penetration = 0;
  };
  /// That state and how many events there were: a quasi-static increment redone in halves
  /// starts again from it (Dynamics::increment); the effort figures (stats) stay counted.
  struct Saved {
    Carried carried;
    std::size_t events = 0;
  };
  Saved save() const;
  void restore(const Saved& saved);

 private:
  struct Part {
    int body = 0;
    geometry::ConvexPolytope local;  ///< in the body frame (origin at the centroid)
  };
  struct Point;
  struct Solver;
  /// Part pairs (A's body first) whose boxes, grown by each body's reach, overlap.
  std::vector<std::pair<int, int>> candidates(const std::vector<RigidState>& states,
                                              const std::vector<double>& reach) const;
  /// The contact points of these part pairs that are within reach.
  std::vector<Point> narrow(const std::vector<RigidState>& states, const std::vector<double>& reach,
                            const std::vector<std::pair<int, int>>& pairs) const;
  /// The supports of the island's free bodies from its solved `rows` (impulses over h):
  /// their pressed points on fixed or driven bodies, and on free bodies that their own
  /// supports hold (none slipping faster than `still_speed`), as far down a stack as that
  /// goes.
  void add_supports(const std::vector<Point*>& rows, const std::vector<RigidState>& states,
                    double h, double still_speed);
  /// Sweeps (or passes) a solve over `points` may take: the budget's share, in bounds.
  int sweeps_for(std::size_t points, int floor, int ceiling) const;

  const Scene& scene_;
  std::vector<ContactRole> roles_;
  ContactOptions options_;
  std::vector<Part> parts_;
  std::vector<double> radius_;  ///< per body: farthest part vertex from the centroid
  struct Mechanism {
    std::vector<int> bodies;
    Eigen::MatrixXd mobility;
  };
  std::vector<Mechanism> mechanisms_;
  /// per body: its mechanism (an index into mechanisms_, or -1) and its slot there
  std::vector<int> mechanism_of_, slot_;
  std::set<std::pair<int, int>> skip_;  ///< nocontact pairs (lower index first)

  Carried now_;  ///< what the next step starts from
  std::vector<ContactEvent> events_;
  mutable Stats stats_;
  /// The parts placed in the world by the narrow phase (storage kept from step to step) and
  /// the configuration each was placed in: its body's state at that call.
  mutable std::vector<geometry::ConvexPolytope> world_parts_;
  mutable std::vector<long> placed_in_;
  mutable long narrow_calls_ = 0;
  PointContactSolver point_solver_;  ///< its workspaces kept from solve to solve
};

}  // namespace vproto::sim
