#include "vproto/sim/contact.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "vproto/geometry/aabb_tree.h"
#include "vproto/geometry/convex_parts.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/point_contact_solver.h"

namespace vproto::sim {
namespace {

Eigen::Quaterniond rotation_by(const Eigen::Vector3d& angle) {
  const double a = angle.norm();
  if (a < 1e-300) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, angle / a));
}

std::pair<int, int> ordered(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

const ContactSetting* pair_setting(const Scene& s, int a, int b, bool want_friction) {
  const ContactSetting* global = nullptr;
  for (const auto& c : s.contacts) {
    const bool has = want_friction ? c.friction.has_value() : c.restitution.has_value();
    if (!has) continue;
    if ((c.body_a == a && c.body_b == b) || (c.body_a == b && c.body_b == a)) return &c;
    if (c.body_a == kGround && c.body_b == kGround) global = &c;
  }
  return global;
}

// A contact polygon of many corners (a faceted round face landing flat) as at most eight
// of them: the extremes along four directions in its plane, so the support it gives is
// kept while the rows stay few (and independent enough for the active-set solve).
void reduce_polygon(geometry::ContactManifold* m) {
  std::vector<geometry::ContactPoint>& pts = m->points;
  if (pts.size() <= 8) return;
  const Eigen::Vector3d n = m->normal;
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = n.cross(helper).normalized(), v = n.cross(u);
  std::vector<char> keep(pts.size(), 0);
  for (const Eigen::Vector3d& dir : {u, v, Eigen::Vector3d(u + v), Eigen::Vector3d(u - v)})
    for (double sign : {1.0, -1.0}) {
      std::size_t best = 0;
      for (std::size_t k = 1; k < pts.size(); ++k)
        if (sign * dir.dot(pts[k].on_b) > sign * dir.dot(pts[best].on_b)) best = k;
      keep[best] = 1;
    }
  std::vector<geometry::ContactPoint> kept;
  for (std::size_t k = 0; k < pts.size(); ++k)
    if (keep[k]) kept.push_back(pts[k]);
  pts = std::move(kept);
}

// When a gap g closing at rate v with acceleration a, g + v t + a t^2 / 2, first reaches
// zero (infinity if never).
double closing_time(double g, double v, double a) {
  double tau = std::numeric_limits<double>::infinity();
  if (std::abs(a) < 1e-300) return v < 0 ? -g / v : tau;
  const double disc = v * v - 2 * a * g;
  if (disc < 0) return tau;
  // the smaller positive root, in the form that keeps its digits
  const double q = -0.5 * (v + std::copysign(std::sqrt(disc), v));
  const double r1 = q / (0.5 * a), r2 = q != 0 ? g / q : -1;
  for (double r : {r1, r2})
    if (r > 0) tau = std::min(tau, r);
  return tau;
}

std::string seconds(double t) {
  char s[32];
  std::snprintf(s, sizeof s, "%.6g", t);
  return s;
}

}  // namespace

double pair_friction(const Scene& s, int a, int b) {
  if (const ContactSetting* c = pair_setting(s, a, b, true)) return *c->friction;
  return std::sqrt(s.bodies[a].material.friction.value_or(0) *
                   s.bodies[b].material.friction.value_or(0));
}

double pair_restitution(const Scene& s, int a, int b) {
  if (const ContactSetting* c = pair_setting(s, a, b, false)) return *c->restitution;
  return std::sqrt(s.bodies[a].material.restitution.value_or(0) *
                   s.bodies[b].material.restitution.value_or(0));
}

// Bodies a joint joins touch each other only through it (a hinge's parts overlap).
std::set<std::pair<int, int>> joined_pairs(const Scene& s) {
  std::set<std::pair<int, int>> out;
  for (const auto& j : s.joints)
    if (j.other != kGround) out.insert(ordered(j.body, j.other));
  return out;
}

bool movable(ContactRole r) { return r == ContactRole::kFree || r == ContactRole::kJointed; }

std::vector<char> contact_bodies(const Scene& s) {
  const std::size_t n = s.bodies.size();
  std::vector<char> capable(n, 0), fixed(n, 0), out(n, 0);
  for (std::size_t i = 0; i < n; ++i) capable[i] = s.bodies[i].kind == BodyKind::kRigid;
  for (const auto& f : s.fixes) fixed[f.body] = fixed[f.body] || !f.region;
  std::set<std::pair<int, int>> skip = joined_pairs(s);
  for (const auto& nc : s.nocontacts) skip.insert(ordered(nc.body_a, nc.body_b));
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      if (!capable[a] || !capable[b] || (fixed[a] && fixed[b])) continue;
      if (skip.count({static_cast<int>(a), static_cast<int>(b)})) continue;
      out[a] = out[b] = 1;
    }
  return out;
}

// One contact point: a point of A that stays outside a plane of B (Eq. 16), places and
// normal in the body frames, and the world quantities of the current solve.
struct ContactSystem::Point {
  int a = 0, b = 0;                                                            ///< bodies
  int part_a = 0, part_b = 0;                                                  ///< parts
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();  ///< body frames
  /// The normal (A towards B) in the frame of the body whose surface it belongs to: A's
  /// for a vertex of B on a face of A (and edge on edge, face on face), else B's.
  Eigen::Vector3d n_local = Eigen::Vector3d::UnitZ();
  bool normal_on_a = true;
  double gap = 0;  ///< m, at detection
  double mu = 0, e = 0;
  Eigen::Vector3d ra = Eigen::Vector3d::Zero(), rb = Eigen::Vector3d::Zero();  ///< world levers
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();  ///< columns n, t1, t2 (world)
  Eigen::Vector3d lambda = Eigen::Vector3d::Zero();     ///< impulse in the basis
  double target = 0;                                    ///< v_n+ >= target
  bool closed = false;
};

// Velocities and inverse masses of the bodies during one solve.
struct ContactSystem::Solver {
  using Wrench = Eigen::Matrix<double, 6, 1>;
  std::vector<Eigen::Vector3d> v, w;
  std::vector<double> inv_mass;
  std::vector<Eigen::Matrix3d> inv_inertia;  ///< world axes
  /// Jointed bodies answer through their mechanism's mobility (their inverse mass and
  /// inertia above are zero: position corrections leave them to their joints).
  std::vector<char> general;
  const std::vector<Mechanism>* mechanisms = nullptr;
  const std::vector<int>* mechanism_of = nullptr;
  const std::vector<int>* slot = nullptr;

