// The elastic contact stage of sim::Dynamics: contact between an FE body's deformed
// surface and held or driven rigid bodies, solved on the bodies' responses (the FE
// compliance from the kept factor, the floating frame's mobility).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "delassus.h"
#include "dynamics_internal.h"
#include "stage_task.h"
#include "two_threads.h"
#include "vproto/geometry/aabb_tree.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/contact.h"
#include "vproto/sim/contact_problem_io.h"
#include "vproto/sim/point_contact_solver.h"
#include "vproto/sim/sparse_cholesky.h"

namespace vproto::sim {

namespace {

// Pairs (a, b) of bodies of the given kinds that can touch: not both held still (nothing
// ever moves them: no gravity, load, velocity, drive or joint), not excluded by `nocontact`.
std::vector<std::pair<int, int>> touchable_pairs(const Scene& s, BodyKind kind_a, BodyKind kind_b) {
  const std::size_t n = s.bodies.size();
  std::vector<char> still(n, s.gravity && s.gravity->norm() > 0 ? 0 : 1);
  for (const auto& f : s.forces) still[f.body] = 0;
  for (const auto& t : s.torques) still[t.body] = 0;
  for (const auto& v : s.velocities) still[v.body] = 0;
  for (const auto& m : s.moves) still[m.body] = 0;
  for (const auto& j : s.joints) {
    still[j.body] = 0;
    if (j.other != kGround) still[j.other] = 0;
  }
  for (const auto& f : s.fixes) still[f.body] = still[f.body] || !f.region;
  std::set<std::pair<int, int>> skip;
  for (const auto& nc : s.nocontacts) {
    skip.insert({nc.body_a, nc.body_b});
    skip.insert({nc.body_b, nc.body_a});
  }
  for (const auto& j : s.joints)  // bodies a joint joins touch only through it
    if (j.other != kGround) {
      skip.insert({j.body, j.other});
      skip.insert({j.other, j.body});
    }
  const bool same = kind_a == kind_b;
  std::vector<std::pair<int, int>> out;
  for (std::size_t a = 0; a < n; ++a) {
    if (s.bodies[a].kind != kind_a) continue;
    for (std::size_t b = same ? a + 1 : 0; b < n; ++b) {
      if (s.bodies[b].kind != kind_b || (still[a] && still[b])) continue;
      if (skip.count({static_cast<int>(a), static_cast<int>(b)})) continue;
      out.push_back({static_cast<int>(a), static_cast<int>(b)});
    }
  }
  return out;
}

}  // namespace

std::vector<std::pair<int, int>> elastic_contact_pairs(const Scene& s) {
  return touchable_pairs(s, BodyKind::kElastic, BodyKind::kRigid);
}

std::vector<std::pair<int, int>> elastic_elastic_pairs(const Scene& s) {
  return touchable_pairs(s, BodyKind::kElastic, BodyKind::kElastic);
}

namespace {

// Nodes asked for times nodal forces above which the motion of the surface under contact
// forces comes from one solve with the kept factor rather than the cached columns.
constexpr double kDirectMotionWork = 4e5;
// the same at the narrow phase of a step's end, whose solve serves the correction as well
constexpr double kEndMotionDirectWork = 2e4;

// Contact problems of at least this many points form W column by column as the solve asks
// (LazyDelassus), not whole: the points of a large patch mostly carry no force.
constexpr Eigen::Index kLazyDelassusPoints = 2000;

// Contact problems of at least this many points are solved in the order of the points'
// first nodes on the surface (elastic_contact_stage).
constexpr Eigen::Index kSurfaceOrderRows = 100;

// VPROTO_DUMP_CONTACT=DIR writes each dense contact problem of at least
// VPROTO_DUMP_CONTACT_POINTS points (1,000 unless set) as DIR/contact_NNNNN_tT.bin
// (contact_problem_io.h), for `point_contact_bench --problem` to solve alone. A problem
// that cannot be written is said once on stderr; the run goes on.
void dump_contact_problem(const PointContactProblem& problem, const Eigen::VectorXd& warm,
                          const PointContactOptions& options, double time) {
  static const char* const dir = std::getenv("VPROTO_DUMP_CONTACT");
  if (!dir || !*dir) return;
  static const Eigen::Index least = [] {
    const char* points = std::getenv("VPROTO_DUMP_CONTACT_POINTS");
    return points && *points ? static_cast<Eigen::Index>(std::atol(points)) : Eigen::Index{1000};
  }();
  if (problem.free.size() / 3 < least) return;
  static int written = 0;
  static bool failed = false;
  char name[64];
  std::snprintf(name, sizeof name, "/contact_%05d_t%.6f.bin", written, time);
  try {
    write_contact_problem(std::string(dir) + name, problem, warm, options);
    ++written;
  } catch (const std::exception& e) {
    if (!failed) std::fprintf(stderr, "vproto: VPROTO_DUMP_CONTACT: %s\n", e.what());
    failed = true;
  }
}

// The contact stage's large allocations (the compliance columns a solve asks for, the dense
// Delassus matrix of its points) are checked against the memory left before they are made:
// a problem too large for the machine stops the run (exit 3) with the body, the time and
// the fix, where the system's out-of-memory killer would end it with nothing said (an LDPE
// cap snapped over a bottle neck's bead, its lip's whole ring pressed at once: 7,270 points
// on a 1 mm tet10 mesh, and the process passed 24 GB).
std::string memory_text(double bytes) {
  char text[32];
  if (bytes >= 1e9)
    std::snprintf(text, sizeof text, "%.3g GB", bytes / 1e9);
  else
    std::snprintf(text, sizeof text, "%.3g MB", bytes / 1e6);
  return text;
}

enum class ContactMemory { kColumns, kDelassus };

void demand_contact_memory(double bytes, ContactMemory what, Eigen::Index count, double time,
                           const Body& body) {
  const double limit = factor_memory_limit();
  if (bytes <= limit) return;
  char text[640];
  std::snprintf(text, sizeof text,
                "contact of '%s' at t = %.6g s: %s %ld contact %s need %s, more than the %s of "
                "memory left (VPROTO_MEMORY_LIMIT sets it): give '%s' a coarser mesh_size where "
                "it touches (now %.3g m; the points grow as its inverse square), or run where "
                "more memory is free",
                body.name.c_str(), time,
                what == ContactMemory::kColumns ? "the compliance columns of its"
                                                : "the dense Delassus matrix of its",
                static_cast<long>(count), what == ContactMemory::kColumns ? "nodes" : "points",
                memory_text(bytes).c_str(), memory_text(limit).c_str(), body.name.c_str(),
                body.tet_mesh.mesh_size);
  throw SimulationError(text);
}

// A link row's part code (Row::part): this less the link's part on its body a.
constexpr int kLinkPart = -1000000000;

using NodeColumns = Dynamics::ElasticBody::NodeColumns;

// A forced surface node of a motion: its compliance columns, the node, and its force (the
// body's axes).
struct ForcedNode {
  const NodeColumns* column;
  int node;
  Eigen::Vector3d f;
};

// Adds to out[q] (q in [q0, q1)) the motion of surface node nodes[q] (each with columns,
// `own[q]`) under the forces of `forced`: each column read down the nodes, which come in
// the columns' row order, the blocks a few nodes ahead fetched while one is summed (a node's
// sum taken column by column had every column's block miss the cache); a node that had no
// columns when a forced node's were solved reads that block from its own.
void add_column_sums(const Dynamics::ElasticBody& eb, const std::vector<ForcedNode>& forced,
                     const std::vector<int>& nodes, const std::vector<const NodeColumns*>& own,
                     std::size_t q0, std::size_t q1, std::vector<Eigen::Vector3d>* out) {
  constexpr std::size_t kAhead = 8;
  for (const ForcedNode& x : forced)
    for (std::size_t q = q0; q < q1; ++q) {
      if (q + kAhead < q1)
        if (const double* data = eb.block_data(*x.column, nodes[q + kAhead]))
          __builtin_prefetch(data);
      (*out)[q].noalias() += eb.compliance(*x.column, x.node, nodes[q], own[q]) * x.f;
    }
}

// Whether `adding` nodes' new columns fit in `budget` bytes with those kept (each at every
// node with columns and new; 72 bytes a node).
bool columns_fit(const Dynamics::ElasticBody& eb, std::size_t adding, double budget) {
  double bytes = 0;
  for (const auto& [node, c] : eb.columns) bytes += 8.0 * static_cast<double>(c.size());
  const auto held = static_cast<double>(eb.column_nodes.size() + adding);
  return bytes + 72.0 * held * static_cast<double>(adding) <= budget;
}

// The nodes with columns that keep them when the columns pass `budget` bytes: the nodes of
// `needed` (the rows' own, which would be solved again at once) and then those whose columns
// rows needed last (ElasticBody::column_use), as many as leave room for the new columns of
// `adding` nodes (each at every node kept and new). All of them when they fit; when the
// needed nodes' alone leave a quarter of the bound free, as many as leave it so (room for
// the next steps' new columns); none when the needed nodes' alone do not fit (only the
// rows' own columns are solved then).
std::vector<int> columns_to_keep(const Dynamics::ElasticBody& eb, const std::vector<int>& needed,
                                 std::size_t adding, double budget) {
  const std::size_t count = eb.column_nodes.size();
  std::vector<int> order;  // indices into column_nodes, the first kept first
  order.reserve(count);
  std::vector<char> now(count, 0);
  for (const int k : needed)
    if (eb.has_columns(k))
      now[static_cast<std::size_t>(eb.column_row[static_cast<std::size_t>(k)])] = 1;
  for (std::size_t j = 0; j < count; ++j) order.push_back(static_cast<int>(j));
  auto use = [&](int j) {
    return eb.column_use[static_cast<std::size_t>(eb.column_nodes[static_cast<std::size_t>(j)])];
  };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    if (now[static_cast<std::size_t>(a)] != now[static_cast<std::size_t>(b)])
      return now[static_cast<std::size_t>(a)] > now[static_cast<std::size_t>(b)];
    return use(a) > use(b);
  });
  const auto needed_kept = static_cast<std::size_t>(std::count(now.begin(), now.end(), 1));
  // the bytes of the first `n` of that order (n >= needed_kept), their columns kept at one
  // another's nodes only (node j's hold the nodes before it and its own batch: rows(j) / 3 of
  // them), and of the new columns
  std::vector<int> sorted;
  auto bytes = [&](std::size_t n) {
    sorted.assign(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n));
    std::sort(sorted.begin(), sorted.end());
    double total = 0;
    for (const int j : sorted) {
      const auto held = eb.columns.at(eb.column_nodes[static_cast<std::size_t>(j)]).rows() / 3;
      total += 72.0 * static_cast<double>(std::lower_bound(sorted.begin(), sorted.end(), held) -
                                          sorted.begin());
    }
    const auto fresh = static_cast<double>(adding);
    return total + 72.0 * (static_cast<double>(n) + fresh) * fresh;
  };
  std::vector<int> kept;
  if (bytes(count) <= budget) {
    kept = eb.column_nodes;
  } else if (bytes(needed_kept) <= budget) {
    if (bytes(needed_kept) <= 0.75 * budget) budget *= 0.75;
    // the most that fit, between the needed nodes alone and all (more bytes with more kept)
    std::size_t lo = needed_kept, hi = count - 1;
    while (lo < hi) {
      const std::size_t mid = (lo + hi + 1) / 2;
      if (bytes(mid) <= budget)
        lo = mid;
      else
        hi = mid - 1;
    }
    for (std::size_t q = 0; q < lo; ++q)
      kept.push_back(eb.column_nodes[static_cast<std::size_t>(order[q])]);
  }
  return kept;
}

// Keeps the columns of the nodes `keep` marks (a subset of those with columns) and drops the
// others': the kept ones lose their rows at the dropped nodes and take new places in the same
// order, so that they still hold one another's blocks as compliance() reads them.
void keep_columns(Dynamics::ElasticBody& eb, const std::vector<char>& keep) {
  const std::size_t count = eb.column_nodes.size();
  std::vector<int> place(count, -1);  // new place by old
  std::vector<int> nodes;
  for (std::size_t j = 0; j < count; ++j)
    if (keep[static_cast<std::size_t>(eb.column_nodes[j])]) {
      place[j] = static_cast<int>(nodes.size());
      nodes.push_back(eb.column_nodes[j]);
    }
  for (std::size_t j = 0; j < count; ++j) {
    const int node = eb.column_nodes[j];
    if (place[j] < 0) {
      eb.columns.erase(node);
      eb.column_row[static_cast<std::size_t>(node)] = -1;
      continue;
    }
    Dynamics::ElasticBody::NodeColumns& c = eb.columns.at(node);
    const auto held = static_cast<std::size_t>(c.rows() / 3);
    Eigen::Index rows = 0;
    for (std::size_t i = 0; i < held; ++i) rows += place[i] >= 0 ? 3 : 0;
    Dynamics::ElasticBody::NodeColumns kept(rows, 3);
    for (std::size_t i = 0; i < held; ++i)
      if (place[i] >= 0)
        kept.middleRows<3>(3 * place[i]) = c.middleRows<3>(3 * static_cast<Eigen::Index>(i));
    c = std::move(kept);
    eb.column_row[static_cast<std::size_t>(node)] = place[j];
  }
  eb.column_nodes = std::move(nodes);
}

// Orders the surface nodes whose motions are asked for: first those read from a
// deformation (`from_deformation`, in their order), then those summed over the compliance
// columns, in the columns' row order, each with its own columns in `own` (null for the
// first). Returns how many come first.
template <class FromDeformation>
std::size_t split_by_columns(const Dynamics::ElasticBody& eb,
                             const FromDeformation& from_deformation, std::vector<int>* nodes,
                             std::vector<const NodeColumns*>* own) {
  const auto summed = std::stable_partition(nodes->begin(), nodes->end(), from_deformation);
  const auto first_summed = static_cast<std::size_t>(summed - nodes->begin());
  std::sort(summed, nodes->end(), [&](int a, int b) {
    return eb.column_row[static_cast<std::size_t>(a)] < eb.column_row[static_cast<std::size_t>(b)];
  });
  own->assign(nodes->size(), nullptr);
  for (std::size_t q = first_summed; q < nodes->size(); ++q)
    (*own)[q] = &eb.columns.at((*nodes)[q]);
  return first_summed;
}

// Removes the items that `marked` marks (those past its end stay), keeping the others' order.
template <class T>
void remove_marked(std::vector<T>* items, const std::vector<char>& marked) {
  std::size_t kept = 0;
  for (std::size_t q = 0; q < items->size(); ++q)
    if (q >= marked.size() || !marked[q]) {
      if (kept != q) (*items)[kept] = std::move((*items)[q]);
      ++kept;
    }
  items->resize(kept);
}

// two unit vectors square to n and to each other
void tangents(const Eigen::Vector3d& n, Eigen::Vector3d* t1, Eigen::Vector3d* t2) {
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *t1 = n.cross(helper).normalized();
  *t2 = n.cross(*t1);
}

// A rigid partner's motion over a step, x -> x1 + turn (x - x0), and (free or jointed)
// how it answers contact: its mobility times dt^2, as a floating frame's.
struct PartnerMotion {
  bool movable = false;
  Eigen::Vector3d x0 = Eigen::Vector3d::Zero(), x1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< of its centre
  Eigen::Matrix<double, 6, 6> mobility = Eigen::Matrix<double, 6, 6>::Zero();
  /// What its velocity jump takes (times dt^2, as `mobility`): its mobility, or for a body
  /// answering with its supports held, its mobility with only their normals held (the rigid
  /// contacts that follow in the step decide what friction holds).
  Eigen::Matrix<double, 6, 6> jump_mobility = Eigen::Matrix<double, 6, 6>::Zero();
  /// How the forces of the elastic contact stages still to come (a wrench, as in their last
  /// step) move it over the step (displacement, rotation vector), as `x1` and `turn` take
  /// them: as loads of its step or as a jump.
  Eigen::Matrix<double, 6, 6> later_response = Eigen::Matrix<double, 6, 6>::Zero();
  /// The turn (rotation vector) that the forces of the stages before and after this one
  /// give a rigid partner over the step: taken to first order, as the Delassus matrix takes
  /// the rows' own. (Taken exactly, as the turn of its free motion, a steel beam on two
  /// rubber pads, each pad's stage turning it against the other's, saw its ends drawn
  /// apart by x phi^2 / 2 a step, 8 nm at 1.7 ms steps, and the pads' friction grew equal
  /// and opposite at 0.66 N/s.)
  Eigen::Vector3d later_turn = Eigen::Vector3d::Zero();
  /// How far its material point at p travels over the step without contact.
  Eigen::Vector3d shift(const Eigen::Vector3d& p) const {
    return x1 - x0 + (turn - Eigen::Matrix3d::Identity()) * (p - x0) + later_turn.cross(p - x0);
  }
  /// How far a velocity jump carries it over the step, per unit (times dt) of the jump:
  /// the identity, or for a body its last step's rows held, Dynamics::held_travel_.
  Eigen::Matrix<double, 6, 6> travel = Eigen::Matrix<double, 6, 6>::Identity();
  /// How far a velocity jump (times dt, as mobility * wrench) carries its point at p.
  Eigen::Vector3d jump_shift(const Eigen::Matrix<double, 6, 1>& jump,
                             const Eigen::Vector3d& p) const {
    const Eigen::Matrix<double, 6, 1> moved = travel * jump;
    return moved.head<3>() + moved.tail<3>().cross(p - x0);
  }
  /// Rows in the directions `d` (columns) at p: their Jacobian on the partner's motion.
  Eigen::Matrix<double, 3, 6> jacobian(const Eigen::Matrix3d& d, const Eigen::Vector3d& p) const {
    Eigen::Matrix<double, 3, 6> j;
    for (int k = 0; k < 3; ++k)
      j.row(k) << d.col(k).transpose(), (p - x0).cross(d.col(k)).transpose();
    return j;
  }
};

// A free rigid body's mobility (world axes): M^-1 for a force, R I^-1 R' for a torque.
Eigen::Matrix<double, 6, 6> free_mobility(const RigidInertia& inertia, const RigidState& s) {
  const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  m.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / inertia.mass;
  m.bottomRightCorner<3, 3>() = r * inertia.inertia.inverse() * r.transpose();
  return m;
}

// A free rigid body held by supports (ContactSystem::Support; on a driven body, moving
// with it) over a step: its mobility
// with their rows held (each normal; a sticking point's two tangents too), the same with
// only the normals held (`jump`), and where its loads and the supports' sliding friction
// carry it, projected on what the rows allow.
RigidState supported_motion(const RigidState& s, const RigidInertia& inertia,
                            const std::vector<ContactSystem::Support>& supports,
                            const Eigen::Vector3d& force, const Eigen::Vector3d& torque, double dt,
                            Eigen::Matrix<double, 6, 6>* mobility,
                            Eigen::Matrix<double, 6, 6>* jump) {
  const Eigen::Matrix<double, 6, 6> minv = free_mobility(inertia, s);
  std::vector<Eigen::Matrix<double, 1, 6>> rows, normals;
  std::vector<double> row_speed;  // how fast each row's direction moves (a driven support)
  Eigen::Matrix<double, 6, 1> load;
  const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
  const Eigen::Matrix3d world_inertia = r * inertia.inertia * r.transpose();
  load << force, torque - s.angular_velocity.cross(world_inertia * s.angular_velocity);
  for (const ContactSystem::Support& sp : supports) {
    const Eigen::Vector3d lever = sp.point - s.position;
    auto row = [&](const Eigen::Vector3d& d) {
      return (Eigen::Matrix<double, 1, 6>() << d.transpose(), lever.cross(d).transpose())
          .finished();
    };
    rows.push_back(row(sp.normal));
    row_speed.push_back(sp.normal.dot(sp.velocity));
    normals.push_back(rows.back());
    if (sp.sticking) {
      const Eigen::Vector3d helper =
          std::abs(sp.normal.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      const Eigen::Vector3d t1 = sp.normal.cross(helper).normalized(), t2 = sp.normal.cross(t1);
      rows.push_back(row(t1));
      rows.push_back(row(t2));
      row_speed.push_back(t1.dot(sp.velocity));
      row_speed.push_back(t2.dot(sp.velocity));
    } else {
      load.head<3>() += sp.friction;
      load.tail<3>() += lever.cross(sp.friction);
    }
  }
  auto stacked = [](const std::vector<Eigen::Matrix<double, 1, 6>>& list) {
    Eigen::MatrixXd j(static_cast<Eigen::Index>(list.size()), 6);
    for (std::size_t k = 0; k < list.size(); ++k) j.row(static_cast<Eigen::Index>(k)) = list[k];
    return j;
  };
  Eigen::VectorXd velocity(6);
  velocity << s.velocity, s.angular_velocity;
  const Eigen::VectorXd speeds = Eigen::Map<const Eigen::VectorXd>(
      row_speed.data(), static_cast<Eigen::Index>(row_speed.size()));
  *mobility = held_inverse_mass(minv, stacked(rows), &velocity, &speeds);
  *jump = held_inverse_mass(minv, stacked(normals));
  const Eigen::Matrix<double, 6, 1> u0 = velocity;
  const Eigen::Matrix<double, 6, 1> u1 = u0 + dt * (*mobility * load);
  RigidState end = s;
  end.velocity = u1.head<3>();
  end.angular_velocity = u1.tail<3>();
  end.position += 0.5 * dt * (u0.head<3>() + u1.head<3>());
  const Eigen::Vector3d turn = 0.5 * dt * (u0.tail<3>() + u1.tail<3>());
  if (turn.norm() > 0)
    end.rotation =
        (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * end.rotation)
            .normalized();
  return end;
}

Eigen::Isometry3d pose_of(const RigidState& s) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = s.rotation.toRotationMatrix();
  p.translation() = s.position;
  return p;
}

}  // namespace

