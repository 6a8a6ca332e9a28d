#include "vproto/sim/sparse_cholesky.h"

#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>

#include "blas_threads.h"
#include "subtree_solve.h"
#include "vproto/materials/errors.h"

namespace vproto::sim {

std::string FactorMemoryError::gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g GB", bytes / 1e9);
  return text;
}

double factor_memory_limit() {
  if (const char* limit = std::getenv("VPROTO_MEMORY_LIMIT")) {
    char* end = nullptr;
    double value = std::strtod(limit, &end);
    const std::string unit = end ? end : "";
    if (unit == "KB" || unit == "kB") value *= 1e3;
    if (unit == "MB") value *= 1e6;
    if (unit == "GB") value *= 1e9;
    if (value > 0 && std::isfinite(value)) return value;
  }
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kilobytes = 0;
  std::string unit;
  while (meminfo >> key >> kilobytes >> unit)
    if (key == "MemAvailable:") return 0.9 * kilobytes * 1e3;
  return 1e12;  // unknown: do not refuse
}

namespace {}  // namespace

// A 3-D elasticity factor's entries grow as about 10.8 n^(4/3) for n unknowns (98k dofs:
// 4.9e7 with nested dissection); the bytes a factor of n unknowns will need, roughly.
double estimated_factor_bytes(double n) { return 8 * 10.8 * std::pow(n, 4.0 / 3.0); }

