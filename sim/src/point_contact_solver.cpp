#include "vproto/sim/point_contact_solver.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>

#include "blas.h"
#include "blas_threads.h"
#include "two_threads.h"

// LAPACK's LU (OpenBLAS here: blocked, twice Eigen's speed on one core for a 2,000-row
// Newton system), with OpenBLAS on one thread (blas_threads.h): its threads cost more than
// they save on the small systems, and their split depends on the cores, so the forces, and
// the run, would too. Large systems deal their trailing updates over two threads of our own
// in fixed chunks instead (lu_factor), the same bits on any number of cores.

namespace vproto::sim {

namespace {

// Products of W with a vector reading at least this many rows times points go over two
// threads.
constexpr Eigen::Index kTwoThreadProduct = 200000;

// W of a problem, dense or formed column by column (DelassusColumns).
class WView {
 public:
  explicit WView(const PointContactProblem& p) : w_(p.w), lazy_(p.columns), rows_(p.free.size()) {}
  Eigen::Index rows() const { return rows_; }
  /// Forms the columns of `which` where W is formed column by column.
  void prepare(const std::vector<Eigen::Index>& which) const {
    if (lazy_) lazy_->prepare(which);
  }
  /// Point j's three columns, one after the other (prepared).
  const double* column(Eigen::Index j) const {
    return lazy_ ? lazy_->column(j) : w_.data() + 3 * j * rows_;
  }
  /// The 3 x 3 block (i, j) (j prepared).
  Eigen::Matrix3d block(Eigen::Index i, Eigen::Index j) const {
    return Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>>(column(j) + 3 * i,
                                                                      Eigen::OuterStride<>(rows_));
  }
  Eigen::Matrix3d diagonal(Eigen::Index i) const {
    return lazy_ ? lazy_->diagonal(i) : w_.block<3, 3>(3 * i, 3 * i).eval();
  }
  double largest_diagonal() const {
    double largest = 0;
    for (Eigen::Index i = 0; i < rows_ / 3; ++i)
      largest = std::max(largest, diagonal(i).diagonal().cwiseAbs().maxCoeff());
    return largest;
  }

