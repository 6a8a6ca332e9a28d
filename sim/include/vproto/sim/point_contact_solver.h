#pragma once
// The complementarity problem of unilateral contact points with Coulomb friction, on a
// Delassus matrix that the bodies' responses assembled (DESIGN.md "One constraint
// language"): for each point three rows (normal, two tangents), the relative motion of
// the point over the step d = free + W lambda, and
//   d_n >= 0, lambda_n >= 0, d_n lambda_n = 0                 (Eq. 18: a row carries
//                                                               force only while pressed)
//   |lambda_t| <= mu lambda_n; d_t = 0 while |lambda_t| < mu lambda_n (sticking), else
//   lambda_t = -mu lambda_n d_t / |d_t| (sliding, friction against the slip).
// Solved by projected Gauss-Seidel on the 3 x 3 point blocks (the block solved exactly
// when it sticks; when it slides, the normal force, then a step along the slip projected on
// the Coulomb disc, whose fixed point has the friction opposite the slip),
// warm-started from a guess, and finished by a semismooth Newton method on Alart and
// Curnier's form of the law (every point's state settled together, which the sweeps cannot
// do where a body's mobility couples its points: a block held by friction on a soft pad,
// where the sweeps creep forever). Newton runs after a few sweeps, and again after twice as
// many when it fails; its dense system is solved by LAPACK. One solver for every contact
// row of the engine: a rigid island's points (sim/contact.cpp, through the bodies'
// velocities) and an elastic body's (sim/dynamics_contact.cpp, on the dense Delassus matrix
// of its kept factor's compliance columns) are PointResponses.

#include <Eigen/Core>
#include <vector>

