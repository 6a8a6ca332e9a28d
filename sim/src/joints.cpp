#include "vproto/sim/joints.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

// two unit vectors square to `axis` and to each other
void square_to(const Eigen::Vector3d& axis, Eigen::Vector3d* u1, Eigen::Vector3d* u2) {
  const Eigen::Vector3d helper =
      std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *u1 = axis.cross(helper).normalized();
  *u2 = axis.cross(*u1).normalized();
}

Eigen::Quaterniond rotation_by(const Eigen::Vector3d& angle) {
  const double a = angle.norm();
  if (a < 1e-300) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, angle / a));
}

Eigen::VectorXd solve_spd(const Eigen::MatrixXd& w, const Eigen::VectorXd& r) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(w);
  if (ldlt.info() == Eigen::Success && ldlt.isPositive() &&
      ldlt.vectorD().minCoeff() > 1e-14 * ldlt.vectorD().maxCoeff())
    return ldlt.solve(r);
  return w.completeOrthogonalDecomposition().solve(r);  // redundant rows
}

}  // namespace

JointSystem::JointSystem(const Scene& scene, const std::vector<bool>& fixed)
    : scene_(scene), member_(scene.bodies.size(), 0), fixed_(fixed) {
  auto origin = [&](int b) {
    return b == kGround ? Eigen::Vector3d::Zero().eval() : scene.bodies[b].mass_properties.centroid;
  };
  for (const Joint& j : scene.joints) {
    const int a = j.body;
    const int b = j.other != kGround && fixed_[j.other] ? kGround : j.other;
    if (fixed_[a]) continue;  // held anyway
    member_[a] = 1;
    if (b != kGround) member_[b] = 1;
    const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                          ez = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d u1, u2;
    square_to(j.axis, &u1, &u2);
    const Eigen::Vector3d anchor =
        j.type == JointType::kSlider || j.type == JointType::kFixed ? origin(a) : j.at;
    switch (j.type) {
      case JointType::kSpherical:
        add_point_rows(a, b, anchor, {ex, ey, ez});
        break;
      case JointType::kRevolute:
        add_point_rows(a, b, anchor, {ex, ey, ez});
        add_perpendicular_row(a, b, j.axis, u1);
        add_perpendicular_row(a, b, j.axis, u2);
        break;
      case JointType::kSlider:
        add_point_rows(a, b, anchor, {u1, u2});
        add_perpendicular_row(a, b, j.axis, u1);
        add_perpendicular_row(a, b, j.axis, u2);
        add_perpendicular_row(a, b, u1, u2);
        break;
      case JointType::kFixed:
        add_point_rows(a, b, anchor, {ex, ey, ez});
        add_perpendicular_row(a, b, ex, ey);
        add_perpendicular_row(a, b, ey, ez);
        add_perpendicular_row(a, b, ez, ex);
        break;
    }
  }
  // mechanisms: the members linked by rows, by union-find
  const auto n = static_cast<int>(scene.bodies.size());
  std::vector<int> parent(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) parent[i] = i;
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const Row& r : rows_)
    if (r.b != kGround) parent[root(r.a)] = root(r.b);
  mechanism_.assign(static_cast<std::size_t>(n), -1);
  std::vector<int> of_root(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    if (!member_[i]) continue;
    int& m = of_root[root(i)];
    if (m < 0) {
      m = static_cast<int>(mechanisms_.size());
      mechanisms_.emplace_back();
    }
    mechanism_[i] = m;
    mechanisms_[m].push_back(i);
  }
}

void JointSystem::add_point_rows(int a, int b, const Eigen::Vector3d& p,
                                 const std::vector<Eigen::Vector3d>& normals) {
  // bodies start unrotated, so a frame's coordinates are world minus its origin
  const Eigen::Vector3d ca = scene_.bodies[a].mass_properties.centroid;
  const Eigen::Vector3d cb =
      b == kGround ? Eigen::Vector3d::Zero() : scene_.bodies[b].mass_properties.centroid;
  for (const auto& n : normals) {
    Row r;
    r.a = a;
    r.b = b;
    r.pa = p - ca;
    r.pb = p - cb;
    r.db = n;
    rows_.push_back(r);
  }
}

