// The PETSc backend of the linear-solver seam. Every rank holds the same matrix (the scene
// is replicated) and takes its own rows into a distributed AIJ matrix (3 x 3 blocks for
// FE nodes): contiguous runs of nodes, so a node's three dofs stay on one rank.
//  - Static solves (SolveUse::kStatic): conjugate gradients, smoothed-aggregation
//    multigrid (GAMG) with the six rigid-body modes as its near null space, to the
//    relative residual of SolverSetup.
//  - Kept step matrices (SolveUse::kKept): MUMPS' distributed Cholesky factor, computed
//    once and reused for every step's right-hand sides and constraint columns.
// Right-hand sides come in whole on every rank and solutions go back whole to every rank
// (one all-gather), so all ranks keep the same state. PETSc_OPTIONS in the environment
// can tune the Krylov method and preconditioner (-ksp_*, -pc_*).

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <vector>

#include "petsc_backend.h"
#include "vproto/materials/errors.h"

#ifdef VPROTO_HAVE_PETSC
#include <mpi.h>
#include <petscksp.h>
#endif

namespace vproto::sim::detail {

#ifdef VPROTO_HAVE_PETSC
namespace {

bool g_started = false;

std::string petsc_text(PetscErrorCode code) {
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  return text ? std::string(text) : "error " + std::to_string(code);
}

void check(PetscErrorCode code, const char* what) {
  if (code) throw SimulationError(std::string("PETSc: ") + what + ": " + petsc_text(code));
}

void ensure_started() {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (!up) petsc_start();
}

const char* mumps_ordering(PetscInt code) {
  switch (code) {
    case 0:
      return "mumps: amd";
    case 2:
      return "mumps: amf";
    case 3:
      return "mumps: scotch";
    case 4:
      return "mumps: pord";
    case 5:
      return "mumps: metis";
    case 6:
      return "mumps: qamd";
    default:
      return "mumps";
  }
}

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

class PetscSolver final : public LinearSolver {
 public:
  PetscSolver(const SolverSetup& setup, const std::string& reason)
      : setup_(setup), direct_(setup.use == SolveUse::kKept) {
    ensure_started();
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank_);
    MPI_Comm_size(PETSC_COMM_WORLD, &ranks_);
    stats_.backend = "petsc";
    stats_.reason = reason;
    stats_.ranks = ranks_;
    stats_.method = direct_ ? "MUMPS Cholesky (distributed factor, kept)"
                            : "CG + GAMG (rigid-body near null space)";
    if (!direct_)
      stats_.relative_tolerance = setup.relative_tolerance > 0 ? setup.relative_tolerance : 1e-8;
  }
  ~PetscSolver() override { destroy(); }
  PetscSolver(const PetscSolver&) = delete;
  PetscSolver& operator=(const PetscSolver&) = delete;

  void factor(const LowerView& a, const std::string& what, int block) override;
  bool factored() const override { return ksp_ != nullptr; }
  Eigen::Index size() const override { return n_; }
  void solve_in_place(Eigen::VectorXd& x) const override;
  void solve_in_place(Eigen::MatrixXd& x) const override;
  const SolverStats& stats() const override { return stats_; }

 private:
  void destroy() {
    if (gather_) VecScatterDestroy(&gather_);
    if (all_) VecDestroy(&all_);
    if (x_) VecDestroy(&x_);
    if (b_) VecDestroy(&b_);
    if (ksp_) KSPDestroy(&ksp_);
    if (a_) MatDestroy(&a_);
    gather_ = nullptr;
    all_ = x_ = b_ = nullptr;
    ksp_ = nullptr;
    a_ = nullptr;
  }
  void split(int block);
  void solve_columns(Eigen::MatrixXd& x, Eigen::Index first, Eigen::Index count) const;

