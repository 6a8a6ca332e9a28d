#include "subtree_solve.h"

#include <algorithm>
#include <numeric>

#include "blas.h"
#include "blas_threads.h"
#include "two_threads.h"

namespace vproto::sim {

namespace {

struct Supernode {
  int first, columns, rows;  // first column, its width, its height (rows of L it holds)
  const int* row;            // its rows' indices (the first `columns` are its own columns)
  const double* values;      // column-major, leading dimension `rows`
};

Supernode supernode(const cholmod_factor* f, int s) {
  const int* super = static_cast<const int*>(f->super);
  const int* pi = static_cast<const int*>(f->pi);
  const int* px = static_cast<const int*>(f->px);
  Supernode sn;
  sn.first = super[s];
  sn.columns = super[s + 1] - super[s];
  sn.rows = pi[s + 1] - pi[s];
  sn.row = static_cast<const int*>(f->s) + pi[s];
  sn.values = static_cast<const double*>(f->x) + px[s];
  return sn;
}

constexpr int kOne = 1;

// L y = b for one supernode's columns: its diagonal block solved, the rows below updated
void forward(const Supernode& sn, double* v, double* t) {
  double* own = v + sn.first;
  dtrsv_("L", "N", "N", &sn.columns, sn.values, &sn.rows, own, &kOne, 1, 1, 1);
  const int below = sn.rows - sn.columns;
  if (below == 0) return;
  const double one = 1, zero = 0;
  dgemv_("N", &below, &sn.columns, &one, sn.values + sn.columns, &sn.rows, own, &kOne, &zero, t,
         &kOne, 1);
  for (int i = 0; i < below; ++i) v[sn.row[sn.columns + i]] -= t[i];
}

// L' x = y for one supernode's columns: the rows below (solved already) taken off, then its
// diagonal block
void backward(const Supernode& sn, double* v, double* t) {
  double* own = v + sn.first;
  const int below = sn.rows - sn.columns;
  if (below > 0) {
    for (int i = 0; i < below; ++i) t[i] = v[sn.row[sn.columns + i]];
    const double minus_one = -1, one = 1;
    dgemv_("T", &below, &sn.columns, &minus_one, sn.values + sn.columns, &sn.rows, t, &kOne, &one,
           own, &kOne, 1);
  }
  dtrsv_("L", "T", "N", &sn.columns, sn.values, &sn.rows, own, &kOne, 1, 1, 1);
}

}  // namespace

SubtreeSolve::SubtreeSolve(const cholmod_factor* f) {
  if (!f || !f->is_super || !f->is_ll || f->xtype != CHOLMOD_REAL || f->itype != CHOLMOD_INT ||
      f->dtype != CHOLMOD_DOUBLE || f->nsuper == 0)
    return;
  const int nsuper = static_cast<int>(f->nsuper);
  n_ = static_cast<int>(f->n);
  // the supernodal elimination tree: a supernode's parent holds its first row below its
  // diagonal block (CHOLMOD numbers children before parents)
  const int* perm = static_cast<const int*>(f->Perm);
  position_.resize(f->n);
  for (std::size_t k = 0; k < f->n; ++k)
    position_[static_cast<std::size_t>(perm ? perm[k] : static_cast<int>(k))] = static_cast<int>(k);
  std::vector<int>& owner = owner_;
  std::vector<int>& parent = parent_;
  owner.assign(static_cast<std::size_t>(n_), 0);
  parent.assign(static_cast<std::size_t>(nsuper), -1);
  std::vector<double> work(static_cast<std::size_t>(nsuper)), subtree;
  for (int s = 0; s < nsuper; ++s) {
    const Supernode sn = supernode(f, s);
    for (int k = 0; k < sn.columns; ++k) owner[static_cast<std::size_t>(sn.first + k)] = s;
    work[static_cast<std::size_t>(s)] = static_cast<double>(sn.rows) * sn.columns;
    max_rows_ = std::max(max_rows_, sn.rows);
  }
  std::vector<std::vector<int>> children(static_cast<std::size_t>(nsuper));
  std::vector<int> roots;
  for (int s = 0; s < nsuper; ++s) {
    const Supernode sn = supernode(f, s);
    const int p = sn.rows > sn.columns ? owner[static_cast<std::size_t>(sn.row[sn.columns])] : -1;
    if (p >= 0 && p <= s) {  // not numbered children first: leave it to CHOLMOD
      owner_.clear();
      parent_.clear();
      return;
    }
    parent[static_cast<std::size_t>(s)] = p;
    if (p < 0)
      roots.push_back(s);
    else
      children[static_cast<std::size_t>(p)].push_back(s);
  }
  subtree = work;
  for (int s = 0; s < nsuper; ++s)
    if (parent[static_cast<std::size_t>(s)] >= 0)
      subtree[static_cast<std::size_t>(parent[static_cast<std::size_t>(s)])] +=
          subtree[static_cast<std::size_t>(s)];
  const double total = std::accumulate(work.begin(), work.end(), 0.0);

  // cut: the subtrees below a top part, dealt largest first to the lighter group; the top
  // grows by the largest subtree's root while that lowers the cost, max(group) + top
  std::vector<int> candidates = roots, best_candidates, best_bins;
  double top = 0, best_cost = total + 1;
  for (int expansion = 0; expansion < 4096 && !candidates.empty(); ++expansion) {
    std::sort(candidates.begin(), candidates.end(), [&](int a, int b) {
      const double wa = subtree[static_cast<std::size_t>(a)],
                   wb = subtree[static_cast<std::size_t>(b)];
      return wa != wb ? wa > wb : a < b;
    });
    double bins[2] = {0, 0};
    std::vector<int> bin_of(candidates.size());
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      const int b = bins[1] < bins[0] ? 1 : 0;
      bin_of[k] = b;
      bins[b] += subtree[static_cast<std::size_t>(candidates[k])];
    }
    const double cost = std::max(bins[0], bins[1]) + top;
    if (cost < best_cost) {
      best_cost = cost;
      best_candidates = candidates;
      best_bins = bin_of;
    }
    // the largest subtree's root moves to the top; its children become candidates
    const int largest = candidates.front();
    if (subtree[static_cast<std::size_t>(largest)] < 0.02 * total) break;
    candidates.erase(candidates.begin());
    top += work[static_cast<std::size_t>(largest)];
    for (int c : children[static_cast<std::size_t>(largest)]) candidates.push_back(c);
  }
  // each supernode's group: 0 or 1 below a candidate of that bin, 2 in the top part
  std::vector<int> group(static_cast<std::size_t>(nsuper), 2);
  std::vector<char> is_candidate(static_cast<std::size_t>(nsuper), 0);
  for (std::size_t k = 0; k < best_candidates.size(); ++k) {
    group[static_cast<std::size_t>(best_candidates[k])] = best_bins[k];
    is_candidate[static_cast<std::size_t>(best_candidates[k])] = 1;
  }
  for (int s = nsuper - 1; s >= 0; --s) {
    const int p = parent[static_cast<std::size_t>(s)];
    if (!is_candidate[static_cast<std::size_t>(s)] && p >= 0)
      group[static_cast<std::size_t>(s)] = group[static_cast<std::size_t>(p)];
  }
  double top_work = 0;
  for (int s = 0; s < nsuper; ++s) {
    const int g = group[static_cast<std::size_t>(s)];
    std::vector<int>& columns = g == 2 ? top_columns_ : group_columns_[g];
    (g == 2 ? top_ : group_[g]).push_back(s);
    const Supernode sn = supernode(f, s);
    for (int k = 0; k < sn.columns; ++k) columns.push_back(sn.first + k);
    if (g == 2) top_work += work[static_cast<std::size_t>(s)];
  }
  top_share_ = total > 0 ? top_work / total : 1;
  usable_ = true;
}