namespace {

// CHOLMOD's view of a sorted, packed lower triangle (a pattern when x is null)
cholmod_sparse lower_view(std::size_t n, std::size_t nnz, const int* p, const int* i,
                          const double* x) {
  cholmod_sparse s{};
  s.nrow = s.ncol = n;
  s.nzmax = nnz;
  s.p = const_cast<int*>(p);
  s.i = const_cast<int*>(i);
  s.x = const_cast<double*>(x);
  s.stype = -1;  // the lower triangle holds the matrix
  s.itype = CHOLMOD_INT;
  s.xtype = x ? CHOLMOD_REAL : CHOLMOD_PATTERN;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = 1;
  s.packed = 1;
  return s;
}

// The pattern of the block graph of a lower-triangle matrix of block x block blocks: the
// first column of each block column, its rows divided by the block size.
struct BlockGraph {
  std::vector<int> p, i;
  cholmod_sparse view(std::size_t n) {
    return lower_view(n, i.size(), p.data(), i.data(), nullptr);
  }
};

BlockGraph block_graph(const LowerView& a, int block) {
  BlockGraph g;
  const Eigen::Index nb = a.cols() / block;
  g.p.reserve(static_cast<std::size_t>(nb) + 1);
  g.p.push_back(0);
  for (Eigen::Index b = 0; b < nb; ++b) {
    const Eigen::Index col = b * block;
    int last = -1;
    for (int k = a.outerIndexPtr()[col]; k < a.outerIndexPtr()[col + 1]; ++k) {
      const int node = a.innerIndexPtr()[k] / block;
      if (node != last) g.i.push_back(node);
      last = node;
    }
    g.p.push_back(static_cast<int>(g.i.size()));
  }
  return g;
}

}  // namespace

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // the pattern the analysis belongs to
  Eigen::Index n = -1;
  std::vector<int> outer, inner;
  // Solve workspaces, reused: one per thread solving at the same time (CHOLMOD keeps its
  // status and scratch in a cholmod_common, and reads the factor only)
  struct Workspace {
    cholmod_common common{};
    cholmod_dense* x = nullptr;
    cholmod_dense* y = nullptr;
    cholmod_dense* e = nullptr;
    SubtreeSolve::Scratch subtree;
    Workspace() { cholmod_start(&common); }
    ~Workspace() {
      if (x) cholmod_free_dense(&x, &common);
      if (y) cholmod_free_dense(&y, &common);
      if (e) cholmod_free_dense(&e, &common);
      cholmod_finish(&common);
    }
    Workspace(const Workspace&) = delete;
    Workspace& operator=(const Workspace&) = delete;
  };
  mutable std::vector<std::unique_ptr<Workspace>> idle;
  mutable std::mutex idle_mutex;
  // the sweeps of subtree_solve.h (one right-hand side on two threads, forward sweeps that
  // visit only what a sparse right-hand side reaches), for factors where they pay
  std::unique_ptr<SubtreeSolve> subtree;
  std::vector<Eigen::Index> position;  ///< each unknown's place in the factor's order
  static constexpr double kSubtreeEntries = 2e5;

  ~Impl() {
    idle.clear();
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  cholmod_sparse wrap(const LowerView& a) const {
    return lower_view(static_cast<std::size_t>(a.rows()), static_cast<std::size_t>(a.nonZeros()),
                      a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr());
  }

  // order the block graph, expand the permutation to every row of each block, and
  // analyse with it
  cholmod_factor* analyze_blocked(const LowerView& a, cholmod_sparse& s, int block,
                                  SparseCholesky::Ordering ordering, std::string* chosen) {
    BlockGraph g = block_graph(a, block);
    const std::size_t nb = static_cast<std::size_t>(a.cols() / block);
    cholmod_sparse gs = g.view(nb);
    auto expand = [&](const std::vector<int>& node_perm) {
      std::vector<int> perm(static_cast<std::size_t>(a.cols()));
      for (std::size_t k = 0; k < nb; ++k)
        for (int r = 0; r < block; ++r) perm[k * block + r] = node_perm[k] * block + r;
      return perm;
    };
    auto order = [&](int method) {
      std::vector<int> node_perm(nb);
      const int ok = method == CHOLMOD_AMD
                         ? cholmod_amd(&gs, nullptr, 0, node_perm.data(), &common)
                         : cholmod_metis(&gs, nullptr, 0, 1, node_perm.data(), &common);
      if (!ok)
        throw InternalError("CHOLMOD ordering failed (status " + std::to_string(common.status) +
                            ")");
      return expand(node_perm);
    };
    auto analyze_with = [&](std::vector<int>& perm) {
      const int saved = common.nmethods, saved_ordering = common.method[0].ordering;
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_GIVEN;
      cholmod_factor* f = cholmod_analyze_p(&s, perm.data(), nullptr, 0, &common);
      common.nmethods = saved;
      common.method[0].ordering = saved_ordering;
      if (!f && (common.status == CHOLMOD_OUT_OF_MEMORY || common.status == CHOLMOD_TOO_LARGE))
        throw FactorMemoryError(
            std::max(estimated_factor_bytes(static_cast<double>(a.cols())), factor_memory_limit()),
            factor_memory_limit());
      if (!f)
        throw InternalError("CHOLMOD analysis failed (status " + std::to_string(common.status) +
                            ")");
      return f;
    };
    if (ordering == SparseCholesky::Ordering::kAmd ||
        ordering == SparseCholesky::Ordering::kMetis) {
      const bool amd = ordering == SparseCholesky::Ordering::kAmd;
      std::vector<int> perm = order(amd ? CHOLMOD_AMD : CHOLMOD_METIS);
      *chosen = amd ? "amd on nodes" : "metis on nodes";
      return analyze_with(perm);
    }
    if (ordering == SparseCholesky::Ordering::kNesdis) {
      std::vector<int> node_perm(nb), cparent(nb), cmember(nb);
      if (cholmod_nested_dissection(&gs, nullptr, 0, node_perm.data(), cparent.data(),
                                    cmember.data(), &common) < 0)
        throw InternalError("CHOLMOD nested dissection failed");
      std::vector<int> perm = expand(node_perm);
      *chosen = "nesdis on nodes";
      return analyze_with(perm);
    }
    // Automatic: AMD is cheap and good for small or slender meshes; METIS on the node
    // graph is as cheap to compute and fills in far less on bulky 3-D meshes (81k dofs of a
    // steel block: 7.3e10 flops against AMD's 1.4e11)
    const bool small = nb < 3000;
    std::vector<int> perm = order(small ? CHOLMOD_AMD : CHOLMOD_METIS);
    *chosen = small ? "amd on nodes" : "metis on nodes";
    return analyze_with(perm);
  }

  void solve(double* data, Eigen::Index rows, Eigen::Index cols) const {
    cholmod_dense b{};
    b.nrow = static_cast<std::size_t>(rows);
    b.ncol = static_cast<std::size_t>(cols);
    b.nzmax = b.nrow * b.ncol;
    b.d = b.nrow;
    b.x = data;
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    std::unique_ptr<Workspace> w = take();
    bool solved = true;
    int status = CHOLMOD_OK;
    if (cols == 1 && subtree && subtree->usable()) {
      subtree->solve(factor, data, true, &w->subtree);
    } else if (subtree && subtree->usable()) {
      subtree->solve_block(factor, data, static_cast<int>(cols), &w->subtree);
    } else {
      const OneBlasThread one_thread;
      solved =
          cholmod_solve2(CHOLMOD_A, factor, &b, nullptr, &w->x, nullptr, &w->y, &w->e, &w->common);
      status = w->common.status;
      if (solved)
        std::memcpy(data, w->x->x, sizeof(double) * static_cast<std::size_t>(rows * cols));
    }
    give_back(std::move(w));
    if (!solved)
      throw InternalError("CHOLMOD solve failed (status " + std::to_string(status) + ")");
  }

  // an idle workspace, or a new one; and back to the idle ones
  std::unique_ptr<Workspace> take() const {
    {
      const std::lock_guard<std::mutex> lock(idle_mutex);
      if (!idle.empty()) {
        std::unique_ptr<Workspace> w = std::move(idle.back());
        idle.pop_back();
        return w;
      }
    }
    return std::make_unique<Workspace>();
  }
  void give_back(std::unique_ptr<Workspace> w) const {
    const std::lock_guard<std::mutex> lock(idle_mutex);
    idle.push_back(std::move(w));
  }
};