  SolverSetup setup_;
  bool direct_;
  int rank_ = 0, ranks_ = 1;
  PetscInt n_ = 0, row0_ = 0, rows_ = 0;
  std::vector<int> counts_, starts_;  ///< rows of each rank
  std::string what_;
  Mat a_ = nullptr;
  KSP ksp_ = nullptr;
  Vec b_ = nullptr, x_ = nullptr, all_ = nullptr;
  VecScatter gather_ = nullptr;
  mutable SolverStats stats_;
};

// Contiguous runs of whole blocks (nodes), as even as the blocks allow.
void PetscSolver::split(int block) {
  const long nb = n_ / block;
  counts_.assign(static_cast<std::size_t>(ranks_), 0);
  starts_.assign(static_cast<std::size_t>(ranks_), 0);
  for (int r = 0; r < ranks_; ++r) {
    const long b0 = nb * r / ranks_, b1 = nb * (r + 1) / ranks_;
    starts_[static_cast<std::size_t>(r)] = static_cast<int>(b0 * block);
    counts_[static_cast<std::size_t>(r)] = static_cast<int>((b1 - b0) * block);
  }
  row0_ = starts_[static_cast<std::size_t>(rank_)];
  rows_ = counts_[static_cast<std::size_t>(rank_)];
}

void PetscSolver::factor(const LowerView& a, const std::string& what, int block) {
  VPROTO_DEMAND(a.rows() == a.cols());
  destroy();
  what_ = what;
  n_ = static_cast<PetscInt>(a.rows());
  if (block < 1 || n_ % block != 0) block = 1;
  split(block);
  const auto assembling = Clock::now();
  // this rank's rows of the whole symmetric matrix, in compressed rows: row i holds the
  // lower triangle's row i (columns j < i, found in columns j) and its column i (j >= i);
  // scanning the columns in order leaves every row's columns sorted
  const PetscInt r0 = row0_, r1 = row0_ + rows_;
  std::vector<PetscInt> ptr(static_cast<std::size_t>(rows_) + 1, 0);
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  for (PetscInt j = 0; j < n_; ++j)
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const PetscInt i = inner[k];
      if (i >= r0 && i < r1) ++ptr[static_cast<std::size_t>(i - r0 + 1)];
      if (i != j && j >= r0 && j < r1) ++ptr[static_cast<std::size_t>(j - r0 + 1)];
    }
  for (std::size_t i = 1; i < ptr.size(); ++i) ptr[i] += ptr[i - 1];
  std::vector<PetscInt> col(static_cast<std::size_t>(ptr.back()));
  std::vector<PetscScalar> val(col.size());
  std::vector<PetscInt> next(ptr.begin(), ptr.end() - 1);
  for (PetscInt j = 0; j < n_; ++j)
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const PetscInt i = inner[k];
      if (i >= r0 && i < r1) {
        const auto at = static_cast<std::size_t>(next[static_cast<std::size_t>(i - r0)]++);
        col[at] = j;
        val[at] = value[k];
      }
      if (i != j && j >= r0 && j < r1) {
        const auto at = static_cast<std::size_t>(next[static_cast<std::size_t>(j - r0)]++);
        col[at] = i;
        val[at] = value[k];
      }
    }
  check(MatCreate(PETSC_COMM_WORLD, &a_), "creating the matrix");
  check(MatSetSizes(a_, rows_, rows_, n_, n_), "sizing the matrix");
  check(MatSetType(a_, MATAIJ), "typing the matrix");
  check(MatSetBlockSize(a_, block), "blocking the matrix");
  check(MatSeqAIJSetPreallocationCSR(a_, ptr.data(), col.data(), val.data()), "filling the matrix");
  check(MatMPIAIJSetPreallocationCSR(a_, ptr.data(), col.data(), val.data()), "filling the matrix");
  check(MatSetOption(a_, MAT_SPD, PETSC_TRUE), "marking the matrix positive definite");
  check(MatCreateVecs(a_, &x_, &b_), "creating vectors");
  check(VecScatterCreateToAll(x_, &gather_, &all_), "creating the gather");

  check(KSPCreate(PETSC_COMM_WORLD, &ksp_), "creating the solver");
  check(KSPSetOperators(ksp_, a_, a_), "setting the operator");
  PC pc = nullptr;
  check(KSPGetPC(ksp_, &pc), "getting the preconditioner");
  if (direct_) {
    check(KSPSetType(ksp_, KSPPREONLY), "choosing the direct solve");
    check(PCSetType(pc, PCCHOLESKY), "choosing Cholesky");
    check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "choosing MUMPS");
  } else {
    check(KSPSetType(ksp_, KSPCG), "choosing CG");
    check(PCSetType(pc, PCGAMG), "choosing GAMG");
    check(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED), "choosing the residual norm");
    check(KSPSetTolerances(ksp_, stats_.relative_tolerance, 1e-300, PETSC_DEFAULT, 20000),
          "setting the tolerance");
    const Eigen::MatrixX3d& xyz = setup_.coordinates;
    if (block == 3 && xyz.rows() * 3 == n_) {
      Vec coordinates = nullptr;
      check(VecCreateMPI(PETSC_COMM_WORLD, rows_, n_, &coordinates), "creating coordinates");
      check(VecSetBlockSize(coordinates, 3), "blocking coordinates");
      PetscScalar* p = nullptr;
      check(VecGetArray(coordinates, &p), "filling coordinates");
      for (PetscInt i = 0; i < rows_; ++i) p[i] = xyz((r0 + i) / 3, (r0 + i) % 3);
      check(VecRestoreArray(coordinates, &p), "filling coordinates");
      MatNullSpace modes = nullptr;
      check(MatNullSpaceCreateRigidBody(coordinates, &modes), "forming the rigid-body modes");
      check(MatSetNearNullSpace(a_, modes), "setting the near null space");
      MatNullSpaceDestroy(&modes);
      VecDestroy(&coordinates);
    }
  }
  check(KSPSetFromOptions(ksp_), "reading PETSC_OPTIONS");
  stats_.analyze_seconds = seconds_since(assembling);
  const auto setting_up = Clock::now();
  const PetscErrorCode setup = KSPSetUp(ksp_);
  PCFailedReason failed = PC_NOERROR;
  PCGetFailedReason(pc, &failed);
  if (setup || failed != PC_NOERROR) {
    PetscInt status = 0;  // MUMPS' INFOG(1): -10 a singular matrix or, for SPD, a pivot <= 0
    Mat f = nullptr;
    if (direct_ && PCFactorGetMatrix(pc, &f) == 0 && f) MatMumpsGetInfog(f, 1, &status);
    destroy();
    if (failed == PC_FACTOR_NUMERIC_ZEROPIVOT || failed == PC_FACTOR_STRUCT_ZEROPIVOT ||
        status == -10)
      throw SimulationError(what + " is not positive definite (MUMPS met a pivot <= 0)");
    if (!direct_ && failed == PC_SUBPC_ERROR)
      throw SimulationError(what +
                            " is not positive definite, or multigrid cannot precondition it "
                            "(GAMG's smoothers failed to set up); try solver=cholmod");
    if (failed == PC_FACTOR_OUTMEMORY)
      throw SimulationError("MUMPS ran out of memory factoring " + what);
    throw SimulationError("PETSc could not set up the solver of " + what +
                          (setup ? ": " + petsc_text(setup) : std::string()) +
                          (status ? " (MUMPS INFOG(1) = " + std::to_string(status) + ")" : "") +
                          " [" + PCFailedReasons[failed] + "]");
  }
  stats_.factor_seconds = seconds_since(setting_up);
  ++stats_.factorizations;
  if (direct_) {
    Mat f = nullptr;
    if (PCFactorGetMatrix(pc, &f) == 0 && f) {
      PetscInt entries = 0, ordering = -1, negative = 0;
      PetscReal flops = 0;
      MatMumpsGetInfog(f, 12, &negative);  // negative pivots met
      if (negative > 0) {
        destroy();
        throw SimulationError(what + " is not positive definite (MUMPS met " +
                              std::to_string(negative) + " negative pivots)");
      }
      MatMumpsGetInfog(f, 29, &entries);  // entries of the factors (negative: millions)
      MatMumpsGetInfog(f, 7, &ordering);
      MatMumpsGetRinfog(f, 3, &flops);  // of the elimination
      stats_.factor_nonzeros = entries < 0 ? -1e6 * entries : static_cast<double>(entries);
      stats_.flops = flops;
      stats_.ordering = mumps_ordering(ordering);
    }
  } else {
    stats_.ordering = "none (iterative)";
  }
}