void SubtreeSolve::solve(const cholmod_factor* f, double* x, bool threads, Scratch* scratch) const {
  const auto n = static_cast<std::size_t>(n_);
  const int* perm = static_cast<const int*>(f->Perm);
  std::vector<double>& y = scratch->y;
  y.resize(n);
  for (std::size_t k = 0; k < n; ++k) y[k] = x[perm ? perm[k] : static_cast<int>(k)];
  for (int g = 0; g < 2; ++g) {
    scratch->group[g].assign(n, 0.0);
    scratch->column[g].resize(static_cast<std::size_t>(max_rows_));
  }
  mark_reached(y.data(), 1, scratch);
  const std::vector<char>& reached = scratch->reached;
  const OneBlasThread one_thread;
  // forward: each group on its own copy of its columns, its updates to the top part
  // gathered apart
  in_two_threads(threads, [&](int first, int stride) {
    for (int g = first; g < 2; g += stride) {
      double* v = scratch->group[g].data();
      for (int c : group_columns_[g]) v[c] = y[static_cast<std::size_t>(c)];
      for (int s : group_[g])
        if (reached[static_cast<std::size_t>(s)])
          forward(supernode(f, s), v, scratch->column[g].data());
    }
  });
  for (int g = 0; g < 2; ++g)
    for (int c : group_columns_[g])
      y[static_cast<std::size_t>(c)] = scratch->group[g][static_cast<std::size_t>(c)];
  for (int c : top_columns_) {
    const auto k = static_cast<std::size_t>(c);
    y[k] = y[k] + scratch->group[0][k] + scratch->group[1][k];
  }
  for (int s : top_)
    if (reached[static_cast<std::size_t>(s)])
      forward(supernode(f, s), y.data(), scratch->column[0].data());
  // backward: the top part, then both groups (each writes its own columns only)
  for (auto s = top_.rbegin(); s != top_.rend(); ++s)
    backward(supernode(f, *s), y.data(), scratch->column[0].data());
  in_two_threads(threads, [&](int first, int stride) {
    for (int g = first; g < 2; g += stride)
      for (auto s = group_[g].rbegin(); s != group_[g].rend(); ++s)
        backward(supernode(f, *s), y.data(), scratch->column[g].data());
  });
  for (std::size_t k = 0; k < n; ++k) x[perm ? perm[k] : static_cast<int>(k)] = y[k];
}

