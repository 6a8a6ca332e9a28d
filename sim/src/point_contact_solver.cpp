#include "vproto/sim/point_contact_solver.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace vproto::sim {

namespace {

// The exact solution for the contact states the forces show (Eq. 18's active set): a
// pressed point that sticks keeps d = 0 (three unknowns), one that slides keeps d_n = 0
// with its friction mu lambda_n against its slip (one unknown), an open one carries
// nothing. The states are corrected and the system solved again until they hold (points
// that pull open, points that would be pushed through close, sticking points that leave
// their cone slide, sliding directions follow the slip); false when they do not settle
// in a few rounds (the sweeps then go on).
bool active_set_solution(const PointContactProblem& p, Eigen::VectorXd* lambda, double tolerance) {
  const Eigen::Index m = p.free.size() / 3;
  const auto count = static_cast<std::size_t>(m);
  enum State : char { kOpen, kStick, kSlide };
  std::vector<char> state(count, kOpen);
  std::vector<Eigen::Vector2d> dir(count, Eigen::Vector2d::Zero());  // friction force's
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d l = lambda->segment<3>(3 * static_cast<Eigen::Index>(k));
    if (l[0] <= 0) continue;
    const double mu = p.mu[k];
    if (mu > 0 && l.tail<2>().norm() < mu * l[0] * (1 - 1e-9)) {
      state[k] = kStick;
    } else {
      state[k] = kSlide;
      if (l.tail<2>().norm() > 0) dir[k] = l.tail<2>().normalized();
    }
  }
  // lambda_k = P_k z_k: the identity (sticking) or [1, mu s] (sliding)
  auto param = [&](std::size_t k) {
    Eigen::Matrix3d q = Eigen::Matrix3d::Zero();
    if (state[k] == kStick) {
      q.setIdentity();
    } else {
      q(0, 0) = 1;
      q.block<2, 1>(1, 0) = p.mu[k] * dir[k];
    }
    return q;
  };
  for (int round = 0; round < 4; ++round) {
    std::vector<int> first(count, -1), size(count, 0);
    int unknowns = 0;
    for (std::size_t k = 0; k < count; ++k) {
      if (state[k] == kOpen) continue;
      first[k] = unknowns;
      size[k] = state[k] == kStick ? 3 : 1;
      unknowns += size[k];
    }
    if (unknowns == 0 || unknowns > 200) return false;  // none, or dearer than sweeps
    Eigen::MatrixXd a(unknowns, unknowns);
    Eigen::VectorXd rhs(unknowns);
    std::vector<Eigen::Matrix3d> q(count);
    for (std::size_t k = 0; k < count; ++k)
      if (state[k] != kOpen) q[k] = param(k);
    for (std::size_t i = 0; i < count; ++i) {
      if (first[i] < 0) continue;
      const auto ii = static_cast<Eigen::Index>(i);
      rhs.segment(first[i], size[i]) = -p.free.segment(3 * ii, size[i]);
      for (std::size_t j = 0; j < count; ++j) {
        if (first[j] < 0) continue;
        const Eigen::Matrix3d b = p.w.block<3, 3>(3 * ii, 3 * static_cast<Eigen::Index>(j)) * q[j];
        a.block(first[i], first[j], size[i], size[j]) = b.topLeftCorner(size[i], size[j]);
      }
    }
    // W of many points on one elastic surface is singular (more rows than the surface
    // has independent motions): factor it with a compliance of 1e-8 of its largest
    // diagonal added, and refine against W itself (proximal steps: a solution of the
    // singular system near the regularized one)
    Eigen::MatrixXd regular = a;
    regular.diagonal().array() += 1e-8 * a.diagonal().cwiseAbs().maxCoeff();
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(regular);
    Eigen::VectorXd z = lu.solve(rhs);
    for (int refine = 0; refine < 4; ++refine) z += lu.solve(rhs - a * z);
    if (!z.allFinite()) return false;
    Eigen::VectorXd next = Eigen::VectorXd::Zero(p.free.size());
    for (std::size_t k = 0; k < count; ++k) {
      if (first[k] < 0) continue;
      Eigen::Vector3d zk = Eigen::Vector3d::Zero();
      zk.head(size[k]) = z.segment(first[k], size[k]);
      next.segment<3>(3 * static_cast<Eigen::Index>(k)) = q[k] * zk;
    }
    const Eigen::VectorXd d = p.free + p.w * next;
    bool settled = true;
    for (std::size_t k = 0; k < count; ++k) {
      const auto kk = static_cast<Eigen::Index>(k);
      const Eigen::Vector3d l = next.segment<3>(3 * kk), dk = d.segment<3>(3 * kk);
      const double mu = p.mu[k];
      if (state[k] == kOpen) {
        if (dk[0] < -tolerance) {  // pushed through: close it
          state[k] = mu > 0 ? kStick : kSlide;
          settled = false;
        }
      } else if (l[0] < 0) {  // pulls: open it
        state[k] = kOpen;
        settled = false;
      } else if (state[k] == kStick && l.tail<2>().norm() > mu * l[0] * (1 + 1e-9)) {
        state[k] = kSlide;  // leaves its cone: slides along its force
        dir[k] = l.tail<2>().normalized();
        settled = false;
      }
      // sliding directions stay as the sweeps found them: the sweeps that follow turn
      // them (a point's direction is local; what the sweeps crawl on is how the normal
      // forces share the load)
    }
    if (settled) {
      *lambda = next;
      return true;
    }
  }
  return false;
}

}  // namespace

