#pragma once
// Linear elastodynamics of one body: M a + C v + K u = f, with Newmark time stepping
// (average acceleration by default: beta = 1/4, gamma = 1/2, unconditionally stable and
// energy-conserving for an undamped linear system), optional Rayleigh damping
// C = alpha M + beta K and optional numerical damping (gamma > 1/2).
//
// Held nodes follow prescribed motion (clamps: zero; grips: the reference frame's motion),
// which is the seed's Eqs. 23-25: the free dofs solve
//   K^_aa u_a = R^_a - K^_ab u_b,
// and the reactions R_b = M_ba a_a + M_bb a_b + C_b v + K_ba u_a + K_bb u_b - f_b are the
// forces the holders apply.
//
// The effective matrix K^ = K + c0 M + c1 C is factored once and reused for every step
// while dt and the held set stay. Constraints that come and go (contacts) need no new
// factor: a step is split into a prediction u* (no constraint force) and a correction
// u = u* + Y lambda, where Y = K^^-1 C^T comes from the same factor (response()); the
// caller solves the small Delassus system W = C Y for lambda and accepts the step.

#include <memory>
#include <vector>

#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/linear_solver.h"

namespace vproto::sim {

struct NewmarkOptions {
  double beta = 0.25;
  double gamma = 0.5;
  double rayleigh_mass = 0;       ///< alpha, 1/s
  double rayleigh_stiffness = 0;  ///< beta, s
  FactorOrdering ordering = FactorOrdering::kAutomatic;
  /// The step solver's backend (linear_solver.h): CHOLMOD, or PETSc (MUMPS, or CG).
  SolverChoice solver = SolverChoice::kAuto;
  /// false: nothing will ask for constraint columns (response, response_at), so PETSc
  /// may solve the steps by warm-started CG instead of a kept factor.
  bool constraint_columns = true;
  /// The body's mesh: its coordinates and quadratic elements let CG use p-multigrid.
  const geometry::TetMesh* mesh = nullptr;
  /// PETSc without constraint columns: warm-started CG even where a factor fits.
  bool iterative_steps = false;
  /// false: the body's own inertia is left out and every step is an equilibrium K u = f
  /// (quasi-static deformation: used when the step cannot resolve the body's vibration,
  /// and by quasi-static runs). Velocities and kinetic energy are then zero.
  bool inertia = true;

  /// Newmark with numerical damping a >= 0 of the high frequencies: gamma = 1/2 + a,
  /// beta = (gamma + 1/2)^2 / 4 (still unconditionally stable, first order when a > 0).
  static NewmarkOptions with_numerical_damping(double a);
};

/// Prescribed motion of the held dofs at one instant (3N vectors; only held entries
/// are read).
struct HeldMotion {
  Eigen::VectorXd u, v, a;
};

class ElasticDynamics {
 public:
  ElasticDynamics(const FeMatrices& fe, std::vector<int> held_nodes, double dt,
                  NewmarkOptions options = {});

  /// Starts at time t0 from u0, v0 (3N) under forces f0; the initial acceleration solves
  /// M a0 = f0 - K u0 - C v0 (conjugate gradients on M). `held`: the held dofs' motion
  /// at t0 (zero when null).
  void start(double t0, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
             const Eigen::VectorXd& f0, const HeldMotion* held = nullptr);

  /// The displacement increment over the step to t + dt under forces f_next with no
  /// constraint force: one pair of triangular solves with the kept factor.
  const Eigen::VectorXd& predict(const Eigen::VectorXd& f_next, const HeldMotion* held = nullptr);

  /// Y = K^^-1 C^T for constraint rows given as C^T (3N by m): a force C^T lambda moves
  /// the prediction by Y lambda. Rows on held dofs have no effect (zero in Y).
  Eigen::MatrixXd response(const Eigen::SparseMatrix<double>& c_transpose) const;

  /// The rows `dofs` of response(c_transpose), solved a block of columns at a time: the
  /// memory stays a few blocks of the mesh's dofs however many rows are asked for (the
  /// whole response of thousands of columns would be gigabytes), and each block of
  /// right-hand sides stays in cache while the factor streams past it.
  Eigen::MatrixXd response_at(const Eigen::SparseMatrix<double>& c_transpose,
                              const std::vector<Eigen::Index>& dofs) const;

  /// Completes the predicted step with the increment du (the prediction, or the
  /// prediction plus Y lambda) and the constraint forces C^T lambda that made it (null:
  /// none).
  void accept(const Eigen::VectorXd& du, const Eigen::VectorXd* constraint_force = nullptr);

