#include "vproto/sim/elastic_dynamics.h"

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <numeric>

#include "two_threads.h"
#include "vproto/materials/errors.h"

namespace vproto::sim {

NewmarkOptions NewmarkOptions::with_numerical_damping(double a) {
  VPROTO_DEMAND(a >= 0);
  NewmarkOptions o;
  o.gamma = 0.5 + a;
  o.beta = 0.25 * (o.gamma + 0.5) * (o.gamma + 0.5);
  return o;
}

ElasticDynamics::ElasticDynamics(const FeMatrices& fe, std::vector<int> held_nodes, double dt,
                                 NewmarkOptions options)
    : fe_(fe), held_nodes_(std::move(held_nodes)), dt_(dt), o_(options) {
  SolverSetup setup;
  setup.choice = o_.solver;
  setup.use = o_.constraint_columns ? SolveUse::kKept : SolveUse::kSteps;
  setup.dofs = fe.dofs;
  if (o_.mesh && o_.mesh->nodes.rows() * 3 == fe.dofs) {
    setup.coordinates = o_.mesh->nodes;
    setup.elements = o_.mesh->elements;
  }
  // the steps' residual far below Newmark's own error, so energy keeps its balance
  setup.relative_tolerance = 1e-10;
  setup.iterative_steps = o_.iterative_steps;
  setup.ordering = o_.ordering;
  solver_ = make_linear_solver(setup);
  VPROTO_DEMAND(dt > 0 && o_.beta > 0 && o_.gamma >= 0.5);
  held_ = dof_mask(fe_.dofs, held_nodes_);
  any_held_ = !held_nodes_.empty();
  if (any_held_) {
    // the rows of the held dofs of K and M, from the lower triangles (an entry (r, c)
    // below the diagonal is also (c, r) above it)
    std::vector<int> index(static_cast<std::size_t>(fe_.dofs), -1);
    for (Eigen::Index i = 0; i < fe_.dofs; ++i)
      if (held_[i]) {
        index[static_cast<std::size_t>(i)] = static_cast<int>(held_dofs_.size());
        held_dofs_.push_back(static_cast<int>(i));
      }
    const auto rows = static_cast<Eigen::Index>(held_dofs_.size());
    std::vector<Eigen::Triplet<double>> k, m;
    for (Eigen::Index c = 0; c < fe_.dofs; ++c)
      for (int e = fe_.outer[static_cast<std::size_t>(c)];
           e < fe_.outer[static_cast<std::size_t>(c) + 1]; ++e) {
        const int r = fe_.inner[static_cast<std::size_t>(e)];
        const double kv = fe_.stiffness_values[static_cast<std::size_t>(e)],
                     mv = fe_.mass_values[static_cast<std::size_t>(e)];
        if (const int h = index[static_cast<std::size_t>(r)]; h >= 0) {
          k.emplace_back(h, static_cast<int>(c), kv);
          m.emplace_back(h, static_cast<int>(c), mv);
        }
        if (const int h = index[static_cast<std::size_t>(c)]; h >= 0 && r != c) {
          k.emplace_back(h, r, kv);
          m.emplace_back(h, r, mv);
        }
      }
    held_k_.resize(rows, fe_.dofs);
    held_m_.resize(rows, fe_.dofs);
    held_k_.setFromTriplets(k.begin(), k.end());
    held_m_.setFromTriplets(m.begin(), m.end());
  }
  u_ = v_ = a_ = f_ = Eigen::VectorXd::Zero(fe_.dofs);
  factor();
}

void ElasticDynamics::factor() {
  const double b = o_.beta, g = o_.gamma, h = dt_;
  c0_ = 1 / (b * h * h);
  c1_ = g / (b * h);
  c2_ = 1 / (b * h);
  c3_ = 1 / (2 * b) - 1;
  c4_ = g / b - 1;
  c5_ = h / 2 * (g / b - 2);
  c6_ = h * (1 - g);
  c7_ = g * h;
  if (!o_.inertia) c0_ = c1_ = c2_ = c3_ = c4_ = c5_ = c6_ = c7_ = 0;
  const double ks = 1 + c1_ * o_.rayleigh_stiffness, ms = c0_ + c1_ * o_.rayleigh_mass;
  effective_.resize(fe_.nonzeros());
  for (std::size_t k = 0; k < effective_.size(); ++k)
    effective_[k] = ks * fe_.stiffness_values[k] + ms * fe_.mass_values[k];
  effective_held_ = hold_dofs(fe_, effective_, held_, 1.0);
  solver_->factor(fe_.view(effective_held_),
                  o_.inertia ? "the effective stiffness K + M/(beta dt^2)" : "the stiffness K", 3);
}

void ElasticDynamics::restore(const State& s) {
  time_ = s.time;
  steps_ = s.steps;
  u_ = s.u;
  v_ = s.v;
  a_ = s.a;
  f_ = s.f;
  work_ = s.work;
  damped_ = s.damped;
  balanced_ = s.balanced;
  changed();
}

void ElasticDynamics::set_time_step(double dt) {
  VPROTO_DEMAND(dt > 0);
  if (dt == dt_) return;
  dt_ = dt;
  // without inertia the matrix is K whatever the step: the factor stays
  if (o_.inertia) factor();
}

Eigen::VectorXd ElasticDynamics::held_times(
    const Eigen::SparseMatrix<double, Eigen::RowMajor>& rows, const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(fe_.dofs);
  const Eigen::VectorXd r = rows * x;
  for (std::size_t h = 0; h < held_dofs_.size(); ++h)
    y[held_dofs_[h]] = r[static_cast<Eigen::Index>(h)];
  return y;
}

Eigen::VectorXd ElasticDynamics::damping_times(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(fe_.dofs);
  if (o_.rayleigh_mass != 0) y += o_.rayleigh_mass * symmetric_times(fe_.mass(), x);
  if (o_.rayleigh_stiffness != 0) y += o_.rayleigh_stiffness * symmetric_times(fe_.stiffness(), x);
  return y;
}

void ElasticDynamics::start(double t0, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
                            const Eigen::VectorXd& f0, const HeldMotion* held) {
  VPROTO_DEMAND(u0.size() == fe_.dofs && v0.size() == fe_.dofs && f0.size() == fe_.dofs);
  changed();
  time_ = t0;
  steps_ = 0;
  work_ = damped_ = 0;
  u_ = u0;
  v_ = v0;
  f_ = f0;
  balanced_ = false;
  Eigen::VectorXd held_a = Eigen::VectorXd::Zero(fe_.dofs);
  for (Eigen::Index i = 0; i < fe_.dofs; ++i)
    if (held_[i]) {
      if (held) {
        u_[i] = held->u[i];
        v_[i] = held->v[i];
        held_a[i] = held->a[i];
      } else {
        u_[i] = v_[i] = 0;
      }
    }
  // M_aa a_a = (f - K u - C v)_a - M_ab a_b, with a_b prescribed
  Eigen::VectorXd rhs = f_ - symmetric_times(fe_.stiffness(), u_) - damping_times(v_) -
                        symmetric_times(fe_.mass(), held_a);
  for (Eigen::Index i = 0; i < fe_.dofs; ++i)
    if (held_[i]) rhs[i] = 0;
  a_ = held_a;
  if (!o_.inertia) {
    v_.setZero();
    a_.setZero();
    return;
  }
  if (rhs.squaredNorm() > 0) {
    const std::vector<double> mv = hold_dofs(fe_, fe_.mass_values, held_, 1.0);
    const Eigen::SparseMatrix<double> m = fe_.view(mv);
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower> cg;
    cg.setTolerance(1e-14);
    cg.setMaxIterations(2000);
    cg.compute(m);
    const Eigen::VectorXd a_free = cg.solve(rhs);
    if (cg.info() != Eigen::Success && cg.error() > 1e-10)
      throw SimulationError("the initial acceleration did not converge (mass matrix error " +
                            std::to_string(cg.error()) + ")");
    for (Eigen::Index i = 0; i < fe_.dofs; ++i)
      if (!held_[i]) a_[i] = a_free[i];
  }
}

const Eigen::VectorXd& ElasticDynamics::predict(const Eigen::VectorXd& f_next,
                                                const HeldMotion* held) {
  VPROTO_DEMAND(f_next.size() == fe_.dofs);
  f_next_ = f_next;
  // K^ u' = f' + M (c0 u + c2 v + c3 a) + C (c1 u + c4 v + c5 a). Solved for u' itself (not
  // for the increment with K^ u on the right): the step is then exactly Newmark's for the
  // matrix the factor holds, rounding and all, so energy does not drift.
  Eigen::VectorXd r = f_next;
  if (o_.inertia) r += symmetric_times(fe_.mass(), c0_ * u_ + c2_ * v_ + c3_ * a_);
  if (o_.rayleigh_mass != 0 || o_.rayleigh_stiffness != 0)
    r += damping_times(c1_ * u_ + c4_ * v_ + c5_ * a_);
  held_moves_ = false;
  if (any_held_) {
    if (held) {
      held_next_ = *held;
    } else {
      held_next_.u = held_next_.v = held_next_.a = Eigen::VectorXd::Zero(fe_.dofs);
    }
    Eigen::VectorXd z = Eigen::VectorXd::Zero(fe_.dofs);
    bool nonzero = false;
    for (Eigen::Index i = 0; i < fe_.dofs; ++i)
      if (held_[i]) {
        z[i] = held_next_.u[i];
        nonzero = nonzero || z[i] != 0;
        held_moves_ = held_moves_ || z[i] != u_[i];
      }
    if (nonzero) r -= symmetric_times(fe_.view(effective_), z);
    for (Eigen::Index i = 0; i < fe_.dofs; ++i)
      if (held_[i]) r[i] = z[i];
  }
  // a body with no load in its frame (quasi-static, loads on the frame) has nothing to
  // solve for
  if (!r.isZero(0)) solver_->solve_in_place(r);
  next_u_ = r;
  prediction_ = r - u_;
  return prediction_;
}

Eigen::MatrixXd ElasticDynamics::response(const Eigen::SparseMatrix<double>& ct) const {
  VPROTO_DEMAND(ct.rows() == fe_.dofs);
  Eigen::MatrixXd b = ct;
  for (Eigen::Index i = 0; i < fe_.dofs; ++i)
    if (held_[i]) b.row(i).setZero();
  Eigen::MatrixXd y = solver_->solve(b);
  for (Eigen::Index i = 0; i < fe_.dofs; ++i)
    if (held_[i]) y.row(i).setZero();
  return y;
}

Eigen::MatrixXd ElasticDynamics::response_at(const Eigen::SparseMatrix<double>& ct,
                                             const std::vector<Eigen::Index>& dofs) const {
  VPROTO_DEMAND(ct.rows() == fe_.dofs);
  // 8,127 nodes, 4,971 columns: with CHOLMOD's sweeps 64 at 7.4 s, 16 at 9.1 s, 256 at 9.5
  // s, all at once 12.7 s and 1.1 GB more; with sweeps that skip what the loads do not reach,
  // in elimination order, 32 and 64 at 2.7 s, 128 at 3.0 s
  constexpr Eigen::Index block = 64;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(dofs.size()), ct.cols());
  const Eigen::Index blocks = (ct.cols() + block - 1) / block;
  // the columns solved in the factor's elimination order of their loads (a block's loads
  // then share most of their paths to the root, which are all its forward sweep visits)
  std::vector<Eigen::Index> order(static_cast<std::size_t>(ct.cols()));
  {
    std::vector<Eigen::Index> key(order.size(), fe_.dofs);
    for (Eigen::Index j = 0; j < ct.cols(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(ct, j); it; ++it)
        key[static_cast<std::size_t>(j)] =
            std::min(key[static_cast<std::size_t>(j)], solver_->elimination_position(it.row()));
    std::iota(order.begin(), order.end(), Eigen::Index{0});
    std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
      return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
    });
  }
  // block k of right-hand sides, solved with its own scratch; a block's answer does not
  // depend on which thread solves it, nor on how many do
  auto solve_blocks = [&](Eigen::Index first_block, Eigen::Index stride) {
    std::vector<Eigen::Triplet<double>> loads;
    for (Eigen::Index k = first_block; k < blocks; k += stride) {
      const Eigen::Index first = k * block, n = std::min(block, ct.cols() - first);
      loads.clear();
      for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::SparseMatrix<double>::InnerIterator it(
                 ct, order[static_cast<std::size_t>(first + j)]);
             it; ++it)
          if (!held_[it.row()]) loads.emplace_back(it.row(), j, it.value());
      Eigen::SparseMatrix<double> b(fe_.dofs, n);
      b.setFromTriplets(loads.begin(), loads.end());
      // the answers at `dofs` only (a kept factor visits what the loads reach and what
      // those rows need)
      const Eigen::MatrixXd x = solver_->solve_sparse(b, dofs);
      for (Eigen::Index j = 0; j < n; ++j) {
        const Eigen::Index column = order[static_cast<std::size_t>(first + j)];
        for (std::size_t q = 0; q < dofs.size(); ++q)
          out(static_cast<Eigen::Index>(q), column) =
              held_[dofs[q]] ? 0.0 : x(static_cast<Eigen::Index>(q), j);
      }
    }
  };
  // two threads where the backend allows it (the snap-fit's landing asks 1,269 nodes' columns
  // at once): both read the factor, each solve is a pair of triangular sweeps over it
  in_two_threads(solver_->concurrent_solves() && blocks > 1, solve_blocks);
  return out;
}

