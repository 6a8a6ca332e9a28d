#pragma once
// The linear-solver seam: a kept solver of one symmetric positive definite system, the
// interface every FE solve goes through (static equilibrium, the Newmark step matrix and
// the constraint rows' compliance columns). Two backends implement it:
//  - CHOLMOD (sparse_cholesky.h): one process, a supernodal Cholesky factor;
//  - PETSc over MPI (built when PETSc is found): the nodes split among the MPI ranks by
//    recursive coordinate bisection; static solves by conjugate gradients preconditioned
//    with p-multigrid (quadratic to linear tetrahedra, MUMPS on the linear level) or,
//    without quadratic elements, smoothed-aggregation algebraic multigrid (GAMG, the
//    rigid-body modes as its near null space); step matrices by MUMPS' distributed
//    Cholesky factor, kept and reused.
// Every rank runs the same program on the same data (the scene is replicated), calls the
// solver collectively with the same right-hand sides and gets the whole solution back,
// so the state stays identical on every rank and rank 0 writes the outputs.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace vproto::sim {

/// What a factor or solve cost and how it was made; the same record for both backends.
struct SolverStats {
  std::string backend = "cholmod";  ///< cholmod | petsc
  std::string method;               ///< e.g. "supernodal Cholesky", "CG + GAMG"
  std::string reason;               ///< why this backend ran (`solver=auto`'s choice)
  int ranks = 1;                    ///< MPI ranks that shared the solve
  std::string ordering;             ///< the fill-reducing ordering (direct methods)
  double factor_nonzeros = 0;       ///< entries of L (with supernodal padding)
  double flops = 0;                 ///< of the numeric factorization
  double analyze_seconds = 0;       ///< last symbolic analysis / preconditioner set-up
  double factor_seconds = 0;        ///< last numeric factorization / preconditioner build
  int factorizations = 0;           ///< numeric factorizations (or set-ups) so far
  double relative_tolerance = 0;    ///< iterative methods: the residual asked for
  int iterations = 0;               ///< iterative methods: of the last solve
  double relative_residual = 0;     ///< iterative methods: ||b - A x|| / ||b||, last solve
  /// Direct methods: how one right-hand side is solved (CHOLMOD's sweeps, or the two-thread
  /// sweeps over the supernodal tree and the share of L's entries left to one thread).
  std::string single_solve;
};

/// The lower triangle of a symmetric matrix in compressed columns, without copying.
using LowerView = Eigen::Map<const Eigen::SparseMatrix<double>>;

inline LowerView view_of(const Eigen::SparseMatrix<double>& lower) {
  return {lower.rows(),          lower.cols(),          lower.nonZeros(),
          lower.outerIndexPtr(), lower.innerIndexPtr(), lower.valuePtr()};
}

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;

  /// Prepares solves with the matrix (analysis kept per pattern, then the numeric
  /// factor or preconditioner). Throws SimulationError when the matrix is not positive
  /// definite (`what` names it), FactorMemoryError when a factor would not fit. `block`:
  /// the matrix is made of block x block blocks (3 for the x, y, z of FE nodes).
  virtual void factor(const LowerView& lower, const std::string& what, int block = 1) = 0;
  /// The same for the stiffness of an isotropic body (SolverSetup's coordinates and
  /// elements) computed from its elements, where the backend shares the matrix between
  /// processes: each computes only the elements its rows need, no process holding the
  /// whole matrix. The dofs of `held_dof` (3N) are held at zero (identity rows and columns,
  /// as hold_dofs). False when the backend takes whole matrices only (then call factor).
  virtual bool factor_elements(double youngs_modulus, double poisson_ratio,
                               const std::vector<char>& held_dof, const std::string& what) {
    (void)youngs_modulus, (void)poisson_ratio, (void)held_dof, (void)what;
    return false;
  }
  virtual bool factored() const = 0;
  virtual Eigen::Index size() const = 0;

  /// x = A^-1 x; one or many right-hand sides (columns).
  virtual void solve_in_place(Eigen::VectorXd& x) const = 0;
  virtual void solve_in_place(Eigen::MatrixXd& x) const = 0;

  /// Rows `rows` of X = A^-1 B for sparse right-hand sides B (the compliance columns' unit
  /// loads): a direct method visits only the parts of its factor that B reaches and that the
  /// answers at `rows` need. Thread-safe where concurrent_solves().
  virtual Eigen::MatrixXd solve_sparse(const Eigen::SparseMatrix<double>& b,
                                       const std::vector<Eigen::Index>& rows) const {
    Eigen::MatrixXd x = b;
    solve_in_place(x);
    Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), x.cols());
    for (std::size_t q = 0; q < rows.size(); ++q)
      out.row(static_cast<Eigen::Index>(q)) = x.row(rows[q]);
    return out;
  }

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const {
    Eigen::VectorXd x = b;
    solve_in_place(x);
    return x;
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const {
    Eigen::MatrixXd x = b;
    solve_in_place(x);
    return x;
  }

  virtual const SolverStats& stats() const = 0;

  /// Whether solve_in_place may run on several threads at once (each call then solves its
  /// own right-hand sides, with the same answer as alone).
  virtual bool concurrent_solves() const { return false; }

  /// Where unknown `row` sits in the factor's elimination order (a direct method's), else
  /// `row`: unit right-hand sides solved together cost least when they are near in it (their
  /// paths to the root of the elimination tree overlap).
  virtual Eigen::Index elimination_position(Eigen::Index row) const { return row; }
};