PointContactSolution solve_point_contacts(const PointContactProblem& p, const Eigen::VectorXd& warm,
                                          const PointContactOptions& options) {
  const Eigen::Index m = p.free.size() / 3;
  PointContactSolution s;
  s.lambda = warm.size() == p.free.size() ? warm : Eigen::VectorXd::Zero(p.free.size());
  for (Eigen::Index i = 0; i < m; ++i)
    if (s.lambda[3 * i] <= 0) s.lambda.segment<3>(3 * i).setZero();
  // the motion d = free + W lambda, kept up to date column by column
  Eigen::VectorXd d = p.free + p.w * s.lambda;
  std::vector<Eigen::Matrix3d> block_inverse(static_cast<std::size_t>(m));
  std::vector<Eigen::Matrix2d> tangent_inverse(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Matrix3d a = p.w.block<3, 3>(3 * i, 3 * i);
    block_inverse[static_cast<std::size_t>(i)] = a.inverse();
    tangent_inverse[static_cast<std::size_t>(i)] = a.block<2, 2>(1, 1).inverse();
  }
  int next_active_set = options.active_set_after, failures = 0;
  for (s.sweeps = 1; s.sweeps <= options.max_sweeps; ++s.sweeps) {
    double change = 0;
    for (Eigen::Index i = 0; i < m; ++i) {
      const Eigen::Matrix3d a = p.w.block<3, 3>(3 * i, 3 * i);
      const Eigen::Vector3d old = s.lambda.segment<3>(3 * i);
      // the motion with this point's own force taken out
      const Eigen::Vector3d c = d.segment<3>(3 * i) - a * old;
      const double mu = p.mu[static_cast<std::size_t>(i)];
      Eigen::Vector3d next = Eigen::Vector3d::Zero();
      if (c[0] < 0) {
        // pressed: stick if the cone allows, else slide
        const Eigen::Vector3d stick = -block_inverse[static_cast<std::size_t>(i)] * c;
        if (stick[0] > 0 && stick.tail<2>().norm() <= mu * stick[0]) {
          next = stick;
        } else if (mu <= 0) {
          next[0] = std::max(0.0, -c[0] / a(0, 0));
        } else {
          next = old;
          if (next[0] <= 0) next[0] = std::max(0.0, -c[0] / a(0, 0));
          for (int it = 0; it < 8; ++it) {
            next[0] = std::max(0.0, -(c[0] + a.block<1, 2>(0, 1).dot(next.tail<2>())) / a(0, 0));
            Eigen::Vector2d t = -tangent_inverse[static_cast<std::size_t>(i)] *
                                (c.tail<2>() + a.block<2, 1>(1, 0) * next[0]);
            const double cap = mu * next[0];
            if (t.norm() > cap) t *= cap / t.norm();
            next.tail<2>() = t;
          }
        }
      }
      const Eigen::Vector3d delta = next - old;
      if (delta.squaredNorm() > 0) {
        d.noalias() += p.w.middleCols<3>(3 * i) * delta;
        s.lambda.segment<3>(3 * i) = next;
        change = std::max(change, (a * delta).cwiseAbs().maxCoeff());
      }
    }
    s.residual = change;
    if (change <= options.tolerance) {
      s.converged = true;
      break;
    }
    // every few sweeps, the exact solution for the states the sweeps have settled on (the
    // sweeps alone crawl on the soft, strongly coupled points of an elastic body); the
    // next sweep checks it and goes on from it
    if (s.sweeps == next_active_set && failures < 2) {
      next_active_set *= 2;
      if (active_set_solution(p, &s.lambda, options.tolerance))
        d = p.free + p.w * s.lambda;
      else
        ++failures;  // the states do not settle: leave it to the sweeps
    }
  }
  s.sweeps = std::min(s.sweeps, options.max_sweeps);
  return s;
}

}  // namespace vproto::sim