 private:
  const Eigen::MatrixXd& w_;
  DelassusColumns* lazy_;
  Eigen::Index rows_;
};

// w x, reading only the columns of the points where x is nonzero (w is 3m x 3m and dense;
// in a Newton step or a warm start most points carry no force). On the 161 contact problems
// of more than 100 points dumped from the snap-fit (its landing: up to 1,269 points, W
// 97 MB), full products took 2.9 of the solver's 18.9 s. The product streams W from memory:
// a large one is split by rows over two threads (each row's sum is taken in the same order
// on either, so the bits do not depend on the split).
Eigen::VectorXd times_forced(const WView& w, const Eigen::VectorXd& x) {
  const Eigen::Index m = x.size() / 3, rows = w.rows();
  std::vector<Eigen::Index> forced;
  for (Eigen::Index j = 0; j < m; ++j)
    if (x.segment<3>(3 * j).squaredNorm() > 0) forced.push_back(j);
  w.prepare(forced);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(rows);
  double* const out = y.data();
  in_two_threads(rows * static_cast<Eigen::Index>(forced.size()) >= kTwoThreadProduct,
                 [&](int first, int stride) {
                   const Eigen::Index chunk = ((rows + stride - 1) / stride + 7) / 8 * 8;
                   const Eigen::Index r0 = std::min(rows, first * chunk),
                                      r1 = std::min(rows, r0 + chunk);
                   for (const Eigen::Index j : forced) {
                     const double* const c0 = w.column(j);
                     const double* const c1 = c0 + rows;
                     const double* const c2 = c1 + rows;
                     const double x0 = x[3 * j], x1 = x[3 * j + 1], x2 = x[3 * j + 2];
                     for (Eigen::Index r = r0; r < r1; ++r)
                       out[r] += c0[r] * x0 + c1[r] * x1 + c2[r] * x2;
                   }
                 });
  return y;
}

}  // namespace

int lu_factor(Eigen::MatrixXd* matrix, std::vector<int>* pivots) {
  const int n = static_cast<int>(matrix->rows());
  pivots->assign(static_cast<std::size_t>(n), 0);
  double* a = matrix->data();
  int* ipiv = pivots->data();
  const OneBlasThread one_thread;
  int info = 0;
  if (n < kTwoThreadLu) {
    dgetrf_(&n, &n, a, &n, ipiv, &info);
    return info;
  }
  // right-looking, in panels of kPanel columns: the panel by LAPACK, then the columns to its
  // right in chunks as wide (its row swaps, the triangular solve for U's rows, the trailing
  // update). Narrow panels below 1,024 rows, where wide ones leave too few chunks to share
  // (from 1,024 rows panels of 128 gain 5-10 % on 64). Looking ahead: the next panel's
  // columns are the first chunk, updated and then factored by the calling thread while the
  // helper takes the other chunks (the panel, serial, was a fifth of the time at 400-1,500
  // rows); whichever thread is free takes the next chunk. GFLOP/s here at 300 / 400 / 700 /
  // 1,000 / 1,500 rows: 43 / 53 / 76 / 94 / 102, dgetrf on one core 28 / 33 / 40 / 46 / 53.
  // Each chunk and each panel is the same calls whichever thread makes them, so the factors
  // are the same bits on one core or two. The row swaps of each panel reach the columns to
  // its left at the end (nothing reads those columns again, and the swaps keep their order).
  const int kPanel = n < 1024 ? 64 : 128;
  const int one = 1;
  const double unit = 1, minus = -1;
  auto factor_panel = [&](int k) {
    const int b = std::min(kPanel, n - k), rows = n - k;
    int panel_info = 0;
    dgetrf_(&rows, &b, a + k + static_cast<std::ptrdiff_t>(k) * n, &n, ipiv + k, &panel_info);
    for (int i = k; i < k + b; ++i) ipiv[i] += k;
    return panel_info != 0 ? panel_info + k : 0;
  };
  info = factor_panel(0);
  for (int k = 0; k < n && info == 0; k += kPanel) {
    const int b = std::min(kPanel, n - k), k1 = k + 1, k2 = k + b, below = n - k - b;
    if (below == 0) break;
    const double* const panel = a + k + static_cast<std::ptrdiff_t>(k) * n;
    const int chunks = (below + kPanel - 1) / kPanel;
    auto update = [&](int c) {
      const int c0 = k + b + c * kPanel, width = std::min(kPanel, n - c0);
      double* const col = a + static_cast<std::ptrdiff_t>(c0) * n;
      dlaswp_(&width, col, &n, &k1, &k2, ipiv, &one);
      dtrsm_("L", "L", "N", "U", &b, &width, &unit, panel, &n, col + k, &n, 1, 1, 1, 1);
      dgemm_("N", "N", &below, &width, &b, &minus, panel + b, &n, col + k, &n, &unit, col + k + b,
             &n, 1, 1);
    };
    std::atomic<int> next{1};
    in_two_threads(true, [&](int first, int) {
      if (first == 0) {
        update(0);
        info = factor_panel(k + b);
      }
      for (int c = next++; c < chunks; c = next++) update(c);
    });
  }
  if (info != 0) return info;
  // the row swaps of each panel on the columns left of it, in the panels' order: each thread
  // one half of the columns
  in_two_threads(true, [&](int first, int stride) {
    const int c0 = stride == 1 ? 0 : first * (n / 2), c1 = stride == 1 || first == 1 ? n : n / 2;
    for (int k = kPanel; k < n; k += kPanel) {
      const int k1 = k + 1, k2 = std::min(n, k + kPanel), width = std::min(c1, k) - c0;
      if (width > 0)
        dlaswp_(&width, a + static_cast<std::ptrdiff_t>(c0) * n, &n, &k1, &k2, ipiv, &one);
    }
  });
  return 0;
}

namespace {

// Solves a x = b in place of both (a dense, square, general); false when a is singular.
bool lu_solve(Eigen::MatrixXd* a, Eigen::VectorXd* b) {
  const int n = static_cast<int>(a->rows()), one = 1;
  std::vector<int> pivots;
  int info = lu_factor(a, &pivots);
  if (info != 0) return false;
  const char trans = 'N';
  dgetrs_(&trans, &n, &one, a->data(), &n, pivots.data(), b->data(), &n, &info, 1);
  return info == 0 && b->allFinite();
}

// Coulomb's law at each point as the root of one function (Alart and Curnier's augmented
// Lagrangian form): with sigma = lambda - r d, r = 1 / W_nn of the point,
//   F_n = lambda_n - max(0, sigma_n),   F_t = lambda_t - proj(sigma_t onto the disc of radius
//   mu max(0, sigma_n)),
// zero exactly when the point is open with no force, pressed and sticking (d = 0), or pressed
// and sliding against its slip on the cone's edge. F / r is in the units of `free` (m).
struct PointState {
  enum Kind : char { kOpen, kStick, kSlide } kind = kOpen;
  // a sliding point's slip direction in its tangent plane, and the cone's radius over the
  // slip, c = mu sigma_n / |sigma_t|: the projection's derivative by sigma is the identity
  // for a sticking point, and [1 0; mu dir, c (I - dir dir')] for a sliding one
  Eigen::Vector2d dir = Eigen::Vector2d::Zero();
  double c = 0;
};

double point_residual(const Eigen::Vector3d& l, const Eigen::Vector3d& d, double r, double mu,
                      Eigen::Vector3d* f, PointState* state) {
  const Eigen::Vector3d sigma = l - r * d;
  Eigen::Vector3d proj = Eigen::Vector3d::Zero();
  if (sigma[0] <= 0) {
    state->kind = PointState::kOpen;
  } else {
    proj[0] = sigma[0];
    const Eigen::Vector2d u = sigma.tail<2>();
    const double cap = mu * sigma[0], slip = u.norm();
    if (slip <= cap) {
      state->kind = PointState::kStick;
      proj.tail<2>() = u;
    } else {
      state->kind = PointState::kSlide;
      const Eigen::Vector2d dir = u / slip;
      proj.tail<2>() = cap * dir;
      state->dir = dir;
      state->c = cap / slip;
    }
  }
  *f = (l - proj) / r;
  return f->cwiseAbs().maxCoeff();
}

// The semismooth Newton method on F = 0 over all points at once, started from the sweeps'
// forces: each iteration solves the generalized Jacobian's system for the pressed points
// (open points go to zero force), J_i = (I - D_i) / r_i + D_i W_i with D_i the projection's
// derivative, and steps along it as far as halves of it lower |F|^2 below the largest of
// the last eight iterations'. It settles the states of many soft, strongly coupled points
// together (the sweeps crawl there: a point's force moves its neighbours, and sticking
// points are told from sliding ones only through the whole block), converging
// quadratically near the solution. False when it does not converge within 50 iterations,
// or its system has more than `max_unknowns` unknowns (the sweeps then go on from the best
// forces found).
bool newton_solution(const PointContactProblem& p, Eigen::VectorXd* lambda, double tolerance,
                     Eigen::Index max_unknowns, double start_damping, double floor, int* iterations,
                     double* residual) {
  const Eigen::Index m = p.free.size() / 3;
  const auto count = static_cast<std::size_t>(m);
  const WView w(p);
  const double scale = w.largest_diagonal();
  if (!(scale > 0)) return false;
  std::vector<double> r(count);
  for (std::size_t k = 0; k < count; ++k) {
    const double wnn = w.diagonal(static_cast<Eigen::Index>(k))(0, 0);
    r[k] = 1 / std::max(wnn, 1e-12 * scale);
  }
  std::vector<PointState> state(count);
  Eigen::VectorXd l = *lambda, f(3 * m), d = p.free + times_forced(w, l);
  auto evaluate = [&](const Eigen::VectorXd& at, const Eigen::VectorXd& motion,
                      Eigen::VectorXd* out, std::vector<PointState>* states) {
    double worst = 0;
    for (std::size_t k = 0; k < count; ++k) {
      const auto i = 3 * static_cast<Eigen::Index>(k);
      Eigen::Vector3d fk;
      worst = std::max(worst, point_residual(at.segment<3>(i), motion.segment<3>(i), r[k], p.mu[k],
                                             &fk, &(*states)[k]));
      out->segment<3>(i) = fk;
    }
    return worst;
  };
  double worst = evaluate(l, d, &f, &state);
  const double start_worst = worst;
  double best_worst = worst;
  Eigen::VectorXd best = l;
  std::vector<PointState> trial_state(count);
  Eigen::VectorXd trial_f(3 * m);
  std::array<double, 8> recent{};
  // the points' kinds (open, sticking, sliding) at the last few accepted iterates, hashed,
  // for the cycle test below (a collision would only make one step's search monotone)
  auto kinds = [&](const std::vector<PointState>& states) {
    std::uint64_t h = 1469598103934665603ULL;
    for (const PointState& st : states)
      h = (h ^ static_cast<std::uint64_t>(st.kind)) * 1099511628211ULL;
    return h;
  };
  std::array<std::uint64_t, 8> visited{};
  visited.fill(kinds(state));
  std::size_t visits = 0;
  // W of many points on one elastic surface is singular (more rows than the surface has
  // independent motions), and a Newton step moves forces along its null space at will:
  // the step's W carries a compliance (Levenberg and Marquardt's damping) that grows
  // when a step fails or has to be cut short and shrinks after a full one; F itself
  // stays exact. It starts where the options say (PointContactOptions::newton_damping)
  double damping = start_damping * scale;
  for (int it = 0; it < 50; ++it) {
    *residual = worst;
    if (worst <= tolerance) {
      *lambda = l;
      return true;
    }
    ++*iterations;
    std::vector<Eigen::Index> closed;
    for (std::size_t k = 0; k < count; ++k)
      if (state[k].kind != PointState::kOpen) closed.push_back(static_cast<Eigen::Index>(k));
    // a point's unknowns in the step's system: a sticking point's three forces; a sliding
    // point's normal force and its friction across the slip (two: along the slip the
    // friction follows the normal force, mu times it, by a row of its own that solves
    // locally)
    auto unknowns = [&](Eigen::Index k) {
      return state[static_cast<std::size_t>(k)].kind == PointState::kSlide ? 2 : 3;
    };
    Eigen::Index total = 0;
    for (const Eigen::Index k : closed) total += unknowns(k);
    if (total > max_unknowns) {
      // more closed points than the dense system may take (the snap-fit's landing: 600-800
      // of 1,200 points, most grazing the base part's sides): the step solves for the
      // points of largest residual, as many as it may, the others' forces kept this step
      // (a block of Newton's method; the line search judges it on every point). The
      // sweeps alone left these problems far from the solution (497 points pressed
      // instead of 429 after 400 sweeps)
      std::stable_sort(closed.begin(), closed.end(), [&](Eigen::Index a, Eigen::Index b) {
        return f.segment<3>(3 * a).norm() + std::abs(f[3 * a]) >
               f.segment<3>(3 * b).norm() + std::abs(f[3 * b]);
      });
      std::size_t fits = 0;
      for (total = 0; fits < closed.size() && total + unknowns(closed[fits]) <= max_unknowns;
           ++fits)
        total += unknowns(closed[fits]);
      closed.resize(fits);
      std::sort(closed.begin(), closed.end());
    }
    const auto n = static_cast<Eigen::Index>(closed.size());
    Eigen::VectorXd step = Eigen::VectorXd::Zero(3 * m);
    // open points: their force goes (a step of -lambda)
    Eigen::VectorXd open_force = Eigen::VectorXd::Zero(3 * m);
    for (std::size_t k = 0; k < count; ++k)
      if (state[k].kind == PointState::kOpen) {
        const auto i = 3 * static_cast<Eigen::Index>(k);
        open_force.segment<3>(i) = l.segment<3>(i);
        step.segment<3>(i) = -l.segment<3>(i);
      }
    if (n > 0) {
      // Each closed point's Newton rows, D (dd + damping dz) + (I - D) dz / r = -F with dd
      // the motion the step makes, in a point's own unknowns u: dz = N u + q. A sticking
      // point: D = I, N = I, q = 0. A sliding point (slip direction s, the direction across
      // it t, c its cone radius over its slip): D's tangential rows are mu s along the
      // normal and c t t' across, so the rows along s read (s'dz_t - mu dz_n) / r =
      // -(s'F_t + mu dd_n) with dd_n = -F_n from the normal row: the friction along the
      // slip is local, dz_t = (mu dz_n + r (mu F_n - s'F_t)) s + u_2 t. The rows left
      // (test T: the normal; c t' across) give 2 unknowns where the full system has 3: a
      // system 3.4 times cheaper to factor when most points slide, the same Newton step.
      std::vector<Eigen::Index> offset(static_cast<std::size_t>(n) + 1, 0);
      std::vector<Eigen::Matrix3d> basis(static_cast<std::size_t>(n)),
          test(static_cast<std::size_t>(n));
      Eigen::VectorXd shift = Eigen::VectorXd::Zero(3 * m);  // q
      for (Eigen::Index bi = 0; bi < n; ++bi) {
        const auto k = static_cast<std::size_t>(closed[static_cast<std::size_t>(bi)]);
        const PointState& st = state[k];
        Eigen::Matrix3d& nb = basis[static_cast<std::size_t>(bi)];
        Eigen::Matrix3d& tb = test[static_cast<std::size_t>(bi)];
        if (st.kind == PointState::kSlide) {
          const Eigen::Vector2d across(-st.dir[1], st.dir[0]);
          const Eigen::Vector3d fk = f.segment<3>(3 * closed[static_cast<std::size_t>(bi)]);
          nb.setZero();
          nb(0, 0) = 1;
          nb.block<2, 1>(1, 0) = p.mu[k] * st.dir;
          nb.block<2, 1>(1, 1) = across;
          tb.setZero();
          tb(0, 0) = 1;
          tb.block<1, 2>(1, 1) = st.c * across.transpose();
          shift.segment<2>(3 * static_cast<Eigen::Index>(k) + 1) =
              r[k] * (p.mu[k] * fk[0] - st.dir.dot(fk.tail<2>())) * st.dir;
        } else {
          nb.setIdentity();
          tb.setIdentity();
        }
        offset[static_cast<std::size_t>(bi) + 1] =
            offset[static_cast<std::size_t>(bi)] + unknowns(static_cast<Eigen::Index>(k));
      }
      const Eigen::Index size = offset.back();
      const Eigen::VectorXd outside = times_forced(w, shift - open_force);
      w.prepare(closed);
      Eigen::MatrixXd a(size, size);
      Eigen::VectorXd rhs(size);
      // T_i W_ij N_j, block by block down each column (W is stored by columns; large
      // systems' columns dealt over two threads)
      in_two_threads(size >= kTwoThreadLu, [&](int first, int stride) {
        for (Eigen::Index bj = first; bj < n; bj += stride) {
          const Eigen::Index j = closed[static_cast<std::size_t>(bj)];
          const Eigen::Matrix3d& nb = basis[static_cast<std::size_t>(bj)];
          const Eigen::Index oj = offset[static_cast<std::size_t>(bj)],
                             nj = offset[static_cast<std::size_t>(bj) + 1] - oj;
          for (Eigen::Index bi = 0; bi < n; ++bi) {
            const Eigen::Index i = closed[static_cast<std::size_t>(bi)];
            const Eigen::Index oi = offset[static_cast<std::size_t>(bi)],
                               ni = offset[static_cast<std::size_t>(bi) + 1] - oi;
            const Eigen::Matrix3d wij = w.block(i, j);
            if (ni == 3 && nj == 3)
              a.block<3, 3>(oi, oj) = wij;
            else if (ni == 3)
              a.block<3, 2>(oi, oj).noalias() = wij * nb.leftCols<2>();
            else if (nj == 3)
              a.block<2, 3>(oi, oj).noalias() =
                  test[static_cast<std::size_t>(bi)].topRows<2>() * wij;
            else
              a.block<2, 2>(oi, oj).noalias() =
                  test[static_cast<std::size_t>(bi)].topRows<2>() * (wij * nb.leftCols<2>());
          }
        }
      });
      for (Eigen::Index bi = 0; bi < n; ++bi) {
        const auto k = static_cast<std::size_t>(closed[static_cast<std::size_t>(bi)]);
        const PointState& st = state[k];
        const Eigen::Index oi = offset[static_cast<std::size_t>(bi)],
                           ni = offset[static_cast<std::size_t>(bi) + 1] - oi;
        const Eigen::Matrix3d& tb = test[static_cast<std::size_t>(bi)];
        const Eigen::Matrix3d& nb = basis[static_cast<std::size_t>(bi)];
        const auto i = 3 * static_cast<Eigen::Index>(k);
        const Eigen::Vector3d fk = f.segment<3>(i);
        const Eigen::Matrix3d tn = damping * tb * nb;
        a.block(oi, oi, ni, ni) += tn.topLeftCorner(ni, ni);
        const Eigen::Vector3d moved = tb * (outside.segment<3>(i) + damping * shift.segment<3>(i));
        if (st.kind == PointState::kSlide) {
          a(oi + 1, oi + 1) += (1 - st.c) / r[k];
          const Eigen::Vector2d across(-st.dir[1], st.dir[0]);
          rhs[oi] = -fk[0] - moved[0];
          rhs[oi + 1] = -across.dot(fk.tail<2>()) - moved[1];
        } else {
          rhs.segment<3>(oi) = -fk - moved;
        }
      }
      if (!lu_solve(&a, &rhs)) return false;
      for (Eigen::Index bi = 0; bi < n; ++bi) {
        const Eigen::Index k = closed[static_cast<std::size_t>(bi)];
        const Eigen::Index oi = offset[static_cast<std::size_t>(bi)],
                           ni = offset[static_cast<std::size_t>(bi) + 1] - oi;
        step.segment<3>(3 * k) =
            basis[static_cast<std::size_t>(bi)].leftCols(ni) * rhs.segment(oi, ni) +
            shift.segment<3>(3 * k);
      }
    }
    const Eigen::VectorXd motion = times_forced(w, step);
    // non-monotone: a step need only lower |F|^2 below the largest of the last few (the
    // states of many points flip on the way, and a monotone search stalls at the kinks)
    recent[static_cast<std::size_t>(it) % recent.size()] = f.squaredNorm();
    const double reference = *std::max_element(recent.begin(), recent.end());
    double alpha = 1;
    bool lowered = false;
    for (int half = 0; half < 12; ++half, alpha *= 0.5) {
      const Eigen::VectorXd trial = l + alpha * step, trial_d = d + alpha * motion;
      const double trial_worst = evaluate(trial, trial_d, &trial_f, &trial_state);
      // A step back to the kinds of points of an iterate a few steps ago closes a cycle (two
      // points at the Coulomb cone's edge swapping sticking and sliding, each full step
      // accepted against the largest residual of the last few: the snap-fit's landing ran
      // 100 iterations of a 2- and 4-cycle so). Such a step must lower |F|^2 itself.
      const std::uint64_t trial_kinds = kinds(trial_state);
      const bool cycle = trial_kinds != visited[visits % visited.size()] &&
                         std::find(visited.begin(), visited.end(), trial_kinds) != visited.end();
      const double bound = cycle ? f.squaredNorm() : reference;
      if (trial_f.squaredNorm() <= (1 - 1e-4 * alpha) * bound) {
        visited[++visits % visited.size()] = trial_kinds;
        l = trial;
        d = trial_d;
        f = trial_f;
        state.swap(trial_state);
        worst = trial_worst;
        lowered = true;
        if (worst < best_worst) {
          best_worst = worst;
          best = l;
        }
        break;
      }
    }
    if (lowered) {
      // a full step: the model holds, trust it more; a short one: less
      if (alpha == 1)
        damping = std::max(0.1 * damping, floor * scale);
      else if (alpha < 0.25)
        damping = std::min(10 * damping, scale);
    } else if (damping < scale) {
      damping *= 100;  // the same forces again, a shorter step
    } else {
      break;
    }
  }
  // the best forces found (the start's, unless Newton lowered the worst point's residual)
  if (best_worst < start_worst) *lambda = best;
  *residual = std::min(best_worst, start_worst);
  return false;
}

}  // namespace

namespace {

// The dense problem as a response: the motions kept up to date column by column.
class DenseResponse final : public PointResponse {
 public:
  explicit DenseResponse(const PointContactProblem& p) : p_(p), w_(p), d_(p.free) {}
  Eigen::Index points() const override { return p_.free.size() / 3; }
  Eigen::Matrix3d block(Eigen::Index i) const override { return w_.diagonal(i); }
  Eigen::Vector3d motion(Eigen::Index i) const override { return d_.segment<3>(3 * i); }
  void add(Eigen::Index i, const Eigen::Vector3d& delta) override {
    w_.prepare({i});
    d_.noalias() +=
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3>>(w_.column(i), w_.rows(), 3) *
        delta;
  }
  void replace(const Eigen::VectorXd&, const Eigen::VectorXd& to) override {
    d_ = p_.free + times_forced(w_, to);
  }
  const PointContactProblem* dense(const Eigen::VectorXd&) override { return &p_; }

