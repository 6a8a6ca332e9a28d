// One right-hand side solved with a supernodal Cholesky factor (CHOLMOD's L L', as
// cholmod_analyze and cholmod_factorize leave it) on two threads.
//
// A single right-hand side is a pair of triangular sweeps over the factor, BLAS-2 work that
// CHOLMOD does on one thread (the snap-fit's contact correction, 6.8M factor entries: about
// 7.5 ms, once per contact step; a Newmark step of an elastic body: once per step). The
// sweeps follow the supernodal elimination tree, whose disjoint subtrees are independent:
// the tree is cut into a top part and subtrees dealt to two groups of about equal entries;
// the forward sweep runs each group's subtrees on its own thread (updates to the top part
// gathered in a buffer per group, then added in a fixed order), then the top part on one;
// the backward sweep runs the top part, then both groups at once (each writes only its own
// rows). The partition depends on the factor's structure only, so the answer is the same
// bits on one thread or two. The forward sweep visits only the supernodes a right-hand side's
// nonzeros reach (the rest would add zeros); several right-hand sides at once go a supernode's
// block of rows at a time (BLAS-3), on the calling thread.
#pragma once

#include <cholmod.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace vproto::sim {

class SubtreeSolve {
 public:
  /// The partition of `factor`'s supernodal tree (kept for its structure: rebuild after a
  /// new analysis, not after a numeric refactorization). usable() is false for a factor
  /// that is not supernodal L L'.
  explicit SubtreeSolve(const cholmod_factor* factor);

  bool usable() const { return usable_; }
  /// The share of the factor's entries in the top part (solved on one thread).
  double top_share() const { return top_share_; }

  /// Vectors a solve works in, kept by the caller from solve to solve.
  struct Scratch {
    std::vector<double> y, group[2], column[2], block;
    std::vector<char> reached, needed;
  };

  /// x = A^-1 b in place, for `factor` (the one the partition was built for, refactored
  /// numerically or not). `threads`: whether the two groups may run on two threads.
  void solve(const cholmod_factor* factor, double* x, bool threads, Scratch* scratch) const;

  /// X = A^-1 B in place for `columns` right-hand sides (n x columns, column-major), on the
  /// calling thread, a supernode's block of rows at a time (BLAS-3).
  void solve_block(const cholmod_factor* factor, double* x, int columns, Scratch* scratch) const;

  /// Rows `rows` of X = A^-1 B for sparse right-hand sides B (n x columns), on the calling
  /// thread: the forward sweep visits what B's nonzeros reach, the backward sweep only the
  /// supernodes holding `rows` and their ancestors (the rows below a supernode are all it
  /// reads).
  void solve_sparse(const cholmod_factor* factor, const Eigen::SparseMatrix<double>& b,
                    const std::vector<Eigen::Index>& rows, Eigen::MatrixXd* out,
                    Scratch* scratch) const;

 private:
  bool usable_ = false;
  double top_share_ = 1;
  int n_ = 0;
  std::vector<int> top_;               ///< top supernodes, increasing
  std::vector<int> group_[2];          ///< each group's supernodes, increasing
  std::vector<int> group_columns_[2];  ///< each group's columns (of L, permuted)
  std::vector<int> top_columns_;       ///< the top part's columns
  int max_rows_ = 0;                   ///< tallest supernode (scratch size)
  std::vector<int> owner_;             ///< each column's supernode
  std::vector<int> parent_;            ///< each supernode's parent (-1: a root)

  /// Marks in scratch->reached the supernodes the forward sweep must visit for right-hand
  /// sides `y` (n x columns): those holding a nonzero, and their ancestors. A sparse right-hand
  /// side (the compliance columns' unit loads, a contact correction's loads on a few surface
  /// nodes) reaches only the paths from its nonzeros to the root; the rest stays zero.
  void mark_reached(const double* y, int columns, Scratch* scratch) const;
  /// Both sweeps over scratch->y (n x columns, in the factor's order), the forward one over
  /// scratch->reached, the backward one over scratch->needed.
  void sweep_block(const cholmod_factor* factor, int columns, Scratch* scratch) const;
  std::vector<int> position_;  ///< each unknown's place in the factor's order
};

}  // namespace vproto::sim
