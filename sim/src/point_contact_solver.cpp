#include "vproto/sim/point_contact_solver.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace vproto::sim {

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
  }
  s.sweeps = std::min(s.sweeps, options.max_sweeps);
  return s;
}

}  // namespace vproto::sim