namespace vproto::sim {

/// W of a large problem read by its points' columns, each formed when first asked for: the
/// solver reads W only at the columns of the points that carry force or are closed, and at
/// its diagonal blocks, so a problem of thousands of points of which a few hundred press is
/// not formed whole (an annular snap-fit's lip: 443 of 7,976 points pressed).
class DelassusColumns {
 public:
  virtual ~DelassusColumns() = default;
  virtual Eigen::Index points() const = 0;
  /// Forms the columns of the points `which` not formed yet (on two threads when many).
  virtual void prepare(const std::vector<Eigen::Index>& which) = 0;
  /// Point j's three columns of W (3m rows each, one after the other), once prepared.
  virtual const double* column(Eigen::Index j) const = 0;
  /// W's diagonal block of point i.
  virtual const Eigen::Matrix3d& diagonal(Eigen::Index i) const = 0;
};

struct PointContactProblem {
  Eigen::MatrixXd w;       ///< 3m by 3m, positive semidefinite (its symmetric part)
  Eigen::VectorXd free;    ///< 3m: per point the normal gap and two tangential slips
  std::vector<double> mu;  ///< m friction coefficients
  /// When set, W is read through it and `w` is empty.
  DelassusColumns* columns = nullptr;
};

struct PointContactOptions {
  int max_sweeps = 400;
  /// Converged when no sweep changes a point's motion (W_ii times its force change) by
  /// more than this, or when every point's Alart-Curnier residual (its force's distance from
  /// what Coulomb's law makes of it, times W_nn) is below it; in the units of `free` (m).
  double tolerance = 1e-12;
  /// After this many sweeps, and again after twice as many (three times at most), Newton's
  /// method from the sweeps' forces.
  int newton_after = 4;
  /// Newton's dense system (three unknowns per closed point) has at most this many
  /// unknowns; beyond, a step solves for the closed points of largest residual and keeps the
  /// others' forces.
  Eigen::Index newton_unknowns = 1500;
  /// A sweep first tries each point as sticking by the exact solve of its 3 x 3 block (normal
  /// and friction together: the points of a soft surface, whose normal and tangential motions
  /// the block couples, settle in fewer sweeps); false: the normal force first, then the
  /// friction (the redundant corners of rigid stacks settle in fewer sweeps).
  bool block_stick = true;
  /// How many times Newton's method is tried (after newton_after sweeps, then twice as many).
  int newton_tries = 3;
  /// Newton's starting Levenberg-Marquardt damping, relative to W's largest diagonal entry.
  /// The points of an elastic surface (W singular: more rows than independent motions)
  /// want 1e-3 (from 1e-6, a resting socket's first full step raised |F| 300-fold and five
  /// steps went to growing it back: the snap-fit took 2,477 Newton iterations and 7.4 s of
  /// solves, 2,065 and 5.9-6.0 s from 1e-3; 1e-4 and 1e-2 both slower); a rigid island's few
  /// independent rows want 1e-6 (a ball's rebound to 1e-14 of e^2 h, 6e-13 from 1e-3).
  double newton_damping = 1e-3;
  /// The least the damping comes down to after full steps, relative to the same. The rows of
  /// several bodies' stages solved as one, with a free rigid body they share and links between
  /// rigid bodies (a block on a beam on two rubber feet: W singular along the friction of
  /// the block's redundant corners, with no compliance there), want 1e-6: from 1e-10 their
  /// Newton steps cycled between sticking and sliding points at residuals of 1e-10 to 1e-7
  /// m, 44 iterations a solve (2,811 in the sample, 7.0 s of solves; 640 and 1.65 s from
  /// 1e-6, 425 from 1e-4). A single elastic body's rows keep 1e-10 (the snap-fit: 1,789
  /// iterations, 1,837 from 1e-6, 3,485 from 1e-4).
  double newton_damping_floor = 1e-10;
};

struct PointContactSolution {
  Eigen::VectorXd lambda;  ///< 3m: normal force and two tangential forces per point
  int sweeps = 0;
  int newton_iterations = 0;  ///< Newton steps taken (each one dense solve of the pressed points)
  double residual = 0;  ///< the last sweep's largest change or Newton's residual, units of `free`
  bool converged = false;
};

/// Systems of at least this many unknowns are factored by lu_factor's two-thread panels.
constexpr int kTwoThreadLu = 192;

/// LU with partial pivoting of a dense square matrix in place, as LAPACK's dgetrf leaves it
/// (unit lower L below the diagonal, U on and above it, 1-based row swaps in `pivots`), for
/// dgetrs. From kTwoThreadLu rows on: panels of 64 columns (128 from 1,024 rows), the updates
/// right of each dealt over two threads in chunks as wide, the next panel factored meanwhile
/// (1.5-2 times dgetrf's speed on one core at 300-1,500 rows); the factors are the same bits
/// on one core or two. Returns LAPACK's info: 0, or k > 0 when U(k, k) is exactly zero (the
/// factors are then unfinished).
int lu_factor(Eigen::MatrixXd* matrix, std::vector<int>* pivots);

/// How the points' relative motions d answer their forces, d = free + W lambda, for the one
/// solver below: the rows' responses of the bodies on either side (a rigid island's through
/// its bodies' velocities, matrix-free; an elastic body's as the dense Delassus matrix its
/// kept factor gave). The solver reads the motions and changes the forces through it.
class PointResponse {
 public:
  virtual ~PointResponse() = default;
  virtual Eigen::Index points() const = 0;
  /// W's diagonal block of point i (3 x 3, rows n, t1, t2).
  virtual Eigen::Matrix3d block(Eigen::Index i) const = 0;
  /// d_i for the forces applied so far.
  virtual Eigen::Vector3d motion(Eigen::Index i) const = 0;
  /// Point i's force changes by `delta`: every motion follows.
  virtual void add(Eigen::Index i, const Eigen::Vector3d& delta) = 0;
  /// The forces were `from` and are now `to` (a Newton step's wholesale change): the motions
  /// follow.
  virtual void replace(const Eigen::VectorXd& from, const Eigen::VectorXd& to) = 0;
  /// The problem as a dense one for the Newton finish, its free motion taken at the forces
  /// `lambda` applied now (free = d - W lambda); null when this response does not form it.
  virtual const PointContactProblem* dense(const Eigen::VectorXd& lambda) = 0;
};

/// The solver below with its per-point workspaces kept from solve to solve (an engine that
/// solves an island every step allocates them once).
class PointContactSolver {
 public:
  PointContactSolution solve(PointResponse& response, const std::vector<double>& mu,
                             const Eigen::VectorXd& warm, const PointContactOptions& options = {});

 private:
  std::vector<Eigen::Matrix3d> blocks_, block_inverse_;
  std::vector<Eigen::Matrix2d> tangent_inverse_;
  std::vector<double> tangent_step_;
  Eigen::VectorXd zero_;
};

/// Solves the points' contact law (above) on `response`: `mu` per point, `warm` (3m, or
/// empty) the forces to start from, applied through the response first. The sweeps read and
/// change the motions through it; the Newton finish runs where it forms the dense problem.
PointContactSolution solve_point_contacts(PointResponse& response, const std::vector<double>& mu,
                                          const Eigen::VectorXd& warm,
                                          const PointContactOptions& options = {});

/// Solves the dense problem; `warm` (3m, or empty) is the starting guess.
PointContactSolution solve_point_contacts(const PointContactProblem& problem,
                                          const Eigen::VectorXd& warm,
                                          const PointContactOptions& options = {});

}  // namespace vproto::sim