void SubtreeSolve::mark_reached(const double* y, int columns, Scratch* scratch) const {
  std::vector<char>& reached = scratch->reached;
  reached.assign(parent_.size(), 0);
  const auto n = static_cast<std::size_t>(n_);
  for (int c = 0; c < columns; ++c) {
    const double* col = y + static_cast<std::size_t>(c) * n;
    for (std::size_t k = 0; k < n; ++k)
      if (col[k] != 0) reached[static_cast<std::size_t>(owner_[k])] = 1;
  }
  for (std::size_t s = 0; s < reached.size(); ++s)  // children before parents
    if (reached[s] && parent_[s] >= 0) reached[static_cast<std::size_t>(parent_[s])] = 1;
}

void SubtreeSolve::solve_block(const cholmod_factor* f, double* x, int columns,
                               Scratch* scratch) const {
  const auto n = static_cast<std::size_t>(n_);
  const int* perm = static_cast<const int*>(f->Perm);
  std::vector<double>& y = scratch->y;
  y.resize(n * static_cast<std::size_t>(columns));
  for (int c = 0; c < columns; ++c)
    for (std::size_t k = 0; k < n; ++k)
      y[static_cast<std::size_t>(c) * n + k] =
          x[static_cast<std::size_t>(c) * n +
            static_cast<std::size_t>(perm ? perm[k] : static_cast<int>(k))];
  mark_reached(y.data(), columns, scratch);
  scratch->needed.assign(parent_.size(), 1);
  sweep_block(f, columns, scratch);
  for (int c = 0; c < columns; ++c)
    for (std::size_t k = 0; k < n; ++k)
      x[static_cast<std::size_t>(c) * n +
        static_cast<std::size_t>(perm ? perm[k] : static_cast<int>(k))] =
          y[static_cast<std::size_t>(c) * n + k];
}