SparseCholesky::SparseCholesky(Ordering ordering)
    : impl_(std::make_unique<Impl>()), ordering_(ordering) {
  stats_.backend = "cholmod";
  stats_.method = "supernodal Cholesky";
  cholmod_common& c = impl_->common;
  cholmod_start(&c);
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.print = 0;
  c.error_handler = nullptr;
  c.quick_return_if_not_posdef = 1;
  switch (ordering) {
    case Ordering::kAutomatic:
      break;  // CHOLMOD's default: AMD, then METIS when AMD fills in badly
    case Ordering::kAmd:
      c.nmethods = 1;
      c.method[0].ordering = CHOLMOD_AMD;
      c.postorder = 1;
      break;
    case Ordering::kMetis:
      c.nmethods = 1;
      c.method[0].ordering = CHOLMOD_METIS;
      c.postorder = 1;
      break;
    case Ordering::kNesdis:
      c.nmethods = 1;
      c.method[0].ordering = CHOLMOD_NESDIS;
      c.postorder = 1;
      break;
  }
}

SparseCholesky::~SparseCholesky() = default;

bool SparseCholesky::factored() const {
  return impl_->factor != nullptr && stats_.factorizations > 0;
}

Eigen::Index SparseCholesky::size() const { return impl_->n; }