void JointSystem::add_perpendicular_row(int a, int b, const Eigen::Vector3d& da,
                                        const Eigen::Vector3d& db) {
  Row r;
  r.perpendicular = true;
  r.a = a;
  r.b = b;
  r.da = da;
  r.db = db;
  rows_.push_back(r);
}

namespace {

struct Frame {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
};

Frame frame_of(const std::vector<RigidState>& states, int body) {
  Frame f;
  if (body != kGround) {
    f.x = states[body].position;
    f.r = states[body].rotation.toRotationMatrix();
  }
  return f;
}

}  // namespace

double JointSystem::value(const Row& row, const std::vector<RigidState>& states) const {
  const Frame fa = frame_of(states, row.a), fb = frame_of(states, row.b);
  return row.perpendicular ? (fa.r * row.da).dot(fb.r * row.db)
                           : (fb.r * row.db).dot(fa.x + fa.r * row.pa - fb.x - fb.r * row.pb);
}

Eigen::Matrix<double, 1, 6> JointSystem::jacobian(const Row& row,
                                                  const std::vector<RigidState>& states,
                                                  bool side_a) const {
  const Frame fa = frame_of(states, row.a), fb = frame_of(states, row.b);
  Eigen::Matrix<double, 1, 6> j = Eigen::Matrix<double, 1, 6>::Zero();
  if (row.perpendicular) {
    const Eigen::Vector3d u = fa.r * row.da, w = fb.r * row.db;
    j.tail<3>() = (side_a ? u.cross(w) : w.cross(u)).transpose();
    return j;
  }
  const Eigen::Vector3d ra = fa.r * row.pa, rb = fb.r * row.pb, nb = fb.r * row.db;
  if (side_a) {
    j << nb.transpose(), ra.cross(nb).transpose();
  } else {
    // b's plane turns with b: the normal's rate acts on the separation d
    const Eigen::Vector3d d = fa.x + ra - fb.x - rb;
    j << -nb.transpose(), (-rb.cross(nb) + nb.cross(d)).transpose();
  }
  return j;
}

Eigen::MatrixXd JointSystem::mechanism_mobility(const std::vector<RigidState>& states,
                                                const std::vector<RigidInertia>& inertias,
                                                int mechanism) const {
  const std::vector<int>& bodies = mechanisms_.at(static_cast<std::size_t>(mechanism));
  const auto k = static_cast<Eigen::Index>(bodies.size());
  Eigen::MatrixXd minv = Eigen::MatrixXd::Zero(6 * k, 6 * k);
  for (Eigen::Index s = 0; s < k; ++s) {
    const int body = bodies[static_cast<std::size_t>(s)];
    const Eigen::Matrix3d r = states[body].rotation.toRotationMatrix();
    minv.block<3, 3>(6 * s, 6 * s) = Eigen::Matrix3d::Identity() / inertias[body].mass;
    minv.block<3, 3>(6 * s + 3, 6 * s + 3) = r * inertias[body].inertia.inverse() * r.transpose();
  }
  // the mechanism's rows (a row's bodies are in one mechanism, or one is the ground)
  std::vector<const Row*> rows;
  for (const Row& row : rows_)
    if (mechanism_[row.a] == mechanism) rows.push_back(&row);
  if (rows.empty()) return minv;
  Eigen::MatrixXd jm = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), 6 * k);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Row& row = *rows[r];
    const auto i = static_cast<Eigen::Index>(r);
    jm.block<1, 6>(i, 6 * static_cast<Eigen::Index>(slot(row.a))) = jacobian(row, states, true);
    if (row.b != kGround)
      jm.block<1, 6>(i, 6 * static_cast<Eigen::Index>(slot(row.b))) += jacobian(row, states, false);
  }
  return held_inverse_mass(minv, jm);
}