/// CHOLMOD's fill-reducing ordering (automatic: it tries AMD and METIS, keeps the best).
enum class FactorOrdering { kAutomatic, kAmd, kMetis, kNesdis };

/// `simulate(solver=...)` / `--solver`.
enum class SolverChoice { kAuto, kCholmod, kPetsc };

SolverChoice solver_choice_from(const std::string& name);  ///< auto | cholmod | petsc
std::string to_string(SolverChoice c);

/// What a solver is for: the backend picks its method from it.
enum class SolveUse {
  kStatic,  ///< one or a few solves with the matrix (iterative methods pay off)
  kKept,    ///< a step matrix solved every step and for constraint columns (a kept factor)
  kSteps,   ///< a step matrix solved once a step, no constraint columns: CG warm started
            ///< from the last step pays off on large meshes
};

struct SolverSetup {
  SolverChoice choice = SolverChoice::kAuto;
  SolveUse use = SolveUse::kKept;
  Eigen::Index dofs = 0;                                 ///< the system's size (for `auto`)
  FactorOrdering ordering = FactorOrdering::kAutomatic;  ///< CHOLMOD only
  /// Node coordinates (N x 3, m), for the rigid-body near null space of algebraic
  /// multigrid; may be empty (then the translations only).
  Eigen::MatrixX3d coordinates;
  /// The mesh's elements (E x 10 for quadratic tetrahedra): with them, a static solve
  /// is preconditioned by p-multigrid (quadratic to linear elements) instead of GAMG.
  Eigen::MatrixXi elements;
  /// Iterative methods stop at this relative residual (0: 1e-8).
  double relative_tolerance = 0;
  /// When given, recorded as the reason for the backend instead of the choice's own.
  std::string reason;
  /// SolveUse::kSteps on PETSc: warm-started CG even where a factor fits (to measure
  /// both: bench/fe_bench --cg-steps).
  bool iterative_steps = false;
};

/// The residual an iterative static solve stops at for quadratic tetrahedra of size h in
/// a body of size l: the algebraic error (at most about sqrt(cond K) ~ l/h times the
/// relative residual, in the energy norm) kept at one percent of the discretisation
/// error (about (h/l)^2 in the energy norm), so 0.01 (h/l)^3, within [1e-12, 1e-6].
double relative_tolerance_for(double h, double l);

/// True when this build has the PETSc backend.
bool petsc_available();
/// Whether an iterative solve of `dofs` unknowns (the matrix and its multigrid hierarchy,
/// about 3 kB a dof for quadratic tetrahedra) fits in factor_memory_limit().
bool iterative_solve_fits(Eigen::Index dofs);
/// The error for PETSc asked for (`asked`: how, e.g. "--solver petsc") in a build
/// without it: what to install, or what to use instead.
std::string no_petsc_message(const std::string& asked);

/// MPI ranks this process runs among (1 without mpirun). Reads the launcher's
/// environment, so it is known before MPI starts.
int launched_ranks();
/// This process's rank (0 without mpirun).
int launched_rank();

/// Starts MPI and PETSc when this process was launched by mpirun with more than one rank
/// (every rank must then take part in the solves); a no-op otherwise. Throws InputError
/// when launched on several ranks by a build without PETSc.
void start_parallel();
/// Ends PETSc and MPI when they were started (by start_parallel or by a PETSc solver).
void finish_parallel();
/// Under mpirun, whether the FE solves are shared among all ranks (the default) or each
/// rank solves alone (a sweep: each rank runs variants of its own).
void share_solves_among_ranks(bool shared);
/// Waits for every rank (MPI_Barrier) when MPI runs; a no-op otherwise.
void parallel_barrier();
/// Says that every rank has passed the last point where another could wait for it (a
/// barrier at the end of a sweep): a failure after it need not abort the job.
void mark_ranks_finished_together();
bool ranks_finished_together();
/// The peak resident memory of each rank, bytes (getrusage), gathered from every rank
/// when they share the solves: a collective call then; this process's alone otherwise.
std::vector<double> peak_memory_per_rank();

/// Ends the whole parallel job at once (a rank that failed alone): MPI_Abort when MPI
/// runs, else nothing.
void abort_parallel(int code);

/// The backend for `setup`, with the reason for the choice: `auto` takes PETSc under
/// mpirun with more than one rank (when built), and for static solves of 100k dofs or
/// more on quadratic tetrahedra (CG + p-multigrid); CHOLMOD otherwise. Throws InputError
/// (no location: the caller adds it) when PETSc is asked for and this build has none.
std::unique_ptr<LinearSolver> make_linear_solver(const SolverSetup& setup);

}  // namespace vproto::sim
