#pragma once
// Which pairs of bodies touch through an elastic body's deformed surface, and the figures
// of that contact (sim::Dynamics carries it out, sim::ContactSurface finds the points,
// sim::solve_point_contacts solves the rows).

#include <string>
#include <utility>
#include <vector>

#include "vproto/sim/scene.h"

namespace vproto::sim {

/// Pairs (elastic body, rigid body) that can touch in a dynamic run: not excluded by
/// `nocontact`, not both held still.
std::vector<std::pair<int, int>> elastic_contact_pairs(const Scene& scene);

/// Pairs (a, b), a < b, of elastic bodies that can touch in a dynamic run: not excluded by
/// `nocontact`, not both held still.
std::vector<std::pair<int, int>> elastic_elastic_pairs(const Scene& scene);

/// The cost of one elastic body's contact solve in one step (a step with rows): what was
/// solved and where the time went (DIR/contact_steps.csv).
struct ContactStepRecord {
  double time = 0;      ///< s, the step's start
  int body = -1;        ///< the elastic body whose stage solved the rows
  int detected = 0;     ///< contact points the narrow phase found at the step's start
  int points = 0;       ///< points in the last solve (Delassus size / 3)
  int node_points = 0;  ///< of which: surface nodes against a partner
  int pressed = 0;      ///< of which: carrying force
  int sliding = 0;      ///< of which: pressed and sliding (on the cone's edge)
  int passes = 0;       ///< solves in the step (points joined or were taken again)
  int newton_iterations = 0;
  int sweeps = 0;         ///< Gauss-Seidel sweeps of the last solve
  bool converged = true;  ///< the last solve
  int new_columns = 0;    ///< compliance columns computed in the step (kept for later steps)
  double column_seconds = 0, delassus_seconds = 0, solve_seconds = 0;
  double seconds = 0;  ///< the body's whole contact stage in the step
};

/// Effort of the elastic contact solves of a run.
struct ElasticContactStats {
  long steps = 0;              ///< steps with at least one contact row
  long rows = 0;               ///< contact points over all solves (3 rows each)
  int max_points = 0;          ///< most contact points in one solve (Delassus size / 3)
  long sweeps = 0;             ///< Gauss-Seidel sweeps
  long newton_iterations = 0;  ///< Newton steps (one dense solve of the pressed points each)
  long unconverged = 0;        ///< solves stopped by the sweep limit
  double worst_residual = 0;   ///< m
  long response_solves = 0;    ///< solves with the kept factor for compliance columns
  long correction_solves = 0;  ///< solves applying the contact forces
  /// Times the compliance columns kept passed their memory bound (a third of the memory
  /// left) and those of the nodes that rows needed longest ago were dropped to make room.
  long column_drops = 0;
  /// Surface nodes with compliance columns (those contact rows touched), and the surface
  /// nodes of those bodies, summed over the elastic bodies that touched.
  long region_nodes = 0, surface_nodes = 0;
  /// Solves whose Delassus matrix was formed column by column as they asked (of at least
  /// 2,000 points), their points, and the points' columns they formed.
  long lazy_solves = 0, lazy_points = 0, lazy_columns = 0;
  double seconds = 0;               ///< wall time in detection, Delassus assembly and solves
  double column_seconds = 0;        ///< of which: compliance columns from the kept factor
  double delassus_seconds = 0;      ///< of which: assembling the Delassus matrices
  double solve_seconds = 0;         ///< of which: the complementarity solves
  long skipped_steps = 0;           ///< steps a floating elastic body spent as a rigid body (no FE)
  long resting_steps = 0;           ///< steps skipped while a floating body rested in equilibrium
  double max_penetration = 0;       ///< m, deepest overlap left after a step
  double max_penetration_time = 0;  ///< s, when it was found
  /// Quasistatic increments redone as two halves (a contact let go within them, or their
  /// rows did not settle within the stage's passes), and increments kept unsettled at the
  /// smallest cut.
  long cut_increments = 0, unsettled_increments = 0;
  /// The first increment kept unsettled: when, which bodies, how unsettled, and the fix
  /// (a sentence for the run's warning; empty when none was).
  std::string first_unsettled;
  /// Steps in which several elastic bodies' stages pressed on one movable rigid body, and
  /// the stage passes redone in them until the forces on it agreed (Dynamics::take_step),
  /// and the steps whose passes ended at their limit without agreeing.
  long shared_steps = 0, shared_passes = 0, shared_unsettled = 0;
  /// Contact solves of the rows of several elastic bodies' stages as one problem (a group
  /// of elastic bodies that share a movable rigid body, and the elastic bodies they touch:
  /// jaws on a gripped block, pads under a beam, blocks on a tray; Dynamics::stage_group),
  /// and their rows.
  long joint_solves = 0, joint_rows = 0;
  int threads = 1;  ///< threads computing compliance columns and Delassus blocks (1 or 2)
  std::vector<ContactStepRecord> step_records;  ///< one per body and step with rows
};

/// Threads the elastic contact stage splits compliance columns and Delassus blocks over:
/// 2 on a machine with two cores or more, unless MPI ranks share them; else 1.
int contact_threads();

}  // namespace vproto::sim