Eigen::VectorXd Dynamics::elastic_load(int body, double t) const {
  const ElasticBody& e = *elastic_[body];
  Eigen::VectorXd f = e.model.load_at(t);
  if (!e.floating) return f;
  // in the frame's axes; the decoupled form of Eqs. 26-27: gravity and point forces act on
  // the frame; the deformation answers the region loads, the contact forces and (in the
  // contact stage, for bodies that can touch) the frame's acceleration as inertial loads
  const Eigen::Matrix3d rt = states_[body].rotation.toRotationMatrix().transpose();
  for (Eigen::Index k = 0; k + 2 < f.size(); k += 3) f.segment<3>(k) = rt * f.segment<3>(k);
  return f;
}

Eigen::MatrixX3d Dynamics::surface_positions(int body, const Eigen::VectorXd& u,
                                             const RigidState& frame) const {
  const ElasticBody& e = *elastic_[body];
  const geometry::TetMesh& mesh = scene_.bodies[body].tet_mesh;
  const Eigen::Vector3d c = scene_.bodies[body].mass_properties.centroid;
  const Eigen::Matrix3d r = frame.rotation.toRotationMatrix();
  const Eigen::Matrix<double, 6, 1> rigid = e.rigid_part(u);
  Eigen::MatrixX3d x(static_cast<Eigen::Index>(e.surface.nodes.size()), 3);
  for (std::size_t k = 0; k < e.surface.nodes.size(); ++k) {
    const int node = e.surface.nodes[k];
    const Eigen::Vector3d at = mesh.nodes.row(node).transpose() - c;
    const Eigen::Vector3d local =
        at + u.segment<3>(3 * node) - ElasticBody::rigid_motion(rigid, at);
    x.row(static_cast<Eigen::Index>(k)) = (frame.position + r * local).transpose();
  }
  return x;
}

void Dynamics::update_absolute(int body) {
  ElasticBody& e = *elastic_[body];
  const geometry::TetMesh& mesh = scene_.bodies[body].tet_mesh;
  const Eigen::Vector3d c = scene_.bodies[body].mass_properties.centroid;
  const RigidState& s = states_[body];
  const Eigen::Matrix3d r = s.rotation.toRotationMatrix();
  const Eigen::VectorXd& u = e.solver->displacement();
  const Eigen::Matrix<double, 6, 1> rigid = e.rigid_part(u);
  for (Eigen::Index k = 0; k < mesh.nodes.rows(); ++k) {
    const Eigen::Vector3d x0 = mesh.nodes.row(k).transpose();
    const Eigen::Vector3d local = u.segment<3>(3 * k) - ElasticBody::rigid_motion(rigid, x0 - c);
    e.absolute_u.segment<3>(3 * k) = s.position + r * (x0 - c + local) - x0;
  }
}

void Dynamics::rigid_modes(int body) {
  ElasticBody& e = *elastic_[static_cast<std::size_t>(body)];
  const geometry::TetMesh& mesh = scene_.bodies[static_cast<std::size_t>(body)].tet_mesh;
  const Eigen::Vector3d c = scene_.bodies[static_cast<std::size_t>(body)].mass_properties.centroid;
  const Eigen::Index dofs = e.model.fe.dofs;
  // the rigid motions of the frame at the nodes: three translations, three rotations
  Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(dofs, 6);
  for (Eigen::Index k = 0; k < mesh.nodes.rows(); ++k)
    phi.middleRows<3>(3 * k) = ElasticBody::rigid_rows(mesh.nodes.row(k).transpose() - c);
  e.inertia_load.resize(dofs, 6);
  for (int j = 0; j < 6; ++j)
    e.inertia_load.col(j) = symmetric_times(e.model.fe.mass(), phi.col(j));
  // (Phi' M Phi: the FE body's mass and inertia about its centroid)
  const Eigen::Matrix<double, 6, 6> rigid_mass = phi.transpose() * e.inertia_load;
  e.rigid_mass_inverse = (0.5 * (rigid_mass + rigid_mass.transpose()))
                             .ldlt()
                             .solve(Eigen::Matrix<double, 6, 6>::Identity());
}

void Dynamics::frame_inertia(int body) {
  ElasticBody& e = *elastic_[static_cast<std::size_t>(body)];
  if (e.inertia_load.size() == 0) rigid_modes(body);
  e.inertia_response = e.solver->response(e.inertia_load.sparseView());
  elastic_stats_.response_solves += 6;
  const Eigen::Matrix<double, 6, 6> coupling = e.inertia_load.transpose() * e.inertia_response;
  e.inertia_coupling = 0.5 * (coupling + coupling.transpose());
}