  const Mechanism& mechanism(int body) const { return (*mechanisms)[(*mechanism_of)[body]]; }
  // how body i's (velocity, angular velocity) answers a wrench on body j
  Eigen::Matrix<double, 6, 6> coupling(int i, int j) const {
    Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
    if (general[i] && general[j]) {
      if ((*mechanism_of)[i] == (*mechanism_of)[j])
        c = mechanism(i).mobility.block<6, 6>(6 * (*slot)[i], 6 * (*slot)[j]);
    } else if (i == j) {
      c.topLeftCorner<3, 3>() = inv_mass[i] * Eigen::Matrix3d::Identity();
      c.bottomRightCorner<3, 3>() = inv_inertia[i];
    }
    return c;
  }
  static Wrench wrench(const Eigen::Vector3d& force, const Eigen::Vector3d& r) {
    return (Wrench() << force, r.cross(force)).finished();
  }

  Eigen::Vector3d point_velocity(int body, const Eigen::Vector3d& r) const {
    return v[body] + w[body].cross(r);
  }
  Eigen::Vector3d relative_velocity(const Point& p) const {
    return point_velocity(p.b, p.rb) - point_velocity(p.a, p.ra);
  }
  // the velocity changes a force on `body` at lever r makes: its own, or its whole
  // mechanism's
  void add_force(int body, const Eigen::Vector3d& r, const Eigen::Vector3d& force) {
    if (general[body]) return add_mechanism_wrench(body, wrench(force, r));
    v[body] += inv_mass[body] * force;
    w[body] += inv_inertia[body] * r.cross(force);
  }
  __attribute__((noinline)) void add_mechanism_wrench(int body, const Wrench& load) {
    const Mechanism& m = mechanism(body);
    const Eigen::Index col = 6 * (*slot)[body];
    for (std::size_t k = 0; k < m.bodies.size(); ++k) {
      const Wrench d = m.mobility.block<6, 6>(6 * static_cast<Eigen::Index>(k), col) * load;
      v[m.bodies[k]] += d.head<3>();
      w[m.bodies[k]] += d.tail<3>();
    }
  }
  void apply(const Point& p, const Eigen::Vector3d& impulse) {
    add_force(p.b, p.rb, impulse);
    add_force(p.a, p.ra, -impulse);
  }
  // a free body's part of a point's Delassus block, m^-1 I - [r]x I^-1 [r]x (world axes)
  Eigen::Matrix3d free_k(int body, const Eigen::Vector3d& r) const {
    Eigen::Matrix3d rx;
    rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
    return inv_mass[body] * Eigen::Matrix3d::Identity() - rx * inv_inertia[body] * rx;
  }
  // the point's Delassus block in its basis: per pair of sides s, t the unit wrenches'
  // coupling, G_s' C(s, t) G_t with signs (a's side negative)
  Eigen::Matrix3d block_of(const Point& p) const {
    if (!general[p.a] && !general[p.b])
      return p.basis.transpose() * (free_k(p.a, p.ra) + free_k(p.b, p.rb)) * p.basis;
    Eigen::Matrix<double, 6, 3> ga, gb;
    for (int c = 0; c < 3; ++c) {
      ga.col(c) = wrench(p.basis.col(c), p.ra);
      gb.col(c) = wrench(p.basis.col(c), p.rb);
    }
    Eigen::Matrix3d k =
        ga.transpose() * coupling(p.a, p.a) * ga + gb.transpose() * coupling(p.b, p.b) * gb;
    if (general[p.a] && general[p.b]) {  // both on one mechanism: the cross terms
      const Eigen::Matrix3d cross = ga.transpose() * coupling(p.a, p.b) * gb;
      k -= cross + cross.transpose();
    }
    return k;
  }
  // The island's points as the one contact solver sees them: a point's motion is its
  // relative velocity in its basis less its normal target, a force changes the bodies'
  // velocities through their inverse masses (or a jointed body's mobility), and the dense
  // Delassus matrix (for Newton's finish) is formed only for islands of at most `dense_rows`
  // rows.
  class IslandResponse final : public PointResponse {
   public:
    IslandResponse(Solver& solver, const std::vector<Point*>& points, int dense_rows)
        : s_(solver), p_(points), dense_rows_(dense_rows) {}
    Eigen::Index points() const override { return static_cast<Eigen::Index>(p_.size()); }
    Eigen::Matrix3d block(Eigen::Index i) const override { return s_.block_of(at(i)); }
    Eigen::Vector3d motion(Eigen::Index i) const override {
      const Point& p = at(i);
      Eigen::Vector3d d = p.basis.transpose() * s_.relative_velocity(p);
      d[0] -= p.target;
      return d;
    }
    void add(Eigen::Index i, const Eigen::Vector3d& delta) override {
      s_.apply(at(i), at(i).basis * delta);
    }
    void replace(const Eigen::VectorXd& from, const Eigen::VectorXd& to) override {
      for (Eigen::Index i = 0; i < points(); ++i) {
        const Eigen::Vector3d delta = to.segment<3>(3 * i) - from.segment<3>(3 * i);
        if (delta.squaredNorm() > 0) add(i, delta);
      }
    }
    const PointContactProblem* dense(const Eigen::VectorXd& lambda) override {
      const Eigen::Index m = points();
      if (3 * m > dense_rows_) return nullptr;
      // per point and side: G, the wrench of a unit force along each basis vector (its
      // transpose maps the body's velocity to the point's motion), and H = M^-1 G, the body's
      // velocity change; W_ij sums s_i s_j G_i' H_j over the bodies points i and j share
      struct Side {
        int body;
        double sign;
        Eigen::Matrix<double, 6, 3> g, h;
      };
      std::vector<std::array<Side, 2>> sides(static_cast<std::size_t>(m));
      for (Eigen::Index i = 0; i < m; ++i) {
        const Point& p = at(i);
        for (int k = 0; k < 2; ++k) {
          Side& sd = sides[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
          sd.body = k ? p.b : p.a;
          sd.sign = k ? 1.0 : -1.0;
          const Eigen::Vector3d r = k ? p.rb : p.ra;
          for (int c = 0; c < 3; ++c) {
            sd.g.block<3, 1>(0, c) = p.basis.col(c);
            sd.g.block<3, 1>(3, c) = r.cross(p.basis.col(c));
          }
          if (!s_.general[sd.body]) {
            sd.h.topRows<3>() = s_.inv_mass[sd.body] * sd.g.topRows<3>();
            sd.h.bottomRows<3>() = s_.inv_inertia[sd.body] * sd.g.bottomRows<3>();
          }
        }
      }
      problem_.w.setZero(3 * m, 3 * m);
      problem_.free.resize(3 * m);
      problem_.mu.resize(static_cast<std::size_t>(m));
      for (Eigen::Index i = 0; i < m; ++i) {
        for (Eigen::Index j = 0; j < m; ++j)
          for (const Side& si : sides[static_cast<std::size_t>(i)])
            for (const Side& sj : sides[static_cast<std::size_t>(j)]) {
              // a free body couples only its own points; a mechanism's bodies couple each
              // other's through its mobility
              if (s_.general[si.body] && s_.general[sj.body]) {
                if ((*s_.mechanism_of)[si.body] == (*s_.mechanism_of)[sj.body])
                  problem_.w.block<3, 3>(3 * i, 3 * j).noalias() +=
                      (si.sign * sj.sign) *
                      (si.g.transpose() * s_.coupling(si.body, sj.body) * sj.g);
              } else if (si.body == sj.body) {
                problem_.w.block<3, 3>(3 * i, 3 * j).noalias() +=
                    (si.sign * sj.sign) * (si.g.transpose() * sj.h);
              }
            }
        problem_.free.segment<3>(3 * i) = motion(i);
        problem_.mu[static_cast<std::size_t>(i)] = at(i).mu;
      }
      problem_.free -= problem_.w * lambda;
      return &problem_;
    }

   private:
    const Point& at(Eigen::Index i) const { return *p_[static_cast<std::size_t>(i)]; }
    Solver& s_;
    const std::vector<Point*>& p_;
    int dense_rows_;
    PointContactProblem problem_;
  };

