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

/// The lower triangle of a symmetric matrix in compressed columns, without copying.
using LowerView = Eigen::Map<const Eigen::SparseMatrix<double>>;

inline LowerView view_of(const Eigen::SparseMatrix<double>& lower) {
  return {lower.rows(),          lower.cols(),          lower.nonZeros(),
          lower.outerIndexPtr(), lower.innerIndexPtr(), lower.valuePtr()};
}

class SparseCholesky {
 public:
  enum class Ordering { kAutomatic, kAmd, kMetis, kNesdis };

  struct Stats {
    std::string ordering;        ///< the fill-reducing ordering CHOLMOD used
    double factor_nonzeros = 0;  ///< entries of L (with supernodal padding)
    double flops = 0;            ///< of the numeric factorization
    double analyze_seconds = 0;  ///< last symbolic analysis
    double factor_seconds = 0;   ///< last numeric factorization
    int factorizations = 0;      ///< numeric factorizations so far
  };

  explicit SparseCholesky(Ordering ordering = Ordering::kAutomatic);
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Analyses (once per pattern) and factors. Throws SimulationError when the matrix is
  /// not positive definite (`what` names it in the message), FactorMemoryError when the
  /// factor would not fit in factor_memory_limit(). `block` > 1: the matrix is
  /// made of block x block blocks (3 for the x, y, z of FE nodes), and the fill-reducing
  /// ordering is computed on the block graph, block^2 times smaller, then expanded.
  void factor(const LowerView& lower, const std::string& what, int block = 1);

  bool factored() const;
  Eigen::Index size() const;

  /// x = A^-1 b; one or many right-hand sides.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  void solve_in_place(Eigen::VectorXd& x) const;
  void solve_in_place(Eigen::MatrixXd& x) const;

  const Stats& stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Ordering ordering_;
  Stats stats_;
};

}  // namespace vproto::sim
