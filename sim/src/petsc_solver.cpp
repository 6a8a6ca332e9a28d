// The PETSc backend of the linear-solver seam. Every rank holds the same matrix (the scene
// is replicated), numbers the nodes by recursive coordinate bisection (a compact piece of
// the body per rank) and takes its own rows into a distributed matrix.
//  - Static solves (SolveUse::kStatic): conjugate gradients preconditioned by a two-level
//    p-multigrid V-cycle on quadratic tetrahedra (the fine level in 3 x 3 blocks, smoothed
//    by Chebyshev on point blocks; the linear tetrahedra of the corner nodes factored by
//    MUMPS), or by smoothed-aggregation multigrid (GAMG, the six rigid-body modes as its
//    near null space) otherwise, to the relative residual of SolverSetup.
//  - Kept step matrices (SolveUse::kKept): MUMPS' distributed Cholesky factor, computed
//    once and reused for every step's right-hand sides and constraint columns.
// Right-hand sides come in whole on every rank and solutions go back whole to every rank
// (one all-gather), so all ranks keep the same state. PETSC_OPTIONS in the environment
// can tune the Krylov method and preconditioner (-ksp_*, -pc_*, -mg_levels_*).

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <vector>

#include "petsc_backend.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/fe_elasticity.h"

#ifdef VPROTO_HAVE_PETSC
#include <mpi.h>
#include <petscksp.h>
#endif

namespace vproto::sim::detail {

#ifdef VPROTO_HAVE_PETSC
namespace {

bool g_started = false;
bool g_shared = true;  // solvers span PETSC_COMM_WORLD, else PETSC_COMM_SELF

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
      : setup_(setup), direct_(setup.use == SolveUse::kKept), warm_(setup.use == SolveUse::kSteps) {
    ensure_started();
    comm_ = g_shared ? PETSC_COMM_WORLD : PETSC_COMM_SELF;
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &ranks_);
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
  bool factor_elements(double youngs_modulus, double poisson_ratio,
                       const std::vector<char>& held_dof, const std::string& what) override;
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
  void order_nodes();
  /// PETSc's index of vproto's dof, and back
  PetscInt to_petsc(PetscInt dof) const {
    return new_of_.empty() ? dof : 3 * new_of_[static_cast<std::size_t>(dof / 3)] + dof % 3;
  }
  PetscInt to_vproto(PetscInt dof) const {
    return old_of_.empty() ? dof : 3 * old_of_[static_cast<std::size_t>(dof / 3)] + dof % 3;
  }
  /// This rank's rows in 3 x 3 blocks (compressed block rows, blocks stored by rows)
  struct BlockRows {
    std::vector<PetscInt> ptr, col;
    std::vector<PetscScalar> val;
  };
  BlockRows block_rows(const LowerView& a) const;
  Mat blocked_matrix(const BlockRows& k) const;
  void finish(const BlockRows* blocks, const std::string& what, Clock::time_point assembling);
  void use_p_multigrid(PC pc, const BlockRows& k);
  void solve_columns(Eigen::MatrixXd& x, Eigen::Index first, Eigen::Index count) const;