  // The island's points solved by the one contact solver (point_contact_solver.h) over
  // the bodies' velocities: projected Gauss-Seidel on the point blocks, and Newton's finish on
  // the island's Delassus matrix while it has at most `newton_rows` rows (Eq. 18's active-set
  // solve: every point's state settled at once). Targets: the normal velocity after the
  // solve stays at or above the point's target, friction keeps to Coulomb's cone. Returns the
  // sweeps taken; `residual` gets the solver's (a contact velocity).
  int solve(PointContactSolver& point_solver, std::vector<Point*>& points, int max_sweeps,
            double tolerance, int newton_rows, double* residual) {
    IslandResponse response(*this, points, newton_rows);
    std::vector<double> mu(points.size());
    Eigen::VectorXd warm(3 * static_cast<Eigen::Index>(points.size()));
    for (std::size_t k = 0; k < points.size(); ++k) {
      mu[k] = points[k]->mu;
      warm.segment<3>(3 * static_cast<Eigen::Index>(k)) = points[k]->lambda;
    }
    PointContactOptions options;
    options.max_sweeps = max_sweeps;
    options.tolerance = tolerance;
    // the sweeps first (on rigid bodies they settle most islands in a few); Newton's finish
    // after 20 of them on an island small enough to form its Delassus matrix
    options.newton_after = 20;
    options.newton_tries = 1;  // a pile's islands that the sweeps do not settle rarely settle by it
    options.block_stick = false;
    options.newton_damping = 1e-6;  // a few independent rows (see PointContactOptions)
    options.newton_unknowns = newton_rows;
    const PointContactSolution s = point_solver.solve(response, mu, warm, options);
    for (std::size_t k = 0; k < points.size(); ++k)
      points[k]->lambda = s.lambda.segment<3>(3 * static_cast<Eigen::Index>(k));
    *residual = s.converged ? std::min(s.residual, tolerance) : s.residual;
    return s.sweeps;
  }
};

ContactSystem::ContactSystem(const Scene& scene, std::vector<ContactRole> roles,
                             ContactOptions options)
    : scene_(scene), roles_(std::move(roles)), options_(options) {
  const std::size_t n = scene.bodies.size();
  VPROTO_DEMAND(roles_.size() == n);
  skip_ = joined_pairs(scene);
  for (const auto& nc : scene.nocontacts) skip_.insert(ordered(nc.body_a, nc.body_b));
  mechanism_of_.assign(n, -1);
  slot_.assign(n, 0);
  now_.supports.assign(n, {});
  // bodies that may touch another: a free one, or a static or kinematic one a free or
  // kinematic body may reach
  std::vector<char> wanted(n, 0);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      const ContactRole ra = roles_[a], rb = roles_[b];
      if (ra == ContactRole::kNone || rb == ContactRole::kNone) continue;
      if (ra == ContactRole::kStatic && rb == ContactRole::kStatic) continue;
      if (skip_.count({static_cast<int>(a), static_cast<int>(b)})) continue;
      wanted[a] = wanted[b] = 1;
    }
  radius_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!wanted[i]) continue;
    const Body& body = scene.bodies[i];
    std::vector<geometry::TriMesh> meshes;
    if (body.convex_parts_computed) {
      meshes = body.convex_parts;
    } else if (geometry::is_convex(body.surface)) {
      meshes = {body.surface};
    } else {
      meshes = geometry::convex_parts(body.surface);
    }
    const Eigen::Vector3d c = body.mass_properties.centroid;
    for (geometry::TriMesh& m : meshes) {
      m.V.rowwise() -= c.transpose();
      Part part;
      part.body = static_cast<int>(i);
      part.local = geometry::make_polytope(m);
      for (const auto& v : part.local.vertices) radius_[i] = std::max(radius_[i], v.norm());
      parts_.push_back(std::move(part));
    }
  }
}

std::vector<std::pair<int, int>> ContactSystem::candidates(const std::vector<RigidState>& states,
                                                           const std::vector<double>& reach) const {
  std::vector<geometry::Bounds> boxes(parts_.size());
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    const int body = parts_[k].body;
    const Eigen::Matrix3d r = states[body].rotation.toRotationMatrix();
    geometry::Bounds& box = boxes[k];
    for (const auto& v : parts_[k].local.vertices) {
      const Eigen::Vector3d w = states[body].position + r * v;
      box.lo = box.lo.cwiseMin(w);
      box.hi = box.hi.cwiseMax(w);
    }
    box.lo.array() -= reach[body];
    box.hi.array() += reach[body];
  }
  std::vector<std::pair<int, int>> out;
  for (auto [i, j] : geometry::AabbTree(boxes).overlapping_pairs()) {
    const int a = parts_[i].body, b = parts_[j].body;
    if (a == b) continue;
    if (!movable(roles_[a]) && !movable(roles_[b])) continue;
    if (skip_.count(ordered(a, b))) continue;
    out.push_back(a < b ? std::make_pair(i, j) : std::make_pair(j, i));
  }
  return out;
}