  /// Adds dv (3N; held dofs ignored) to the velocity after a step: contact making a closed
  /// point plastic. The kinetic energy it takes counts as dissipated.
  void change_velocity(const Eigen::VectorXd& dv);

  /// predict + accept with no constraint force.
  void step(const Eigen::VectorXd& f_next, const HeldMotion* held = nullptr);

  /// What a step changes: a quasi-static increment that is redone in two halves starts
  /// again from the state before it (Dynamics, quasistatic mode).
  struct State {
    double time = 0;
    long steps = 0;
    Eigen::VectorXd u, v, a, f;
    double work = 0, damped = 0;
    bool balanced = true;
  };
  State state() const { return {time_, steps_, u_, v_, a_, f_, work_, damped_, balanced_}; }
  void restore(const State& s);

  /// Changes dt; refactors only when the factor holds inertia (without it the factor is K).
  void set_time_step(double dt);

  /// Forms and factors the step matrix again (the same one): what every step would cost
  /// without the kept factor (`vproto bench` measures that skip with it).
  void refactor() { factor(); }

  double time() const { return time_; }
  double time_step() const { return dt_; }
  long steps() const { return steps_; }
  /// Changes whenever the state does (a body at rest keeps its figures).
  long version() const { return version_; }
  const Eigen::VectorXd& displacement() const { return u_; }
  const Eigen::VectorXd& velocity() const { return v_; }
  const Eigen::VectorXd& acceleration() const { return a_; }
  const std::vector<int>& held_nodes() const { return held_nodes_; }

  double kinetic_energy() const;  ///< 1/2 v'Mv
  double strain_energy() const;   ///< 1/2 u'Ku
  /// Work of the applied, constraint and holding forces so far (trapezoidal in u, which
  /// makes kinetic + strain - work - damped exactly zero for average acceleration).
  double external_work() const { return work_; }
  /// Dissipated by Rayleigh damping and plastic contact.
  double damped_energy() const { return damped_; }

  /// Forces the holders apply to the body at the held dofs (3N, zero elsewhere), N.
  Eigen::VectorXd reactions() const;

  const SolverStats& factor_stats() const { return solver_->stats(); }
  /// Where a load at `dof` sits in the kept factor's elimination order: response_at solves
  /// its columns in the order of their first load's place, 64 at a time.
  Eigen::Index elimination_position(Eigen::Index dof) const {
    return solver_->elimination_position(dof);
  }
  const FeMatrices& matrices() const { return fe_; }

 private:
  void factor();
  Eigen::VectorXd damping_times(const Eigen::VectorXd& x) const;
  /// (A x) at the held dofs only, for A given by its rows at the held dofs.
  Eigen::VectorXd held_times(const Eigen::SparseMatrix<double, Eigen::RowMajor>& rows,
                             const Eigen::VectorXd& x) const;
  void changed() { ++version_; }

  const FeMatrices& fe_;
  std::vector<int> held_nodes_;
  std::vector<char> held_;
  bool any_held_ = false;
  double dt_;
  NewmarkOptions o_;
  double c0_ = 0, c1_ = 0, c2_ = 0, c3_ = 0, c4_ = 0, c5_ = 0, c6_ = 0, c7_ = 0;
  std::vector<double> effective_;         ///< K^ values
  std::vector<double> effective_held_;    ///< K^ with held rows and columns as identity
  std::unique_ptr<LinearSolver> solver_;  ///< the kept factor of K^ (held dofs as identity)

  double time_ = 0;
  long steps_ = 0;
  Eigen::VectorXd u_, v_, a_, f_;  ///< state and total force (applied + constraint) at time_
  /// K and M at the rows of the held dofs (held dofs by all dofs): the reactions cost
  /// the held rows only, not a product with the whole matrices.
  Eigen::SparseMatrix<double, Eigen::RowMajor> held_k_, held_m_;
  std::vector<int> held_dofs_;
  /// Figures derived from the state, computed once per state (a body at rest asks every
  /// step and its state does not change).
  long version_ = 0;
  mutable long reaction_version_ = -1, strain_version_ = -1, kinetic_version_ = -1;
  mutable Eigen::VectorXd reaction_cache_;
  mutable double strain_cache_ = 0, kinetic_cache_ = 0;
  /// K u = f at the free dofs (an equilibrium state: no inertia, no damping, u from accept),
  /// so the strain energy is u'f plus the held dofs' u'r, without a product with K.
  bool balanced_ = true;
  // the step in progress
  Eigen::VectorXd f_next_, prediction_, next_u_;
  HeldMotion held_next_;
  bool held_moves_ = false;
  double work_ = 0, damped_ = 0;
};

}  // namespace vproto::sim