Eigen::MatrixXd held_inverse_mass(const Eigen::MatrixXd& minv, const Eigen::MatrixXd& j,
                                  Eigen::VectorXd* velocity, const Eigen::VectorXd* target) {
  const Eigen::MatrixXd minv_jt = minv * j.transpose();
  const Eigen::MatrixXd w = j * minv_jt;
  // redundant rows (a slider's rotation locks) make W singular: a least-norm solve
  const auto cod = w.completeOrthogonalDecomposition();
  if (velocity) {
    Eigen::VectorXd off = j * *velocity;
    if (target) off -= *target;
    *velocity -= minv_jt * cod.solve(off);
  }
  return minv - minv_jt * cod.solve(minv_jt.transpose());
}

int JointSystem::slot(int body) const {
  const std::vector<int>& bodies = mechanisms_.at(static_cast<std::size_t>(mechanism_of(body)));
  return static_cast<int>(std::lower_bound(bodies.begin(), bodies.end(), body) - bodies.begin());
}

Eigen::Matrix<double, 6, 6> JointSystem::mobility(const std::vector<RigidState>& states,
                                                  const std::vector<RigidInertia>& inertias,
                                                  int body) const {
  const int m = mechanism_of(body);
  VPROTO_DEMAND(m >= 0);
  const Eigen::Index s = slot(body);
  return mechanism_mobility(states, inertias, m).block<6, 6>(6 * s, 6 * s);
}

double JointSystem::drift(const std::vector<RigidState>& states) const {
  double worst = 0;
  for (const Row& row : rows_) worst = std::max(worst, std::abs(value(row, states)));
  return worst;
}