  SolverSetup setup_;
  bool direct_;
  bool warm_;  ///< iterative, each solve starting from the last solution (Newmark steps)
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, ranks_ = 1;
  PetscInt n_ = 0, row0_ = 0, rows_ = 0;
  int block_ = 1;
  /// PETSc's numbering of the nodes (recursive coordinate bisection: each rank a compact
  /// piece of the body, nearby nodes near in memory) and back; empty: vproto's own
  std::vector<int> new_of_, old_of_;
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

// Recursive coordinate bisection of the nodes: cut at the median of the longest side,
// first into one piece per rank (sizes in proportion to the ranks on each side), then on
// inside each piece down to 64 nodes, so the nodes of a neighbourhood are near in memory
// too. Ranks own the pieces in order.
void PetscSolver::order_nodes() {
  const Eigen::MatrixX3d& xyz = setup_.coordinates;
  const auto nodes = static_cast<int>(n_ / 3);
  std::vector<int> order(static_cast<std::size_t>(nodes));
  for (int v = 0; v < nodes; ++v) order[static_cast<std::size_t>(v)] = v;
  std::vector<int> piece;  // nodes per rank
  auto cut = [&](auto begin, auto end, std::ptrdiff_t at) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (auto it = begin; it != end; ++it) {
      lo = lo.cwiseMin(xyz.row(*it).transpose());
      hi = hi.cwiseMax(xyz.row(*it).transpose());
    }
    Eigen::Index axis = 0;
    (hi - lo).maxCoeff(&axis);
    std::nth_element(begin, begin + at, end,
                     [&](int a, int b) { return xyz(a, axis) < xyz(b, axis); });
  };
  auto localize = [&](auto self, auto begin, auto end) -> void {
    const std::ptrdiff_t n = end - begin;
    if (n <= 64) return;
    cut(begin, end, n / 2);
    self(self, begin, begin + n / 2);
    self(self, begin + n / 2, end);
  };
  auto partition = [&](auto self, auto begin, auto end, int parts) -> void {
    const std::ptrdiff_t n = end - begin;
    if (parts == 1) {
      piece.push_back(static_cast<int>(n));
      localize(localize, begin, end);
      return;
    }
    const int left = parts / 2;
    const std::ptrdiff_t at = n * left / parts;
    cut(begin, end, at);
    self(self, begin, begin + at, left);
    self(self, begin + at, end, parts - left);
  };
  partition(partition, order.begin(), order.end(), ranks_);
  old_of_ = order;
  new_of_.assign(order.size(), 0);
  for (int k = 0; k < nodes; ++k)
    new_of_[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
  int start = 0;
  for (int r = 0; r < ranks_; ++r) {
    starts_[static_cast<std::size_t>(r)] = 3 * start;
    counts_[static_cast<std::size_t>(r)] = 3 * piece[static_cast<std::size_t>(r)];
    start += piece[static_cast<std::size_t>(r)];
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
  block_ = block;
  split(block);
  new_of_.clear();
  old_of_.clear();
  if (block == 3 && setup_.coordinates.rows() * 3 == n_ && n_ > 0) order_nodes();
  const auto assembling = Clock::now();
  // quadratic tetrahedra solved iteratively: p-multigrid, the matrix in 3 x 3 blocks (BAIJ:
  // a third less memory traffic in the products than AIJ), taken straight from the lower
  // triangle: on a 157k-dof beam the whole set-up took 0.65-0.74 s, against 0.94-0.99 s
  // through sorted scalar rows and their blocked copy
  const bool p_multigrid =
      !direct_ && block == 3 && setup_.elements.cols() == 10 && setup_.elements.rows() > 0;
  BlockRows blocks;
  if (p_multigrid) {
    blocks = block_rows(a);
    a_ = blocked_matrix(blocks);
  } else {
    // this rank's rows of the whole symmetric matrix in PETSc's numbering, in compressed
    // rows: an entry (i, j) of the lower triangle is (i, j) and (j, i) of the matrix
    const PetscInt r0 = row0_, r1 = row0_ + rows_;
    std::vector<PetscInt> ptr(static_cast<std::size_t>(rows_) + 1, 0);
    const int* outer = a.outerIndexPtr();
    const int* inner = a.innerIndexPtr();
    const double* value = a.valuePtr();
    for (PetscInt j = 0; j < n_; ++j) {
      const PetscInt nj = to_petsc(j);
      for (int k = outer[j]; k < outer[j + 1]; ++k) {
        const PetscInt i = inner[k], ni = to_petsc(i);
        if (ni >= r0 && ni < r1) ++ptr[static_cast<std::size_t>(ni - r0 + 1)];
        if (i != j && nj >= r0 && nj < r1) ++ptr[static_cast<std::size_t>(nj - r0 + 1)];
      }
    }
    for (std::size_t i = 1; i < ptr.size(); ++i) ptr[i] += ptr[i - 1];
    std::vector<PetscInt> col(static_cast<std::size_t>(ptr.back()));
    std::vector<PetscScalar> val(col.size());
    std::vector<PetscInt> next(ptr.begin(), ptr.end() - 1);
    for (PetscInt j = 0; j < n_; ++j) {
      const PetscInt nj = to_petsc(j);
      for (int k = outer[j]; k < outer[j + 1]; ++k) {
        const PetscInt i = inner[k], ni = to_petsc(i);
        if (ni >= r0 && ni < r1) {
          const auto at = static_cast<std::size_t>(next[static_cast<std::size_t>(ni - r0)]++);
          col[at] = nj;
          val[at] = value[k];
        }
        if (i != j && nj >= r0 && nj < r1) {
          const auto at = static_cast<std::size_t>(next[static_cast<std::size_t>(nj - r0)]++);
          col[at] = ni;
          val[at] = value[k];
        }
      }
    }
    if (!new_of_.empty()) {  // renumbered: sort each row by column
      std::vector<std::pair<PetscInt, PetscScalar>> row;
      for (std::size_t r = 0; r + 1 < ptr.size(); ++r) {
        row.clear();
        for (auto k = static_cast<std::size_t>(ptr[r]); k < static_cast<std::size_t>(ptr[r + 1]);
             ++k)
          row.emplace_back(col[k], val[k]);
        std::sort(row.begin(), row.end(),
                  [](const auto& x, const auto& y) { return x.first < y.first; });
        for (std::size_t k = 0; k < row.size(); ++k) {
          col[static_cast<std::size_t>(ptr[r]) + k] = row[k].first;
          val[static_cast<std::size_t>(ptr[r]) + k] = row[k].second;
        }
      }
    }
    check(MatCreate(comm_, &a_), "creating the matrix");
    check(MatSetSizes(a_, rows_, rows_, n_, n_), "sizing the matrix");
    check(MatSetType(a_, MATAIJ), "typing the matrix");
    check(MatSetBlockSize(a_, block), "blocking the matrix");
    check(MatSeqAIJSetPreallocationCSR(a_, ptr.data(), col.data(), val.data()),
          "filling the matrix");
    check(MatMPIAIJSetPreallocationCSR(a_, ptr.data(), col.data(), val.data()),
          "filling the matrix");
    check(MatSetOption(a_, MAT_SPD, PETSC_TRUE), "marking the matrix positive definite");
  }
  finish(p_multigrid ? &blocks : nullptr, what, assembling);
}

// The solver for a_ (made by factor or factor_elements): vectors, the Krylov method and its
// preconditioner (p-multigrid from the block rows when given), set up.
void PetscSolver::finish(const BlockRows* blocks, const std::string& what,
                         Clock::time_point assembling) {
  const bool p_multigrid = blocks != nullptr;
  const int block = block_;
  check(MatCreateVecs(a_, &x_, &b_), "creating vectors");
  check(VecScatterCreateToAll(x_, &gather_, &all_), "creating the gather");

  check(KSPCreate(comm_, &ksp_), "creating the solver");
  check(KSPSetOperators(ksp_, a_, a_), "setting the operator");
  PC pc = nullptr;
  check(KSPGetPC(ksp_, &pc), "getting the preconditioner");
  if (direct_) {
    check(KSPSetType(ksp_, KSPPREONLY), "choosing the direct solve");
    check(PCSetType(pc, PCCHOLESKY), "choosing Cholesky");
    check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "choosing MUMPS");
  } else {
    check(KSPSetType(ksp_, KSPCG), "choosing CG");
    if (p_multigrid) {
      use_p_multigrid(pc, *blocks);
      stats_.method = "CG + p-multigrid (tet10 to tet4, MUMPS on tet4)";
    } else {
      check(PCSetType(pc, PCGAMG), "choosing GAMG");
    }
    check(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED), "choosing the residual norm");
    check(KSPSetTolerances(ksp_, stats_.relative_tolerance, 1e-300, PETSC_DEFAULT, 20000),
          "setting the tolerance");
    const Eigen::MatrixX3d& xyz = setup_.coordinates;
    if (!p_multigrid && block == 3 && xyz.rows() * 3 == n_) {  // GAMG's near null space
      Vec coordinates = nullptr;
      check(VecCreateMPI(comm_, rows_, n_, &coordinates), "creating coordinates");
      check(VecSetBlockSize(coordinates, 3), "blocking coordinates");
      PetscScalar* p = nullptr;
      check(VecGetArray(coordinates, &p), "filling coordinates");
      for (PetscInt i = 0; i < rows_; ++i) {
        const PetscInt dof = to_vproto(row0_ + i);
        p[i] = xyz(dof / 3, dof % 3);
      }
      check(VecRestoreArray(coordinates, &p), "filling coordinates");
      MatNullSpace modes = nullptr;
      check(MatNullSpaceCreateRigidBody(coordinates, &modes), "forming the rigid-body modes");
      check(MatSetNearNullSpace(a_, modes), "setting the near null space");
      MatNullSpaceDestroy(&modes);
      VecDestroy(&coordinates);
    }
  }
  if (warm_) {
    // start from the last step's displacement; the residual measured against the
    // right-hand side, not against the (small) starting residual
    check(KSPSetInitialGuessNonzero(ksp_, PETSC_TRUE), "warm starts");
    check(KSPConvergedDefaultSetUIRNorm(ksp_), "the residual's reference");
    check(VecSet(x_, 0.0), "the first guess");
    stats_.method += ", warm started from the last step";
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

// Each rank computes only the elements that hold one of its nodes, into its own block rows
// (a block (I, J) of an element: ke's rows of node I, columns of node J), the held dofs'
// rows and columns then replaced by the identity. Nothing holds the whole matrix.
bool PetscSolver::factor_elements(double youngs_modulus, double poisson_ratio,
                                  const std::vector<char>& held_dof, const std::string& what) {
  const Eigen::MatrixXi& el = setup_.elements;
  if (direct_ || el.cols() != 10 || el.rows() == 0 || setup_.coordinates.rows() == 0) return false;
  destroy();
  what_ = what;
  n_ = static_cast<PetscInt>(3 * setup_.coordinates.rows());
  VPROTO_DEMAND(static_cast<PetscInt>(held_dof.size()) == n_);
  block_ = 3;
  split(3);
  order_nodes();
  const auto assembling = Clock::now();
  geometry::TetMesh mesh;  // the elements' view of the setup's mesh
  mesh.nodes = setup_.coordinates;
  mesh.elements = el;
  const PetscInt g0 = row0_ / 3, g1 = (row0_ + rows_) / 3;
  auto mine = [&](int v) {
    const PetscInt g = new_of_[static_cast<std::size_t>(v)];
    return g >= g0 && g < g1;
  };
  std::vector<Eigen::Index> elements;
  for (Eigen::Index e = 0; e < el.rows(); ++e)
    for (int k = 0; k < 10; ++k)
      if (mine(el(e, k))) {
        elements.push_back(e);
        break;
      }
  // the pattern: each own node's row, the nodes sharing an element with it
  std::vector<std::vector<PetscInt>> cols(static_cast<std::size_t>(g1 - g0));
  for (const Eigen::Index e : elements)
    for (int p = 0; p < 10; ++p)
      if (mine(el(e, p))) {
        auto& row =
            cols[static_cast<std::size_t>(new_of_[static_cast<std::size_t>(el(e, p))] - g0)];
        for (int q = 0; q < 10; ++q) row.push_back(new_of_[static_cast<std::size_t>(el(e, q))]);
      }
  BlockRows b;
  b.ptr.assign(cols.size() + 1, 0);
  for (std::size_t r = 0; r < cols.size(); ++r) {
    std::sort(cols[r].begin(), cols[r].end());
    cols[r].erase(std::unique(cols[r].begin(), cols[r].end()), cols[r].end());
    b.col.insert(b.col.end(), cols[r].begin(), cols[r].end());
    b.ptr[r + 1] = static_cast<PetscInt>(b.col.size());
    std::vector<PetscInt>().swap(cols[r]);
  }
  b.val.assign(9 * b.col.size(), 0.0);
  auto held = [&](int v) { return held_dof[static_cast<std::size_t>(3 * v)] != 0; };
  for (const Eigen::Index e : elements) {
    const Eigen::MatrixXd ke = element_stiffness(mesh, e, youngs_modulus, poisson_ratio);
    for (int p = 0; p < 10; ++p) {
      const int vp = el(e, p);
      if (!mine(vp) || held(vp)) continue;
      const auto r = static_cast<std::size_t>(new_of_[static_cast<std::size_t>(vp)] - g0);
      const auto first = b.col.begin() + b.ptr[r], last = b.col.begin() + b.ptr[r + 1];
      for (int q = 0; q < 10; ++q) {
        const int vq = el(e, q);
        if (held(vq)) continue;
        const auto at = static_cast<std::size_t>(
            std::lower_bound(first, last, new_of_[static_cast<std::size_t>(vq)]) - b.col.begin());
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            b.val[9 * at + static_cast<std::size_t>(3 * i + j)] += ke(3 * p + i, 3 * q + j);
      }
    }
  }
  for (std::size_t r = 0; r + 1 < b.ptr.size(); ++r) {  // held nodes: identity rows
    const int v = old_of_[static_cast<std::size_t>(g0) + r];
    if (!held(v)) continue;
    const auto first = b.col.begin() + b.ptr[r], last = b.col.begin() + b.ptr[r + 1];
    const auto at = static_cast<std::size_t>(
        std::lower_bound(first, last, g0 + static_cast<PetscInt>(r)) - b.col.begin());
    for (int i = 0; i < 3; ++i) b.val[9 * at + static_cast<std::size_t>(4 * i)] = 1.0;
  }
  a_ = blocked_matrix(b);
  finish(&b, what, assembling);
  stats_.method += ", each rank's rows from its own elements";
  return true;
}

// Two levels: the quadratic tetrahedra, smoothed by Chebyshev on 3 x 3 point blocks, and
// the linear tetrahedra of their corner nodes (a sixth of the dofs), factored by MUMPS.
// The linear field of the corners is exactly a quadratic field (a mid-edge node takes the
// mean of its edge's ends), so the interpolation P is exact and the coarse operator is
// P^T K P (Galerkin). Coarse dofs follow their nodes' ranks.
void PetscSolver::use_p_multigrid(PC pc, const BlockRows& k) {
  const Eigen::MatrixXi& el = setup_.elements;
  const auto nodes = static_cast<std::size_t>(n_ / 3);
  // tet10 (VTK and CalculiX order): mid-edge nodes 4..9 on edges 01 12 02 03 13 23
  static constexpr int kEnds[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  std::vector<int> coarse(nodes, -1);  // by vproto's node
  std::vector<std::array<int, 2>> ends(nodes, {-1, -1});
  for (Eigen::Index e = 0; e < el.rows(); ++e) {
    for (int c = 0; c < 4; ++c) coarse[static_cast<std::size_t>(el(e, c))] = 0;
    for (int q = 0; q < 6; ++q)
      ends[static_cast<std::size_t>(el(e, 4 + q))] = {el(e, kEnds[q][0]), el(e, kEnds[q][1])};
  }
  // corner nodes numbered in PETSc's order of the nodes, so each rank owns the corners
  // among its own nodes: coarse rows [c0, c0 + mine)
  int count = 0, mine = 0, c0 = 0;
  const auto v0 = static_cast<std::size_t>(row0_ / 3),
             v1 = static_cast<std::size_t>((row0_ + rows_) / 3);
  for (std::size_t g = 0; g < nodes; ++g) {
    const auto v = static_cast<std::size_t>(to_vproto(3 * static_cast<PetscInt>(g)) / 3);
    if (coarse[v] < 0) continue;
    if (g < v0) ++c0;
    if (g >= v0 && g < v1) ++mine;
    coarse[v] = count++;
  }
  // P by PETSc's node: one corner with weight 1, or a mid-edge node's two ends with 1/2
  std::vector<std::array<int, 2>> to(nodes, {-1, -1});
  for (std::size_t g = 0; g < nodes; ++g) {
    const auto v = static_cast<std::size_t>(to_vproto(3 * static_cast<PetscInt>(g)) / 3);
    if (coarse[v] >= 0)
      to[g] = {coarse[v], -1};
    else if (ends[v][0] >= 0)
      to[g] = {coarse[static_cast<std::size_t>(ends[v][0])],
               coarse[static_cast<std::size_t>(ends[v][1])]};
  }
  auto weight = [](const std::array<int, 2>& t) { return t[1] < 0 ? 1.0 : 0.5; };

  std::vector<PetscInt> pptr(static_cast<std::size_t>(rows_) + 1, 0), pcol;
  std::vector<PetscScalar> pval;
  pcol.reserve(2 * static_cast<std::size_t>(rows_));
  pval.reserve(pcol.capacity());
  for (PetscInt i = 0; i < rows_; ++i) {
    const std::array<int, 2>& t = to[static_cast<std::size_t>((row0_ + i) / 3)];
    const int d = static_cast<int>((row0_ + i) % 3);
    std::array<int, 2> c = {t[0] < 0 ? -1 : 3 * t[0] + d, t[1] < 0 ? -1 : 3 * t[1] + d};
    if (c[1] >= 0 && c[0] > c[1]) std::swap(c[0], c[1]);
    for (const int j : c)
      if (j >= 0) {
        pcol.push_back(j);
        pval.push_back(weight(t));
      }
    pptr[static_cast<std::size_t>(i) + 1] = static_cast<PetscInt>(pcol.size());
  }
  Mat p = nullptr;
  check(MatCreate(comm_, &p), "creating the interpolation");
  check(MatSetSizes(p, rows_, 3 * mine, n_, 3 * count), "sizing the interpolation");
  check(MatSetType(p, MATAIJ), "typing the interpolation");
  check(MatSetBlockSizes(p, 3, 3), "blocking the interpolation");
  check(MatSeqAIJSetPreallocationCSR(p, pptr.data(), pcol.data(), pval.data()),
        "filling the interpolation");
  check(MatMPIAIJSetPreallocationCSR(p, pptr.data(), pcol.data(), pval.data()),
        "filling the interpolation");

  // The coarse operator P^T K P, summed here block by block from this rank's block rows
  // (PETSc 3.18 forms P^T K P only from a scalar AIJ copy of K: 0.3 s and a third more
  // memory for the copy and 0.17 s for the product on a 157k-dof beam). Its pattern is the
  // linear tetrahedra's: a fine block (g, h) lies in one element, whose corners hold the
  // ends of g and h.
  std::vector<std::vector<int>> adjacent(static_cast<std::size_t>(mine));
  for (Eigen::Index e = 0; e < el.rows(); ++e)
    for (int x = 0; x < 4; ++x) {
      const int a = coarse[static_cast<std::size_t>(el(e, x))] - c0;
      if (a < 0 || a >= mine) continue;
      for (int y = 0; y < 4; ++y)
        adjacent[static_cast<std::size_t>(a)].push_back(coarse[static_cast<std::size_t>(el(e, y))]);
    }
  std::vector<PetscInt> cptr(static_cast<std::size_t>(mine) + 1, 0), ccol;
  for (std::size_t a = 0; a < adjacent.size(); ++a) {
    std::vector<int>& row = adjacent[a];
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    ccol.insert(ccol.end(), row.begin(), row.end());
    cptr[a + 1] = static_cast<PetscInt>(ccol.size());
    std::vector<int>().swap(row);
  }
  std::vector<PetscScalar> cval(9 * ccol.size(), 0.0);                    // blocks by rows
  std::vector<std::pair<std::array<int, 2>, Eigen::Matrix3d>> elsewhere;  // other ranks' rows
  for (std::size_t r = 0; r + 1 < k.ptr.size(); ++r) {
    const std::array<int, 2>& tg = to[v0 + r];
    const double wg = weight(tg);
    for (PetscInt q = k.ptr[r]; q < k.ptr[r + 1]; ++q) {
      const std::array<int, 2>& th =
          to[static_cast<std::size_t>(k.col[static_cast<std::size_t>(q)])];
      const double w = wg * weight(th);
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> block(
          k.val.data() + 9 * static_cast<std::size_t>(q));
      for (const int a : tg) {
        if (a < 0) continue;
        for (const int b : th) {
          if (b < 0) continue;
          if (a >= c0 && a < c0 + mine) {
            const auto first = ccol.begin() + cptr[static_cast<std::size_t>(a - c0)],
                       last = ccol.begin() + cptr[static_cast<std::size_t>(a - c0) + 1];
            const auto at =
                static_cast<std::size_t>(std::lower_bound(first, last, b) - ccol.begin());
            Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cval.data() + 9 * at) +=
                w * block;
          } else {
            elsewhere.push_back({{a, b}, w * block});
          }
        }
      }
    }
  }
  // in scalar rows (MUMPS' Cholesky in PETSc takes AIJ, not BAIJ)
  std::vector<PetscInt> sptr(3 * static_cast<std::size_t>(mine) + 1, 0), scol;
  std::vector<PetscScalar> sval;
  scol.reserve(9 * ccol.size());
  sval.reserve(9 * ccol.size());
  for (std::size_t a = 0; a < static_cast<std::size_t>(mine); ++a)
    for (int i = 0; i < 3; ++i) {
      for (PetscInt q = cptr[a]; q < cptr[a + 1]; ++q)
        for (int j = 0; j < 3; ++j) {
          scol.push_back(3 * ccol[static_cast<std::size_t>(q)] + j);
          sval.push_back(
              cval[9 * static_cast<std::size_t>(q) + static_cast<std::size_t>(3 * i + j)]);
        }
      sptr[3 * a + static_cast<std::size_t>(i) + 1] = static_cast<PetscInt>(scol.size());
    }
  Mat coarse_k = nullptr;
  check(MatCreate(comm_, &coarse_k), "creating the coarse operator");
  check(MatSetSizes(coarse_k, 3 * mine, 3 * mine, 3 * count, 3 * count),
        "sizing the coarse operator");
  check(MatSetType(coarse_k, MATAIJ), "typing the coarse operator");
  check(MatSetBlockSize(coarse_k, 3), "blocking the coarse operator");
  check(MatSeqAIJSetPreallocationCSR(coarse_k, sptr.data(), scol.data(), sval.data()),
        "filling the coarse operator");
  check(MatMPIAIJSetPreallocationCSR(coarse_k, sptr.data(), scol.data(), sval.data()),
        "filling the coarse operator");
  if (ranks_ > 1) {  // the sums that belong to other ranks' rows (all within the pattern)
    for (const auto& [ab, m] : elsewhere) {
      const PetscInt a = ab[0], b = ab[1];
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rows = m;
      check(MatSetValuesBlocked(coarse_k, 1, &a, 1, &b, rows.data(), ADD_VALUES),
            "summing the coarse operator");
    }
    check(MatAssemblyBegin(coarse_k, MAT_FINAL_ASSEMBLY), "summing the coarse operator");
    check(MatAssemblyEnd(coarse_k, MAT_FINAL_ASSEMBLY), "summing the coarse operator");
  }
  check(MatSetOption(coarse_k, MAT_SPD, PETSC_TRUE), "marking the coarse operator");

  check(PCSetType(pc, PCMG), "choosing multigrid");
  check(PCMGSetLevels(pc, 2, nullptr), "setting the levels");
  check(PCMGSetType(pc, PC_MG_MULTIPLICATIVE), "setting the cycle");
  check(PCMGSetCycleType(pc, PC_MG_CYCLE_V), "setting the cycle");
  check(PCMGSetGalerkin(pc, PC_MG_GALERKIN_NONE), "setting the coarse operator");
  check(PCMGSetInterpolation(pc, 1, p), "setting the interpolation");
  MatDestroy(&p);  // the preconditioner holds it
  KSP smooth = nullptr, solve = nullptr;
  PC smooth_pc = nullptr, solve_pc = nullptr;
  check(PCMGGetSmoother(pc, 1, &smooth), "getting the smoother");
  check(KSPSetType(smooth, KSPCHEBYSHEV), "choosing Chebyshev");
  check(KSPChebyshevEstEigSet(smooth, 0, 0.1, 0, 1.1), "estimating eigenvalues");
  check(KSPSetTolerances(smooth, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, 2),
        "setting the smoothing steps");
  check(KSPGetPC(smooth, &smooth_pc), "getting the smoother");
  check(PCSetType(smooth_pc, PCPBJACOBI), "choosing point-block Jacobi");
  check(PCMGGetCoarseSolve(pc, &solve), "getting the coarse solve");
  check(KSPSetOperators(solve, coarse_k, coarse_k), "setting the coarse operator");
  MatDestroy(&coarse_k);
  check(KSPSetType(solve, KSPPREONLY), "choosing the coarse solve");
  check(KSPGetPC(solve, &solve_pc), "getting the coarse solve");
  check(PCSetType(solve_pc, PCCHOLESKY), "choosing the coarse factor");
  check(PCFactorSetMatSolverType(solve_pc, MATSOLVERMUMPS), "choosing MUMPS");
}

// This rank's block rows of the symmetric matrix whose lower triangle is `a` (3 x 3 blocks
// of the nodes, in PETSc's numbering, each row sorted by column): a block (I, J), I > J,
// of the lower triangle is (I, J) and transposed (J, I) of the matrix; a diagonal block
// is filled from its lower half.
PetscSolver::BlockRows PetscSolver::block_rows(const LowerView& a) const {
  const auto nodes = static_cast<std::size_t>(n_ / 3);
  const PetscInt g0 = row0_ / 3, g1 = (row0_ + rows_) / 3;
  auto node = [&](std::size_t v) -> PetscInt {
    return new_of_.empty() ? static_cast<PetscInt>(v) : new_of_[v];
  };
  auto mine = [&](PetscInt g) { return g >= g0 && g < g1; };
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  // the nodes of node column J's three scalar columns, each once
  std::vector<std::size_t> seen(nodes, nodes), pattern;
  auto nodes_of = [&](std::size_t j) {
    pattern.clear();
    for (std::size_t d = 0; d < 3; ++d)
      for (int k = outer[3 * j + d]; k < outer[3 * j + d + 1]; ++k) {
        const auto i = static_cast<std::size_t>(inner[k]) / 3;
        if (seen[i] != j) {
          seen[i] = j;
          pattern.push_back(i);
        }
      }
  };
  BlockRows b;
  b.ptr.assign(static_cast<std::size_t>(g1 - g0) + 1, 0);
  for (std::size_t j = 0; j < nodes; ++j) {
    nodes_of(j);
    const PetscInt gj = node(j);
    for (const std::size_t i : pattern) {
      const PetscInt gi = node(i);
      if (mine(gi)) ++b.ptr[static_cast<std::size_t>(gi - g0) + 1];
      if (i != j && mine(gj)) ++b.ptr[static_cast<std::size_t>(gj - g0) + 1];
    }
  }
  for (std::size_t r = 1; r < b.ptr.size(); ++r) b.ptr[r] += b.ptr[r - 1];
  b.col.resize(static_cast<std::size_t>(b.ptr.back()));
  b.val.assign(9 * b.col.size(), 0.0);
  std::vector<PetscInt> next(b.ptr.begin(), b.ptr.end() - 1);
  std::fill(seen.begin(), seen.end(), nodes);
  constexpr std::size_t kNone = ~std::size_t{0};
  std::vector<std::size_t> in_row(nodes, kNone),
      in_column(nodes, kNone);  // slots of (I, J), (J, I)
  for (std::size_t j = 0; j < nodes; ++j) {
    nodes_of(j);
    const PetscInt gj = node(j);
    for (const std::size_t i : pattern) {
      const PetscInt gi = node(i);
      in_row[i] = in_column[i] = kNone;
      if (mine(gi)) {
        in_row[i] = static_cast<std::size_t>(next[static_cast<std::size_t>(gi - g0)]++);
        b.col[in_row[i]] = gj;
      }
      if (i != j && mine(gj)) {
        in_column[i] = static_cast<std::size_t>(next[static_cast<std::size_t>(gj - g0)]++);
        b.col[in_column[i]] = gi;
      }
    }
    for (std::size_t dj = 0; dj < 3; ++dj)
      for (int k = outer[3 * j + dj]; k < outer[3 * j + dj + 1]; ++k) {
        const auto i = static_cast<std::size_t>(inner[k]) / 3,
                   di = static_cast<std::size_t>(inner[k]) % 3;
        if (in_row[i] != kNone) {
          b.val[9 * in_row[i] + 3 * di + dj] = value[k];
          if (i == j) b.val[9 * in_row[i] + 3 * dj + di] = value[k];
        }
        if (in_column[i] != kNone) b.val[9 * in_column[i] + 3 * dj + di] = value[k];
      }
  }
  // each row by column (renumbered nodes come in any order)
  std::vector<std::size_t> order;
  std::vector<PetscInt> cols;
  std::vector<PetscScalar> vals;
  for (std::size_t r = 0; r + 1 < b.ptr.size(); ++r) {
    const auto first = static_cast<std::size_t>(b.ptr[r]),
               last = static_cast<std::size_t>(b.ptr[r + 1]);
    if (std::is_sorted(b.col.begin() + static_cast<std::ptrdiff_t>(first),
                       b.col.begin() + static_cast<std::ptrdiff_t>(last)))
      continue;
    order.resize(last - first);
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = first + k;
    std::sort(order.begin(), order.end(),
              [&](std::size_t x, std::size_t y) { return b.col[x] < b.col[y]; });
    cols.clear();
    vals.clear();
    for (const std::size_t k : order) {
      cols.push_back(b.col[k]);
      vals.insert(vals.end(), b.val.begin() + static_cast<std::ptrdiff_t>(9 * k),
                  b.val.begin() + static_cast<std::ptrdiff_t>(9 * k + 9));
    }
    std::copy(cols.begin(), cols.end(), b.col.begin() + static_cast<std::ptrdiff_t>(first));
    std::copy(vals.begin(), vals.end(), b.val.begin() + static_cast<std::ptrdiff_t>(9 * first));
  }
  return b;
}

Mat PetscSolver::blocked_matrix(const BlockRows& k) const {
  Mat m = nullptr;
  check(MatCreate(comm_, &m), "creating the blocked matrix");
  check(MatSetSizes(m, rows_, rows_, n_, n_), "sizing the blocked matrix");
  check(MatSetType(m, MATBAIJ), "typing the blocked matrix");
  check(MatSeqBAIJSetPreallocationCSR(m, 3, k.ptr.data(), k.col.data(), k.val.data()),
        "filling the blocked matrix");
  check(MatMPIBAIJSetPreallocationCSR(m, 3, k.ptr.data(), k.col.data(), k.val.data()),
        "filling the blocked matrix");
  MatSetOption(m, MAT_SPD, PETSC_TRUE);  // a hint; MPIBAIJ does not take it
  return m;
}

void PetscSolver::solve_in_place(Eigen::VectorXd& x) const {
  VPROTO_DEMAND(factored() && x.size() == n_);
  PetscScalar* p = nullptr;
  check(VecGetArray(b_, &p), "filling the right-hand side");
  for (PetscInt i = 0; i < rows_; ++i) p[i] = x[to_vproto(row0_ + i)];
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
  for (PetscInt i = 0; i < n_; ++i) x[to_vproto(i)] = q[i];
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
  check(MatCreateDense(comm_, rows_, PETSC_DECIDE, n_, k, nullptr, &b),
        "creating the right-hand sides");
  PetscScalar* p = nullptr;
  PetscInt lda = 0;
  check(MatDenseGetLDA(b, &lda), "filling the right-hand sides");
  check(MatDenseGetArrayWrite(b, &p), "filling the right-hand sides");
  for (PetscInt c = 0; c < k; ++c)
    for (PetscInt i = 0; i < rows_; ++i)
      p[static_cast<std::ptrdiff_t>(c) * lda + i] = x(to_vproto(row0_ + i), first + c);
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
                 counts.data(), starts.data(), MPI_DOUBLE, comm_);
  for (std::size_t r = 0; r < counts_.size(); ++r)
    for (PetscInt c = 0; c < k; ++c) {
      const double* from = whole.data() + starts[r] + static_cast<std::ptrdiff_t>(c) * counts_[r];
      for (int i = 0; i < counts_[r]; ++i) x(to_vproto(starts_[r] + i), first + c) = from[i];
    }
}

void PetscSolver::solve_in_place(Eigen::MatrixXd& x) const {
  VPROTO_DEMAND(factored() && x.rows() == n_);
  if (!direct_) {
    // columns start from zero; the steps' warm start is kept for the next step
    Vec kept = nullptr;
    if (warm_) {
      check(VecDuplicate(x_, &kept), "keeping the warm start");
      check(VecCopy(x_, kept), "keeping the warm start");
      check(KSPSetInitialGuessNonzero(ksp_, PETSC_FALSE), "cold starts");
    }
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      Eigen::VectorXd column = x.col(c);
      solve_in_place(column);
      x.col(c) = column;
    }
    if (warm_) {
      check(VecCopy(kept, x_), "restoring the warm start");
      VecDestroy(&kept);
      check(KSPSetInitialGuessNonzero(ksp_, PETSC_TRUE), "warm starts");
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

void petsc_share(bool shared) { g_shared = shared; }

void petsc_barrier() {
  int up = 0, down = 0;
  MPI_Initialized(&up);
  MPI_Finalized(&down);
  if (up && !down) MPI_Barrier(MPI_COMM_WORLD);
}

std::vector<double> petsc_gather(double value) {
  int up = 0, down = 0, ranks = 1;
  MPI_Initialized(&up);
  MPI_Finalized(&down);
  if (!up || down) return {value};
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  std::vector<double> all(static_cast<std::size_t>(ranks));
  MPI_Allgather(&value, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD);
  return all;
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
void petsc_share(bool) {}
void petsc_barrier() {}
std::vector<double> petsc_gather(double value) { return {value}; }
std::unique_ptr<LinearSolver> make_petsc_solver(const SolverSetup&, const std::string&) {
  throw InternalError("make_petsc_solver in a build without PETSc");
}

#endif

}  // namespace vproto::sim::detail