 private:
  const PointContactProblem& p_;
  WView w_;
  Eigen::VectorXd d_;
};

}  // namespace

PointContactSolution solve_point_contacts(const PointContactProblem& p, const Eigen::VectorXd& warm,
                                          const PointContactOptions& options) {
  DenseResponse response(p);
  return solve_point_contacts(response, p.mu, warm, options);
}

PointContactSolution solve_point_contacts(PointResponse& response, const std::vector<double>& mus,
                                          const Eigen::VectorXd& warm,
                                          const PointContactOptions& options) {
  PointContactSolver solver;
  return solver.solve(response, mus, warm, options);
}

PointContactSolution PointContactSolver::solve(PointResponse& response,
                                               const std::vector<double>& mus,
                                               const Eigen::VectorXd& warm,
                                               const PointContactOptions& options) {
  const Eigen::Index m = response.points();
  const auto count = static_cast<std::size_t>(m);
  PointContactSolution s;
  s.lambda = warm.size() == 3 * m ? warm : Eigen::VectorXd::Zero(3 * m);
  for (Eigen::Index i = 0; i < m; ++i)
    if (s.lambda[3 * i] <= 0) s.lambda.segment<3>(3 * i).setZero();
  zero_.setZero(3 * m);
  response.replace(zero_, s.lambda);
  std::vector<Eigen::Matrix3d>& blocks = blocks_;
  blocks.resize(count);
  // per point: 1 / the largest eigenvalue of its tangential block (a step that never
  // overshoots along the slip)
  std::vector<double>& tangent_step = tangent_step_;
  tangent_step.resize(count);
  std::vector<Eigen::Matrix2d>& tangent_inverse = tangent_inverse_;
  tangent_inverse.resize(count);
  std::vector<Eigen::Matrix3d>& block_inverse = block_inverse_;
  block_inverse.resize(count);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Matrix3d a = blocks[static_cast<std::size_t>(i)] = response.block(i);
    block_inverse[static_cast<std::size_t>(i)] = a.inverse();
    tangent_inverse[static_cast<std::size_t>(i)] = a.block<2, 2>(1, 1).inverse();
    const Eigen::Matrix2d t = 0.5 * (a.block<2, 2>(1, 1) + a.block<2, 2>(1, 1).transpose());
    const double mean = 0.5 * t.trace(), dev = 0.5 * (t(0, 0) - t(1, 1));
    tangent_step[static_cast<std::size_t>(i)] =
        1 / (mean + std::sqrt(dev * dev + t(0, 1) * t(0, 1)));
  }
  int next_newton = options.newton_after, failures = 0;
  // Newton's method from a step's forces, where the response forms the dense problem; true
  // when it converged (the sweeps go on from its best forces otherwise)
  auto newton = [&]() {
    const PointContactProblem* dense = response.dense(s.lambda);
    if (!dense) {
      failures = options.newton_tries;  // a response too large to form: the sweeps alone
      return false;
    }
    const Eigen::VectorXd before = s.lambda;
    double residual = 0;
    const bool solved = newton_solution(
        *dense, &s.lambda, options.tolerance, options.newton_unknowns, options.newton_damping,
        options.newton_damping_floor, &s.newton_iterations, &residual);
    response.replace(before, s.lambda);
    if (solved) {
      s.residual = residual;
      s.converged = true;
    } else {
      ++failures;
    }
    return solved;
  };
  for (s.sweeps = 1; s.sweeps <= options.max_sweeps; ++s.sweeps) {
    double change = 0;
    for (Eigen::Index i = 0; i < m; ++i) {
      const Eigen::Matrix3d& a = blocks[static_cast<std::size_t>(i)];
      const double mu = mus[static_cast<std::size_t>(i)];
      auto lambda = s.lambda.segment<3>(3 * i);
      const Eigen::Vector3d d = response.motion(i);
      // pressed and sticking, if the cone allows: the exact solve of the point's block
      if (options.block_stick) {
        const Eigen::Vector3d stick = lambda - block_inverse[static_cast<std::size_t>(i)] * d;
        if (stick[0] > 0 && stick.tail<2>().norm() <= mu * stick[0]) {
          const Eigen::Vector3d delta = stick - lambda;
          change = std::max(change, (a * delta).cwiseAbs().maxCoeff());
          if (delta.squaredNorm() > 0) {
            response.add(i, delta);
            lambda = stick;
          }
          continue;
        }
      }
      // else the normal force: the gap (or the normal velocity) closed, never pulling
      const double ln = std::max(0.0, lambda[0] - d[0] / a(0, 0));
      const double dn = ln - lambda[0];
      change = std::max(change, std::abs(dn) * a(0, 0));
      Eigen::Vector2d dt = Eigen::Vector2d::Zero();
      if (mu > 0 || lambda.tail<2>().squaredNorm() > 0) {
        // the friction, with that normal force: sticking by the exact tangential solve if
        // the disc allows it; else a step along the slip projected on the disc, whose fixed
        // point has the friction opposite the slip (projecting the exact solve instead would
        // bias its direction by the block's anisotropy: a rigid block sliding on four corners
        // turns)
        const Eigen::Vector2d slip = d.tail<2>() + a.block<2, 1>(1, 0) * dn;
        const double limit = mu * ln;
        Eigen::Vector2d lt = lambda.tail<2>() - tangent_inverse[static_cast<std::size_t>(i)] * slip;
        if (lt.norm() > limit) {
          lt = lambda.tail<2>() - tangent_step[static_cast<std::size_t>(i)] * slip;
          if (lt.norm() > limit) lt *= limit / lt.norm();
        }
        dt = lt - lambda.tail<2>();
        change = std::max(change, dt.norm() / tangent_step[static_cast<std::size_t>(i)]);
      }
      const Eigen::Vector3d delta(dn, dt[0], dt[1]);
      if (delta.squaredNorm() > 0) {
        response.add(i, delta);
        lambda += delta;
      }
    }
    s.residual = change;
    if (change <= options.tolerance) {
      s.converged = true;
      break;
    }
    // every few sweeps, Newton's method from the sweeps' forces (the sweeps alone crawl on
    // the soft, strongly coupled points of an elastic body); when it fails, the sweeps go on
    // and it is tried again after twice as many
    if (s.sweeps == next_newton && failures < options.newton_tries) {
      next_newton *= 2;
      if (newton()) break;
    }
  }
  s.sweeps = std::min(s.sweeps, options.max_sweeps);
  return s;
}

}  // namespace vproto::sim