Eigen::VectorXd ElasticDynamics::reactions() const {
  if (!any_held_) return Eigen::VectorXd::Zero(fe_.dofs);
  if (reaction_version_ == version_) return reaction_cache_;
  Eigen::VectorXd r = held_times(held_k_, u_) - f_;
  if (o_.inertia) r += held_times(held_m_, a_);
  if (o_.rayleigh_mass != 0) r += o_.rayleigh_mass * held_times(held_m_, v_);
  if (o_.rayleigh_stiffness != 0) r += o_.rayleigh_stiffness * held_times(held_k_, v_);
  for (Eigen::Index i = 0; i < fe_.dofs; ++i)
    if (!held_[i]) r[i] = 0;
  reaction_cache_ = std::move(r);
  reaction_version_ = version_;
  return reaction_cache_;
}

void ElasticDynamics::accept(const Eigen::VectorXd& du, const Eigen::VectorXd* constraint) {
  VPROTO_DEMAND(du.size() == fe_.dofs && f_next_.size() == fe_.dofs);
  Eigen::VectorXd f_total = f_next_;
  if (constraint) f_total += *constraint;
  const Eigen::VectorXd old_reaction = held_moves_ ? reactions() : Eigen::VectorXd::Zero(fe_.dofs);
  Eigen::VectorXd a_next = c0_ * du - c2_ * v_ - c3_ * a_;
  Eigen::VectorXd v_next = v_ + c6_ * a_ + c7_ * a_next;
  if (!o_.inertia) a_next.setZero(), v_next.setZero();
  if (any_held_)
    for (Eigen::Index i = 0; i < fe_.dofs; ++i)
      if (held_[i]) {
        v_next[i] = held_next_.v[i];
        a_next[i] = held_next_.a[i];
      }
  if (!du.allFinite() || !v_next.allFinite())
    throw SimulationError(
        "the elastic state became non-finite at t = " + std::to_string(time_ + dt_) + " s");
  if (o_.rayleigh_mass != 0 || o_.rayleigh_stiffness != 0)
    damped_ += 0.5 * (damping_times(v_) + damping_times(v_next)).dot(du);
  work_ += 0.5 * (f_ + f_total).dot(du);
  // the solved displacement itself when the step is the prediction (no rounding from
  // adding the increment back)
  if (constraint == nullptr && du.data() == prediction_.data())
    u_ = next_u_;
  else
    u_ += du;
  if (any_held_)
    for (Eigen::Index i = 0; i < fe_.dofs; ++i)
      if (held_[i]) u_[i] = held_next_.u[i];
  v_ = std::move(v_next);
  a_ = std::move(a_next);
  f_ = std::move(f_total);
  balanced_ = !o_.inertia && o_.rayleigh_mass == 0 && o_.rayleigh_stiffness == 0;
  changed();
  if (held_moves_) work_ += 0.5 * (old_reaction + reactions()).dot(du);
  time_ += dt_;
  ++steps_;
}