void SparseCholesky::factor(const LowerView& a, const std::string& what, int block) {
  VPROTO_DEMAND(a.rows() == a.cols());
  Impl& m = *impl_;
  cholmod_common& c = m.common;
  const bool same_pattern = m.factor && m.n == a.rows() &&
                            static_cast<Eigen::Index>(m.inner.size()) == a.nonZeros() &&
                            std::equal(m.outer.begin(), m.outer.end(), a.outerIndexPtr()) &&
                            std::equal(m.inner.begin(), m.inner.end(), a.innerIndexPtr());
  cholmod_sparse s = m.wrap(a);
  using Clock = std::chrono::steady_clock;
  if (!same_pattern) {
    const auto t0 = Clock::now();
    std::string blocked_ordering;
    if (m.factor) cholmod_free_factor(&m.factor, &c);
    // hopeless sizes are refused before the analysis, which would itself run out
    const double limit = factor_memory_limit();
    const double rough = estimated_factor_bytes(static_cast<double>(a.rows()));
    if (rough > 4 * limit) throw FactorMemoryError(rough, limit);
    if (block > 1 && a.cols() % block == 0 && a.cols() > 0)
      m.factor = m.analyze_blocked(a, s, block, ordering_, &blocked_ordering);
    else
      m.factor = cholmod_analyze(&s, &c);
    if (!m.factor && (c.status == CHOLMOD_OUT_OF_MEMORY || c.status == CHOLMOD_TOO_LARGE))
      throw FactorMemoryError(std::max(rough, limit), limit);
    if (!m.factor)
      throw InternalError("CHOLMOD analysis failed (status " + std::to_string(c.status) + ")");
    // the analysis knows the factor's size: refuse before any numeric work
    const double entries =
        std::max(c.lnz, m.factor->is_super ? static_cast<double>(m.factor->xsize) : 0.0);
    const double needed = 8 * 1.1 * entries;
    if (needed > limit) {
      cholmod_free_factor(&m.factor, &c);
      throw FactorMemoryError(needed, limit);
    }
    m.n = a.rows();
    m.subtree.reset();
    m.position.clear();
    m.outer.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.cols() + 1);
    m.inner.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
    stats_.analyze_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    static const char* names[] = {"natural", "given",  "amd",        "metis",
                                  "nesdis",  "colamd", "postordered"};
    const int ord = m.factor->ordering;
    stats_.ordering = ord >= 0 && ord < 7 ? names[ord] : "unknown";
    if (!blocked_ordering.empty()) stats_.ordering = blocked_ordering;
  }
  const auto t0 = Clock::now();
  const int ok = cholmod_factorize(&s, m.factor, &c);
  stats_.factor_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (!ok || c.status == CHOLMOD_NOT_POSDEF || c.status < CHOLMOD_OK) {
    stats_.factorizations = 0;
    if (c.status == CHOLMOD_NOT_POSDEF)
      throw SimulationError(what + " is not positive definite (singular at column " +
                            std::to_string(m.factor->minor) + " of " + std::to_string(m.n) + ")");
    if (c.status == CHOLMOD_OUT_OF_MEMORY || c.status == CHOLMOD_TOO_LARGE)
      throw FactorMemoryError(8 * 1.1 * static_cast<double>(m.factor->xsize),
                              factor_memory_limit());
    throw SimulationError("factoring " + what + " failed (CHOLMOD status " +
                          std::to_string(c.status) + ")");
  }
  ++stats_.factorizations;
  // the partition for single right-hand sides, once per analysis (the supernodes' layout
  // is known once the factor holds its values)
  if (!m.subtree && m.factor->is_super &&
      static_cast<double>(m.factor->xsize) >= Impl::kSubtreeEntries)
    m.subtree = std::make_unique<SubtreeSolve>(m.factor);
  if (m.position.size() != static_cast<std::size_t>(m.n)) {
    const int* perm = static_cast<const int*>(m.factor->Perm);
    m.position.resize(static_cast<std::size_t>(m.n));
    for (Eigen::Index k = 0; k < m.n; ++k)
      m.position[static_cast<std::size_t>(perm ? perm[k] : k)] = k;
  }
  if (m.subtree && m.subtree->usable()) {
    char text[96];
    std::snprintf(text, sizeof text,
                  "two-thread sweeps over the supernodal tree (%.1f %% of L on one)",
                  100 * m.subtree->top_share());
    stats_.single_solve = text;
  } else {
    stats_.single_solve = "cholmod sweeps";
  }
  stats_.flops = c.fl;
  // entries of L as stored (supernodal: the dense supernode blocks)
  const double nnz = m.factor->is_super ? static_cast<double>(m.factor->xsize) : c.lnz;
  stats_.factor_nonzeros = nnz;
}

Eigen::Index SparseCholesky::elimination_position(Eigen::Index row) const {
  VPROTO_DEMAND(factored() && row >= 0 && row < impl_->n);
  return impl_->position.empty() ? row : impl_->position[static_cast<std::size_t>(row)];
}

Eigen::MatrixXd SparseCholesky::solve_sparse(const Eigen::SparseMatrix<double>& b,
                                             const std::vector<Eigen::Index>& rows) const {
  VPROTO_DEMAND(factored() && b.rows() == impl_->n);
  const Impl& m = *impl_;
  if (!m.subtree || !m.subtree->usable() || b.cols() == 0)
    return LinearSolver::solve_sparse(b, rows);
  for (Eigen::Index r : rows) VPROTO_DEMAND(r >= 0 && r < m.n);
  std::unique_ptr<Impl::Workspace> w = m.take();
  Eigen::MatrixXd out;
  m.subtree->solve_sparse(m.factor, b, rows, &out, &w->subtree);
  m.give_back(std::move(w));
  return out;
}

void SparseCholesky::solve_in_place(Eigen::VectorXd& x) const {
  VPROTO_DEMAND(factored() && x.size() == impl_->n);
  impl_->solve(x.data(), x.size(), 1);
}

void SparseCholesky::solve_in_place(Eigen::MatrixXd& x) const {
  VPROTO_DEMAND(factored() && x.rows() == impl_->n);
  if (x.cols() > 0) impl_->solve(x.data(), x.rows(), x.cols());
}

}  // namespace vproto::sim