void PetscSolver::solve_in_place(Eigen::VectorXd& x) const {
  VPROTO_DEMAND(factored() && x.size() == n_);
  PetscScalar* p = nullptr;
  check(VecGetArray(b_, &p), "filling the right-hand side");
  std::copy(x.data() + row0_, x.data() + row0_ + rows_, p);
  check(VecRestoreArray(b_, &p), "filling the right-hand side");
  check(KSPSolve(ksp_, b_, x_), ("solving " + what_).c_str());
  KSPConvergedReason why = KSP_CONVERGED_ITERATING;
  KSPGetConvergedReason(ksp_, &why);
  if (!direct_) {
    PetscInt its = 0;
    PetscReal residual = 0, norm_b = 0;
    KSPGetIterationNumber(ksp_, &its);
    KSPGetResidualNorm(ksp_, &residual);
    VecNorm(b_, NORM_2, &norm_b);
    stats_.iterations = static_cast<int>(its);
    stats_.relative_residual = norm_b > 0 ? residual / norm_b : 0;
  }
  if (why < 0) {
    if (why == KSP_DIVERGED_INDEFINITE_PC || why == KSP_DIVERGED_INDEFINITE_MAT)
      throw SimulationError(what_ + " is not positive definite (CG met a negative curvature)");
    throw SimulationError("PETSc's solve of " + what_ + " did not converge (" +
                          KSPConvergedReasons[why] + " after " + std::to_string(stats_.iterations) +
                          " iterations); try solver=cholmod or PETSC_OPTIONS");
  }
  check(VecScatterBegin(gather_, x_, all_, INSERT_VALUES, SCATTER_FORWARD), "gathering");
  check(VecScatterEnd(gather_, x_, all_, INSERT_VALUES, SCATTER_FORWARD), "gathering");
  const PetscScalar* q = nullptr;
  check(VecGetArrayRead(all_, &q), "reading the solution");
  std::copy(q, q + n_, x.data());
  check(VecRestoreArrayRead(all_, &q), "reading the solution");
}