std::vector<ContactSystem::Point> ContactSystem::narrow(
    const std::vector<RigidState>& states, const std::vector<double>& reach,
    const std::vector<std::pair<int, int>>& pairs) const {
  // each part placed once per call, in storage kept from call to call
  world_parts_.resize(parts_.size());
  placed_in_.resize(parts_.size(), -1);
  const long call = narrow_calls_++;
  auto placed = [&](int part) -> const geometry::ConvexPolytope& {
    geometry::ConvexPolytope& world = world_parts_[static_cast<std::size_t>(part)];
    if (placed_in_[static_cast<std::size_t>(part)] == call) return world;
    const int body = parts_[part].body;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = states[body].rotation.toRotationMatrix();
    pose.translation() = states[body].position;
    geometry::place(parts_[part].local, pose, &world);
    placed_in_[static_cast<std::size_t>(part)] = call;
    return world;
  };
  std::vector<Point> points;
  points.reserve(8 * pairs.size());
  for (const auto& [i, j] : pairs) {
    const int a = parts_[i].body, b = parts_[j].body;
    const geometry::ConvexPolytope &pa = placed(i), &pb = placed(j);
    geometry::ConvexDistance d = geometry::gjk_distance(pa, pb);
    ++stats_.queries;
    // touching to rounding: the witness direction is noise; the separating axes give the
    // touching faces' normal
    if (!d.overlap && d.distance <= 1e-9 * std::max(radius_[a], radius_[b])) {
      Eigen::Vector3d axis;
      const double depth = geometry::penetration_depth(pa, pb, &axis);
      if (depth > -1e-9 * std::max(radius_[a], radius_[b])) {
        d.overlap = true;
        d.distance = 0;
        d.penetration = std::max(depth, 0.0);
        d.normal = axis;
      }
    }
    if (!d.overlap && d.distance > reach[a] + reach[b]) continue;
    // faces within 0.1 rad count as face on face: a tilted face that lands gets a point at
    // every corner (each a row with its own gap), not only its lowest corner
    geometry::ContactManifold m = geometry::contact_manifold(pa, pb, d, 0.1);
    reduce_polygon(&m);
    const Eigen::Matrix3d rot_a = states[a].rotation.toRotationMatrix(),
                          rot_b = states[b].rotation.toRotationMatrix();
    const double mu = pair_friction(scene_, a, b), e = pair_restitution(scene_, a, b);
    for (const auto& c : m.points) {
      Point p;
      p.a = a;
      p.b = b;
      p.part_a = i;
      p.part_b = j;
      p.pa = rot_a.transpose() * (c.on_a - states[a].position);
      p.pb = rot_b.transpose() * (c.on_b - states[b].position);
      p.normal_on_a = m.feature != geometry::ContactFeature::kFaceVertex;
      p.n_local = (p.normal_on_a ? rot_a : rot_b).transpose() * m.normal;
      p.gap = c.gap;
      p.mu = mu;
      p.e = e;
      points.push_back(p);
    }
  }
  return points;
}

ContactSystem::Saved ContactSystem::save() const { return {now_, events_.size()}; }

void ContactSystem::restore(const Saved& s) {
  now_ = s.carried;
  events_.resize(s.events);
}

void ContactSystem::check_start(const std::vector<RigidState>& states) const {
  const std::vector<double> reach(states.size(), 0.0);
  for (const Point& p : narrow(states, reach, candidates(states, reach))) {
    const double allowed = 1e-6;  // m: faces placed on one another meet to rounding
    if (p.gap < -allowed) {
      char depth[32];
      std::snprintf(depth, sizeof depth, "%.3g", -p.gap);
      throw InputError(scene_.bodies[p.b].loc,
                       "bodies '" + scene_.bodies[p.a].name + "' and '" + scene_.bodies[p.b].name +
                           "' overlap by " + depth +
                           " m at the start; move them apart (they may touch), or add "
                           "'nocontact " +
                           scene_.bodies[p.a].name + " " + scene_.bodies[p.b].name + ";'");
    }
  }
}

void ContactSystem::set_mechanism(const std::vector<int>& bodies, const Eigen::MatrixXd& mobility) {
  VPROTO_DEMAND(!bodies.empty() &&
                mobility.rows() == 6 * static_cast<Eigen::Index>(bodies.size()) &&
                mobility.cols() == mobility.rows());
  int& index = mechanism_of_.at(static_cast<std::size_t>(bodies.front()));
  if (index < 0) {
    index = static_cast<int>(mechanisms_.size());
    mechanisms_.push_back({bodies, {}});
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      mechanism_of_.at(static_cast<std::size_t>(bodies[k])) = index;
      slot_[static_cast<std::size_t>(bodies[k])] = static_cast<int>(k);
    }
  }
  Mechanism& m = mechanisms_[static_cast<std::size_t>(index)];
  VPROTO_DEMAND(m.bodies == bodies);
  m.mobility = mobility;
}

void ContactSystem::add_supports(const std::vector<Point*>& rows,
                                 const std::vector<RigidState>& states, double h,
                                 double still_speed) {
  // A point where `held` presses on `free` (its force on `free`: +basis lambda when `free` is
  // b): a support of `free`, the point on `held`'s surface moving with it.
  auto support = [&](const Point& p, int held) {
    const bool b_free = held == p.a;
    const double sign = b_free ? 1.0 : -1.0;
    Support sp;
    sp.body = held;
    sp.point = states[held].position + states[held].rotation * (b_free ? p.pa : p.pb);
    sp.normal = sign * p.basis.col(0);
    sp.friction = sign * (p.basis.rightCols<2>() * p.lambda.tail<2>()) / h;
    sp.sticking = p.mu > 0 && p.lambda.tail<2>().norm() < p.mu * p.lambda[0] * (1 - 1e-9);
    sp.velocity = states[held].velocity +
                  states[held].angular_velocity.cross(sp.point - states[held].position);
    const int free = b_free ? p.b : p.a;
    const Eigen::Vector3d slip =
        states[free].velocity +
        states[free].angular_velocity.cross(sp.point - states[free].position) - sp.velocity;
    sp.still =
        sp.sticking || (p.mu > 0 && (slip - slip.dot(sp.normal) * sp.normal).norm() <= still_speed);
    now_.supports[static_cast<std::size_t>(b_free ? p.b : p.a)].push_back(sp);
  };
  auto is_free = [&](int body) { return roles_[body] == ContactRole::kFree; };
  // on fixed or driven bodies
  for (const Point* p : rows) {
    if (p->lambda[0] <= 0 || is_free(p->a) == is_free(p->b)) continue;
    const int holder = is_free(p->b) ? p->a : p->b;
    if (roles_[holder] == ContactRole::kStatic || roles_[holder] == ContactRole::kKinematic)
      support(*p, holder);
  }
  // on free bodies their supports hold still (a block on a block on a plate): a stage that
  // moves the upper one (an elastic body's contact stage) answers with it held, as the
  // contact solve that follows will have it, where a free upper block crept under a push its
  // friction holds
  auto held = [&](int body) {
    const std::vector<Support>& list = now_.supports[static_cast<std::size_t>(body)];
    return !list.empty() &&
           std::all_of(list.begin(), list.end(), [](const Support& sp) { return sp.still; });
  };
  std::vector<char> done(rows.size(), 0);
  for (bool grew = true; grew;) {
    grew = false;
    std::vector<std::pair<const Point*, int>> found;  // (point, holder)
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const Point& p = *rows[k];
      if (done[k] || p.lambda[0] <= 0 || !is_free(p.a) || !is_free(p.b)) continue;
      const bool a_held = held(p.a), b_held = held(p.b);
      if (a_held == b_held) continue;
      done[k] = 1;
      found.push_back({&p, a_held ? p.a : p.b});
    }
    // (added after the pass: a body takes supports only on bodies held before it)
    for (const auto& [p, holder] : found) support(*p, holder);
    grew = !found.empty();
  }
}