void SubtreeSolve::solve_sparse(const cholmod_factor* f, const Eigen::SparseMatrix<double>& b,
                                const std::vector<Eigen::Index>& rows, Eigen::MatrixXd* out,
                                Scratch* scratch) const {
  const auto n = static_cast<std::size_t>(n_);
  const int columns = static_cast<int>(b.cols());
  // the supernodes the loads reach, and those the answers at `rows` need (theirs and their
  // ancestors': the backward sweep reads only rows below)
  std::vector<char>& reached = scratch->reached;
  reached.assign(parent_.size(), 0);
  for (int c = 0; c < columns; ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(b, c); it; ++it)
      reached[static_cast<std::size_t>(
          owner_[static_cast<std::size_t>(position_[static_cast<std::size_t>(it.row())])])] = 1;
  std::vector<char>& needed = scratch->needed;
  needed.assign(parent_.size(), 0);
  for (Eigen::Index r : rows)
    needed[static_cast<std::size_t>(
        owner_[static_cast<std::size_t>(position_[static_cast<std::size_t>(r)])])] = 1;
  for (std::size_t s = 0; s < parent_.size(); ++s)  // children before parents
    if (parent_[s] >= 0) {
      const auto p = static_cast<std::size_t>(parent_[s]);
      if (reached[s]) reached[p] = 1;
      if (needed[s]) needed[p] = 1;
    }
  // the loads in the factor's order, over zeros in the rows the sweeps visit (those of
  // supernodes reached or needed; zeroing all of y, 12 MB a block of 64 loads on the
  // snap-fit's socket, cost more than the rest of this set-up)
  std::vector<double>& y = scratch->y;
  y.resize(n * static_cast<std::size_t>(columns));
  const int* super = static_cast<const int*>(f->super);
  for (std::size_t s = 0; s < parent_.size(); ++s)
    if (reached[s] || needed[s])
      for (int c = 0; c < columns; ++c)
        std::fill(y.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(c) * n +
                                                          static_cast<std::size_t>(super[s])),
                  y.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(c) * n +
                                                          static_cast<std::size_t>(super[s + 1])),
                  0.0);
  for (int c = 0; c < columns; ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(b, c); it; ++it)
      y[static_cast<std::size_t>(c) * n +
        static_cast<std::size_t>(position_[static_cast<std::size_t>(it.row())])] = it.value();
  sweep_block(f, columns, scratch);
  out->resize(static_cast<Eigen::Index>(rows.size()), columns);
  for (int c = 0; c < columns; ++c)
    for (std::size_t q = 0; q < rows.size(); ++q)
      (*out)(static_cast<Eigen::Index>(q), c) =
          y[static_cast<std::size_t>(c) * n +
            static_cast<std::size_t>(position_[static_cast<std::size_t>(rows[q])])];
}

void SubtreeSolve::sweep_block(const cholmod_factor* f, int columns, Scratch* scratch) const {
  const auto n = static_cast<std::size_t>(n_);
  std::vector<double>& y = scratch->y;
  std::vector<double>& t = scratch->block;
  t.resize(static_cast<std::size_t>(max_rows_) * static_cast<std::size_t>(columns));
  const OneBlasThread one_thread;
  const int ld = n_;
  const double one = 1, zero = 0, minus_one = -1;
  // forward: a supernode's own rows solved with its diagonal block, the rows below updated
  // by its off-diagonal block times them (gathered, scattered)
  for (std::size_t s = 0; s < parent_.size(); ++s) {
    if (!scratch->reached[s]) continue;
    const Supernode sn = supernode(f, static_cast<int>(s));
    double* own = y.data() + sn.first;
    dtrsm_("L", "L", "N", "N", &sn.columns, &columns, &one, sn.values, &sn.rows, own, &ld, 1, 1, 1,
           1);
    const int below = sn.rows - sn.columns;
    if (below == 0) continue;
    dgemm_("N", "N", &below, &columns, &sn.columns, &one, sn.values + sn.columns, &sn.rows, own,
           &ld, &zero, t.data(), &below, 1, 1);
    for (int c = 0; c < columns; ++c) {
      double* col = y.data() + static_cast<std::size_t>(c) * n;
      const double* tc = t.data() + static_cast<std::size_t>(c) * static_cast<std::size_t>(below);
      for (int i = 0; i < below; ++i) col[sn.row[sn.columns + i]] -= tc[i];
    }
  }
  // backward: the rows below (solved) gathered and taken off, then the diagonal block
  for (std::size_t s = parent_.size(); s-- > 0;) {
    if (!scratch->needed[s]) continue;
    const Supernode sn = supernode(f, static_cast<int>(s));
    double* own = y.data() + sn.first;
    const int below = sn.rows - sn.columns;
    if (below > 0) {
      for (int c = 0; c < columns; ++c) {
        const double* col = y.data() + static_cast<std::size_t>(c) * n;
        double* tc = t.data() + static_cast<std::size_t>(c) * static_cast<std::size_t>(below);
        for (int i = 0; i < below; ++i) tc[i] = col[sn.row[sn.columns + i]];
      }
      dgemm_("T", "N", &sn.columns, &columns, &below, &minus_one, sn.values + sn.columns, &sn.rows,
             t.data(), &below, &one, own, &ld, 1, 1);
    }
    dtrsm_("L", "L", "T", "N", &sn.columns, &columns, &one, sn.values, &sn.rows, own, &ld, 1, 1, 1,
           1);
  }
}

}  // namespace vproto::sim