void Dynamics::elastic_contact_stage(double dt, const std::vector<RigidState>& before,
                                     std::vector<Eigen::Vector3d>& forces,
                                     std::vector<Eigen::Vector3d>& torques,
                                     std::vector<char>& done) {
  if (std::none_of(elastic_.begin(), elastic_.end(),
                   [](const auto& e) { return e && e->touchable; }))
    return;
  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  const double t_mid = time_ + 0.5 * dt, t_end = time_ + dt;
  elastic_points_ = 0;
  elastic_force_ = 0;
  elastic_stats_.threads = contact_threads();
  choose_owners();
  std::set<std::pair<int, int>> touching;

  // where the floating frames and the free or jointed rigid partners go without contact
  // forces
  std::vector<RigidState> free_motion = before;
  std::vector<char> free_moving(elastic_.size(), 0);
  for (std::size_t i = 0; i < elastic_.size(); ++i) {
    const ElasticBody* e = elastic_[i].get();
    if (!e || !e->touchable) continue;
    if (e->floating) free_moving[i] = 1;
    for (int r : e->partners)
      if (movable_partner(r)) free_moving[static_cast<std::size_t>(r)] = 1;
  }
  bool any_jointed = false;
  for (std::size_t i = 0; i < elastic_.size(); ++i) {
    if (!free_moving[i]) continue;
    if (joints_->moves(static_cast<int>(i)))
      any_jointed = true;
    else
      step_rigid(free_motion[i], inertias_[i], forces[i], torques[i], dt);
  }
  if (any_jointed) joints_->step(free_motion, inertias_, forces, torques, dt);

  // jointed bodies of one mechanism move one another: how body q's motion answers a wrench
  // on body r (their mechanism's mobility block at the step's start, times dt^2 as a
  // partner's own `mobility`); null when they are not (or q is r)
  std::map<int, Eigen::MatrixXd> mechanism_mobility;  // by mechanism, times dt^2
  auto coupled = [&](int q, int r) -> const Eigen::MatrixXd* {
    const int m = joints_->mechanism_of(q);
    if (q == r || m < 0 || joints_->mechanism_of(r) != m) return nullptr;
    // (computed at the first call: the Delassus threads only read it)
    const auto found = mechanism_mobility.find(m);
    if (found != mechanism_mobility.end()) return &found->second;
    Eigen::MatrixXd& p = mechanism_mobility[m];
    p = joints_->mechanism_mobility(before, inertias_, m) * (dt * dt);
    return &p;
  };
  auto coupling = [&](int q, int r) -> Eigen::Matrix<double, 6, 6> {
    const Eigen::MatrixXd* p = coupled(q, r);
    return p->block<6, 6>(6 * joints_->slot(q), 6 * joints_->slot(r));
  };
  // the rest of a jointed body's mechanism moves along with its velocity jump under the
  // wrench w (an impulse dt w; the joints' reactions do no work)
  auto jump_along = [&](int body, const Eigen::Matrix<double, 6, 1>& w) {
    const int mech = joints_->mechanism_of(body);
    if (mech < 0) return;
    for (const int q : joints_->mechanisms()[static_cast<std::size_t>(mech)]) {
      if (q == body) continue;
      const Eigen::Matrix<double, 6, 1> along = coupling(q, body) * w / dt;
      states_[q].velocity += along.head<3>();
      states_[q].angular_velocity += along.tail<3>();
    }
  };
  // where a jointed body's joints carry it over the step: its motion without contact and (to
  // first order) the velocity jumps earlier stages of this step gave it
  auto jointed_end = [&](int r) {
    RigidState end = free_motion[static_cast<std::size_t>(r)];
    const Eigen::Vector3d dv = states_[r].velocity - before[r].velocity,
                          dw = states_[r].angular_velocity - before[r].angular_velocity;
    end.position += dv * dt;
    if (dw.norm() > 0)
      end.rotation =
          (Eigen::Quaterniond(Eigen::AngleAxisd(dw.norm() * dt, dw.normalized())) * end.rotation)
              .normalized();
    end.velocity += dv;
    end.angular_velocity += dw;
    return end;
  };
  // the reactions of a body's last contact forces on its elastic partners: loads of their
  // steps, which come later in this stage
  auto load_partners = [&](const ElasticBody& owner) {
    for (const auto& [other, forces] : owner.last_partner_forces) {
      ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      // (world axes; a floating partner's load in its frame's axes at the step's start)
      Eigen::Matrix3d rt = Eigen::Matrix3d::Identity();
      if (eb.floating)
        rt = before[static_cast<std::size_t>(other)].rotation.toRotationMatrix().transpose();
      for (const auto& [node, f] : forces)
        eb.pending_load.segment<3>(3 * eb.surface.nodes[static_cast<std::size_t>(node)]) += rt * f;
    }
  };
  // a free rigid body on supports (the plate under a tray) takes the stages' contact
  // forces as loads of the step (below), and a stage's view of where it goes takes those
  // of the stages still to come as they were in their last step: each cube's stage on a
  // tray then sees the tray carry the other's friction too, not as if it alone touched it
  auto on_supports = [&](int r) {
    return !elastic_[static_cast<std::size_t>(r)] && !joints_->moves(r) && contact_ &&
           !contact_->supports(r).empty();
  };
  // one that all its supports held by friction in the last step takes the stages' forces as
  // loads of the step whole: the rigid contact that follows holds it against them in one
  // solve (as a jump at the step's start that the supports' friction then stops, a tray
  // under two pushing cubes crept by half a step's travel every step). Else it jumps, as
  // a free body does, so that a contact that closes ends the step at rest (as a load, the
  // rows' forces would double to close it and it would bounce off)
  auto held_still = [&](int r) {
    if (!on_supports(r)) return false;
    for (const ContactSystem::Support& sp : contact_->supports(r))
      if (!sp.sticking) return false;
    return true;
  };
  // (of rigid bodies that contact moves: free or jointed; a body of a mechanism moves the
  // others along)
  auto rigid_movable = [&](int r) {
    return !elastic_[static_cast<std::size_t>(r)] && movable_partner(r);
  };
  // a stage's wrenches on its movable partners as the stages before it take them: its last
  // step's, or in a pass redone (coupled_stages) the pass before's; a floating body's stage
  // on its own frame too, by its own key (ElasticBody::last_own_wrench)
  auto stage_wrench = [&](int body) -> PartnerWrenches {
    if (pass_wrenches_)
      if (const auto it = pass_wrenches_->find(body); it != pass_wrenches_->end())
        return it->second;
    return stage_wrenches(body);
  };
  // (a floating elastic body's frame: the stages after the one that solves it move it too)
  auto floating_frame = [&](int r) { return floating(r); };
  // and its forces on floating bodies' surface nodes (its own by its own key), likewise
  auto pass_or_stage_loads = [&](int body) -> NodeLoads {
    if (pass_loads_)
      if (const auto it = pass_loads_->find(body); it != pass_loads_->end()) return it->second;
    return stage_loads(body);
  };
  // the links between free rigid bodies (ContactSystem::Link) a stage took as rows of its
  // own: the stages after it leave them (their bodies move as its forces left them)
  std::set<std::pair<int, int>> links_taken;
  std::map<int, Eigen::Matrix<double, 6, 1>> later;  // by body: force, torque
  // by floating body: the nodal forces to come (frame axes at the step's start, its dofs)
  std::map<int, Eigen::VectorXd> later_loads;
  auto add_loads = [&](int body, double sign) {
    for (const auto& [r, forces] : pass_or_stage_loads(body)) {
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(r)];
      Eigen::VectorXd& load = later_loads[r];
      if (load.size() == 0) load = Eigen::VectorXd::Zero(eb.solver->displacement().size());
      const Eigen::Matrix3d rt =
          before[static_cast<std::size_t>(r)].rotation.toRotationMatrix().transpose();
      for (const auto& [node, f] : forces)
        load.segment<3>(3 * eb.surface.nodes[static_cast<std::size_t>(node)]) += sign * (rt * f);
    }
  };
  for (const int body : stage_order_) {
    const ElasticBody* e = elastic_[static_cast<std::size_t>(body)].get();
    if (!e || !e->touchable) continue;
    for (const auto& [r, w] : stage_wrench(body))
      if (rigid_movable(r) || floating_frame(r))
        later.try_emplace(r, Eigen::Matrix<double, 6, 1>::Zero()).first->second += w;
    add_loads(body, 1);
  }
  // the forces of the other stages of a group on the bodies they share (by stage, by body),
  // as the last solve of their rows gave them: each stage's view of where those bodies go
  std::map<int, std::map<int, Eigen::Matrix<double, 6, 1>>> group_wrenches;
  // and on the bodies' surface nodes (by stage, by body: node, force in the body's axes)
  using NodeList = std::vector<std::pair<int, Eigen::Vector3d>>;
  std::map<int, std::map<int, NodeList>> group_nodes;
  std::set<int> in_group;  // the stages of the group being solved (none when one alone)
  // the compliance columns of surface nodes (kept for the run: ElasticBody::columns)
  auto body_of = [&](const ElasticBody& eb) {  // (the scene's body of its elastic state)
    std::size_t i = 0;
    while (i < elastic_.size() && elastic_[i].get() != &eb) ++i;
    VPROTO_DEMAND(i < elastic_.size());
    return i;
  };
  // (the nodes `wanted` that have none yet get their columns, at every node with columns:
  // those before them and themselves)
  auto fill_columns = [&](ElasticBody& eb, std::vector<int> wanted) {
    std::vector<int> nodes;
    const std::size_t count = eb.surface.nodes.size();
    if (eb.column_row.size() != count) eb.column_row.assign(count, -1);
    // (in the surface's order: neighbours mostly next to each other in the columns)
    std::sort(wanted.begin(), wanted.end());
    for (const int k : wanted)
      if (k >= 0 && eb.column_row[static_cast<std::size_t>(k)] < 0) {
        eb.column_row[static_cast<std::size_t>(k)] = static_cast<int>(eb.column_nodes.size());
        eb.column_nodes.push_back(k);
        nodes.push_back(k);
      }
    if (nodes.empty()) return;
    const Eigen::Index body_dofs = eb.solver->displacement().size();
    const auto held = static_cast<Eigen::Index>(eb.column_nodes.size());
    std::vector<Eigen::Index> held_dofs;
    held_dofs.reserve(static_cast<std::size_t>(3 * held));
    for (const int k : eb.column_nodes)
      for (int q = 0; q < 3; ++q)
        held_dofs.push_back(3 * eb.surface.nodes[static_cast<std::size_t>(k)] + q);
    // the new columns, and the solve's own while they are copied: in one solve when both
    // fit in half the memory left, else in solves of as many nodes as a tenth of it holds
    const double per_node = 72.0 * static_cast<double>(held);
    const double kept = per_node * static_cast<double>(nodes.size());
    std::size_t chunk = nodes.size();
    const double limit = factor_memory_limit();
    if (2 * kept > 0.5 * limit)
      chunk = std::max<std::size_t>(16, static_cast<std::size_t>(0.1 * limit / per_node));
    demand_contact_memory(kept + per_node * static_cast<double>(std::min(chunk, nodes.size())),
                          ContactMemory::kColumns, static_cast<Eigen::Index>(nodes.size()), time_,
                          scene_.bodies[body_of(eb)]);
    for (std::size_t from = 0; from < nodes.size(); from += chunk) {
      const std::size_t to = std::min(nodes.size(), from + chunk);
      Eigen::SparseMatrix<double> ct(body_dofs, 3 * static_cast<Eigen::Index>(to - from));
      std::vector<Eigen::Triplet<double>> entries;
      for (std::size_t q = from; q < to; ++q)
        for (int k = 0; k < 3; ++k)
          entries.emplace_back(3 * eb.surface.nodes[static_cast<std::size_t>(nodes[q])] + k,
                               static_cast<int>(3 * (q - from)) + k, 1.0);
      ct.setFromTriplets(entries.begin(), entries.end());
      const Eigen::MatrixXd y = eb.solver->response_at(ct, held_dofs);
      elastic_stats_.response_solves += ct.cols();
      column_solves_ += ct.cols();
      for (std::size_t q = from; q < to; ++q)
        eb.columns[nodes[q]] = y.middleCols<3>(3 * static_cast<Eigen::Index>(q - from));
    }
  };
  // each stage's forces of the last solve on the bodies its rows move (frames: wrenches by
  // its frame sides' signs; surface nodes: by its node sides'), handed to the other stages of
  // the group as their view of those bodies
  auto hand_on = [&](const std::vector<StageRequest*>& requests) {
    std::map<int, std::map<int, Eigen::Matrix<double, 6, 1>>> own;
    std::map<int, std::map<int, NodeList>> own_nodes;
    for (const StageRequest* q : requests)
      for (std::size_t r = 0; r < q->sides->size(); ++r) {
        const RowSides& row = (*q->sides)[r];
        const Eigen::Vector3d l = q->solution->lambda.segment<3>(3 * static_cast<Eigen::Index>(r));
        if (l.squaredNorm() == 0) continue;
        for (int x = 0; x < row.frame_count; ++x) {
          const FrameSide& f = row.frames[static_cast<std::size_t>(x)];
          own[q->body]
              .try_emplace(f.id, Eigen::Matrix<double, 6, 1>::Zero())
              .first->second.noalias() += f.sign * (f.jac.transpose() * l);
        }
        for (int x = 0; x < row.node_count; ++x) {
          const NodeSide& n = row.nodes[static_cast<std::size_t>(x)];
          const Eigen::Vector3d f = n.sign * (n.basis * l);
          for (std::size_t k = 0; k < 3; ++k)
            if (n.nodes[k] >= 0) own_nodes[q->body][n.id].push_back({n.nodes[k], n.weights[k] * f});
        }
      }
    for (const int m : in_group) {
      auto& view = group_wrenches[m];
      auto& nodes = group_nodes[m];
      view.clear();
      nodes.clear();
      for (const auto& [other, ws] : own)
        if (other != m)
          for (const auto& [r, w] : ws)
            view.try_emplace(r, Eigen::Matrix<double, 6, 1>::Zero()).first->second += w;
      for (const auto& [other, bodies] : own_nodes)
        if (other != m)
          for (const auto& [x, list] : bodies)
            nodes[x].insert(nodes[x].end(), list.begin(), list.end());
    }
  };
  // (in a group, a stage's rows on another's body took its columns before that stage's own
  // rows may have dropped them to bound their memory (add_columns): every column the rows
  // read is solved again where missing, and looked up again, before they are assembled)
  auto bring_up = [&](std::vector<RowSides>* sides) {
    std::map<int, std::set<int>> needed;
    for (const RowSides& row : *sides)
      for (int x = 0; x < row.node_count; ++x) {
        const NodeSide& n = row.nodes[static_cast<std::size_t>(x)];
        for (const int node : n.nodes)
          if (node >= 0) needed[n.id].insert(node);
      }
    for (const auto& [id, nodes] : needed) {
      ElasticBody& eb = *elastic_[static_cast<std::size_t>(id)];
      fill_columns(eb, std::vector<int>(nodes.begin(), nodes.end()));
    }
    for (RowSides& row : *sides)
      for (int x = 0; x < row.node_count; ++x) {
        NodeSide& n = row.nodes[static_cast<std::size_t>(x)];
        for (std::size_t k = 0; k < 3; ++k)
          if (n.nodes[k] >= 0) n.columns[k] = &n.body->columns.at(n.nodes[k]);
      }
  };
  // One solve of the rows of one stage, or of the stages of a group together: W of all
  // their rows from their sides (a body two stages touch couples their rows), the forces
  // handed back to each.
  // (a solve's effort in the stage's figures)
  auto count_solve = [&](const PointContactSolution& sol, Clock::time_point started) {
    elastic_stats_.solve_seconds += std::chrono::duration<double>(Clock::now() - started).count();
    elastic_stats_.sweeps += sol.sweeps;
    elastic_stats_.newton_iterations += sol.newton_iterations;
    if (!sol.converged) {
      ++elastic_stats_.unconverged;
      elastic_stats_.worst_residual = std::max(elastic_stats_.worst_residual, sol.residual);
    }
  };
  auto solve_rows = [&](const std::vector<StageRequest*>& requests, double step) {
    if (requests.size() == 1) {
      StageRequest& q = *requests[0];
      if (in_group.size() > 1) bring_up(q.sides);
      const auto rows = static_cast<Eigen::Index>(q.sides->size());
      const Body& owner = scene_.bodies[static_cast<std::size_t>(q.body)];
      if (rows >= kLazyDelassusPoints) {
        // W formed column by column as the solve asks (its forced and closed points')
        LazyDelassus lazy(*q.sides, *q.mobility, *q.floating, step, [&](double bytes) {
          demand_contact_memory(bytes, ContactMemory::kDelassus, rows, time_, owner);
        });
        q.problem->w.resize(0, 0);
        q.problem->columns = &lazy;
        const auto solve_started = Clock::now();
        *q.solution = solve_point_contacts(*q.problem, *q.warm, q.options);
        q.problem->columns = nullptr;
        count_solve(*q.solution, solve_started);
        elastic_stats_.delassus_seconds +=
            std::chrono::duration<double>(solve_started - q.started).count() + lazy.seconds();
        elastic_stats_.solve_seconds -= lazy.seconds();
        ++elastic_stats_.lazy_solves;
        elastic_stats_.lazy_columns += lazy.formed();
        elastic_stats_.lazy_points += rows;
      } else {
        demand_contact_memory(72.0 * static_cast<double>(rows) * static_cast<double>(rows),
                              ContactMemory::kDelassus, rows, time_, owner);
        assemble_delassus(*q.sides, *q.mobility, *q.floating, step, &q.problem->w);
        const auto solve_started = Clock::now();
        elastic_stats_.delassus_seconds +=
            std::chrono::duration<double>(solve_started - q.started).count();
        dump_contact_problem(*q.problem, *q.warm, q.options, time_);  // (its time: the solve's)
        *q.solution = solve_point_contacts(*q.problem, *q.warm, q.options);
        count_solve(*q.solution, solve_started);
      }
      if (in_group.size() > 1) hand_on(requests);
      return;
    }
    const auto assembly_started = Clock::now();
    std::vector<RowSides> sides;
    std::vector<FloatingSide> floating_sides;
    std::map<int, const FrameMobility*> mobility_by_frame;  // (the stage whose rows move it)
    PointContactProblem joint;
    Eigen::Index total = 0;
    for (const StageRequest* q : requests) total += q->problem->free.size();
    joint.free.resize(total);
    Eigen::VectorXd warm(total);
    PointContactOptions options = requests[0]->options;
    Eigen::Index at = 0;
    for (const StageRequest* q : requests) {
      sides.insert(sides.end(), q->sides->begin(), q->sides->end());
      for (const FloatingSide& f : *q->floating)  // (a body two stages' rows move: once)
        if (std::none_of(floating_sides.begin(), floating_sides.end(),
                         [&](const FloatingSide& g) { return g.id == f.id; }))
          floating_sides.push_back(f);
      for (const RowSides& row : *q->sides)
        for (int x = 0; x < row.frame_count; ++x)
          mobility_by_frame.try_emplace(row.frames[static_cast<std::size_t>(x)].id, q->mobility);
      const Eigen::Index n = q->problem->free.size();
      joint.free.segment(at, n) = q->problem->free;
      joint.mu.insert(joint.mu.end(), q->problem->mu.begin(), q->problem->mu.end());
      warm.segment(at, n) = q->warm->size() == n ? *q->warm : Eigen::VectorXd::Zero(n);
      options.tolerance = std::min(options.tolerance, q->options.tolerance);
      at += n;
    }
    bring_up(&sides);
    demand_contact_memory(8.0 * static_cast<double>(total) * static_cast<double>(total),
                          ContactMemory::kDelassus, total / 3, time_,
                          scene_.bodies[static_cast<std::size_t>(requests[0]->body)]);
    const FrameMobility mobility = [&](int a, int b) -> std::optional<Eigen::Matrix<double, 6, 6>> {
      const auto it = mobility_by_frame.find(a);
      if (it == mobility_by_frame.end()) return std::nullopt;
      return (*it->second)(a, b);
    };
    assemble_delassus(sides, mobility, floating_sides, step, &joint.w);
    const auto solve_started = Clock::now();
    elastic_stats_.delassus_seconds +=
        std::chrono::duration<double>(solve_started - assembly_started).count();
    options.newton_damping_floor = 1e-6;  // (PointContactOptions: the joint problem's)
    const PointContactSolution sol = solve_point_contacts(joint, warm, options);
    count_solve(sol, solve_started);
    ++elastic_stats_.joint_solves;
    elastic_stats_.joint_rows += total / 3;
    // each stage's share
    at = 0;
    for (StageRequest* q : requests) {
      const Eigen::Index n = q->problem->free.size();
      *q->solution = sol;
      q->solution->lambda = sol.lambda.segment(at, n);
      at += n;
    }
    hand_on(requests);
  };
  auto stage = [&](const int body, const bool alone) -> StageTask {
    const auto i = static_cast<std::size_t>(body);
    ElasticBody* e = elastic_[i].get();
    ElasticDynamics& solver = *e->solver;
    const Body& b = scene_.bodies[i];
    // rest: constant loads, partners still, nothing moved for a few steps (not on a
    // mechanism of moving rigid bodies: they move it)
    const int mech = joints_->mechanism_of(body);
    bool steady = e->floating &&
                  (mech < 0 || joints_->mechanisms()[static_cast<std::size_t>(mech)].size() == 1);
    for (const auto& f : scene_.forces)
      if (f.body == body && f.ramp > time_) steady = false;
    for (int r : e->partners)
      if (driven_[r] >= 0 || movable_partner(r)) steady = false;
    for (int r : e->elastic_partners) {
      if (driven_[r] >= 0) steady = false;
      // a floating partner that moved in its last step (its own contacts can move it)
      const ElasticBody& ep = *elastic_[static_cast<std::size_t>(r)];
      const double hr = scene_.bodies[static_cast<std::size_t>(r)].tet_mesh.mesh_size;
      if (ep.floating && !ep.resting &&
          !((before[r].position - ep.last_frame_position).norm() < 1e-7 * hr &&
            ep.last_motion < 1e-7 * hr))
        steady = false;
    }
    for (int o : e->floating_owners) {  // an owner that moved this step can push it
      const ElasticBody& eo = *elastic_[static_cast<std::size_t>(o)];
      if (!eo.resting && eo.still_steps == 0) steady = false;
    }
    // a floating body held only through rows its owners' stages solve (it has none of its
    // own) rests with them: its loads are then their last reactions, step after step
    bool owners_resting = !e->floating_owners.empty() && e->last_forces.empty();
    for (int o : e->floating_owners)
      if (!elastic_[static_cast<std::size_t>(o)]->resting) owners_resting = false;
    if (steady && (!e->last_forces.empty() || owners_resting)) {
      const double h = b.tet_mesh.mesh_size;
      // nothing moves by more than rounding and the contact force on the frame has
      // settled to 1e-6 of itself
      const bool still = (before[i].position - e->last_frame_position).norm() < 1e-7 * h &&
                         e->last_motion < 1e-7 * h &&
                         e->force_change <= 1e-6 * e->last_frame_force.norm();
      e->still_steps = still ? e->still_steps + 1 : 0;
      if (e->still_steps >= 5) e->resting = true;
    } else {
      e->still_steps = 0;
      e->resting = false;
    }
    if (!alone) {
      // a group's floating bodies rest together or not at all: one at rest holds the others
      // with its last forces only, not with rows (a loose mat asleep under two cubes that a
      // push pressed together: their pair's rows, solved without the mat's, slipped them
      // 2-6 um every 25 ms). (A held body never rests: its stage goes on solving its rows.)
      StageRequest decided;
      decided.kind = StageRequest::kDecided;
      decided.body = body;
      decided.settled = e->resting || !e->floating;
      const StageRequest vote = co_await StageAwait{decided, alone, [](StageRequest&) {}};
      if (!vote.stop) e->resting = false;
    }
    if (e->resting) {
      // the frame stays where its contacts hold it
      forces[i].setZero();
      torques[i].setZero();
      states_[i].velocity.setZero();
      states_[i].angular_velocity.setZero();
      elastic_points_ += e->last_points;
      for (const auto& [partner, f] : e->last_pair_force) {
        elastic_force_ += f;
        touching.insert({body, partner});
      }
      load_partners(*e);  // its elastic partners go on carrying it
      for (const auto& [r, w] : e->last_partner_wrench) {
        // and a floating one's frame its weight (free, or on joints: its mechanism along)
        const ElasticBody* ep = elastic_[static_cast<std::size_t>(r)].get();
        if (!ep || !ep->floating || ep->resting) continue;
        const Eigen::Matrix<double, 6, 1> jump =
            (joints_->moves(r) ? joints_->mobility(before, inertias_, r)
                               : free_mobility(inertias_[r], before[r])) *
            w * dt;
        states_[r].velocity += jump.head<3>();
        states_[r].angular_velocity += jump.tail<3>();
        jump_along(r, w);
      }
      // what its owners' resting stages load it with is already in its deformation
      if (e->pending_load.size() > 0) e->pending_load.setZero();
      ++elastic_stats_.resting_steps;
      done[i] = 1;
      co_return;
    }
    e->last_frame_position = before[i].position;
    e->supports.clear();
    const auto body_started = Clock::now();
    const Eigen::Vector3d centroid = b.mass_properties.centroid;
    RigidState frame0, frame1;  // the frame now and after free motion
    frame0.position = frame1.position = centroid;
    if (e->floating) {
      frame0 = before[i];
      frame1 = free_motion[i];
      if (!e->floating_owners.empty()) {
        // from the velocity jumps its owners' stages gave it this step
        if (joints_->moves(body)) {
          frame1 = jointed_end(body);
        } else {
          frame1 = states_[i];
          step_rigid(frame1, inertias_[i], forces[i], torques[i], dt);
        }
      }
      // (held by its rows in its last step: as take_step moves it, Dynamics::held_shifts)
      if (!held_travel_[i].isZero())
        shift_by(frame1, held_shift_[i] + jump_lag(body, before[i], states_[i], dt));
    }
    const Eigen::MatrixX3d x0 = surface_positions(body, solver.displacement(), frame0);
    e->keep_start(time_, x0);

    // the partners' parts near the body's surface (boxes grown by how far the surface and
    // the partners can move in the step), checked first: a sleeping body stays rigid
    // each partner's rigid motion over the step without contact: still, driven (a
    // translation) or, free or jointed, where its loads and joints carry it; and how a
    // movable one answers a contact impulse (its mobility, times dt^2 as the frame's)
    std::vector<PartnerMotion> partner(scene_.bodies.size());
    std::vector<RigidState> partner_end(scene_.bodies.size());  // movable ones, free motion
    double partner_speed = 0;
    // a free or jointed partner (a rigid body, or a floating elastic body's frame), from
    // where earlier bodies' contacts left it this step; `radius` bounds its points' distance
    // from its centre
    auto movable = [&](int r, double radius) {
      PartnerMotion& pm = partner[static_cast<std::size_t>(r)];
      RigidState end;
      Eigen::Vector3d earlier_turn = Eigen::Vector3d::Zero();
      // the forces the stages still to come will give it, as in their last step: loads of
      // its step when its supports held it by friction, else a jump
      const auto it = later.find(r);
      const bool as_loads = held_still(r) && it != later.end();
      if (joints_->moves(r)) {
        end = jointed_end(r);
        pm.mobility = pm.jump_mobility = joints_->mobility(before, inertias_, r);
      } else if (contact_ && !contact_->supports(r).empty()) {
        // a free body its last step's contacts held on fixed bodies answers with them held
        // (their normals, and a sticking point's friction, as rows of a joint) and goes where
        // its loads and their sliding friction carry it, as the rigid contacts that follow in
        // this step will have it
        Eigen::Matrix<double, 6, 1> load;
        load << forces[r], torques[r];
        if (as_loads) load += it->second;
        end = supported_motion(states_[r], inertias_[r], contact_->supports(r), load.head<3>(),
                               load.tail<3>(), dt, &pm.mobility, &pm.jump_mobility);
      } else {
        // from the step's start, and the velocity jumps the stages before this one gave it,
        // their turn to first order (later_turn)
        end = before[static_cast<std::size_t>(r)];
        step_rigid(end, inertias_[r], forces[r], torques[r], dt);
        pm.mobility = pm.jump_mobility = free_mobility(inertias_[r], before[r]);
        const Eigen::Vector3d dv = states_[r].velocity - before[r].velocity,
                              dw = states_[r].angular_velocity - before[r].angular_velocity;
        end.velocity += dv;
        end.angular_velocity += dw;
        end.position += dv * dt;
        earlier_turn = dw * dt;
      }
      // one that stages held in its last step (as take_step moves it): farther along what
      // held it, a jump's friction along the rest a force over the step
      if (!held_travel_[static_cast<std::size_t>(r)].isZero()) {
        shift_by(end,
                 held_shift_[static_cast<std::size_t>(r)] + jump_lag(r, before[r], states_[r], dt));
        pm.travel = held_travel_[static_cast<std::size_t>(r)];
      }
      pm.later_response =
          as_loads ? (0.5 * dt * dt * pm.mobility).eval() : (pm.jump_mobility * dt * dt).eval();
      // (as a jump: the forces on it, and on the other bodies of its mechanism)
      Eigen::Matrix<double, 6, 1> jump = Eigen::Matrix<double, 6, 1>::Zero();
      if (!as_loads)
        for (const auto& [q, w] : later) {
          if (q == r)
            jump += pm.jump_mobility * w * dt;
          else if (coupled(r, q))
            jump += coupling(r, q) * w / dt;
        }
      pm.later_turn = earlier_turn;
      if (jump.squaredNorm() > 0) {
        end.velocity += jump.head<3>();
        end.angular_velocity += jump.tail<3>();
        const Eigen::Matrix<double, 6, 1> travel = pm.travel * jump;
        end.position += travel.head<3>() * dt;
        const Eigen::Vector3d turn = travel.tail<3>() * dt;
        if (!elastic_[static_cast<std::size_t>(r)]) {
          // a rigid body: the turn as the rows' own forces turn it, to first order (the
          // jumps of the stages before and after cancel where they hold it still)
          pm.later_turn += turn;
        } else if (turn.norm() > 0) {
          end.rotation =
              (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * end.rotation)
                  .normalized();
        }
      }
      partner_end[static_cast<std::size_t>(r)] = end;
      pm.movable = true;
      pm.x1 = end.position;
      pm.turn = (end.rotation * before[r].rotation.conjugate()).toRotationMatrix();
      // (one that takes the rows' forces as loads moves half as far under them as under an
      // impulse at the step's start: its velocity grows over the step)
      pm.mobility *= (held_still(r) ? 0.5 : 1.0) * dt * dt;
      pm.jump_mobility *= dt * dt;
      pm.velocity = (pm.x1 - pm.x0) / dt;
      const double angle = Eigen::AngleAxisd(pm.turn).angle();
      partner_speed = std::max(partner_speed, (pm.x1 - pm.x0).norm() / dt + angle / dt * radius);
    };
    // how far a rigid body's points lie from its centre
    auto rigid_radius = [&](int r) {
      double radius = 0;
      for (const RigidPart& part : rigid_parts_)
        if (part.body == r)
          for (const auto& v : part.local.vertices) radius = std::max(radius, v.norm());
      return radius;
    };
    for (int r : e->partners) {
      PartnerMotion& pm = partner[static_cast<std::size_t>(r)];
      pm.x0 = pm.x1 = before[r].position;
      if (driven_[r] >= 0) {
        Eigen::Vector3d v;
        frame_offset(r, t_mid, &v);
        pm.x1 += v * dt;
        pm.velocity = v;
      } else if (movable_partner(r)) {
        movable(r, rigid_radius(r));
      }
      partner_speed = std::max(partner_speed, pm.velocity.norm());
    }
    for (int r : e->elastic_partners) {  // floating ones: their frames
      if (!elastic_[static_cast<std::size_t>(r)]->floating) continue;
      PartnerMotion& pm = partner[static_cast<std::size_t>(r)];
      pm.x0 = pm.x1 = before[r].position;
      const Body& rb = scene_.bodies[static_cast<std::size_t>(r)];
      const double radius = (rb.surface.V.rowwise() - rb.mass_properties.centroid.transpose())
                                .rowwise()
                                .norm()
                                .maxCoeff();
      movable(r, radius);
      partner_speed = std::max(partner_speed, pm.velocity.norm());
    }
    const double h = b.tet_mesh.mesh_size;
    const double margin = 1e-2 * h;
    double body_reach = (frame1.position - frame0.position).norm() + partner_speed * dt + margin;
    {
      const Eigen::VectorXd& v = solver.velocity();
      double vmax = 0;
      for (int node : e->surface.nodes) vmax = std::max(vmax, v.segment<3>(3 * node).norm());
      body_reach += 2 * vmax * dt;
      const Eigen::Vector3d lo = b.surface.V.colwise().minCoeff(),
                            hi = b.surface.V.colwise().maxCoeff();
      body_reach += before[i].angular_velocity.norm() * dt * (hi - lo).norm();
    }
    geometry::Bounds all;
    for (Eigen::Index k = 0; k < x0.rows(); ++k) {
      all.lo = all.lo.cwiseMin(x0.row(k).transpose());
      all.hi = all.hi.cwiseMax(x0.row(k).transpose());
    }
    all.lo.array() -= body_reach;
    all.hi.array() += body_reach;
    struct Near {
      int part;
      geometry::ConvexPolytope world;
      geometry::Bounds box;
    };
    std::vector<Near> near;
    for (std::size_t p = 0; p < rigid_parts_.size(); ++p) {
      const RigidPart& part = rigid_parts_[p];
      if (std::find(e->partners.begin(), e->partners.end(), part.body) == e->partners.end())
        continue;
      Near nr{
          static_cast<int>(p), geometry::transformed(part.local, pose_of(before[part.body])), {}};
      for (const auto& v : nr.world.vertices) {
        nr.box.lo = nr.box.lo.cwiseMin(v);
        nr.box.hi = nr.box.hi.cwiseMax(v);
      }
      if (geometry::overlap(nr.box, all)) near.push_back(std::move(nr));
    }
    // the held elastic bodies whose contact with this one this stage solves: where their
    // surfaces are and go over the step without contact (their own prediction; a held
    // body's frame is its centroid, in world axes), and how far each node can reach
    struct ElasticNear {
      int body = -1;
      Eigen::MatrixX3d x0, x1;
      Eigen::VectorXd reach;
      std::vector<int> triangles, near_triangles;  ///< its candidates, and this body's near them
      bool floating = false;
      Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();  ///< its axes at the step's start
      Eigen::Matrix<double, 6, 6> rt6 = Eigen::Matrix<double, 6, 6>::Identity();  ///< to them
    };
    std::vector<ElasticNear> elastic_near;
    for (int other : e->elastic_partners) {
      ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      ElasticNear en;
      en.body = other;
      if (std::abs(dt - eb.solver->time_step()) > 1e-9 * dt) eb.solver->set_time_step(dt);
      if (eb.floating) {
        // a floating partner: its surface in its frame, which moves freely over the step,
        // deformed by its loads and (quasi-statically) its frame's free acceleration
        en.floating = true;
        const RigidState& f0 = before[static_cast<std::size_t>(other)];
        const RigidState& f1 = partner_end[static_cast<std::size_t>(other)];
        en.rot = f0.rotation.toRotationMatrix();
        en.rt6.topLeftCorner<3, 3>() = en.rot.transpose();
        en.rt6.bottomRightCorner<3, 3>() = en.rot.transpose();
        if (!eb.awake) {
          const Eigen::VectorXd zero = Eigen::VectorXd::Zero(eb.solver->displacement().size());
          eb.solver->start(time_, zero, zero, elastic_load(other, time_));
          eb.awake = true;
        }
        if (eb.inertia_response.size() == 0) frame_inertia(other);
        const Eigen::Vector3d g = scene_.gravity ? *scene_.gravity : Eigen::Vector3d::Zero();
        Eigen::Matrix<double, 6, 1> acceleration;
        acceleration << (f1.velocity - f0.velocity) / dt - g,
            (f1.angular_velocity - f0.angular_velocity) / dt;
        Eigen::VectorXd other_prediction = eb.solver->predict(elastic_load(other, t_end), nullptr);
        other_prediction.noalias() -= eb.inertia_response * (en.rt6 * acceleration);
        // and by the stages after this one: their forces on it as in their last step (or
        // pass), as its frame's motion takes their wrenches (`later`)
        if (const auto it = later_loads.find(other);
            it != later_loads.end() && it->second.squaredNorm() > 0) {
          other_prediction += eb.solver->response(it->second.sparseView()).col(0);
          ++elastic_stats_.correction_solves;
        }
        en.x0 = surface_positions(other, eb.solver->displacement(), f0);
        en.x1 = surface_positions(other, eb.solver->displacement() + other_prediction, f1);
      } else {
        RigidState centre;
        centre.position = scene_.bodies[static_cast<std::size_t>(other)].mass_properties.centroid;
        en.x0 = surface_positions(other, eb.solver->displacement(), centre);
        const HeldMotion other_held = held_motion(other, t_end);
        const Eigen::VectorXd& other_prediction =
            eb.solver->predict(elastic_load(other, t_end), &other_held);
        en.x1 = surface_positions(other, eb.solver->displacement() + other_prediction, centre);
      }
      en.reach = (en.x1 - en.x0).rowwise().norm().array() + margin;
      geometry::Bounds box;
      box.lo = en.x0.colwise().minCoeff().transpose().array() - en.reach.maxCoeff();
      box.hi = en.x0.colwise().maxCoeff().transpose().array() + en.reach.maxCoeff();
      if (!geometry::overlap(box, all)) continue;
      if (time_ <= 0) {
        // where the run starts, neither may lie deep inside the other: the contact points
        // reach a quarter of the mesh size below a surface, and a body started deeper in
        // would pass through unseen
        const double depth =
            0.25 * std::min(b.tet_mesh.mesh_size,
                            scene_.bodies[static_cast<std::size_t>(other)].tet_mesh.mesh_size);
        auto check = [&](const Eigen::MatrixX3d& from, const ContactSurface& into_surface,
                         const Eigen::MatrixX3d& into, const std::string& from_name,
                         const std::string& into_name) {
          const Eigen::Vector3d lo = into.colwise().minCoeff().transpose(),
                                hi = into.colwise().maxCoeff().transpose();
          for (Eigen::Index k = 0; k < from.rows(); ++k) {
            const Eigen::Vector3d p = from.row(k).transpose();
            if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
            if (!deep_inside(into_surface, into, p, depth)) continue;
            char at[96];
            std::snprintf(at, sizeof at, "(%.4g, %.4g, %.4g) m", p.x(), p.y(), p.z());
            throw SimulationError("elastic bodies '" + from_name + "' and '" + into_name +
                                  "' overlap where the run starts: a surface node of '" +
                                  from_name + "' at " + at + " lies inside '" + into_name +
                                  "', deeper than a quarter of the mesh size; move them apart");
          }
        };
        const std::string& other_name = scene_.bodies[static_cast<std::size_t>(other)].name;
        check(x0, eb.surface, en.x0, b.name, other_name);
        check(en.x0, e->surface, x0, other_name, b.name);
      }
      elastic_near.push_back(std::move(en));
    }
    if (near.empty() && elastic_near.empty() && !e->awake) {
      ++elastic_stats_.skipped_steps;  // a floating body far from everything: rigid only
      done[i] = 1;
      co_return;
    }
    if (!e->awake) {
      // something may touch it within the step: the FE state starts (at rest in its frame)
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(solver.displacement().size());
      solver.start(time_, zero, zero, elastic_load(body, time_));
      e->awake = true;
    }
    if (std::abs(dt - solver.time_step()) > 1e-9 * dt) solver.set_time_step(dt);
    HeldMotion held;
    if (!e->floating) held = held_motion(body, t_end);
    const Eigen::VectorXd f_next = elastic_load(body, t_end);
    Eigen::VectorXd prediction = solver.predict(f_next, e->floating ? nullptr : &held);
    // the contact forces an owner's stage put on this body this step: the deformation they
    // cause joins its free motion (they are loads of this step, as its own rows' forces)
    const bool owner_loaded = e->pending_load.size() > 0 && !e->pending_load.isZero(0);
    if (owner_loaded) {
      prediction += solver.response(e->pending_load.sparseView()).col(0);
      ++elastic_stats_.correction_solves;
    }
    // a floating body deforms in its accelerating frame: each node carries its share of the
    // frame's acceleration without contact (loads, gravity, joints) as an inertial load,
    // less its weight
    const Eigen::Matrix3d rt0 = frame0.rotation.toRotationMatrix().transpose();
    auto to_frame = [&](const Eigen::Matrix<double, 6, 1>& a) {
      Eigen::Matrix<double, 6, 1> local;
      local << rt0 * a.head<3>(), rt0 * a.tail<3>();
      return local;
    };
    Eigen::Matrix<double, 6, 1> free_acceleration = Eigen::Matrix<double, 6, 1>::Zero();
    if (e->floating) {
      if (e->inertia_response.size() == 0) frame_inertia(body);
      // gravity acts on the frame and, as the weight of each node, on the deformation:
      // the nodes carry M (g - a), nothing in free fall, their weight at rest
      const Eigen::Vector3d g = scene_.gravity ? *scene_.gravity : Eigen::Vector3d::Zero();
      free_acceleration << (frame1.velocity - frame0.velocity) / dt - g,
          (frame1.angular_velocity - frame0.angular_velocity) / dt;
      free_acceleration = to_frame(free_acceleration);
      prediction.noalias() -= e->inertia_response * free_acceleration;
    }
    // where the surface goes without contact, and how far each node can reach
    const Eigen::MatrixX3d x1 = surface_positions(body, solver.displacement() + prediction, frame1);
    Eigen::VectorXd reach(x0.rows());
    for (Eigen::Index k = 0; k < x0.rows(); ++k)
      reach[k] = (x1.row(k) - x0.row(k)).norm() + partner_speed * dt + margin;
    const Eigen::Index tris = e->surface.triangles.rows();
    std::vector<geometry::Bounds> boxes(static_cast<std::size_t>(tris));
    for (Eigen::Index t = 0; t < tris; ++t) {
      geometry::Bounds& bx = boxes[static_cast<std::size_t>(t)];
      double grow = 0;
      for (int k = 0; k < 3; ++k) {
        const int j = e->surface.triangles(t, k);
        bx.lo = bx.lo.cwiseMin(x0.row(j).transpose());
        bx.hi = bx.hi.cwiseMax(x0.row(j).transpose());
        grow = std::max(grow, reach[j]);
      }
      bx.lo.array() -= grow;
      bx.hi.array() += grow;
    }

    // narrow phase at the start of the step
    struct Row {
      SurfaceContact c;
      int part = 0;  ///< the rigid part; against an elastic body -(2 + 2 body), -(3 + 2 body)
      int partner = 0;
      int elastic = -1;  ///< against an elastic body: its entry in `elastic_near`
      std::array<int, 3> b_nodes{-1, -1, -1};  ///< its point: surface nodes and weights
      std::array<double, 3> b_weights{0, 0, 0};
      /// A support of the elastic partner (a floating body this stage owns) on this body (a
      /// rigid one, or a held elastic one): no point of this body (c.nodes none, c.on_b the
      /// partner's point, c.normal the force on the holding body), `part` the holding body's rigid
      /// part (or the elastic pair's code). It moves the partner (and the holding body) in the
      /// solve; the partner's own stage applies it.
      int fixed = -1;
      Eigen::Vector3d fixed_travel = Eigen::Vector3d::Zero();  ///< the holding body's, this step
      /// A support on a held elastic body: its entry in `elastic_near`, and its surface nodes
      /// and weights at the point (its compliance moves them under the rows' forces).
      int fixed_elastic = -1;
      std::array<int, 3> f_nodes{-1, -1, -1};
      std::array<double, 3> f_weights{0, 0, 0};
      /// A link between two free rigid bodies (ContactSystem::Link: `partner` its a,
      /// `fixed` its b, c.normal the force on b, c.on_b the point) that this stage solves
      /// with its own rows and applies (the rigid contact that follows in the step finds
      /// the bodies moving together): blocks stacked on a rubber pad, which its rows and
      /// the blocks' contacts hold in one solve. (As two stages, the pad's and the rigid
      /// contact's, the upper block crept over the lower one under a push friction holds.)
      bool link = false;
      /// The normal as found where the step starts (c.normal is turned to where the step
      /// ends it, once: normal_prediction); zero until then.
      Eigen::Vector3d found_normal = Eigen::Vector3d::Zero();
    };
    std::vector<Row> rows;
    // A point's normal is where its row's force acts and along which its gap closes. Taken
    // where the step starts, it lags the surface's turn over the step: an error of first
    // order in the step. Riding over the catch's edge, the hook's lead face turns 0.4
    // degrees per 0.07 mm of travel, and with friction 0.3 on a face at 45 degrees the
    // push's peak came out 8 % high at that increment (quasistatic), 5 % with the turn
    // below (the rest: the rows' planes, taken anew below). A row whose normal is an elastic
    // surface's triangle's, where the part's feature slides over it, takes the normal that
    // the triangle's turn over the last step extrapolates to this step's end (the gap at
    // the start along it): second order while the surface turns smoothly.
    constexpr double kTurnLimit = 0.1;  // a larger turn in a step is not extrapolated
    // A part's vertex or edge on a triangle is taken anew where a pass ends it (the narrow
    // phase after a solve, below) when its gap there differs from its plane's by more than
    // kEdgeGapTolerance mesh sizes: in the first kEdgeRetakePasses passes, in problems of
    // up to kEdgeRetakeRows points (a pass of the snap-fit's landing, 1,200 points, costs
    // 0.5-1.5 s, and its impact is over in a few steps), and for points that slide at least
    // kEdgeSlide mesh sizes in the step (so does the turn above: a body at rest keeps its
    // rows, and sleeps; at 1e-4 the bench's soft slab, settling on its plate, took 18 s
    // instead of 12 s and rested in 49 of 250 steps instead of 140: the turn kept its rows
    // changing)
    // A step solves its rows at most kMaxPasses times and keeps the last solve. Edge rows
    // are taken anew in the first 3 passes of a dynamic step, whose points slide a small
    // part of the mesh size (the step is set by the fastest speed the loads could give: the
    // snap-fit's edges slide about 0.1 mm on the hooks per 0.56 ms step), and in every pass
    // of a quasi-static increment, which is the drive's travel itself (a quarter of the
    // finest mesh size): at 0.38 mm per increment the base part's edge crosses several of
    // the socket hook's lead-face triangles in one, and after 3 passes its rows were still
    // on triangles it had left (137 N against 90 N at 3.39 mm). A quasi-static increment
    // is redone in halves (Dynamics::increment, `unsettled_`) when its rows have not
    // settled: at the pass limit the force of the last passes differs by more than
    // kSettledForce, or, at the limit or not, pressed rows carrying more than kLeftForce of
    // it are on triangles the points have left (an apex passing an edge within the
    // increment: the rows hold the face out past its end, and the released state finds
    // the face again, pass after pass)
    // (an increment at its last cut, a 64th, passes up to 32 times: where a hook's apex
    // passes a part's edge the edge leaves the lead face's triangles a few rows a pass along
    // the hook's width while the apex's nodes join on the part's side face; the paw sample's
    // hook at 60 degrees took 30 passes, its 82 rows on the lead face going down to 5)
    const int kMaxPasses = last_cut_ ? 32 : 8;
    constexpr double kSettledForce = 0.02, kLeftForce = 0.25;
    // the rows did not settle: where (said when a quasi-static increment's last cut keeps it)
    auto not_settled = [&](const std::vector<Row>& rows, const Eigen::VectorXd& lambda,
                           double share, int passes) {
      unsettled_ = true;
      std::map<int, double> by_partner;
      for (std::size_t r = 0; r < rows.size() && 3 * r < static_cast<std::size_t>(lambda.size());
           ++r)
        if (rows[r].fixed < 0) by_partner[rows[r].partner] += std::max(0.0, lambda[3 * r]);
      int partner = -1;
      double most = -1;
      for (const auto& [q, f] : by_partner)
        if (f > most) most = f, partner = q;
      unsettled_at_ = {body, partner, share, passes};
    };
    const bool quasistatic_run = scene_.simulation.mode == SimulationMode::kQuasistatic;
    const int kEdgeRetakePasses = quasistatic_run ? kMaxPasses : 3;
    constexpr double kEdgeGapTolerance = 2e-5;
    constexpr Eigen::Index kEdgeRetakeRows = 400;
    constexpr double kEdgeSlide = 1e-3;
    // (the body's own triangle `nodes`, whose normal at the step's start is +-`normal`)
    auto triangle_turned = [&](const std::array<int, 3>& nodes, const Eigen::Vector3d& normal,
                               Eigen::Vector3d* out) {
      if (nodes[0] < 0 || nodes[1] < 0 || nodes[2] < 0) return false;
      const double since = time_ - e->last_start_time;
      if (e->last_start_time < 0 || e->last_start.rows() != x0.rows() || !(since < 1.5 * dt))
        return false;  // (no step just before this one: a body that was asleep)
      auto unit_normal = [&](const Eigen::MatrixX3d& x) {
        const Eigen::Vector3d a = x.row(nodes[0]).transpose();
        return (x.row(nodes[1]).transpose() - a)
            .cross(x.row(nodes[2]).transpose() - a)
            .normalized()
            .eval();
      };
      const Eigen::Vector3d n = unit_normal(x0);
      const double along = n.dot(normal);
      if (std::abs(along) < 1 - 1e-9) return false;  // not this triangle's normal
      const Eigen::Vector3d turn = n - unit_normal(e->last_start);
      if (!(turn.norm() < kTurnLimit)) return false;
      *out = std::copysign(1.0, along) * (n + turn * (dt / since)).normalized();
      return true;
    };
    auto normal_prediction = [&](Row& row, const Eigen::Vector3d& free_motion) {
      if (row.found_normal.squaredNorm() > 0 || row.fixed >= 0) return;
      SurfaceContact& c = row.c;
      row.found_normal = c.normal;
      // (only where the part's feature slides over the triangle: a point at rest turns the
      // surface under it no more than its force does, and a body at rest keeps its rows)
      if ((free_motion - c.normal.dot(free_motion) * c.normal).norm() < kEdgeSlide * h) return;
      if (c.node_row || row.elastic >= 0) return;  // a rigid part's normal, or a pair's
      Eigen::Vector3d n;
      if (!triangle_turned(c.nodes, c.normal, &n)) return;
      c.gap *= n.dot(c.normal);  // the same offset between the points, along the new normal
      c.normal = n;
    };
    // a support of an elastic partner on a rigid body that the rows' forces move (free or
    // jointed)
    auto free_support = [&](const Row& r) {
      return r.fixed >= 0 && partner[static_cast<std::size_t>(r.fixed)].movable;
    };
    std::vector<std::vector<int>> near_candidates(near.size());  // triangles near each part
    if (!near.empty() || !elastic_near.empty()) {
      if (e->surface_tree)
        e->surface_tree->refit(boxes);
      else
        e->surface_tree.emplace(boxes);
    }
    if (!near.empty()) {
      const geometry::AabbTree& tree = *e->surface_tree;
      for (std::size_t k = 0; k < near.size(); ++k) {
        const Near& nr = near[k];
        const std::vector<int>& candidates = near_candidates[k] = tree.overlapping(nr.box);
        if (candidates.empty()) continue;
        for (SurfaceContact& c : surface_part_contacts(e->surface, x0, nr.world, candidates, reach))
          rows.push_back({c, nr.part, rigid_parts_[static_cast<std::size_t>(nr.part)].body});
      }
    }
    if (!elastic_near.empty()) {
      const geometry::AabbTree& tree = *e->surface_tree;
      for (std::size_t k = 0; k < elastic_near.size(); ++k) {
        ElasticNear& en = elastic_near[k];
        const ContactSurface& other = elastic_[static_cast<std::size_t>(en.body)]->surface;
        // its triangles near this body, and this body's near them
        geometry::Bounds other_box;
        std::vector<int> other_candidates;
        for (Eigen::Index t = 0; t < other.triangles.rows(); ++t) {
          geometry::Bounds bx;
          double grow = 0;
          for (int q = 0; q < 3; ++q) {
            const int j = other.triangles(t, q);
            bx.lo = bx.lo.cwiseMin(en.x0.row(j).transpose());
            bx.hi = bx.hi.cwiseMax(en.x0.row(j).transpose());
            grow = std::max(grow, en.reach[j]);
          }
          bx.lo.array() -= grow;
          bx.hi.array() += grow;
          if (!geometry::overlap(bx, all)) continue;
          other_candidates.push_back(static_cast<int>(t));
          other_box.extend(bx);
        }
        if (other_candidates.empty()) continue;
        en.triangles = std::move(other_candidates);
        en.near_triangles = tree.overlapping(other_box);
        for (const SurfacePairContact& c : surface_surface_contacts(
                 e->surface, x0, en.near_triangles, reach, other, en.x0, en.triangles, en.reach)) {
          Row r{c.a, c.a_node ? -(2 + 2 * en.body) : -(3 + 2 * en.body), en.body};
          r.elastic = static_cast<int>(k);
          r.b_nodes = c.b_nodes;
          r.b_weights = c.b_weights;
          rows.push_back(r);
        }
      }
    }
    // the owned partners' supports, where the pair touches: the fixed body's plane against
    // the partner's point as it starts the step
    for (std::size_t k = 0; k < elastic_near.size(); ++k) {
      const ElasticNear& en = elastic_near[k];
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(en.body)];
      // (a partner of this stage's group solves its own rows with these, unless it rests)
      if (in_group.count(en.body) && !eb.resting) continue;
      if (eb.supports.empty() || std::none_of(rows.begin(), rows.end(), [&](const Row& r) {
            return r.elastic == static_cast<int>(k);
          }))
        continue;
      for (const ElasticBody::SupportRow& sp : eb.supports) {
        Row r;
        r.part = sp.part;
        r.partner = en.body;
        r.elastic = static_cast<int>(k);
        r.fixed = sp.body;
        r.b_nodes = sp.c.nodes;
        r.b_weights = sp.c.weights;
        Eigen::Vector3d at = Eigen::Vector3d::Zero();
        for (std::size_t q = 0; q < 3; ++q)
          if (sp.c.nodes[q] >= 0) at += sp.c.weights[q] * en.x0.row(sp.c.nodes[q]).transpose();
        r.c.node_row = false;
        r.c.key = sp.c.key;
        r.c.on_b = at;
        if (elastic_[static_cast<std::size_t>(sp.body)]) {
          // a held elastic body: its point where its surface is now, and where its own
          // motion takes it in the step; its compliance joins the rows (Delassus), a body
          // this stage solves rows on (else the support is left out)
          const auto held = std::find_if(elastic_near.begin(), elastic_near.end(),
                                         [&](const ElasticNear& q) { return q.body == sp.body; });
          if (held == elastic_near.end()) continue;
          r.fixed_elastic = static_cast<int>(held - elastic_near.begin());
          r.f_nodes = sp.held_nodes;
          r.f_weights = sp.held_weights;
          Eigen::Vector3d point = Eigen::Vector3d::Zero();
          for (std::size_t q = 0; q < 3; ++q)
            if (sp.held_nodes[q] >= 0) {
              point += sp.held_weights[q] * held->x0.row(sp.held_nodes[q]).transpose();
              r.fixed_travel +=
                  sp.held_weights[q] *
                  (held->x1.row(sp.held_nodes[q]) - held->x0.row(sp.held_nodes[q])).transpose();
            }
          r.c.normal = -sp.c.normal;  // the force on the holding body
          r.c.gap = sp.c.normal.dot(at - point);
          rows.push_back(r);
          continue;
        }
        if (movable_partner(sp.body)) {
          // a free or jointed body: its plane carried along with it since, and where its
          // loads (and its own supports or joints) take it in the step; its mobility joins
          // the rows (Delassus)
          PartnerMotion& pm = partner[static_cast<std::size_t>(sp.body)];
          if (!pm.movable) {
            pm.x0 = pm.x1 = before[sp.body].position;
            movable(sp.body, rigid_radius(sp.body));
          }
          const Eigen::Isometry3d since = pose_of(before[sp.body]) * sp.pose.inverse();
          const Eigen::Vector3d normal = since.linear() * sp.c.normal;
          r.c.normal = -normal;  // the force on the holding body
          r.fixed_travel = pm.shift(at);
          r.c.gap = normal.dot(at - since * sp.c.on_b);
          rows.push_back(r);
          continue;
        }
        r.c.normal = -sp.c.normal;  // the force on the fixed body
        // a driven body's plane where it is now, and how far it goes in the step
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        const Eigen::Vector3d moved =
            frame_offset(sp.body, time_, nullptr) - frame_offset(sp.body, sp.time, nullptr);
        frame_offset(sp.body, t_mid, &v);
        r.fixed_travel = v * dt;
        r.c.gap = sp.c.normal.dot(at - sp.c.on_b - moved);
        rows.push_back(r);
      }
    }
    // the links between free rigid bodies on no joint and on supports on fixed or driven
    // bodies only (ContactSystem::Support: a support on a free body is a link), from this
    // body's movable partners through the bodies linked to them, as they touched where the
    // step starts
    std::set<int> linked;
    if (contact_ && !contact_->links().empty()) {
      auto loose = [&](int q) {  // (its supports, if any, on fixed or driven bodies)
        const std::vector<ContactSystem::Support>& held = contact_->supports(q);
        return !elastic_[static_cast<std::size_t>(q)] && !joints_->moves(q) && movable_partner(q) &&
               std::all_of(held.begin(), held.end(),
                           [&](const ContactSystem::Support& sp) { return holds_still(sp.body); });
      };
      for (const int q : e->partners)
        if (loose(q)) linked.insert(q);
      std::vector<const ContactSystem::Link*> links;
      for (bool grew = !linked.empty(); grew;) {
        grew = false;
        links.clear();
        for (const ContactSystem::Link& l : contact_->links()) {
          if (!loose(l.a) || !loose(l.b) || (!linked.count(l.a) && !linked.count(l.b)) ||
              links_taken.count({l.a, l.b}))
            continue;
          links.push_back(&l);
          grew = linked.insert(l.a).second || grew;
          grew = linked.insert(l.b).second || grew;
        }
      }
      if (links.empty()) linked.clear();
      for (const int q : linked) {
        PartnerMotion& pm = partner[static_cast<std::size_t>(q)];
        if (pm.movable) continue;
        pm.x0 = pm.x1 = before[q].position;
        movable(q, rigid_radius(q));
      }
      for (const ContactSystem::Link* l : links) {
        links_taken.insert({l->a, l->b});
        Row r;
        r.link = true;
        r.partner = l->a;
        r.fixed = l->b;
        r.part = kLinkPart - l->part_a;
        r.c.node_row = false;
        r.c.normal = l->normal;
        r.c.on_b = 0.5 * (l->on_a + l->on_b);
        r.c.gap = l->normal.dot(l->on_b - l->on_a);
        // (its place on a, in a's frame, to a micrometre: the same point step after step)
        const Eigen::Vector3d local =
            before[l->a].rotation.conjugate() * (l->on_a - before[l->a].position);
        std::int64_t key = l->part_b;
        for (int k = 0; k < 3; ++k)
          key = key * 1000003 + static_cast<std::int64_t>(std::llround(local[k] * 1e6));
        r.c.key = key;
        r.fixed_travel = partner[static_cast<std::size_t>(l->b)].shift(r.c.on_b);
        rows.push_back(r);
      }
    }
    struct Effort {
      long newton_iterations;
      double column_seconds, delassus_seconds, solve_seconds;
    };
    const Effort effort_before{elastic_stats_.newton_iterations, elastic_stats_.column_seconds,
                               elastic_stats_.delassus_seconds, elastic_stats_.solve_seconds};
    std::unordered_map<int, std::size_t> near_of;  // part -> its entry in `near`
    for (std::size_t k = 0; k < near.size(); ++k) near_of[near[k].part] = k;
    Eigen::Matrix<double, 6, 6> mobility = Eigen::Matrix<double, 6, 6>::Zero();
    if (e->floating) {
      mobility = joints_->moves(body) ? joints_->mobility(before, inertias_, body)
                                      : free_mobility(inertias_[i], frame0);
      // the contact impulse dt F jumps the frame's velocity at the start of the step, so
      // it moves dt^2 M^-1 F further: a closed point then ends the step at rest relative
      // to the surface (a plastic contact), not bouncing off it
      mobility *= dt * dt;
    }
    // how far a jump of the frame carries it over the step, per unit (PartnerMotion::travel)
    const Eigen::Matrix<double, 6, 6> own_travel =
        held_travel_[i].isZero() ? Eigen::Matrix<double, 6, 6>::Identity().eval() : held_travel_[i];
    // the motion of surface nodes (world) under contact forces on surface nodes (frame
    // axes) and on the frame, from the kept compliance columns and the frame's mobility;
    // evaluated only at the nodes asked for (the rows' nodes), each once
    using Wrenches = std::map<int, Eigen::Matrix<double, 6, 1>>;
    using NodeForces = std::vector<std::pair<int, Eigen::Vector3d>>;
    struct ContactMotion {
      const NodeForces* node_forces = nullptr;
      Eigen::Matrix<double, 6, 1> jump = Eigen::Matrix<double, 6, 1>::Zero();
      std::unordered_map<int, Eigen::Vector3d> at;
      Wrenches partner_jump;  ///< movable partners' jumps (dt^2 held, as `jump`)
      /// The reactions on the elastic partners' surface nodes (their axes: world), and
      /// where they move those nodes (per partner body and node).
      const std::map<int, NodeForces>* partner_forces = nullptr;
      std::map<std::pair<int, int>, Eigen::Vector3d> partner_at;
      /// Asked at many nodes under many forces: the deformation of every node from one
      /// solve with the kept factor (`deformation`, filled when first needed), not each
      /// node's sum over the cached columns. (Nodes without columns read it always.)
      bool direct = false;
      Eigen::VectorXd deformation;
      /// The forced nodes' columns and forces, looked up once (a node's motion sums them).
      std::vector<ForcedNode> forced;
      /// In mean axes (ElasticBody::mean_axes): the rigid part of the body's deformation
      /// under these forces, and of each floating partner's (taken out of their motions).
      Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
      std::map<int, Eigen::Matrix<double, 6, 1>> partner_mean;
      /// Per elastic partner: its forced nodes' columns and forces (its axes), looked up
      /// once; its deformation from one solve with its factor, for its nodes without
      /// columns (for all of them when a forced node has none: `direct`).
      struct Partner {
        std::vector<ForcedNode> forced;
        bool direct = false;
        Eigen::VectorXd deformation;
      };
      std::map<int, Partner> partner_forced;
    };
    const std::map<int, NodeForces> no_partner_forces;
    auto contact_motion = [&](const NodeForces& node_forces, const Eigen::Vector3d& frame_force,
                              const Eigen::Vector3d& frame_torque, const Wrenches& partner_wrench,
                              const std::map<int, NodeForces>& partner_forces) {
      ContactMotion cm;
      cm.node_forces = &node_forces;
      cm.partner_forces = &partner_forces;
      cm.forced.reserve(node_forces.size());
      for (const auto& [node, f] : node_forces) {
        if (e->has_columns(node))
          cm.forced.push_back({&e->columns.at(node), node, f});
        else
          cm.direct = true;  // (dropped by the memory bound: one solve instead)
      }
      auto add = [&](int q, const Eigen::Matrix<double, 6, 1>& jump) {
        auto [it, fresh] = cm.partner_jump.try_emplace(q, Eigen::Matrix<double, 6, 1>::Zero());
        it->second += jump;
      };
      // the movable partners (rigid bodies, floating elastic bodies' frames) of a mechanism
      auto along = [&](int r, const Eigen::Matrix<double, 6, 1>& w) {
        for (const std::vector<int>* list : {&e->partners, &e->elastic_partners})
          for (const int q : *list)
            if (partner[static_cast<std::size_t>(q)].movable && coupled(q, r))
              add(q, coupling(q, r) * w);
      };
      if (e->floating) {
        Eigen::Matrix<double, 6, 1> load;
        load << frame_force, frame_torque;
        cm.jump = mobility * load;
        along(body, load);  // partners of the frame's own mechanism move along
      }
      for (const auto& [r, w] : partner_wrench) {
        if (!partner[static_cast<std::size_t>(r)].movable) continue;
        add(r, partner[static_cast<std::size_t>(r)].mobility * w);
        along(r, w);                                                            // its mechanism
        if (e->floating && coupled(body, r)) cm.jump += coupling(body, r) * w;  // and the frame
      }
      // and the other stages' of its group on the bodies they share, as their rows' last
      // solve gave them (their own stages' passes see these forces' effect on them, and the
      // joint solve takes both)
      if (const auto g = group_wrenches.find(body); g != group_wrenches.end())
        for (const auto& [r, w] : g->second) {
          if (!partner[static_cast<std::size_t>(r)].movable) continue;
          add(r, partner[static_cast<std::size_t>(r)].mobility * w);
          along(r, w);
          if (e->floating && coupled(body, r)) cm.jump += coupling(body, r) * w;
        }
      if (e->mean_axes) cm.mean = e->rigid_part_of(node_forces, to_frame(cm.jump) / (dt * dt));
      return cm;
    };
    // how far partner r's material point at p travels over the step: its free motion and
    // its answer to the contact forces of `cm`
    auto partner_travel = [&](const ContactMotion& cm, int r, const Eigen::Vector3d& p) {
      const PartnerMotion& pm = partner[static_cast<std::size_t>(r)];
      Eigen::Vector3d d = pm.shift(p);
      const auto it = cm.partner_jump.find(r);
      if (it != cm.partner_jump.end()) d += pm.jump_shift(it->second, p);
      return d;
    };
    auto start_point = [&](const SurfaceContact& c) {
      if (c.nodes[0] < 0 && c.nodes[1] < 0 && c.nodes[2] < 0) return c.on_b;  // a support's
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k)
        if (c.nodes[k] >= 0) x += c.weights[k] * x0.row(c.nodes[k]).transpose();
      return x;
    };
    // a point the narrow phase found where `x_end` ends the surface (its partner where `cm`
    // takes it): the same plane, from where the step starts
    auto seen_from_start = [&](SurfaceContact& c, const ContactMotion& cm,
                               const Eigen::MatrixX3d& x_end, int partner_body) {
      Eigen::Vector3d travel = -partner_travel(cm, partner_body, start_point(c));
      for (int q = 0; q < 3; ++q)
        if (c.nodes[q] >= 0)
          travel += c.weights[q] * (x_end.row(c.nodes[q]) - x0.row(c.nodes[q])).transpose();
      c.gap -= c.normal.dot(travel);
    };
    std::unordered_map<int, std::size_t> elastic_near_of;  // body -> its entry
    for (std::size_t k = 0; k < elastic_near.size(); ++k) elastic_near_of[elastic_near[k].body] = k;
    // how far an elastic partner's surface node k moves under the reactions of `cm`: its
    // compliance (in its axes), and a floating one's frame jump and the deformation the
    // jump's acceleration causes
    // an elastic partner's forced nodes' columns and forces (its axes), looked up once per
    // partner and motion (a node's motion sums them, in the forces' order)
    // the deformation of eb under nodal forces (turned into its axes by `rt`) from one solve
    // with its kept factor
    auto solve_node_forces = [&](const ElasticBody& eb, const NodeForces& forces,
                                 const Eigen::Matrix3d& rt) -> Eigen::VectorXd {
      std::vector<Eigen::Triplet<double>> entries;
      for (const auto& [node, f] : forces) {
        const Eigen::Vector3d local = rt * f;
        for (int q = 0; q < 3; ++q)
          entries.emplace_back(3 * eb.surface.nodes[static_cast<std::size_t>(node)] + q, 0,
                               local[q]);
      }
      Eigen::SparseMatrix<double> load(eb.solver->displacement().size(), 1);
      load.setFromTriplets(entries.begin(), entries.end());  // sums a node's shares
      ++elastic_stats_.correction_solves;
      return eb.solver->response(load).col(0);
    };
    auto partner_forced_of = [&](ContactMotion& cm, int other) -> ContactMotion::Partner& {
      auto [it, fresh] = cm.partner_forced.try_emplace(other);
      ContactMotion::Partner& pf = it->second;
      if (!fresh) return pf;
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      const ElasticNear& en = elastic_near[elastic_near_of.at(other)];
      const auto forces = cm.partner_forces->find(other);
      if (forces != cm.partner_forces->end())
        for (const auto& [node, f] : forces->second) {
          if (eb.has_columns(node))
            pf.forced.push_back({&eb.columns.at(node), node, en.rot.transpose() * f});
          else
            pf.direct = true;  // (dropped by the memory bound: one solve instead)
        }
      // (in mean axes, the rigid part of its deformation under them, taken out below)
      if (eb.mean_axes) {
        NodeForces local;
        if (forces != cm.partner_forces->end())
          for (const auto& [node, f] : forces->second)
            local.push_back({node, en.rot.transpose() * f});
        const auto jump = cm.partner_jump.find(other);
        const Eigen::Matrix<double, 6, 1> a = jump != cm.partner_jump.end()
                                                  ? (en.rt6 * jump->second / (dt * dt)).eval()
                                                  : Eigen::Matrix<double, 6, 1>::Zero();
        cm.partner_mean[other] = eb.rigid_part_of(local, a);
      }
      return pf;
    };
    // the partner's deformation under the forces from one solve with its factor (once)
    auto partner_deformation = [&](ContactMotion& cm, int other, ContactMotion::Partner& pf) {
      if (pf.deformation.size() > 0) return;
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      const ElasticNear& en = elastic_near[elastic_near_of.at(other)];
      const auto forces = cm.partner_forces->find(other);
      pf.deformation =
          solve_node_forces(eb, forces != cm.partner_forces->end() ? forces->second : NodeForces{},
                            en.rot.transpose());
    };
    // where partner node k goes, given its deformation u under the forces (its axes): less
    // the rigid part in mean axes, a floating one's frame jump and the deformation the
    // jump's acceleration causes (partner_forced_of first)
    auto partner_finish = [&](const ContactMotion& cm, int other, int k,
                              Eigen::Vector3d u) -> Eigen::Vector3d {
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      const ElasticNear& en = elastic_near[elastic_near_of.at(other)];
      const auto jump = cm.partner_jump.find(other);
      if (eb.mean_axes) {
        const geometry::TetMesh& mesh = scene_.bodies[static_cast<std::size_t>(other)].tet_mesh;
        u -= ElasticBody::rigid_motion(
            cm.partner_mean.at(other),
            mesh.nodes.row(eb.surface.nodes[static_cast<std::size_t>(k)]).transpose() -
                scene_.bodies[static_cast<std::size_t>(other)].mass_properties.centroid);
      }
      if (en.floating && jump != cm.partner_jump.end()) {
        u.noalias() -=
            eb.inertia_response.middleRows<3>(3 * eb.surface.nodes[static_cast<std::size_t>(k)]) *
            (en.rt6 * jump->second / (dt * dt));
        return (en.rot * u).eval() + partner[static_cast<std::size_t>(other)].jump_shift(
                                         jump->second, en.x0.row(k).transpose());
      }
      return (en.rot * u).eval();
    };
    // how far an elastic partner's surface node k moves under the reactions of `cm`: its
    // compliance (in its axes), and a floating one's frame jump and the deformation the
    // jump's acceleration causes
    // (a node without columns, or all when the forces lack theirs: from the partner's
    // deformation, one solve)
    auto partner_motion_of = [&](ContactMotion& cm, int other, int k) -> Eigen::Vector3d {
      const auto found = cm.partner_at.find({other, k});
      if (found != cm.partner_at.end()) return found->second;
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      ContactMotion::Partner& pf = partner_forced_of(cm, other);
      Eigen::Vector3d u = Eigen::Vector3d::Zero();
      if (pf.direct || !eb.has_columns(k)) {
        partner_deformation(cm, other, pf);
        u = pf.deformation.segment<3>(3 * eb.surface.nodes[static_cast<std::size_t>(k)]);
      } else {
        for (const ForcedNode& x : pf.forced)
          u.noalias() += eb.compliance(*x.column, x.node, k) * x.f;
      }
      u = partner_finish(cm, other, k, u);
      cm.partner_at.emplace(std::make_pair(other, k), u);
      return u;
    };
    // partner_motion_of for many nodes at once (the partner's surface near this body where
    // a pass ends: a landing on an elastic part asks a thousand nodes under a thousand
    // forces), as motions_of below: the nodes with columns in their row order, each column
    // read down them, on two threads (each node's sum in the same order: the same bits)
    auto partner_motions_of = [&](ContactMotion& cm, int other, std::vector<int> nodes) {
      const ElasticBody& eb = *elastic_[static_cast<std::size_t>(other)];
      ContactMotion::Partner& pf = partner_forced_of(cm, other);
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
      nodes.erase(std::remove_if(nodes.begin(), nodes.end(),
                                 [&](int k) {
                                   return k < 0 || cm.partner_at.count({other, k});
                                 }),
                  nodes.end());
      std::vector<const NodeColumns*> own;
      const std::size_t first_summed = split_by_columns(
          eb, [&](int k) { return pf.direct || !eb.has_columns(k); }, &nodes, &own);
      if (first_summed > 0) partner_deformation(cm, other, pf);
      std::vector<Eigen::Vector3d> out(nodes.size(), Eigen::Vector3d::Zero());
      for (std::size_t q = 0; q < first_summed; ++q)
        out[q] =
            pf.deformation.segment<3>(3 * eb.surface.nodes[static_cast<std::size_t>(nodes[q])]);
      const std::size_t count = nodes.size() - first_summed;
      const double work = static_cast<double>(count) * static_cast<double>(pf.forced.size() + 1);
      in_two_threads(work >= 2e4, [&](int part, int parts) {
        const std::size_t q0 = first_summed + count * static_cast<std::size_t>(part) /
                                                  static_cast<std::size_t>(parts),
                          q1 = first_summed + count * static_cast<std::size_t>(part + 1) /
                                                  static_cast<std::size_t>(parts);
        add_column_sums(eb, pf.forced, nodes, own, q0, q1, &out);
      });
      for (std::size_t q = 0; q < nodes.size(); ++q)
        cm.partner_at.emplace(std::make_pair(other, nodes[q]),
                              partner_finish(cm, other, nodes[q], out[q]));
    };
    // how far the partner's point of a row travels over the step: its free motion and its
    // answer to the contact forces of `cm`
    auto row_travel = [&](ContactMotion& cm, const auto& row) -> Eigen::Vector3d {
      if (row.elastic < 0) return partner_travel(cm, row.partner, start_point(row.c));
      const ElasticNear& en = elastic_near[static_cast<std::size_t>(row.elastic)];
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const int j = row.b_nodes[static_cast<std::size_t>(k)];
        if (j < 0) continue;
        d += row.b_weights[static_cast<std::size_t>(k)] *
             ((en.x1.row(j) - en.x0.row(j)).transpose() + partner_motion_of(cm, en.body, j));
      }
      return d;
    };
    // what forces f_r on the body's rows (world) do to the movable partners: -f_r at the
    // rows' points, as force and torque about each partner's centre
    auto partner_wrenches = [&](const auto& rows_of, const auto& force_of, std::size_t count) {
      Wrenches w;
      for (std::size_t r = 0; r < count; ++r) {
        const auto& row = rows_of(r);
        // (a support on a free body pushes that body as well: its normal is the force on it)
        for (const int side : {row.partner, free_support(row) ? row.fixed : -1}) {
          if (side < 0) continue;
          const PartnerMotion& pm = partner[static_cast<std::size_t>(side)];
          if (!pm.movable) continue;
          const Eigen::Vector3d f = side == row.partner ? (-force_of(r)).eval() : force_of(r);
          if (f.squaredNorm() == 0) continue;
          auto& sum = w.try_emplace(side, Eigen::Matrix<double, 6, 1>::Zero()).first->second;
          sum.template head<3>() += f;
          sum.template tail<3>() += (start_point(row.c) - pm.x0).cross(f);
        }
      }
      return w;
    };
    // the reactions -f_r of forces f_r on the rows (world) on the elastic partners' nodes
    auto partner_forces = [&](const auto& force_of) {
      std::map<int, NodeForces> out;
      for (std::size_t r = 0; r < rows.size(); ++r) {
        const Row& row = rows[r];
        if (row.elastic < 0) continue;
        const Eigen::Vector3d f = force_of(r);
        if (f.squaredNorm() == 0) continue;
        NodeForces& to = out[row.partner];
        for (int k = 0; k < 3; ++k)
          if (row.b_nodes[static_cast<std::size_t>(k)] >= 0)
            to.push_back({row.b_nodes[static_cast<std::size_t>(k)],
                          -row.b_weights[static_cast<std::size_t>(k)] * f});
        if (row.fixed_elastic < 0) continue;
        NodeForces& held = out[row.fixed];  // (a support's force is on the held body)
        for (std::size_t k = 0; k < 3; ++k)
          if (row.f_nodes[k] >= 0) held.push_back({row.f_nodes[k], row.f_weights[k] * f});
      }
      return out;
    };
    const Eigen::Matrix3d r0 = frame0.rotation.toRotationMatrix();
    // where the forces of `cm` carry surface node k, given its deformation u under them (frame
    // axes)
    auto finish_motion = [&](const ContactMotion& cm, int k, Eigen::Vector3d u) -> Eigen::Vector3d {
      if (e->floating)  // the deformation of the frame's acceleration jump (jump holds dt^2)
        u.noalias() -= e->inertia_response.middleRows<3>(3 * e->surface.nodes[k]) *
                       (to_frame(cm.jump) / (dt * dt));
      if (e->mean_axes)  // less its rigid part
        u -= ElasticBody::rigid_motion(
            cm.mean, b.tet_mesh.nodes.row(e->surface.nodes[k]).transpose() - centroid);
      Eigen::Vector3d mv = r0 * u;
      if (e->floating) {
        const Eigen::Matrix<double, 6, 1> travel = own_travel * cm.jump;
        mv += travel.head<3>() + travel.tail<3>().cross(x0.row(k).transpose() - frame0.position);
      }
      return mv;
    };
    // the deformation under cm's forces from one solve with the kept factor (once)
    auto solve_deformation = [&](ContactMotion& cm) {
      if (cm.deformation.size() == 0)
        cm.deformation = solve_node_forces(*e, *cm.node_forces, Eigen::Matrix3d::Identity());
    };
    // whether node k's motion is read from that deformation: when cm is direct, and for a
    // node without columns (a node with them reads them, as the rows' Delassus matrix does,
    // step after step: a motion read from the one solve differs in its last bits, and at a
    // resting contact's points, with neither force nor gap, that flips which are pressed)
    auto from_deformation = [&](const ContactMotion& cm, int k) {
      return cm.direct || !e->has_columns(k);
    };
    // the same from scratch (cm's deformation solved first where read)
    auto compute_motion = [&](const ContactMotion& cm, int k) -> Eigen::Vector3d {
      Eigen::Vector3d u = Eigen::Vector3d::Zero();
      if (from_deformation(cm, k))
        u = cm.deformation.segment<3>(3 * e->surface.nodes[static_cast<std::size_t>(k)]);
      else
        for (const ForcedNode& x : cm.forced)
          u.noalias() += e->compliance(*x.column, x.node, k) * x.f;
      return finish_motion(cm, k, u);
    };
    auto motion_of = [&](ContactMotion& cm, int k) -> Eigen::Vector3d {
      const auto found = cm.at.find(k);
      if (found != cm.at.end()) return found->second;
      if (from_deformation(cm, k)) solve_deformation(cm);
      const Eigen::Vector3d mv = compute_motion(cm, k);
      cm.at.emplace(k, mv);
      return mv;
    };
    // motion_of for many nodes at once: thousands of nodes under hundreds of forces at a
    // landing. The nodes with columns in their row order, each forced node's column read
    // down them (a node's sum taken column by column had every column's block miss the
    // cache: the sums took 8 % of the snap-fit's run), the nodes split in two halves over
    // two threads (each node's sum in the same order, so the same bits)
    auto motions_of = [&](ContactMotion& cm, std::vector<int> nodes) {
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
      nodes.erase(std::remove_if(nodes.begin(), nodes.end(),
                                 [&](int k) { return k < 0 || cm.at.count(k) > 0; }),
                  nodes.end());
      std::vector<const NodeColumns*> own;
      const std::size_t first_summed = split_by_columns(
          *e, [&](int k) { return from_deformation(cm, k); }, &nodes, &own);
      if (first_summed > 0) solve_deformation(cm);
      std::vector<Eigen::Vector3d> out(nodes.size(), Eigen::Vector3d::Zero());
      const std::size_t count = nodes.size() - first_summed;
      const double work = static_cast<double>(first_summed) +
                          static_cast<double>(count) * static_cast<double>(cm.forced.size() + 1);
      in_two_threads(work >= 2e4, [&](int part, int parts) {
        auto range = [&](std::size_t from, std::size_t n) {
          return std::make_pair(
              from + n * static_cast<std::size_t>(part) / static_cast<std::size_t>(parts),
              from + n * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(parts));
        };
        const auto [d0, d1] = range(0, first_summed);
        for (std::size_t q = d0; q < d1; ++q) out[q] = compute_motion(cm, nodes[q]);
        const auto [q0, q1] = range(first_summed, count);
        add_column_sums(*e, cm.forced, nodes, own, q0, q1, &out);
        for (std::size_t q = q0; q < q1; ++q) out[q] = finish_motion(cm, nodes[q], out[q]);
      });
      for (std::size_t q = 0; q < nodes.size(); ++q) cm.at.emplace(nodes[q], out[q]);
    };
    auto nodes_of_rows = [](const auto& list) {
      std::vector<int> nodes;
      nodes.reserve(3 * list.size());
      for (const auto& r : list)
        for (int k = 0; k < 3; ++k) nodes.push_back(r.c.nodes[k]);
      return nodes;
    };
    // where last step's contact forces would carry the surface: a point whose gap stays
    // open under them need not take part (with quasi-static deformation the free motion
    // alone relaxes every pressed part into its partner)
    // In a group, the other stages' last forces on the floating bodies they share with this
    // one go with them: the free motion leaves them out (they are solved with these rows now,
    // not taken as forces to come). Without them, two cubes pressed together at rest on a
    // loose mat saw the pushed cube, in the mat's stage, tip under the mat's friction alone
    // (the pair's push missing) by about the keep distance below at its front and back
    // edges, and its rows there came and went from step to step: it never slept at steps
    // from 2 ms. (Their rigid partners' share is in group_wrenches from the start.)
    NodeForces warm_nodes = e->last_forces;
    Eigen::Matrix<double, 6, 1> warm_frame;
    warm_frame << e->last_frame_force, e->last_frame_torque;
    Wrenches warm_partners = e->last_partner_wrench;
    std::map<int, NodeForces> warm_partner_nodes = e->last_partner_forces;
    if (in_group.count(body))
      for (const int other : in_group) {
        if (other == body) continue;
        for (const auto& [r, w] : stage_wrench(other)) {
          if (r == body && e->floating)
            warm_frame += w;
          else if (r != body && floating(r) && partner[static_cast<std::size_t>(r)].movable)
            warm_partners.try_emplace(r, Eigen::Matrix<double, 6, 1>::Zero()).first->second += w;
        }
        for (const auto& [r, forces] : pass_or_stage_loads(other)) {  // (world axes)
          if (r == body) {
            for (const auto& [node, f] : forces) warm_nodes.push_back({node, r0.transpose() * f});
          } else if (elastic_near_of.count(r)) {
            NodeForces& to = warm_partner_nodes[r];
            to.insert(to.end(), forces.begin(), forces.end());
          }
        }
      }
    ContactMotion warm_motion = contact_motion(
        warm_nodes, warm_frame.head<3>(), warm_frame.tail<3>(), warm_partners, warm_partner_nodes);
    // the point's motion against the other side's over the step (the forces `extra` added)
    auto end_motion = [&](const Row& r, ContactMotion& extra) {
      // (a free holding body: its travel under the forces as well)
      Eigen::Vector3d motion =
          (free_support(r) ? partner_travel(extra, r.fixed, r.c.on_b) : r.fixed_travel) -
          row_travel(extra, r);
      for (std::size_t k = 0; k < 3 && r.fixed_elastic >= 0; ++k)  // (a held elastic body too)
        if (r.f_nodes[k] >= 0)
          motion += r.f_weights[k] * partner_motion_of(extra, r.fixed, r.f_nodes[k]);
      for (int k = 0; k < 3; ++k)
        if (r.c.nodes[k] >= 0)
          motion += r.c.weights[k] * ((x1.row(r.c.nodes[k]) - x0.row(r.c.nodes[k])).transpose() +
                                      motion_of(extra, r.c.nodes[k]));
      return motion;
    };
    auto end_gap = [&](const Row& r, ContactMotion& extra) {
      return r.c.gap + r.c.normal.dot(end_motion(r, extra));
    };
    // whether a row takes part: end_gap, but for a node on a rigid part's edge or vertex
    // the node's distance from the part where `extra` ends it. Planar, the row's normal from
    // the edge turns with the node: a hook's lowest node just outside the base part's corner
    // and above it was held up by the corner's near-vertical normal, as if on its top face,
    // while the node passes beside it (a quasistatic socket driven 1.1 mm per increment
    // pushed 570-1,430 N instead of about 100 N over the edges)
    auto passes_edge = [&](const Row& r) {
      return r.fixed < 0 && r.elastic < 0 && r.c.node_row && !r.c.on_face &&
             near_of.count(r.part) > 0;
    };
    auto take_gap = [&](const Row& r, ContactMotion& extra) {
      if (!passes_edge(r)) return end_gap(r, extra);
      const int k = r.c.nodes[0];
      const Eigen::Vector3d start = x0.row(k).transpose();
      const Eigen::Vector3d end =
          x1.row(k).transpose() + motion_of(extra, k) - partner_travel(extra, r.partner, start);
      Eigen::Vector3d foot, normal;
      bool on_face = false;
      return signed_distance(near[near_of.at(r.part)].world, end, &foot, &normal, &on_face);
    };
    // only the points that are closed or would close within the step (rows sliding past
    // at a distance cost solves and carry nothing); a point pressed in the last step stays
    // up to 8 times farther (hysteresis: two rubber blocks pressed together at rest, 2 ms
    // steps, had their rows' set cycle every 3 steps, 35 / 28 / 33 points, the push answered
    // to 1.5e-4 and never asleep; the solve still lets such a point go)
    std::vector<Row> excluded;
    {
      const double keep = 2e-3 * h;
      std::size_t kept = 0;
      motions_of(warm_motion, nodes_of_rows(rows));
      for (const Row& r : rows) {
        if (r.fixed < 0 &&
            take_gap(r, warm_motion) < (e->warm.count({r.part, r.c.key}) ? 8 * keep : keep))
          rows[kept++] = r;
        else if (r.fixed < 0)
          excluded.push_back(r);
      }
      // a partner's supports go with its pair's rows
      std::vector<Row> supports;
      for (const Row& r : rows)
        if (r.fixed >= 0) supports.push_back(r);
      rows.resize(kept);
      for (const Row& r : supports) {
        const bool paired = std::any_of(rows.begin(), rows.end(), [&](const Row& q) {
          if (r.link) return q.fixed < 0 && q.elastic < 0 && linked.count(q.partner) > 0;
          return q.fixed < 0 && q.elastic == r.elastic;
        });
        (paired ? rows : excluded).push_back(r);
      }
      if (rows.empty() && !excluded.empty()) {
        // no force at all: the points are checked against the free motion alone (the
        // last forces that kept them open are gone with them)
        std::vector<std::pair<int, Eigen::Vector3d>> none;
        ContactMotion free_only = contact_motion(none, Eigen::Vector3d::Zero(),
                                                 Eigen::Vector3d::Zero(), {}, no_partner_forces);
        std::size_t out = 0;
        for (const Row& r : excluded) {
          if (take_gap(r, free_only) < keep)
            rows.push_back(r);
          else
            excluded[out++] = r;
        }
        excluded.resize(out);
      }
    }
    if (rows.empty() && std::any_of(excluded.begin(), excluded.end(), passes_edge)) {
      // nodes left out as passing a part's edge: what the free motion ends inside a part
      // (the edge on the face behind the node) joins, its row taken at the end and seen
      // from the start, as the narrow phase does after a solve below
      std::vector<std::pair<int, Eigen::Vector3d>> none;
      ContactMotion free_end = contact_motion(none, Eigen::Vector3d::Zero(),
                                              Eigen::Vector3d::Zero(), {}, no_partner_forces);
      std::set<std::pair<int, std::int64_t>> left_out;  // (a point is one row or left out)
      for (const Row& r : excluded) left_out.insert({r.part, r.c.key});
      for (std::size_t k = 0; k < near.size(); ++k) {
        if (near_candidates[k].empty()) continue;
        const int partner_body = rigid_parts_[static_cast<std::size_t>(near[k].part)].body;
        Eigen::MatrixX3d relative = x1;  // as seen by the partner at the step's end
        Eigen::VectorXd touch = Eigen::VectorXd::Zero(x1.rows());
        for (int t : near_candidates[k])
          for (int q = 0; q < 3; ++q) {
            const int j = e->surface.triangles(t, q);
            if (touch[j] > 0) continue;
            relative.row(j) -=
                partner_travel(free_end, partner_body, x1.row(j).transpose()).transpose();
            touch[j] = (x1.row(j) - x0.row(j)).norm() + partner_speed * dt + margin;
          }
        for (SurfaceContact& c : surface_part_contacts(e->surface, relative, near[k].world,
                                                       near_candidates[k], touch)) {
          if (c.gap > -1e-3 * h || left_out.count({near[k].part, c.key})) continue;
          seen_from_start(c, free_end, x1, partner_body);
          rows.push_back({c, near[k].part, partner_body});
          rows.back().found_normal = c.normal;  // found where the step ends: not turned
        }
      }
    }
    if (rows.empty()) {
      Eigen::VectorXd applied = Eigen::VectorXd::Zero(prediction.size());
      if (e->floating) applied -= e->inertia_load * free_acceleration;
      if (owner_loaded) applied += e->pending_load;
      bool late_load = false;
      if (!alone) {
        // (in a group: after the other stages have applied their forces, which may be on
        // this body: an owner's reactions on its nodes and frame)
        StageRequest barrier;
        barrier.kind = StageRequest::kJumpsApplied;
        co_await StageAwait{barrier, alone, [](StageRequest&) {}};
        late_load = !owner_loaded && e->pending_load.size() > 0 && !e->pending_load.isZero(0);
        if (late_load) {
          applied += e->pending_load;
          prediction += solver.response(e->pending_load.sparseView()).col(0);
          ++elastic_stats_.correction_solves;
        }
        if (const auto g = group_wrenches.find(body); g != group_wrenches.end() && e->floating)
          if (const auto w = g->second.find(body); w != g->second.end()) {
            const Eigen::Matrix<double, 6, 1> a = to_frame(mobility * w->second / (dt * dt));
            prediction.noalias() -= e->inertia_response * a;
            applied.noalias() -= e->inertia_load * a;
          }
      }
      if (e->floating || owner_loaded || late_load)
        solver.accept(prediction, &applied);
      else
        solver.accept(prediction);
      e->last_motion = 0;
      for (int node : e->surface.nodes)
        e->last_motion = std::max(e->last_motion, prediction.segment<3>(3 * node).norm());
      e->force_change = 0;
      e->pending_load.setZero();
      e->last_partner_forces.clear();
      e->last_points = 0;
      e->last_pair_force.clear();
      done[i] = 1;
      e->warm.clear();
      e->last_forces.clear();
      e->last_frame_force.setZero();
      e->contact_force.setZero();
      e->last_frame_torque.setZero();
      e->last_partner_wrench.clear();
      e->last_own_wrench.setZero();
      e->last_own_forces.clear();
      e->sticking_on.clear();
      e->last_held_rows.clear();
      co_return;
    }
    Eigen::Index m = static_cast<Eigen::Index>(rows.size());
    ++elastic_stats_.steps;
    for (const Row& r : rows)  // (a support's overlap is its own stage's)
      if (r.fixed < 0 && -r.c.gap > elastic_stats_.max_penetration) {
        elastic_stats_.max_penetration = -r.c.gap;
        elastic_stats_.max_penetration_time = time_;
      }
    for (const Row& r : rows)
      if (r.fixed < 0 && r.c.gap < -0.25 * h) {
        const Body& other = scene_.bodies[static_cast<std::size_t>(r.partner)];
        char t[320];
        std::snprintf(t, sizeof t,
                      "' could not be resolved at t = %.6g s (an overlap of %.3g m, more than a "
                      "quarter of the mesh size %.3g m): use a smaller dt (now %.3g s: "
                      "simulate(dt=...) or --dt)",
                      time_, -r.c.gap, h, dt);
        std::string fix = t;
        // an elastic partner meshed coarser than this body: the body's features sink between
        // its nodes (the snap-fit's hooks passing a 0.5 in base part's edges), and a finer
        // partner mesh is the fix
        const double partner_h = other.kind == BodyKind::kElastic ? other.tet_mesh.mesh_size : 0.0;
        if (partner_h > 1.5 * h) {
          std::snprintf(t, sizeof t, " or a finer mesh_size for '%s' (now %.3g m",
                        other.name.c_str(), partner_h);
          fix += t;
          fix += ", coarser than '" + b.name + "''s: features sink between its nodes)";
        }
        // a wall far thinner than this body's elements (under a quarter of them; the
        // compiler warns under a sixteenth): a partner passes through it whatever the step
        // (the 85-degree hook failed so at a quarter of the step, and at elements five times
        // its wall)
        if (b.thinnest_wall > 0 && b.thinnest_wall < 0.25 * h) {
          std::snprintf(t, sizeof t,
                        " or a finer mesh_size for '%s' (now %.3g m, %.0f times its thinnest "
                        "wall, %.3g m: a partner passes through a wall the elements cannot "
                        "follow)",
                        b.name.c_str(), h, h / b.thinnest_wall, b.thinnest_wall);
          fix += t;
        }
        throw SimulationError("contact between '" + b.name + "' and '" + other.name + fix);
      }

    const Eigen::Matrix3d rot = frame0.rotation.toRotationMatrix();
    const Eigen::Index dofs = solver.displacement().size();
    PointContactProblem problem;
    std::vector<Eigen::Matrix3d> basis;  // per point: columns n, t1, t2 (world)
    std::vector<Eigen::Vector3d> arm;    // per point: from the frame's origin
    PointContactSolution sol;
    ContactStepRecord record;
    record.time = time_;
    record.body = body;
    record.detected = static_cast<int>(m + static_cast<Eigen::Index>(excluded.size()));
    // solve; points left out that the solution would still push through join, and again
    // the last pass's deformation under its forces when it was solved for (the narrow phase
    // at the step's end): the correction below, without solving again
    Eigen::VectorXd final_deformation;
    // the points (part, key) of part features whose rows left their triangles this step:
    // such a point does not take over again (at a ridge between two triangles a feature
    // would flip from one to the other)
    std::set<std::pair<int, std::int64_t>> left_triangle;
    // (dynamic steps: a feature's rows leave their triangles only in the pass where it
    // first leaves one; the part features (part, vertex, edge) and that pass)
    std::map<std::tuple<int, int, int>, int> switched;
    std::vector<Eigen::Vector3d> last_resultants;  // the force of the passes before the last two
    double left_force = 0;
    // the forces of the last pass by (part, point key): the next pass's start
    std::map<std::pair<int, std::int64_t>, Eigen::Vector3d> pass_warm;
    for (int pass = 0;; ++pass) {
      record.passes = pass + 1;
      m = static_cast<Eigen::Index>(rows.size());
      // the compliance columns for the touched nodes (kept for the run): this body's, and
      // the elastic partners' for their points
      const auto columns_started = Clock::now();
      auto add_columns = [&](int which, auto nodes_of_row) {
        ElasticBody& eb = *elastic_[static_cast<std::size_t>(which)];
        std::vector<int> needed, missing;
        std::unordered_set<int> seen;
        for (const Row& r : rows)
          for (int j : nodes_of_row(r))
            if (j >= 0 && seen.insert(j).second) needed.push_back(j);
        for (int j : needed)
          if (!eb.has_columns(j)) missing.push_back(j);
        // (when rows last needed each node's columns: which to drop first)
        ++eb.column_clock;
        if (eb.column_use.size() != eb.surface.nodes.size())
          eb.column_use.assign(eb.surface.nodes.size(), 0);
        for (int j : needed) eb.column_use[static_cast<std::size_t>(j)] = eb.column_clock;
        if (missing.empty()) return;
        // a solve costs about the same for a few columns as for a few dozen (the factor is
        // read once per block of right-hand sides): take along the nodes of the points
        // about to close, which the next steps would ask for one by one
        const std::size_t own = missing.size();
        for (const Row& r : excluded)
          for (int j : nodes_of_row(r))
            if (missing.size() < needed.size() + 48 && j >= 0 && !eb.has_columns(j) &&
                seen.insert(j).second)
              missing.push_back(j);
        for (std::size_t q = own; q < missing.size(); ++q)  // (soon needed, likely)
          eb.column_use[static_cast<std::size_t>(missing[q])] = eb.column_clock;
        // bound their memory to a third of what is left (each new node's columns hold every
        // node's with columns): past it, the columns of the nodes that rows needed longest ago
        // are dropped to make room for the new ones and a quarter of the bound more (a cap's
        // lip sliding round a bead presses new nodes as it leaves others), and solved again
        // if rows need them again; where the rows' own nodes leave no room for those taken
        // along, only theirs are added
        const double bound = factor_memory_limit() / 3;
        if (!columns_fit(eb, missing.size(), bound)) {
          std::vector<int> kept = columns_to_keep(eb, needed, missing.size(), bound);
          if (kept.empty()) {
            missing.resize(own);
            kept = columns_to_keep(eb, needed, own, bound);
          }
          if (kept.size() < eb.column_nodes.size()) {
            std::vector<char> keep(eb.surface.nodes.size(), 0);
            for (const int k : kept) keep[static_cast<std::size_t>(k)] = 1;
            if (kept.empty()) missing = needed;  // (none kept: the rows' own columns only)
            keep_columns(eb, keep);
            ++elastic_stats_.column_drops;
          }
        }
        fill_columns(eb, std::move(missing));
      };
      add_columns(body, [](const Row& r) { return r.c.nodes; });
      for (std::size_t k = 0; k < elastic_near.size(); ++k)
        add_columns(elastic_near[k].body, [&](const Row& r) {
          // (its points of the rows on it, and of the supports on it)
          std::array<int, 3> nodes{-1, -1, -1};
          if (r.fixed_elastic == static_cast<int>(k))
            nodes = r.f_nodes;
          else if (r.partner == elastic_near[k].body && r.elastic >= 0)
            nodes = r.b_nodes;
          return nodes;
        });
      elastic_stats_.column_seconds +=
          std::chrono::duration<double>(Clock::now() - columns_started).count();
      elastic_stats_.region_nodes = elastic_stats_.surface_nodes = 0;
      for (const auto& other : elastic_)
        if (other && !other->column_nodes.empty()) {
          elastic_stats_.region_nodes += static_cast<long>(other->column_nodes.size());
          elastic_stats_.surface_nodes += static_cast<long>(other->surface.nodes.size());
        }

      // a large problem's rows in the order of their first node on the surface (its
      // numbering, which does not depend on the run's history), a partner's supports last.
      // The order decides, in the last bits, which of a resting contact's points (neither
      // force nor gap) are pressed, and how many Newton iterations a large solve takes:
      // in the order the nodes got their compliance columns, or in a Morton order of their
      // places, a block on a loose mat never came to rest (its points' states flickered from
      // step to step); in this one it rests from t = 0.06 s, but the snap-fit's landing at
      // 0.088 s (run with 120 frames: 1,128 points, 700 pressed) takes 64 iterations, not
      // 14. In the order the nodes joined a region of columns (until 2026-11-27) its solves
      // took 3.9 s against 4.7 s in the narrow phase's. (Small problems keep the narrow
      // phase's order: two rubber cubes pushed together below their friction then hold the
      // push to 1e-6 as before, 7e-6 in the other order.)
      if (m >= kSurfaceOrderRows)
        std::stable_sort(rows.begin(), rows.end(), [&](const Row& x, const Row& y) {
          auto place = [&](const Row& r) {
            return r.fixed >= 0 || r.c.nodes[0] < 0 ? std::numeric_limits<int>::max()
                                                    : r.c.nodes[0];
          };
          return place(x) < place(y);
        });
      // (points joined in later passes count: the largest Delassus matrix solved)
      elastic_stats_.max_points = std::max(elastic_stats_.max_points, static_cast<int>(m));
      // the free motion of each point over the step: normal gap and tangential slip
      problem.free.resize(3 * m);
      problem.mu.resize(rows.size());
      basis.resize(rows.size());
      arm.resize(rows.size());
      Eigen::VectorXd warm(3 * m);
      // a movable body the rows' supports are on: its free motion (and its mechanism's) took
      // their elastic bodies' last forces on it as forces to come (`later`), which those rows
      // now solve for; how far those forces carry a body's point at p, taken back out
      std::map<int, Eigen::Matrix<double, 6, 1>> solved_here;  // by body: their wrench
      {
        std::set<std::pair<int, int>> counted;  // (holding body, elastic body)
        for (const Row& row : rows) {
          if (!free_support(row) || row.link || !later.count(row.fixed) ||
              !counted.insert({row.fixed, row.partner}).second)
            continue;
          const PartnerWrenches& last = stage_wrench(row.partner);
          if (const auto it = last.find(row.fixed); it != last.end())
            solved_here.try_emplace(row.fixed, Eigen::Matrix<double, 6, 1>::Zero()).first->second +=
                it->second;
        }
      }
      auto lagged_shift = [&](int r, const Eigen::Vector3d& p) -> Eigen::Vector3d {
        const PartnerMotion& pm = partner[static_cast<std::size_t>(r)];
        Eigen::Matrix<double, 6, 1> motion = Eigen::Matrix<double, 6, 1>::Zero();
        for (const auto& [q, w] : solved_here) {  // (the body's own, or its mechanism's)
          if (q == r)
            motion += pm.later_response * w;
          else if (coupled(r, q))
            motion += coupling(r, q) * w;
        }
        return pm.jump_shift(motion, p);
      };
      for (Eigen::Index r = 0; r < m; ++r) {
        Row& row = rows[static_cast<std::size_t>(r)];
        const int partner_body = row.partner;
        Eigen::Vector3d xa0 = Eigen::Vector3d::Zero(), xa1 = Eigen::Vector3d::Zero();
        for (int k = 0; k < 3; ++k)
          if (row.c.nodes[k] >= 0) {
            xa0 += row.c.weights[k] * x0.row(row.c.nodes[k]).transpose();
            xa1 += row.c.weights[k] * x1.row(row.c.nodes[k]).transpose();
          }
        arm[static_cast<std::size_t>(r)] =
            row.fixed < 0 ? (xa0 - frame0.position).eval() : Eigen::Vector3d::Zero().eval();
        Eigen::Vector3d rel = xa1 - xa0 + row.fixed_travel;
        if (free_support(row)) rel -= lagged_shift(row.fixed, row.c.on_b);
        if (row.elastic < 0) {
          const Eigen::Vector3d at = row.link ? row.c.on_b : xa0;  // (a link's: its point)
          rel -= partner[static_cast<std::size_t>(partner_body)].shift(at) -
                 lagged_shift(partner_body, at);
        } else {
          const ElasticNear& en = elastic_near[static_cast<std::size_t>(row.elastic)];
          for (int k = 0; k < 3; ++k)
            if (row.b_nodes[static_cast<std::size_t>(k)] >= 0)
              rel -= row.b_weights[static_cast<std::size_t>(k)] *
                     (en.x1.row(row.b_nodes[static_cast<std::size_t>(k)]) -
                      en.x0.row(row.b_nodes[static_cast<std::size_t>(k)]))
                         .transpose();
        }
        normal_prediction(row, rel);
        const SurfaceContact& c = row.c;
        Eigen::Vector3d t1, t2;
        tangents(c.normal, &t1, &t2);
        Eigen::Matrix3d& d = basis[static_cast<std::size_t>(r)];
        d << c.normal, t1, t2;
        problem.free.segment<3>(3 * r) = d.transpose() * rel;
        problem.free[3 * r] += c.gap;
        warm.segment<3>(3 * r).setZero();
        if (row.link) {  // from this stage's last pass or step
          problem.mu[static_cast<std::size_t>(r)] = pair_friction(scene_, partner_body, row.fixed);
          const auto here = pass_warm.find({row.part, c.key});
          const auto last = e->warm.find({row.part, c.key});
          if (here != pass_warm.end())
            warm.segment<3>(3 * r) = d.transpose() * here->second;
          else if (last != e->warm.end())
            warm.segment<3>(3 * r) = d.transpose() * last->second;
          continue;
        }
        if (row.fixed >= 0) {  // a partner's support: its own stage's last force, reversed
          problem.mu[static_cast<std::size_t>(r)] = pair_friction(scene_, partner_body, row.fixed);
          const auto& last = elastic_[static_cast<std::size_t>(partner_body)]->warm;
          const auto it = last.find({row.part, c.key});
          if (it != last.end()) warm.segment<3>(3 * r) = -(d.transpose() * it->second);
          continue;
        }
        problem.mu[static_cast<std::size_t>(r)] = pair_friction(scene_, body, partner_body);
        // from the last pass's force at the point, else last step's
        if (const auto here = pass_warm.find({row.part, c.key}); here != pass_warm.end()) {
          warm.segment<3>(3 * r) = d.transpose() * here->second;
          continue;
        }
        const auto it = e->warm.find({row.part, c.key});
        if (it != e->warm.end()) warm.segment<3>(3 * r) = d.transpose() * it->second;
      }

      // the Delassus matrix of the rows from the responses of the bodies on their sides
      // (delassus.h): this body's surface nodes (frame axes) and, floating, its frame; an
      // elastic partner's nodes (its axes) and, floating, its frame; a movable partner; the
      // body a support is on (a held elastic body's nodes, or a free or jointed one)
      const auto delassus_started = Clock::now();
      std::vector<RowSides> sides(rows.size());
      auto columns_of = [](const ElasticBody& eb, const std::array<int, 3>& nodes) {
        std::array<const ElasticBody::NodeColumns*, 3> c{};
        for (std::size_t k = 0; k < 3; ++k)
          if (nodes[k] >= 0) c[k] = &eb.columns.at(nodes[k]);
        return c;
      };
      for (std::size_t r = 0; r < rows.size(); ++r) {
        const Row& row = rows[r];
        RowSides& x = sides[r];
        if (row.fixed < 0)  // (a support or a link has no point of this body)
          x.add(NodeSide{e, body, 1, row.c.nodes, row.c.weights, columns_of(*e, row.c.nodes),
                         rot.transpose() * basis[r]});
        if (row.elastic >= 0) {
          const ElasticNear& en = elastic_near[static_cast<std::size_t>(row.elastic)];
          const ElasticBody& ep = *elastic_[static_cast<std::size_t>(row.partner)];
          x.add(NodeSide{&ep, row.partner, -1, row.b_nodes, row.b_weights,
                         columns_of(ep, row.b_nodes), en.rot.transpose() * basis[r]});
        }
        if (row.fixed_elastic >= 0) {
          const ElasticNear& held = elastic_near[static_cast<std::size_t>(row.fixed_elastic)];
          const ElasticBody& eh = *elastic_[static_cast<std::size_t>(held.body)];
          x.add(NodeSide{&eh, held.body, 1, row.f_nodes, row.f_weights, columns_of(eh, row.f_nodes),
                         held.rot.transpose() * basis[r]});
        }
        if (e->floating && row.fixed < 0) {
          Eigen::Matrix<double, 3, 6> j;
          for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d dir = basis[r].col(k);
            j.row(k) << dir.transpose(), arm[r].cross(dir).transpose();
          }
          x.add(FrameSide{body, 1, j});
        }
        const PartnerMotion& pm = partner[static_cast<std::size_t>(row.partner)];
        if (pm.movable)
          x.add(FrameSide{row.partner, -1, pm.jacobian(basis[r], start_point(row.c))});
        if (free_support(row))
          x.add(FrameSide{
              row.fixed, 1,
              partner[static_cast<std::size_t>(row.fixed)].jacobian(basis[r], row.c.on_b)});
      }
      // how a frame answers a wrench on itself (times dt^2), or on another body of its
      // mechanism (looked up before the assembly's threads share them)
      auto frame_mobility = [&](int q, int r) -> std::optional<Eigen::Matrix<double, 6, 6>> {
        // (how far it travels: a held one's jump along its free directions carries it half as
        // far; FloatingSide::jump_mobility keeps the jump)
        if (q == r) {
          if (q == body) return (own_travel * mobility).eval();
          const PartnerMotion& pm = partner[static_cast<std::size_t>(q)];
          return (pm.travel * pm.mobility).eval();
        }
        if (!coupled(q, r)) return std::nullopt;
        return coupling(q, r);
      };
      std::vector<FloatingSide> floating_sides;
      if (e->floating) {
        Eigen::Matrix<double, 6, 6> rt6 = Eigen::Matrix<double, 6, 6>::Zero();
        rt6.topLeftCorner<3, 3>() = rt0;
        rt6.bottomRightCorner<3, 3>() = rt0;
        floating_sides.push_back({body, e, rt6, &b.tet_mesh, centroid, mobility});
      }
      for (const ElasticNear& en : elastic_near)
        if (en.floating) {
          const Body& other = scene_.bodies[static_cast<std::size_t>(en.body)];
          const PartnerMotion& pm = partner[static_cast<std::size_t>(en.body)];
          floating_sides.push_back({en.body, elastic_[static_cast<std::size_t>(en.body)].get(),
                                    en.rt6, &other.tet_mesh, other.mass_properties.centroid,
                                    pm.movable ? std::optional(pm.mobility) : std::nullopt});
        }
      // the contact forces: this stage's rows alone, or with the rows of the other stages of
      // its group in one solve (solve_rows)
      const FrameMobility mobility_of = frame_mobility;
      {
        StageRequest request;
        request.kind = StageRequest::kSolve;
        request.problem = &problem;
        request.sides = &sides;
        request.floating = &floating_sides;
        request.mobility = &mobility_of;
        request.warm = &warm;
        // the gaps to a billionth of the mesh size (a body comes to rest only on a converged
        // solve)
        request.options.tolerance = 1e-9 * h;
        request.solution = &sol;
        request.started = delassus_started;
        request.body = body;
        co_await StageAwait{request, alone, [&](StageRequest& q) { solve_rows({&q}, dt); }};
      }
      // the pass's resultant contact force on the body
      Eigen::Vector3d resultant = Eigen::Vector3d::Zero();
      for (Eigen::Index r = 0; r < m; ++r)
        if (rows[static_cast<std::size_t>(r)].fixed < 0)
          resultant += basis[static_cast<std::size_t>(r)] * sol.lambda.segment<3>(3 * r);
      if (pass == kMaxPasses - 1) {
        // rows still changing, and the force with them over the last passes (rows dropped
        // one pass and found again the next), or pressed rows whose features left their
        // triangles in the last narrow phase (the force then passes to fewer rows on the
        // same planes: a hook's return face held out past its apex). (Rows that only refine
        // their planes leave the force within 2 %.)
        double change = 0, size = resultant.norm();
        for (const Eigen::Vector3d& f : last_resultants) {
          change = std::max(change, (resultant - f).norm());
          size = std::max(size, f.norm());
        }
        if (change > kSettledForce * size || left_force > kLeftForce * resultant.norm())
          not_settled(rows, sol.lambda,
                      std::max(change / std::max(size, 1e-300),
                               left_force / std::max(resultant.norm(), 1e-300)),
                      pass + 1);
        break;
      }
      if (pass >= kMaxPasses - 3) last_resultants.push_back(resultant);
      pass_warm.clear();
      for (Eigen::Index r = 0; r < m; ++r)
        if (rows[static_cast<std::size_t>(r)].fixed < 0 || rows[static_cast<std::size_t>(r)].link)
          pass_warm[{rows[static_cast<std::size_t>(r)].part,
                     rows[static_cast<std::size_t>(r)].c.key}] =
              basis[static_cast<std::size_t>(r)] * sol.lambda.segment<3>(3 * r);
      // where the forces found carry the points
      std::vector<std::pair<int, Eigen::Vector3d>> node_forces;
      Eigen::Vector3d ff = Eigen::Vector3d::Zero(), ft = Eigen::Vector3d::Zero();
      for (Eigen::Index r = 0; r < m; ++r) {
        const Eigen::Vector3d f = basis[static_cast<std::size_t>(r)] * sol.lambda.segment<3>(3 * r);
        if (f.squaredNorm() == 0 || rows[static_cast<std::size_t>(r)].fixed >= 0) continue;
        for (int k = 0; k < 3; ++k)
          if (rows[static_cast<std::size_t>(r)].c.nodes[k] >= 0)
            node_forces.push_back(
                {rows[static_cast<std::size_t>(r)].c.nodes[k],
                 rows[static_cast<std::size_t>(r)].c.weights[k] * (rot.transpose() * f)});
        ff += f;
        ft += arm[static_cast<std::size_t>(r)].cross(f);
      }
      const Wrenches pw = partner_wrenches(
          [&](std::size_t r) -> const Row& { return rows[r]; },
          [&](std::size_t r) -> Eigen::Vector3d {
            return basis[r] * sol.lambda.segment<3>(3 * static_cast<Eigen::Index>(r));
          },
          rows.size());
      std::map<int, NodeForces> pf = partner_forces([&](std::size_t r) -> Eigen::Vector3d {
        return basis[r] * sol.lambda.segment<3>(3 * static_cast<Eigen::Index>(r));
      });
      // (in a group: the other stages' forces of this solve on this body's nodes and frame,
      // and on its elastic partners' nodes)
      bool merged = false;
      if (const auto g = group_nodes.find(body); g != group_nodes.end())
        for (const auto& [x, list] : g->second) {
          if (list.empty()) continue;
          if (x == body) {
            node_forces.insert(node_forces.end(), list.begin(), list.end());
            merged = true;
          } else if (const auto en = elastic_near_of.find(x); en != elastic_near_of.end()) {
            const Eigen::Matrix3d& xr = elastic_near[en->second].rot;
            for (const auto& [node, f] : list) pf[x].push_back({node, xr * f});
          }
        }
      if (const auto g = group_wrenches.find(body); g != group_wrenches.end() && e->floating)
        if (const auto w = g->second.find(body); w != g->second.end()) {
          ff += w->second.head<3>();
          ft += w->second.tail<3>();
        }
      ContactMotion pushed = contact_motion(node_forces, ff, ft, pw, pf);
      // the node rows again at where the nodes end the step: a row's plane is the part's
      // surface only near where it was taken (a node carried past the part's edge is no
      // longer under the face it started over, and the face's plane would hold it where
      // the part is not); rows that moved off their plane are taken anew there (the
      // plane through the closest feature at the end, as seen from the start) and the
      // forces solved again
      std::size_t relinearized = 0;
      left_force = 0;  // (normal force of the pressed rows whose features left their triangles)
      {
        std::vector<int> at_nodes;
        for (const Row& row : rows)
          if (row.c.node_row) at_nodes.push_back(row.c.nodes[0]);
        motions_of(pushed, std::move(at_nodes));
      }
      for (Row& row : rows) {
        if (!row.c.node_row) continue;
        const auto it = near_of.find(row.part);
        if (it == near_of.end()) continue;
        const int k = row.c.nodes[0];
        const Eigen::Vector3d start = x0.row(k).transpose();
        const Eigen::Vector3d end = x1.row(k).transpose() + motion_of(pushed, k) -
                                    partner_travel(pushed, row.partner, start);
        const double planar = row.c.gap + row.c.normal.dot(end - start);
        if (planar > 1e-3 * h) continue;  // open and staying open: nothing it holds
        Eigen::Vector3d foot, normal;
        bool on_face = false;
        const double actual =
            signed_distance(near[it->second].world, end, &foot, &normal, &on_face);
        if (std::abs(actual - planar) <= 1e-3 * h) continue;
        row.c.normal = normal;
        row.c.on_b = foot;
        row.c.gap = normal.dot(start - foot);
        ++relinearized;
      }
      // points left out that these forces would push through join
      std::size_t joined = 0, still_out = 0;
      motions_of(pushed, nodes_of_rows(excluded));
      for (const Row& r : excluded) {
        if (take_gap(r, pushed) < -1e-4 * h) {
          rows.push_back(r);
          ++joined;
        } else {
          excluded[still_out++] = r;
        }
      }
      excluded.resize(still_out);
      // the narrow phase again where the step ends the surface: a contact that only the
      // end configuration has (an apex passing a part's corner hands the load to the face
      // behind it within one step) joins, its row taken at the end and seen from the start
      {
        std::set<std::pair<int, std::int64_t>> have;
        for (const Row& r : rows)
          if (r.fixed < 0) have.insert({r.part, r.c.key});
        for (const Row& r : excluded)
          if (r.fixed < 0) have.insert({r.part, r.c.key});
        Eigen::MatrixX3d x_end = x1;
        std::vector<int> moved;
        for (std::size_t k = 0; k < near.size(); ++k)
          for (int t : near_candidates[k])
            for (int q = 0; q < 3; ++q) moved.push_back(e->surface.triangles(t, q));
        std::sort(moved.begin(), moved.end());
        moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
        // how deep a point can have gone in the step (deeper finds belong to the other side)
        Eigen::VectorXd touch = Eigen::VectorXd::Zero(x_end.rows());
        // by one solve with the kept factor rather than the columns' sums where those pass a
        // few hundred microseconds: when this pass is the last, that solve is the step's
        // correction too (below), so it costs nothing (the snap-fit's sliding paws: 1 ms of
        // sums a step at 66 points, 2,000 nodes)
        if (static_cast<double>(moved.size()) * static_cast<double>(pushed.node_forces->size()) >
            kEndMotionDirectWork)
          pushed.direct = true;
        motions_of(pushed, moved);
        for (int k : moved) {
          x_end.row(k) += motion_of(pushed, k).transpose();
          touch[k] = (x_end.row(k) - x0.row(k)).norm() + partner_speed * dt + margin;
        }
        std::vector<char> dropped(rows.size(), 0);  // rows whose feature left their triangle
        for (std::size_t k = 0; k < near.size(); ++k) {
          if (near_candidates[k].empty()) continue;
          const int partner_body = rigid_parts_[static_cast<std::size_t>(near[k].part)].body;
          Eigen::MatrixX3d relative = x_end;  // as seen by the partner at the step's end
          for (int q : moved)
            relative.row(q) -=
                partner_travel(pushed, partner_body, x_end.row(q).transpose()).transpose();
          std::vector<SurfaceContact> at_end =
              surface_part_contacts(e->surface, relative, near[k].world, near_candidates[k], touch);
          // a part's vertex or edge on a triangle holds the triangle's plane, which is the
          // surface only over the triangle: a feature sliding over a bent surface past the
          // triangle's side (the base part's edge up a hook's lead face, 0.1 mm a step)
          // holds the surface out by the kink's angle times how far it went past, a
          // micrometre, and a sharp edge's local compliance turns that into force: the push
          // over the catch came out 4 % high at 0.07 mm of travel per increment with no
          // friction, at the same deflection and strain energy as at 0.013 mm. Such a row,
          // closed, is taken anew where the pass ends it: on its triangle when the feature is
          // still over it, else (pressed) it goes, and the feature's points on the triangles
          // it is over now join when within 2e-3 mesh sizes (except the points that went in
          // this step: at a ridge between two triangles a feature would flip from one to the
          // other). (Until 2026-11-26 only in the pass the feature first left a triangle: the
          // base part's edge is one feature across a hook's whole width, and its rows on
          // the triangles it left in later passes stayed, holding the face out.)
          std::set<std::pair<int, int>> slid;  // (vertex, edge) of rows that left their triangle
          if (pass < kEdgeRetakePasses && m <= kEdgeRetakeRows) {
            std::unordered_map<std::int64_t, const SurfaceContact*> by_key;
            // and by triangle and feature (the deepest of its points there): an edge nearly
            // along a triangle's plane has both ends of its stretch over it as points, or
            // only the lower end once it tilts by 1e-3, so a key can go while the edge is
            // still over its triangle (a hook's lead face under a horizontal edge)
            std::map<std::tuple<int, int, int, int, int>, const SurfaceContact*> by_feature;
            auto feature_on = [](const SurfaceContact& c) {
              return std::make_tuple(c.nodes[0], c.nodes[1], c.nodes[2], c.part_vertex,
                                     c.part_edge);
            };
            for (const SurfaceContact& c : at_end) {
              if (c.node_row) continue;
              by_key[c.key] = &c;
              const auto [at, added] = by_feature.try_emplace(feature_on(c), &c);
              if (!added && c.gap < at->second->gap) at->second = &c;
            }
            const double tolerance = kEdgeGapTolerance * h;
            for (std::size_t q = 0; q < rows.size(); ++q) {
              Row& row = rows[q];
              if (row.fixed >= 0 || row.elastic >= 0 || row.c.node_row ||
                  row.part != near[k].part || (row.c.part_vertex < 0 && row.c.part_edge < 0) ||
                  dropped[q])
                continue;
              const Eigen::Vector3d motion = end_motion(row, pushed);
              const double planar = row.c.gap + row.c.normal.dot(motion);
              if (planar >= 1e-3 * h) continue;  // open and staying open: nothing it holds
              // (a point that hardly slid has its plane where it is: a body at rest keeps
              // its rows, and rests)
              if ((motion - row.c.normal.dot(motion) * row.c.normal).norm() < kEdgeSlide * h)
                continue;
              const bool pressed = static_cast<Eigen::Index>(q) < m &&
                                   sol.lambda[3 * static_cast<Eigen::Index>(q)] > 0;
              auto it = by_key.find(row.c.key);
              if (it == by_key.end() && quasistatic_run) {
                // still over its triangle: its plane holds; taken anew at the feature's point
                // there unless that is a row already
                if (const auto same = by_feature.find(feature_on(row.c));
                    same != by_feature.end()) {
                  if (have.count({row.part, same->second->key})) continue;
                  have.erase({row.part, row.c.key});
                  have.insert({row.part, same->second->key});
                  it = by_key.find(same->second->key);
                }
              }
              if (it == by_key.end()) {
                if (pressed) left_force += sol.lambda[3 * static_cast<Eigen::Index>(q)];
                // it goes: in a quasi-static increment in any pass before the last two (the
                // last solve keeps every pressed row, so nothing it lets go passes through
                // unseen); in a dynamic step only in the pass where its feature first left a
                // triangle (its points slide a small part of a triangle per step; the
                // snap-fit's path stays as it was)
                if (pressed && (quasistatic_run ? pass < kMaxPasses - 2
                                                : switched.try_emplace({row.part, row.c.part_vertex,
                                                                        row.c.part_edge},
                                                                       pass)
                                                          .first->second == pass)) {
                  left_triangle.insert({row.part, row.c.key});
                  slid.insert({row.c.part_vertex, row.c.part_edge});
                  have.erase({row.part, row.c.key});
                  dropped[q] = 1;
                  ++relinearized;
                }
                continue;
              }
              if ((pressed || it->second->gap < -tolerance) &&
                  std::abs(it->second->gap - planar) > tolerance) {
                SurfaceContact c = *it->second;
                seen_from_start(c, pushed, x_end, partner_body);
                row.c = c;
                row.found_normal = c.normal;
                ++relinearized;
              }
            }
          }
          for (SurfaceContact& c : at_end) {
            if (have.count({near[k].part, c.key})) continue;
            const bool takes_over =
                !c.node_row && slid.count({c.part_vertex, c.part_edge}) && c.gap < 2e-3 * h &&
                !(quasistatic_run && left_triangle.count({near[k].part, c.key}));
            if (c.gap > -1e-3 * h && !takes_over) continue;
            seen_from_start(c, pushed, x_end, partner_body);
            rows.push_back({c, near[k].part, partner_body});
            rows.back().found_normal = c.normal;
            have.insert({near[k].part, c.key});
            ++joined;
          }
        }
        remove_marked(&rows, dropped);
        // and against the elastic partners, both surfaces where the step ends them
        std::vector<char> gone;  // pressed pair rows whose points the partner no longer has
        for (std::size_t k = 0; k < elastic_near.size(); ++k) {
          const ElasticNear& en = elastic_near[k];
          if (en.triangles.empty()) continue;
          const ContactSurface& other = elastic_[static_cast<std::size_t>(en.body)]->surface;
          Eigen::MatrixX3d a_end = x1, b_end = en.x1;
          Eigen::VectorXd a_touch = Eigen::VectorXd::Zero(x0.rows()),
                          b_touch = Eigen::VectorXd::Zero(en.x0.rows());
          {
            std::vector<int> a_nodes;
            for (int t : en.near_triangles)
              for (int q = 0; q < 3; ++q) a_nodes.push_back(e->surface.triangles(t, q));
            motions_of(pushed, std::move(a_nodes));
          }
          for (int t : en.near_triangles)
            for (int q = 0; q < 3; ++q) {
              const int j = e->surface.triangles(t, q);
              if (a_touch[j] > 0) continue;
              a_end.row(j) += motion_of(pushed, j).transpose();
              a_touch[j] = (a_end.row(j) - x0.row(j)).norm() + margin;
            }
          {
            std::vector<int> b_nodes;
            for (int t : en.triangles)
              for (int q = 0; q < 3; ++q) b_nodes.push_back(other.triangles(t, q));
            partner_motions_of(pushed, en.body, std::move(b_nodes));
          }
          for (int t : en.triangles)
            for (int q = 0; q < 3; ++q) {
              const int j = other.triangles(t, q);
              if (b_touch[j] > 0) continue;
              b_end.row(j) += partner_motion_of(pushed, en.body, j).transpose();
              b_touch[j] = (b_end.row(j) - en.x0.row(j)).norm() + margin;
            }
          // the rows on this partner by their point
          std::map<std::pair<int, std::int64_t>, std::size_t> row_of;
          for (std::size_t q = 0; q < rows.size(); ++q)
            if (rows[q].elastic == static_cast<int>(k) && rows[q].fixed < 0)
              row_of[{rows[q].part, rows[q].c.key}] = q;
          std::set<std::size_t> found_again;
          for (const SurfacePairContact& c :
               surface_surface_contacts(e->surface, a_end, en.near_triangles, a_touch, other, b_end,
                                        en.triangles, b_touch)) {
            Row r{c.a, c.a_node ? -(2 + 2 * en.body) : -(3 + 2 * en.body), en.body};
            r.found_normal = c.a.normal;  // found where the step ends: not turned
            r.elastic = static_cast<int>(k);
            r.b_nodes = c.b_nodes;
            r.b_weights = c.b_weights;
            // the same plane, from where the step starts: less both sides' travel
            Eigen::Vector3d travel = Eigen::Vector3d::Zero();
            for (std::size_t q = 0; q < 3; ++q) {
              if (c.a.nodes[q] >= 0)
                travel +=
                    c.a.weights[q] * (a_end.row(c.a.nodes[q]) - x0.row(c.a.nodes[q])).transpose();
              if (c.b_nodes[q] >= 0)
                travel -= c.b_weights[q] *
                          (b_end.row(c.b_nodes[q]) - en.x0.row(c.b_nodes[q])).transpose();
            }
            r.c.gap -= r.c.normal.dot(travel);
            const auto found = row_of.find({r.part, c.a.key});
            if (found != row_of.end()) {
              // a point in the solve: its plane at the start holds it where the other surface
              // is only near where it was taken (the surfaces turn and slide over each
              // other); taken anew where the step ends it when that differs by more than
              // 1e-3 of the mesh size
              found_again.insert(found->second);
              Row& old = rows[found->second];
              if (std::abs(end_gap(old, pushed) - c.a.gap) <= 1e-3 * h) continue;
              old = r;
              ++relinearized;
              continue;
            }
            if (c.a.gap > -1e-3 * h || have.count({r.part, c.a.key})) continue;
            rows.push_back(r);
            have.insert({r.part, c.a.key});
            ++joined;
          }
          // pressed points on the partner that its surface no longer has where the step
          // ends them: they hold a plane past the surface's edge (a hook's return face on
          // an elastic catch, past its apex). In a quasi-static increment they go, as a
          // part's feature that left its triangle does, in any pass before the last two:
          // the points past the edge are solved again without them (while they stayed, five
          // increments of the paw sample over an elastic steel catch, where the paw's apex
          // passed its edges, were still unsettled at a 64th)
          for (const auto& [key, q] : row_of) {
            const auto f = pass_warm.find(key);
            if (found_again.count(q) || f == pass_warm.end() || !(f->second.squaredNorm() > 0))
              continue;
            left_force += f->second.norm();
            if (quasistatic_run && pass < kMaxPasses - 2) {
              gone.resize(rows.size(), 0);
              gone[q] = 1;
              have.erase(key);
              ++relinearized;
            }
          }
        }
        remove_marked(&rows, gone);
      }
      // (a group's passes end when every stage's rows have settled)
      StageRequest end;
      end.kind = StageRequest::kPassEnd;
      end.settled = relinearized == 0 && joined == 0;
      if ((co_await StageAwait{end, alone, [](StageRequest& q) { q.stop = q.settled; }}).stop) {
        // (kept rows of an elastic partner whose points its surface no longer has)
        if (left_force > kLeftForce * resultant.norm())
          not_settled(rows, sol.lambda, left_force / std::max(resultant.norm(), 1e-300), pass + 1);
        // the deformation under these forces, solved above: the correction's
        if (pushed.direct && !merged) final_deformation = std::move(pushed.deformation);
        break;
      }
      // else solve again
    }
    elastic_stats_.rows += m;

    // apply them: nodal forces on the FE body (frame axes), and on the floating frame
    Eigen::VectorXd nodal = Eigen::VectorXd::Zero(dofs);
    Eigen::Vector3d frame_force = Eigen::Vector3d::Zero(), frame_torque = Eigen::Vector3d::Zero();
    e->last_own_wrench.setZero();
    e->last_own_forces.clear();
    std::map<int, Eigen::Vector3d> pair_force;
    e->warm.clear();
    for (Eigen::Index r = 0; r < m; ++r) {
      const Row& row = rows[static_cast<std::size_t>(r)];
      const Eigen::Vector3d f = basis[static_cast<std::size_t>(r)] * sol.lambda.segment<3>(3 * r);
      if (row.link && sol.lambda[3 * r] > 0) e->warm[{row.part, row.c.key}] = f;
      if (sol.lambda[3 * r] <= 0 || row.fixed >= 0) continue;  // (supports: their own stage's)
      ++elastic_points_;
      pair_force.try_emplace(row.partner, Eigen::Vector3d::Zero()).first->second += f;
      touching.insert({body, row.partner});
      e->warm[{row.part, row.c.key}] = f;
      const Eigen::Vector3d local = rot.transpose() * f;
      for (int k = 0; k < 3; ++k)
        if (row.c.nodes[k] >= 0)
          nodal.segment<3>(3 * e->surface.nodes[static_cast<std::size_t>(row.c.nodes[k])]) +=
              row.c.weights[k] * local;
      if (e->floating) {
        frame_force += f;
        frame_torque += arm[static_cast<std::size_t>(r)].cross(f);
        if (!row.link && floating_frame(row.partner)) {
          e->last_own_wrench.head<3>() += f;
          e->last_own_wrench.tail<3>() += arm[static_cast<std::size_t>(r)].cross(f);
          for (int k = 0; k < 3; ++k)
            if (row.c.nodes[k] >= 0)
              e->last_own_forces.push_back({row.c.nodes[k], row.c.weights[k] * f});
        }
      }
    }
    // the pair's forces, less the partners' supports (which their own stages apply)
    auto applied_force = [&](std::size_t r) -> Eigen::Vector3d {
      const auto q = static_cast<Eigen::Index>(r);
      return sol.lambda[3 * q] > 0 && (rows[r].fixed < 0 || rows[r].link)
                 ? (basis[r] * sol.lambda.segment<3>(3 * q)).eval()
                 : Eigen::Vector3d::Zero().eval();
    };
    // the reactions on the elastic partners: loads of their own steps, which come later in
    // this stage
    e->last_partner_forces = partner_forces(applied_force);
    load_partners(*e);
    e->last_points = 0;
    for (Eigen::Index r = 0; r < m; ++r)
      e->last_points += sol.lambda[3 * r] > 0 && rows[static_cast<std::size_t>(r)].fixed < 0;
    // a floating body's pressed points on rigid bodies that are fixed, driven or free, and
    // on held elastic bodies: its supports, solved with the pair in its owners' stages of
    // the next step
    for (Eigen::Index r = 0; r < m && e->floating; ++r) {
      const Row& row = rows[static_cast<std::size_t>(r)];
      if (!(sol.lambda[3 * r] > 0) || row.fixed >= 0 || !can_support(row.partner)) continue;
      if (row.elastic < 0)
        e->supports.push_back({row.c, row.part, row.partner, time_, pose_of(before[row.partner])});
      else  // a held elastic body
        e->supports.push_back({row.c, row.part, row.partner, time_, Eigen::Isometry3d::Identity(),
                               row.b_nodes, row.b_weights});
    }
    e->force_change = (frame_force - e->last_frame_force).norm();
    e->last_pair_force.clear();
    e->contact_force.setZero();
    for (const auto& [other, f] : pair_force) {
      e->contact_force += f;
      e->last_pair_force[other] = f.norm();
      elastic_force_ += f.norm();
      elastic_peak_force_ = std::max(elastic_peak_force_, f.norm());
    }
    e->last_forces.clear();
    for (std::size_t k = 0; k < e->surface.nodes.size(); ++k) {
      const Eigen::Vector3d f = nodal.segment<3>(3 * e->surface.nodes[k]);
      if (f.squaredNorm() > 0) e->last_forces.push_back({static_cast<int>(k), f});
    }
    e->last_frame_force = frame_force;
    e->last_frame_torque = frame_torque;
    Eigen::VectorXd du = prediction;
    Eigen::VectorXd applied = nodal;  // the nodes' loads: contact and, floating, inertia
    if (owner_loaded) applied += e->pending_load;
    // (in a group, an owner's stage applies its reactions on this body after this one
    // started: loads of this step too)
    const bool late_load =
        !owner_loaded && !alone && e->pending_load.size() > 0 && !e->pending_load.isZero(0);
    if (late_load) {
      applied += e->pending_load;
      du += solver.response(e->pending_load.sparseView()).col(0);
      ++elastic_stats_.correction_solves;
    }
    // the reactions on the movable partners (their velocity jumps follow below)
    e->last_partner_wrench = partner_wrenches([&](std::size_t r) -> const Row& { return rows[r]; },
                                              applied_force, rows.size());
    if (e->floating) {
      Eigen::Matrix<double, 6, 1> wrench, jump_acceleration;
      wrench << frame_force, frame_torque;
      if (const auto g = group_wrenches.find(body); g != group_wrenches.end())
        if (const auto w = g->second.find(body); w != g->second.end()) wrench += w->second;
      Eigen::Matrix<double, 6, 1> moved = mobility * wrench;
      for (const auto& [r, w] : e->last_partner_wrench)  // partners of its own mechanism
        if (coupled(body, r)) moved += coupling(body, r) * w;
      jump_acceleration = to_frame(moved / (dt * dt));
      du.noalias() -= e->inertia_response * jump_acceleration;
      applied.noalias() -= e->inertia_load * (free_acceleration + jump_acceleration);
    }
    if (final_deformation.size() == dofs) {
      du += final_deformation;
    } else if (nodal.squaredNorm() > 0) {
      Eigen::SparseMatrix<double> ct(dofs, 1);
      std::vector<Eigen::Triplet<double>> entries;
      for (Eigen::Index k = 0; k < dofs; ++k)
        if (nodal[k] != 0) entries.emplace_back(static_cast<int>(k), 0, nodal[k]);
      ct.setFromTriplets(entries.begin(), entries.end());
      du += solver.response(ct).col(0);
      ++elastic_stats_.correction_solves;
    }
    solver.accept(du, &applied);
    record.points = static_cast<int>(m);
    e->sticking_on.clear();
    e->last_held_rows.clear();
    bool own_on_free = false;  // a row of its own frame pressed on a free body
    for (Eigen::Index r = 0; r < m; ++r) {
      const Row& row = rows[static_cast<std::size_t>(r)];
      const double ln = sol.lambda[3 * r];
      record.node_points += row.c.node_row ? 1 : 0;
      if (ln <= 0) continue;
      ++record.pressed;
      const double mu = problem.mu[static_cast<std::size_t>(r)];
      const bool sliding =
          mu > 0 && sol.lambda.segment<2>(3 * r + 1).norm() >= mu * ln * (1 - 1e-9);
      if (sliding)
        ++record.sliding;
      else if (mu > 0 && row.fixed < 0)
        e->sticking_on.insert(row.partner);
      // the directions it held a free rigid partner along, or its own floating frame against
      // bodies that stay where they are or are driven (Dynamics::held_shifts)
      if (row.fixed >= 0 || row.link) continue;
      auto hold = [&](int q, const Eigen::Vector3d& lever) {
        Eigen::Matrix<double, 6, 6>& held =
            e->last_held_rows.try_emplace(q, Eigen::Matrix<double, 6, 6>::Zero()).first->second;
        const Eigen::Matrix3d& d = basis[static_cast<std::size_t>(r)];
        for (int k = 0; k < (mu > 0 && !sliding ? 3 : 1); ++k) {
          Eigen::Matrix<double, 6, 1> j;
          j << d.col(k), lever.cross(d.col(k));
          held += j * j.transpose();
        }
      };
      if (rigid_movable(row.partner) && !joints_->moves(row.partner))
        hold(row.partner, start_point(row.c) - before[row.partner].position);
      if (e->floating && !joints_->moves(body)) {
        if (!rigid_movable(row.partner) && !floating(row.partner))
          hold(body, arm[static_cast<std::size_t>(r)]);
        else if (!floating(row.partner))
          own_on_free = true;
        // (on another floating frame: Dynamics::held_shifts holds the two alike, or neither)
      }
    }
    if (own_on_free) e->last_held_rows.erase(body);  // (pressed on a free rigid body: not held)
    record.newton_iterations =
        static_cast<int>(elastic_stats_.newton_iterations - effort_before.newton_iterations);
    record.sweeps = sol.sweeps;
    record.converged = sol.converged;
    record.new_columns = static_cast<int>(column_solves_ - recorded_columns_);
    recorded_columns_ = column_solves_;
    record.column_seconds = elastic_stats_.column_seconds - effort_before.column_seconds;
    record.delassus_seconds = elastic_stats_.delassus_seconds - effort_before.delassus_seconds;
    record.solve_seconds = elastic_stats_.solve_seconds - effort_before.solve_seconds;
    if (owner_loaded || late_load) e->pending_load.setZero();
    e->last_motion = 0;
    for (int node : e->surface.nodes)
      e->last_motion = std::max(e->last_motion, du.segment<3>(3 * node).norm());
    if (e->floating && (frame_force.squaredNorm() > 0 || frame_torque.squaredNorm() > 0)) {
      // the frame's velocity jump (mobility already holds dt^2)
      Eigen::Matrix<double, 6, 1> load;
      load << frame_force, frame_torque;
      const Eigen::Matrix<double, 6, 1> jump = mobility * load / dt;
      RigidState& st = states_[i];
      rigid_work_ += dt * (frame_force.dot(st.velocity + 0.5 * jump.head<3>()) +
                           frame_torque.dot(st.angular_velocity + 0.5 * jump.tail<3>()));
      st.velocity += jump.head<3>();
      st.angular_velocity += jump.tail<3>();
      jump_along(body, load);
    }
    // the movable partners take the reactions the same way: a velocity jump at the step's
    // start (their free motion follows in the step). A free rigid body on supports jumps
    // with their normals held, and the part of the reaction that presses on them is a load
    // of the step, which the rigid contact that follows answers with their normal forces
    // and the friction those allow (without it, rubber cubes sliding on a light tray pushed
    // it along as if the tray's friction on the plate carried only its own weight)
    for (const auto& [r, w] : e->last_partner_wrench) {
      if (held_still(r)) {  // (its work: the step's, as its loads')
        forces[static_cast<std::size_t>(r)] += w.head<3>();
        torques[static_cast<std::size_t>(r)] += w.tail<3>();
        continue;
      }
      const Eigen::Matrix<double, 6, 1> jump =
          partner[static_cast<std::size_t>(r)].jump_mobility * w / dt;
      Eigen::Matrix<double, 6, 1> jumped = w;  // what the jump takes
      if (on_supports(r)) {
        // w - M jump / dt: the wrench of normal forces on the supports (jump_mobility is the
        // inverse mass with their normals held), a load of the step
        const Eigen::Matrix3d rot = before[r].rotation.toRotationMatrix();
        jumped << inertias_[r].mass * jump.head<3>() / dt,
            rot * inertias_[r].inertia * rot.transpose() * jump.tail<3>() / dt;
        forces[static_cast<std::size_t>(r)] += w.head<3>() - jumped.head<3>();
        torques[static_cast<std::size_t>(r)] += w.tail<3>() - jumped.tail<3>();
      }
      RigidState& ps = states_[r];
      rigid_work_ += dt * (jumped.head<3>().dot(ps.velocity + 0.5 * jump.head<3>()) +
                           jumped.tail<3>().dot(ps.angular_velocity + 0.5 * jump.tail<3>()));
      ps.velocity += jump.head<3>();
      ps.angular_velocity += jump.tail<3>();
      jump_along(r, w);
    }
    // (a group's stages: every stage's velocity jumps applied before any stage's closing
    // velocities below are taken against them)
    {
      StageRequest barrier;
      barrier.kind = StageRequest::kJumpsApplied;
      co_await StageAwait{barrier, alone, [](StageRequest&) {}};
    }
    auto partner_point_velocity = [&](int r, const Eigen::Vector3d& p) -> Eigen::Vector3d {
      const PartnerMotion& pm = partner[static_cast<std::size_t>(r)];
      if (!pm.movable) return pm.velocity;
      if (!held_travel_[static_cast<std::size_t>(r)].isZero()) {
        // (one moved by its end velocity along what holds it: that velocity, the loads' step
        // added to the jumps)
        const Eigen::Matrix3d r0 = before[r].rotation.toRotationMatrix();
        const Eigen::Vector3d w =
            states_[r].angular_velocity +
            dt * (r0 * (inertias_[r].inertia.inverse() * (r0.transpose() * torques[r])));
        return states_[r].velocity + dt * forces[r] / inertias_[r].mass + w.cross(p - pm.x0);
      }
      return states_[r].velocity + states_[r].angular_velocity.cross(p - pm.x0);
    };
    // closed nodes end the step at rest against the surface along its normal: the
    // correction that closed them must not throw them off again (Newmark would give back
    // the velocity 2 du / dt: a contact that rings)
    {
      Eigen::VectorXd dv = Eigen::VectorXd::Zero(dofs);
      const RigidState& st = states_[i];
      for (Eigen::Index r = 0; r < m; ++r) {
        const Row& row = rows[static_cast<std::size_t>(r)];
        if (!row.c.node_row || sol.lambda[3 * r] <= 0) continue;
        const int node = e->surface.nodes[static_cast<std::size_t>(row.c.nodes[0])];
        const Eigen::Vector3d n = row.c.normal;
        Eigen::Vector3d v = rot * solver.velocity().segment<3>(3 * node) -
                            partner_point_velocity(row.partner, start_point(row.c));
        if (e->floating)
          v += st.velocity + st.angular_velocity.cross(arm[static_cast<std::size_t>(r)]);
        const double away = n.dot(v);
        if (away > 0) dv.segment<3>(3 * node) -= away * (rot.transpose() * n);
      }
      solver.change_velocity(dv);
    }
    record.seconds = std::chrono::duration<double>(Clock::now() - body_started).count();
    elastic_stats_.step_records.push_back(record);
    done[i] = 1;
  };
  // the stages in their order, a group's together where its first one comes: their rows
  // solved as one problem at each pass (they pass in step until every one has settled), each
  // applying its forces, then each its closing velocities
  std::vector<char> staged(elastic_.size(), 0);
  for (const int first : stage_order_) {
    const ElasticBody* e = elastic_[static_cast<std::size_t>(first)].get();
    if (!e || !e->touchable || staged[static_cast<std::size_t>(first)]) continue;
    const std::vector<int> group = stage_group(first);
    for (const int body : group) {
      staged[static_cast<std::size_t>(body)] = 1;
      for (const auto& [r, w] : stage_wrench(body))  // (this stage's own: solved now)
        if (later.count(r)) later[r] -= w;
      add_loads(body, -1);
    }
    const bool alone = group.size() == 1;
    group_wrenches.clear();
    group_nodes.clear();
    in_group.clear();
    if (!alone) in_group.insert(group.begin(), group.end());
    if (!alone)  // (before the first solve: the others' forces of the last step)
      for (const int body : group)
        for (const int other : group)
          if (other != body)
            for (const auto& [r, w] : stage_wrench(other))
              if (rigid_movable(r))
                group_wrenches[body]
                    .try_emplace(r, Eigen::Matrix<double, 6, 1>::Zero())
                    .first->second += w;
    std::vector<StageTask> tasks;
    tasks.reserve(group.size());
    for (const int body : group) tasks.push_back(stage(body, alone));
    // (each started up to where it has decided whether its body rests, owners first as stage
    // by stage, so that an owner's stage knows whether an owned one rests, and solves its
    // supports then, before it looks for rows)
    for (StageTask& t : tasks) t.resume();
    for (;;) {
      std::vector<StageTask*> waiting;
      for (StageTask& t : tasks)
        if (!t.done()) waiting.push_back(&t);
      if (waiting.empty()) break;
      auto at = [&](StageRequest::Kind kind) {
        std::vector<StageTask*> out;
        for (StageTask* t : waiting)
          if (t->request().kind == kind) out.push_back(t);
        return out;
      };
      // a vote: every one of them settled (rests; its rows settled), or none stops
      auto vote = [](const std::vector<StageTask*>& voters) {
        bool all = true;
        for (StageTask* t : voters) all = all && t->request().settled;
        for (StageTask* t : voters) t->request().stop = all;
      };
      std::vector<StageTask*> next = at(StageRequest::kDecided);
      if (!next.empty()) {  // (all of them: resumed in the group's order)
        vote(next);
        // (none rests unless all do: every member's flag is down before any member looks
        // at another's, an owner's stage taking an owned body's supports as rows only where
        // it rests: the middle cube of a stack took the bottom one's once where the bottom's
        // own stage solved them too, and the stack slid 1e-8 m)
        if (!next.front()->request().stop)
          for (StageTask* t : next)
            elastic_[static_cast<std::size_t>(t->request().body)]->resting = false;
      } else if (!(next = at(StageRequest::kSolve)).empty()) {
        std::vector<StageRequest*> requests;
        for (StageTask* t : next) requests.push_back(&t->request());
        solve_rows(requests, dt);
      } else if (!(next = at(StageRequest::kPassEnd)).empty()) {
        vote(next);
      } else {
        next = waiting;  // (all at kJumpsApplied)
      }
      for (StageTask* t : next) t->resume();
    }
  }

  // events: pairs that started or stopped touching
  for (const auto& p : touching)
    if (!elastic_touching_.count(p)) events_.push_back({t_end, true, p.first, p.second});
  for (const auto& p : elastic_touching_)
    if (!touching.count(p)) events_.push_back({t_end, false, p.first, p.second});
  elastic_touching_ = std::move(touching);
  elastic_stats_.seconds += std::chrono::duration<double>(Clock::now() - started).count();
}

}  // namespace vproto::sim
