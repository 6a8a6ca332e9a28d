#pragma once
// A supernodal sparse Cholesky factor (SuiteSparse CHOLMOD) of a symmetric positive
// definite matrix given by its lower triangle. The symbolic analysis (fill-reducing
// ordering, supernodes) is kept, so a matrix with the same pattern and new values is
// refactored numerically only; solves reuse their workspace, so a time step allocates
// nothing.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

#include "vproto/materials/errors.h"
#include "vproto/sim/linear_solver.h"

namespace vproto::sim {

/// A factor that would not fit in memory: raised after the symbolic analysis (which
/// gives the factor's size) and before any numeric work, or when CHOLMOD runs out.
class FactorMemoryError : public SimulationError {
 public:
  FactorMemoryError(double needed, double available)
      : SimulationError("the factor needs about " + gigabytes(needed) + " of memory and " +
                        gigabytes(available) + " is available"),
        needed_(needed),
        available_(available) {}
  double needed() const { return needed_; }        ///< bytes
  double available() const { return available_; }  ///< bytes

 private:
  static std::string gigabytes(double bytes);
  double needed_, available_;
};

/// Bytes a factor may use: the environment's VPROTO_MEMORY_LIMIT (e.g. 8GB, 500MB) when
/// set, else nine tenths of the memory available now (/proc/meminfo MemAvailable).
double factor_memory_limit();

/// Roughly the bytes a Cholesky factor of a 3-D elasticity matrix of n unknowns needs
/// (8 x 10.8 n^(4/3): 98k dofs gave 4.9e7 entries with nested dissection).
double estimated_factor_bytes(double n);

class SparseCholesky : public LinearSolver {
 public:
  using Ordering = FactorOrdering;

  using Stats = SolverStats;

  explicit SparseCholesky(Ordering ordering = Ordering::kAutomatic);
  ~SparseCholesky() override;
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Analyses (once per pattern) and factors. Throws SimulationError when the matrix is
  /// not positive definite (`what` names it in the message), FactorMemoryError when the
  /// factor would not fit in factor_memory_limit(). `block` > 1: the matrix is
  /// made of block x block blocks (3 for the x, y, z of FE nodes), and the fill-reducing
  /// ordering is computed on the block graph, block^2 times smaller, then expanded.
  void factor(const LowerView& lower, const std::string& what, int block = 1) override;

  bool factored() const override;
  Eigen::Index size() const override;

  /// x = A^-1 b; one or many right-hand sides.
  using LinearSolver::solve;
  void solve_in_place(Eigen::VectorXd& x) const override;
  void solve_in_place(Eigen::MatrixXd& x) const override;
  Eigen::MatrixXd solve_sparse(const Eigen::SparseMatrix<double>& b,
                               const std::vector<Eigen::Index>& rows) const override;

  const Stats& stats() const override { return stats_; }
  /// Solves on several threads each take a workspace of their own; the factor is shared.
  bool concurrent_solves() const override { return true; }
  Eigen::Index elimination_position(Eigen::Index row) const override;
  /// Why this backend runs (summary.json `solver.reason`).
  void set_reason(std::string reason) { stats_.reason = std::move(reason); }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Ordering ordering_;
  Stats stats_;
};

}  // namespace vproto::sim