void ElasticDynamics::change_velocity(const Eigen::VectorXd& dv) {
  VPROTO_DEMAND(dv.size() == fe_.dofs);
  if (dv.squaredNorm() == 0) return;
  const double before = kinetic_energy();
  for (Eigen::Index i = 0; i < fe_.dofs; ++i)
    if (!held_[i]) v_[i] += dv[i];
  changed();
  damped_ += before - kinetic_energy();
}

void ElasticDynamics::step(const Eigen::VectorXd& f_next, const HeldMotion* held) {
  accept(predict(f_next, held));
}

double ElasticDynamics::kinetic_energy() const {
  if (!o_.inertia) return 0.0;
  if (kinetic_version_ != version_) {
    kinetic_cache_ = 0.5 * quadratic_form(fe_.mass(), v_);
    kinetic_version_ = version_;
  }
  return kinetic_cache_;
}

double ElasticDynamics::strain_energy() const {
  if (strain_version_ != version_) {
    if (balanced_) {
      // u'K u = u'f at the free dofs plus u'(f + r) at the held ones (r the reactions):
      // 24k products instead of the 1.1M entries of K (0.6 ms a step on the snap-fit's
      // socket, on two threads)
      double sum = u_.dot(f_);
      if (any_held_) {
        const Eigen::VectorXd& r = reactions();
        for (const int i : held_dofs_) sum += u_[i] * r[i];
      }
      strain_cache_ = 0.5 * sum;
    } else {
      strain_cache_ = 0.5 * quadratic_form(fe_.stiffness(), u_);
    }
    strain_version_ = version_;
  }
  return strain_cache_;
}

}  // namespace vproto::sim