int ContactSystem::sweeps_for(std::size_t points, int floor, int ceiling) const {
  const long share = options_.sweep_budget / static_cast<long>(std::max<std::size_t>(points, 1));
  return static_cast<int>(std::clamp<long>(share, floor, std::max(floor, ceiling)));
}

void ContactSystem::step(std::vector<RigidState>& states, const std::vector<RigidInertia>& inertias,
                         const std::vector<Eigen::Vector3d>& forces,
                         const std::vector<Eigen::Vector3d>& torques, double t, double dt,
                         std::vector<char>* advanced) {
  const std::size_t n = states.size();
  advanced->assign(n, 0);
  now_.jointed_impulse.assign(n, Eigen::Matrix<double, 6, 1>::Zero());
  now_.jointed_correction.assign(n, Eigen::Matrix<double, 6, 1>::Zero());
  now_.travel.assign(n, Eigen::Matrix<double, 6, 1>::Zero());
  for (auto& list : now_.supports) list.clear();
  now_.links.clear();
  now_.active_points = 0;
  now_.contact_force = 0;
  if (parts_.empty()) return;
  // how far each body can travel within `h`, plus a small margin that keeps resting
  // contacts in view
  auto reach_over = [&](double h) {
    std::vector<double> r(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const RigidState& s = states[i];
      const double margin = 1e-3 * radius_[i];
      if (movable(roles_[i]))
        r[i] = (s.velocity.norm() + s.angular_velocity.norm() * radius_[i]) * h +
               0.5 * forces[i].norm() / inertias[i].mass * h * h + margin;
      else if (roles_[i] == ContactRole::kKinematic)
        r[i] = s.velocity.norm() * h + margin;
      else
        r[i] = margin;
    }
    return r;
  };
  std::vector<Point> all_points =
      narrow(states, reach_over(dt), candidates(states, reach_over(dt)));

  // islands: free bodies linked by contact points (static and driven bodies link nothing);
  // each is advanced on its own, with its own cuts at times of first contact
  std::vector<int> parent(n);
  for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<int>(i);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const Point& p : all_points)
    if (movable(roles_[p.a]) && movable(roles_[p.b])) parent[root(p.a)] = root(p.b);
  // a mechanism's bodies move together: contacts on any of them are one island, which
  // advances all of them (those that touch nothing too)
  for (const Mechanism& m : mechanisms_)
    for (int b : m.bodies) parent[root(b)] = root(m.bodies.front());
  auto by_joints = [&](int b) { return mechanism_of_[static_cast<std::size_t>(b)] >= 0; };
  for (std::size_t i = 0; i < n; ++i)
    VPROTO_DEMAND(roles_[i] != ContactRole::kJointed || by_joints(static_cast<int>(i)));
  if (!options_.islands) {  // one island of every body that touches (measuring the skip)
    int first = -1;
    for (const Point& p : all_points)
      for (int b : {p.a, p.b}) {
        if (!movable(roles_[b])) continue;
        if (first < 0) first = root(b);
        parent[root(b)] = root(first);
      }
  }
  std::map<int, std::vector<Point>> islands;
  std::set<std::pair<int, int>> within_reach;  // pairs with points: their islands report them
  for (const Point& p : all_points) {
    islands[root(movable(roles_[p.a]) ? p.a : p.b)].push_back(p);
    within_reach.insert({p.a, p.b});
  }

  Solver solver;
  solver.v.resize(n);
  solver.w.resize(n);
  solver.inv_mass.assign(n, 0.0);
  solver.inv_inertia.assign(n, Eigen::Matrix3d::Zero());
  solver.general.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) solver.general[i] = mechanism_of_[i] >= 0;
  solver.mechanisms = &mechanisms_;
  solver.mechanism_of = &mechanism_of_;
  solver.slot = &slot_;
  std::map<std::pair<int, int>, Eigen::Vector3d> pair_impulse;  // over the step, on b
  auto add_impulse = [&](const Point& p) {
    auto [it, fresh] = pair_impulse.try_emplace({p.a, p.b}, Eigen::Vector3d::Zero());
    it->second += p.basis * p.lambda;
  };
  std::map<std::pair<int, int>, char> touching_after;
  decltype(now_.warm) warm_after;
  std::vector<char>& in_island = *advanced;  // the bodies of the island being advanced

  for (auto& [island_root, island_points] : islands) {
    std::vector<int> bodies;
    bool jointed = false;  // a body of the island is moved by its joints
    for (std::size_t i = 0; i < n; ++i)
      if ((movable(roles_[i]) || by_joints(static_cast<int>(i))) &&
          root(static_cast<int>(i)) == island_root) {
        bodies.push_back(static_cast<int>(i));
        in_island[i] = 2;  // this island's; 1 once done
        jointed = jointed || by_joints(static_cast<int>(i));
      }
    std::vector<std::pair<int, int>> island_pairs;
    std::map<std::pair<int, int>, char> touching;  // this island's pairs touching now
    for (const Point& p : island_points) {
      if (island_pairs.empty() || island_pairs.back() != std::make_pair(p.part_a, p.part_b))
        island_pairs.emplace_back(p.part_a, p.part_b);
      if (now_.touching.count({p.a, p.b})) touching[{p.a, p.b}] = 1;
    }
    std::vector<Point> points = std::move(island_points);
    double remaining = dt, now = t;
    for (int substep = 0; remaining > 0; ++substep) {
      if (substep > 0) points = narrow(states, reach_over(remaining), island_pairs);
      auto moved = [&](int b) { return in_island[b] == 2; };
      for (std::size_t i = 0; i < n; ++i) {
        solver.v[i] = states[i].velocity;
        solver.w[i] = states[i].angular_velocity;
      }
      for (int i : bodies) {
        if (by_joints(i)) continue;  // their mechanism's mobility
        const Eigen::Matrix3d r = states[i].rotation.toRotationMatrix();
        solver.inv_mass[i] = 1 / inertias[i].mass;
        solver.inv_inertia[i] = r * inertias[i].inertia.inverse() * r.transpose();
      }
      // world quantities of the points
      for (Point& p : points) {
        const Eigen::Matrix3d rot_a = states[p.a].rotation.toRotationMatrix(),
                              rot_b = states[p.b].rotation.toRotationMatrix();
        p.ra = rot_a * p.pa;
        p.rb = rot_b * p.pb;
        const Eigen::Vector3d nrm = (p.normal_on_a ? rot_a : rot_b) * p.n_local;
        const Eigen::Vector3d helper =
            std::abs(nrm.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
        const Eigen::Vector3d t1 = nrm.cross(helper).normalized();
        p.basis.col(0) = nrm;
        p.basis.col(1) = t1;
        p.basis.col(2) = nrm.cross(t1);
        p.gap = nrm.dot(states[p.b].position + p.rb - states[p.a].position - p.ra);
      }
      auto free_acceleration_vector = [&](const Point& p) {
        Eigen::Vector3d acc = Eigen::Vector3d::Zero();
        if (moved(p.b)) acc += forces[p.b] / inertias[p.b].mass;
        if (moved(p.a)) acc -= forces[p.a] / inertias[p.a].mass;
        return acc;
      };
      auto free_acceleration = [&](const Point& p) {
        return p.basis.col(0).dot(free_acceleration_vector(p));
      };
      // the speed the loads give either body within a step: slower approaches are not
      // impacts (no restitution, no cut) but the closing of a resting contact
      auto impact_speed = [&](const Point& p) {
        double a = 0;
        for (int b : {p.a, p.b})
          if (moved(b)) a = std::max(a, forces[b].norm() / inertias[b].mass);
        return 2 * a * dt + 1e-12;
      };
      // the velocity scale of the substep: relative speeds and what the loads add in it
      double velocity_scale = 0;
      for (const Point& p : points)
        velocity_scale = std::max({velocity_scale, solver.relative_velocity(p).norm(),
                                   free_acceleration_vector(p).norm() * remaining});
      const double tolerance = options_.tolerance * std::max(velocity_scale, 1e-300);
      // closed: touching to rounding, or closing within a negligible part of the step
      for (Point& p : points) {
        const double vn = p.basis.col(0).dot(solver.relative_velocity(p));
        const double tol = 1e-9 * std::max(radius_[p.a], radius_[p.b]);
        p.closed = p.gap <= tol || (vn < 0 && p.gap <= -vn * 1e-6 * dt);
      }

      // 1. impacts: an instantaneous impulse with Newton's restitution on the closed
      // points that approach faster than the step's loads could bring them
      std::vector<Point*> closed;
      bool impact = false;
      for (Point& p : points) {
        if (!p.closed) continue;
        const double vn = p.basis.col(0).dot(solver.relative_velocity(p));
        const double threshold = impact_speed(p);
        p.target = vn < -threshold ? -p.e * vn : 0.0;
        p.lambda.setZero();
        impact = impact || vn < -threshold;
        closed.push_back(&p);
      }
      if (impact) {
        double residual = 0;
        stats_.sweeps +=
            solver.solve(point_solver_, closed,
                         sweeps_for(closed.size(), options_.min_sweeps, options_.max_sweeps),
                         tolerance, options_.active_set_rows, &residual);
        ++stats_.solves;
        for (const Point* p : closed) add_impulse(*p);
        for (int i : bodies) {
          states[i].velocity = solver.v[i];
          states[i].angular_velocity = solver.w[i];
        }
      }

      // 2. the time of first contact of the open points: the gap closing under the
      // current velocity and the free acceleration, g + v t + a t^2 / 2 = 0
      double h = remaining;
      std::map<std::pair<int, int>, double> meets;  // pairs closing plastically: when
      // (an island with a jointed body is not cut: its joints carry it over the whole
      // step, so its impacts are taken at the step's start or end)
      if (substep < options_.max_substeps && !jointed) {
        for (const Point& p : points) {
          if (p.closed) continue;
          const double g = p.gap, vn = p.basis.col(0).dot(solver.relative_velocity(p)),
                       an = free_acceleration(p);
          const double tau = closing_time(g, vn, an);
          // only impacts are located: a point that closes slower than the step's loads
          // could stop it is left to the rows of the smooth step (-gap / h)
          const double speed = -(vn + an * tau);
          if (!(tau < remaining) || speed <= impact_speed(p)) continue;
          if (p.e <= 0) {
            // a plastic impact needs no cut: the row of the smooth step brings the point
            // to the surface at the end of the step and stops it there, as the impact
            // would; the event keeps the instant
            auto [it, fresh] = meets.try_emplace({p.a, p.b}, tau);
            it->second = std::min(it->second, tau);
          } else if (tau < h) {
            h = std::max(tau, 1e-6 * dt);
          }
        }
      }
      if (h < remaining) ++stats_.substeps;

      // 3. the smooth part of the substep: Moreau's midpoint with the unilateral rows
      std::vector<Point*> rows;
      for (Point& p : points) {
        // an open point may close by the end of the substep, not pass: with the midpoint
        // update the gap ends at g + h (v_n + v_n+) / 2 (never a bounce, so at most 0)
        const double vn0 = p.basis.col(0).dot(solver.relative_velocity(p));
        p.target = p.closed ? 0.0 : std::min(0.0, -2 * p.gap / h - vn0);
        // an island with a jointed body is not cut at its impacts (its joints carry it over
        // the whole step): a point that strikes within the step leaves it at Newton's
        // rebound speed (Moreau-Jean: the law at the step's end; the overlap the midpoint
        // update leaves is undone below)
        if (jointed && !p.closed && p.e > 0 && vn0 < -impact_speed(p) && p.gap + h * vn0 < 0)
          p.target = -p.e * vn0;
        // warm start from the last step's force at the nearest point of the same parts
        p.lambda.setZero();
        const auto it = now_.warm.find({p.part_a, p.part_b});
        if (it != now_.warm.end()) {
          double best = 1e-2 * radius_[p.a];
          for (const auto& [place, force] : it->second) {
            const double dist = (place - p.pa).norm();
            if (dist < best) {
              best = dist;
              Eigen::Vector3d l = p.basis.transpose() * (force * h);
              l[0] = std::max(0.0, l[0]);
              const double tn = l.tail<2>().norm(), limit = p.mu * l[0];
              if (tn > limit) l.tail<2>() *= tn > 0 ? limit / tn : 0.0;
              p.lambda = l;
            }
          }
        }
        rows.push_back(&p);
      }
      std::vector<Eigen::Vector3d> v0(bodies.size()), w0(bodies.size());
      // a jointed body's load: forces and torques with the gyroscopic term, world axes
      auto load_on = [&](int i) {
        const RigidState& s = states[i];
        const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
        const Eigen::Matrix3d inertia = r * inertias[i].inertia * r.transpose();
        return (Solver::Wrench() << forces[i],
                torques[i] - s.angular_velocity.cross(inertia * s.angular_velocity))
            .finished();
      };
      for (std::size_t k = 0; k < bodies.size(); ++k) {
        const int i = bodies[k];
        const RigidState& s = states[i];
        v0[k] = s.velocity;
        w0[k] = s.angular_velocity;
        if (by_joints(i)) {
          // the loads as the joints let them act: every load on its mechanism moves it
          const Mechanism& m = solver.mechanism(i);
          Solver::Wrench a = Solver::Wrench::Zero();
          for (std::size_t q = 0; q < m.bodies.size(); ++q)
            a += m.mobility.block<6, 6>(6 * slot_[static_cast<std::size_t>(i)],
                                        6 * static_cast<Eigen::Index>(q)) *
                 load_on(m.bodies[q]);
          solver.v[i] = s.velocity + h * a.head<3>();
          solver.w[i] = s.angular_velocity + h * a.tail<3>();
        } else {
          solver.v[i] = s.velocity + h * forces[i] / inertias[i].mass;
          // the free spin by the energy-keeping rule of free flight (the spin then turns with
          // the body below)
          solver.w[i] = spin_after(s, inertias[i], torques[i], h);
        }
      }
      {
        double residual = 0;
        stats_.sweeps += solver.solve(
            point_solver_, rows, sweeps_for(rows.size(), options_.min_sweeps, options_.max_sweeps),
            tolerance, options_.active_set_rows, &residual);
        ++stats_.solves;
        if (residual > tolerance) {
          ++stats_.unconverged;
          stats_.worst_residual = std::max(stats_.worst_residual, residual / velocity_scale);
        }
      }
      for (const Point* p : rows) {
        add_impulse(*p);
        const Eigen::Vector3d impulse = p->basis * p->lambda;
        if (by_joints(p->b))
          now_.jointed_impulse[static_cast<std::size_t>(p->b)] +=
              (Eigen::Matrix<double, 6, 1>() << impulse, p->rb.cross(impulse)).finished();
        if (by_joints(p->a))
          now_.jointed_impulse[static_cast<std::size_t>(p->a)] -=
              (Eigen::Matrix<double, 6, 1>() << impulse, p->ra.cross(impulse)).finished();
      }
      std::vector<std::pair<int, RigidState>> jointed_start;
      for (std::size_t k = 0; k < bodies.size(); ++k) {
        RigidState& s = states[bodies[k]];
        // a jointed body goes where its joints will carry it (Moreau's midpoint rule is
        // what they do with the contact impulse as a load over the step) for the position
        // corrections and the events below, then back: its joints move it
        if (by_joints(bodies[k])) jointed_start.emplace_back(bodies[k], s);
        s.velocity = solver.v[bodies[k]];
        s.angular_velocity = solver.w[bodies[k]];
        s.position += 0.5 * h * (v0[k] + s.velocity);
        now_.travel[static_cast<std::size_t>(bodies[k])] +=
            (Eigen::Matrix<double, 6, 1>() << 0.5 * h * (v0[k] + s.velocity),
             0.5 * h * (w0[k] + s.angular_velocity))
                .finished();
        // the spin turns with the body (its body-frame angular velocity, and so its kinetic
        // energy, is kept): a world vector held while the body turns under it would put a
        // needle's fast spin about its axis onto an axis of a million times the inertia
        const Eigen::Quaterniond turn =
            (rotation_by(0.5 * h * s.angular_velocity) * rotation_by(0.5 * h * w0[k])).normalized();
        s.rotation = (turn * s.rotation).normalized();
        s.angular_velocity = turn * s.angular_velocity;
      }
      // driven partners move at their velocity (the caller sets their exact place after
      // the step); moved once per island, so put back after it
      std::vector<std::pair<int, Eigen::Vector3d>> driven;
      for (const Point& p : points)
        for (int b : {p.a, p.b})
          if (roles_[b] == ContactRole::kKinematic) driven.emplace_back(b, states[b].position);
      std::sort(driven.begin(), driven.end(),
                [](const auto& x, const auto& y) { return x.first < y.first; });
      driven.erase(std::unique(driven.begin(), driven.end(),
                               [](const auto& x, const auto& y) { return x.first == y.first; }),
                   driven.end());
      for (auto& [b, x] : driven) states[b].position += h * states[b].velocity;

      // 4. positions out of any penetration: mass-weighted pushes along the normals
      // (nonlinear Gauss-Seidel, push only), velocities untouched
      auto gap_now = [&](const Point& p) {
        const Eigen::Vector3d nrm = states[p.normal_on_a ? p.a : p.b].rotation * p.n_local;
        return nrm.dot(states[p.b].position + states[p.b].rotation * p.pb - states[p.a].position -
                       states[p.a].rotation * p.pa);
      };
      std::vector<double> pushed(points.size(), 0.0);
      double target = 1e-10;
      for (const Point& p : points)
        target = std::min(target, 1e-10 * std::max(radius_[p.a], radius_[p.b]));
      const int passes = sweeps_for(points.size(), 5, 100);
      for (int pass = 0; pass < passes; ++pass) {
        double worst = 0;
        for (std::size_t k = 0; k < points.size(); ++k) {
          const Point& p = points[k];
          const double g = gap_now(p);
          worst = std::max(worst, -g);
          if (g >= 0 && pushed[k] == 0) continue;
          if (g >= -target && g <= target) continue;
          const Eigen::Vector3d nrm = p.basis.col(0);
          const Eigen::Vector3d ca = p.ra.cross(nrm), cb = p.rb.cross(nrm);
          // the push's compliance along the normal: each side's own, and for two bodies of
          // one mechanism their coupling (a jointed body moves as its joints let it, its
          // mechanism along; it keeps the push for its joints to start from:
          // jointed_correction)
          const Solver::Wrench unit_a = (Solver::Wrench() << nrm, ca).finished(),
                               unit_b = (Solver::Wrench() << nrm, cb).finished();
          double w = unit_a.dot(solver.coupling(p.a, p.a) * unit_a) +
                     unit_b.dot(solver.coupling(p.b, p.b) * unit_b) -
                     2 * unit_a.dot(solver.coupling(p.a, p.b) * unit_b);
          if (w <= 0) continue;
          const double delta = std::max(-g / w, -pushed[k]);
          pushed[k] += delta;
          for (int side : {p.a, p.b}) {
            if (!moved(side)) continue;
            const double sign = side == p.b ? 1.0 : -1.0;
            const Eigen::Vector3d c = side == p.b ? cb : ca;
            if (solver.general[side]) {
              const Mechanism& m = solver.mechanism(side);
              for (std::size_t q = 0; q < m.bodies.size(); ++q) {
                const int body = m.bodies[q];
                const Solver::Wrench push =
                    sign * delta *
                    m.mobility.block<6, 6>(6 * static_cast<Eigen::Index>(q),
                                           6 * slot_[static_cast<std::size_t>(side)]) *
                    (side == p.b ? unit_b : unit_a);
                now_.jointed_correction[static_cast<std::size_t>(body)] += push;
                if (!moved(body)) continue;
                states[body].position += push.head<3>();
                states[body].rotation =
                    (rotation_by(push.tail<3>()) * states[body].rotation).normalized();
              }
              continue;
            }
            states[side].position += sign * delta * solver.inv_mass[side] * nrm;
            const Eigen::Quaterniond turn =
                rotation_by(sign * delta * (solver.inv_inertia[side] * c));
            states[side].rotation = (turn * states[side].rotation).normalized();
            states[side].angular_velocity =
                turn * states[side].angular_velocity;  // spin turns along
            now_.travel[static_cast<std::size_t>(side)] +=
                (Eigen::Matrix<double, 6, 1>() << sign * delta * solver.inv_mass[side] * nrm,
                 sign * delta * (solver.inv_inertia[side] * c))
                    .finished();
          }
        }
        if (worst <= std::max(target, 1e-15)) break;
      }
      double left = 0;
      for (const Point& p : points) {
        const double depth = -gap_now(p);
        left = std::max(left, depth);
        if (depth > 0.05 * std::min(radius_[p.a], radius_[p.b])) {
          char what[160];
          std::snprintf(what, sizeof what, "%.3g m (%.0f %% of the smaller one's size)", depth,
                        100 * depth / std::min(radius_[p.a], radius_[p.b]));
          throw SimulationError("contact could not be resolved: bodies '" +
                                scene_.bodies[p.a].name + "' and '" + scene_.bodies[p.b].name +
                                "' interpenetrate by " + what + " at t = " + seconds(now + h) +
                                " s; use a smaller dt");
        }
      }
      now_.max_penetration = std::max(now_.max_penetration, left);
      for (auto& [b, x] : driven) states[b].position = x;  // the next island sees them as before

      // 5. events: pairs touching now (a compressive force, or closed to rounding)
      now += h;
      remaining = remaining - h <= 1e-12 * dt ? 0.0 : remaining - h;
      std::map<std::pair<int, int>, char> touching_now;
      for (const Point& p : points) {
        const bool pressed = p.lambda[0] > 0;
        if (pressed || gap_now(p) <= 1e-9 * std::max(radius_[p.a], radius_[p.b]))
          touching_now[{p.a, p.b}] = 1;
      }
      for (const auto& [pair, on] : touching_now)
        if (!touching.count(pair)) {
          const auto m = meets.find(pair);
          const double when = m != meets.end() && m->second < h ? now - h + m->second : now;
          events_.push_back({when, true, pair.first, pair.second});
        }
      for (const auto& [pair, on] : touching)
        if (!touching_now.count(pair)) events_.push_back({now, false, pair.first, pair.second});
      touching = std::move(touching_now);
      for (const auto& [b, s] : jointed_start) states[b] = s;
      if (remaining == 0) {
        for (const Point* p : rows) {
          warm_after[{p->part_a, p->part_b}].push_back({p->pa, p->basis * p->lambda / h});
          now_.active_points += p->lambda[0] > 0;
        }
        // the links between free bodies: pressed, or within 1e-3 of the smaller one's size
        // (an elastic stage that solved the link left it to carry nothing here, and the
        // midpoint rule can open it by a little more than rounding: lost for a step, the
        // upper of two blocks on a beam on two rubber pads fell onto it every 17 steps)
        for (const Point* p : rows) {
          if (roles_[p->a] != ContactRole::kFree || roles_[p->b] != ContactRole::kFree ||
              !(p->lambda[0] > 0 || gap_now(*p) <= 1e-3 * std::min(radius_[p->a], radius_[p->b])))
            continue;
          Link link;
          link.a = p->a;
          link.b = p->b;
          link.part_a = p->part_a;
          link.part_b = p->part_b;
          link.on_a = states[p->a].position + states[p->a].rotation * p->pa;
          link.on_b = states[p->b].position + states[p->b].rotation * p->pb;
          link.normal = states[p->normal_on_a ? p->a : p->b].rotation * p->n_local;
          now_.links.push_back(link);
        }
        add_supports(rows, states, h, 1e-6 * velocity_scale);
      }
      for (int i : bodies)
        if (!states[i].position.allFinite() || !states[i].velocity.allFinite() ||
            !states[i].angular_velocity.allFinite())
          throw SimulationError("the state of body '" + scene_.bodies[i].name +
                                "' became non-finite in contact at t = " + seconds(now) + " s");
    }
    touching_after.insert(touching.begin(), touching.end());
    for (int i : bodies) in_island[i] = 1;
  }
  // pairs that touched and now have no point within reach parted during the step
  // (the islands' points were moved out as they were solved: the pairs were noted before)
  for (const auto& [pair, on] : now_.touching)
    if (!touching_after.count(pair) && !within_reach.count(pair))
      events_.push_back({t + dt, false, pair.first, pair.second});
  now_.touching = std::move(touching_after);
  now_.warm = std::move(warm_after);
  for (const auto& [pair, impulse] : pair_impulse) {
    const double f = impulse.norm() / dt;
    now_.contact_force += f;
    now_.peak_contact_force = std::max(now_.peak_contact_force, f);
  }
}

}  // namespace vproto::sim