// Columns [first, first + count) of x through MUMPS at once (MatMatSolve), gathered back
// whole to every rank.
void PetscSolver::solve_columns(Eigen::MatrixXd& x, Eigen::Index first, Eigen::Index count) const {
  const auto k = static_cast<PetscInt>(count);
  Mat b = nullptr, y = nullptr, f = nullptr;
  PC pc = nullptr;
  check(KSPGetPC(ksp_, &pc), "getting the factor");
  check(PCFactorGetMatrix(pc, &f), "getting the factor");
  check(MatCreateDense(PETSC_COMM_WORLD, rows_, PETSC_DECIDE, n_, k, nullptr, &b),
        "creating the right-hand sides");
  PetscScalar* p = nullptr;
  PetscInt lda = 0;
  check(MatDenseGetLDA(b, &lda), "filling the right-hand sides");
  check(MatDenseGetArrayWrite(b, &p), "filling the right-hand sides");
  for (PetscInt c = 0; c < k; ++c)
    std::copy(x.col(first + c).data() + row0_, x.col(first + c).data() + row0_ + rows_,
              p + static_cast<std::ptrdiff_t>(c) * lda);
  check(MatDenseRestoreArrayWrite(b, &p), "filling the right-hand sides");
  check(MatAssemblyBegin(b, MAT_FINAL_ASSEMBLY), "filling the right-hand sides");
  check(MatAssemblyEnd(b, MAT_FINAL_ASSEMBLY), "filling the right-hand sides");
  check(MatDuplicate(b, MAT_DO_NOT_COPY_VALUES, &y), "creating the solutions");
  check(MatMatSolve(f, b, y), ("solving " + what_).c_str());
  // every rank's rows, column after column, into one buffer on every rank
  std::vector<double> mine(static_cast<std::size_t>(rows_) * static_cast<std::size_t>(k));
  const PetscScalar* q = nullptr;
  check(MatDenseGetLDA(y, &lda), "reading the solutions");
  check(MatDenseGetArrayRead(y, &q), "reading the solutions");
  for (PetscInt c = 0; c < k; ++c)
    std::copy(q + static_cast<std::ptrdiff_t>(c) * lda,
              q + static_cast<std::ptrdiff_t>(c) * lda + rows_,
              mine.begin() + static_cast<std::ptrdiff_t>(c) * rows_);
  check(MatDenseRestoreArrayRead(y, &q), "reading the solutions");
  MatDestroy(&b);
  MatDestroy(&y);
  std::vector<int> counts(counts_.size()), starts(starts_.size());
  for (std::size_t r = 0; r < counts_.size(); ++r) {
    counts[r] = counts_[r] * static_cast<int>(k);
    starts[r] = starts_[r] * static_cast<int>(k);
  }
  std::vector<double> whole(static_cast<std::size_t>(n_) * static_cast<std::size_t>(k));
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, whole.data(),
                 counts.data(), starts.data(), MPI_DOUBLE, PETSC_COMM_WORLD);
  for (std::size_t r = 0; r < counts_.size(); ++r)
    for (PetscInt c = 0; c < k; ++c)
      std::copy(whole.begin() + starts[r] + static_cast<std::ptrdiff_t>(c) * counts_[r],
                whole.begin() + starts[r] + static_cast<std::ptrdiff_t>(c + 1) * counts_[r],
                x.col(first + c).data() + starts_[r]);
}