void JointSystem::step(std::vector<RigidState>& states, const std::vector<RigidInertia>& inertias,
                       const std::vector<Eigen::Vector3d>& forces,
                       const std::vector<Eigen::Vector3d>& torques, double dt) const {
  // slots of the member bodies in the generalized velocity u = (v, w) per body
  std::vector<int> slot(states.size(), -1), bodies;
  for (std::size_t i = 0; i < states.size(); ++i)
    if (member_[i] && !fixed_[i]) {
      slot[i] = static_cast<int>(bodies.size());
      bodies.push_back(static_cast<int>(i));
    }
  const Eigen::Index n = 6 * static_cast<Eigen::Index>(bodies.size());
  const Eigen::Index m = static_cast<Eigen::Index>(rows_.size());
  // inverse mass per body, world axes at the current rotation
  std::vector<Eigen::Matrix3d> inv_inertia(bodies.size());
  auto update_inertia = [&] {
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const Eigen::Matrix3d r = states[bodies[k]].rotation.toRotationMatrix();
      inv_inertia[k] = r * inertias[bodies[k]].inertia.inverse() * r.transpose();
    }
  };
  auto apply_inverse_mass = [&](const Eigen::VectorXd& f) {
    Eigen::VectorXd out(n);
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const auto s = static_cast<Eigen::Index>(6 * k);
      out.segment<3>(s) = f.segment<3>(s) / inertias[bodies[k]].mass;
      out.segment<3>(s + 3) = inv_inertia[k] * f.segment<3>(s + 3);
    }
    return out;
  };
  // rows' values and Jacobian at the current configuration
  auto rows_at = [&](Eigen::MatrixXd* j, Eigen::VectorXd* phi) {
    j->setZero(m, n);
    phi->resize(m);
    for (Eigen::Index k = 0; k < m; ++k) {
      const Row& row = rows_[k];
      (*phi)[k] = value(row, states);
      const int sa = slot[row.a], sb = row.b == kGround ? -1 : slot[row.b];
      if (sa >= 0) j->block<1, 6>(k, 6 * sa) = jacobian(row, states, true);
      if (sb >= 0) j->block<1, 6>(k, 6 * sb) += jacobian(row, states, false);
    }
  };
  auto delassus = [&](const Eigen::MatrixXd& j) {
    Eigen::MatrixXd minv_jt(n, m);
    for (Eigen::Index k = 0; k < m; ++k) minv_jt.col(k) = apply_inverse_mass(j.row(k).transpose());
    return std::make_pair(Eigen::MatrixXd(j * minv_jt), minv_jt);
  };

  // A RATTLE-like splitting, second order: half a kick, velocities made consistent with
  // the rows, a drift projected back onto the rows, half a kick, consistent velocities.
  // 1. half a kick (the gyroscopic torque at the current rotation)
  auto load = [&](const Eigen::VectorXd& vel) {
    Eigen::VectorXd f(n);
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const RigidState& s = states[bodies[k]];
      const auto o = static_cast<Eigen::Index>(6 * k);
      const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
      const Eigen::Vector3d w = vel.segment<3>(o + 3);
      const Eigen::Vector3d l = r * inertias[bodies[k]].inertia * r.transpose() * w;
      f.segment<3>(o) = forces[bodies[k]];
      f.segment<3>(o + 3) = torques[bodies[k]] - w.cross(l);
    }
    return f;
  };
  auto gather = [&] {
    Eigen::VectorXd u(n);
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const auto o = static_cast<Eigen::Index>(6 * k);
      u.segment<3>(o) = states[bodies[k]].velocity;
      u.segment<3>(o + 3) = states[bodies[k]].angular_velocity;
    }
    return u;
  };
  auto scatter = [&](const Eigen::VectorXd& u) {
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const auto o = static_cast<Eigen::Index>(6 * k);
      states[bodies[k]].velocity = u.segment<3>(o);
      states[bodies[k]].angular_velocity = u.segment<3>(o + 3);
    }
  };
  update_inertia();
  Eigen::VectorXd u = gather();
  u += 0.5 * dt * apply_inverse_mass(load(u));
  // 2-4. RATTLE: the half-step velocity takes the rows' reaction along their directions at
  // the start, just as much as carries the bodies to where every row holds (to 1e-13 m).
  // (Projecting the half-step velocity onto the rows at the start and the positions onto
  // them at the end instead lost energy at first order: a pendulum released horizontal lost
  // 13 % of m g d in 10 s at dt 1 ms; issue 13.)
  Eigen::MatrixXd j;
  Eigen::VectorXd phi;
  rows_at(&j, &phi);
  const auto [w0, minv_j0t] = delassus(j);
  const std::vector<RigidState> start = states;
  const Eigen::VectorXd u_free = u;
  // first guess: the reaction that makes the half-step velocities satisfy the rows there
  Eigen::VectorXd lambda = solve_spd(w0, -(j * u_free));
  for (int it = 0;; ++it) {
    u = u_free + minv_j0t * lambda;
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      RigidState& s = states[bodies[k]];
      const RigidState& s0 = start[bodies[k]];
      const auto o = static_cast<Eigen::Index>(6 * k);
      s.velocity = u.segment<3>(o);
      s.angular_velocity = u.segment<3>(o + 3);
      s.position = s0.position + dt * s.velocity;
      s.rotation = (rotation_by(dt * s.angular_velocity) * s0.rotation).normalized();
    }
    rows_at(&j, &phi);
    if (phi.cwiseAbs().maxCoeff() <= 1e-13) break;
    if (it == 50)
      throw SimulationError("the joints cannot all be satisfied (a row is off by " +
                            std::to_string(phi.cwiseAbs().maxCoeff()) +
                            "): are two joints fighting each other, or is dt too long for "
                            "how fast the jointed bodies turn?");
    // simplified Newton: the rows move by dt J M^-1 J0' per unit of reaction, J ~ J0
    lambda += solve_spd(w0, -phi / dt);
  }
  // 5. the second half kick, and velocities consistent with the rows at the new
  // configuration
  update_inertia();
  const auto [w, minv_jt] = delassus(j);
  u = gather();
  u += 0.5 * dt * apply_inverse_mass(load(u));
  u += minv_jt * solve_spd(w, -(j * u));
  scatter(u);
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const RigidState& s = states[bodies[k]];
    if (!s.position.allFinite() || !s.velocity.allFinite() || !s.angular_velocity.allFinite())
      throw SimulationError("the state of body '" + scene_.bodies[bodies[k]].name +
                            "' became non-finite");
  }
}

}  // namespace vproto::sim