void PetscSolver::solve_in_place(Eigen::MatrixXd& x) const {
  VPROTO_DEMAND(factored() && x.rows() == n_);
  if (!direct_) {
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      Eigen::VectorXd column = x.col(c);
      solve_in_place(column);
      x.col(c) = column;
    }
    return;
  }
  constexpr Eigen::Index kBlock = 64;  // right-hand sides per MUMPS solve
  for (Eigen::Index first = 0; first < x.cols(); first += kBlock)
    solve_columns(x, first, std::min(kBlock, x.cols() - first));
}

}  // namespace

bool petsc_built() { return true; }

void petsc_start() {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (up) return;
  // PETSc reads its options from PETSC_OPTIONS only: vproto's own arguments are not its
  const PetscErrorCode e = PetscInitializeNoArguments();
  if (e) throw SimulationError("PETSc would not start (error " + std::to_string(e) + ")");
  // vproto's exceptions and exit codes report errors, not PETSc's handlers
  PetscPopSignalHandler();
  PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
  g_started = true;
}

void petsc_finish() {
  if (!g_started) return;
  g_started = false;
  PetscFinalize();
}

void petsc_abort(int code) {
  int up = 0;
  MPI_Initialized(&up);
  int down = 0;
  MPI_Finalized(&down);
  if (up && !down) MPI_Abort(MPI_COMM_WORLD, code);
}

std::unique_ptr<LinearSolver> make_petsc_solver(const SolverSetup& setup,
                                                const std::string& reason) {
  return std::make_unique<PetscSolver>(setup, reason);
}

#else  // a build without PETSc

bool petsc_built() { return false; }
void petsc_start() {}
void petsc_finish() {}
void petsc_abort(int) {}
std::unique_ptr<LinearSolver> make_petsc_solver(const SolverSetup&, const std::string&) {
  throw InternalError("make_petsc_solver in a build without PETSc");
}

#endif

}  // namespace vproto::sim::detail
