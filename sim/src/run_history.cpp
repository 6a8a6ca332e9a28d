#include "vproto/sim/run_history.h"

#include <algorithm>

namespace vproto::sim {

std::string history_header(const Scene& scene, const std::vector<int>& reaction_bodies,
                           const std::vector<int>& pushed_bodies,
                           const std::vector<int>& corner_bodies) {
  std::string h =
      "t,step,contacts,contact_force,kinetic_energy,strain_energy,external_work,max_von_mises";
  for (const auto& b : scene.bodies) h += "," + b.name + "_x," + b.name + "_y," + b.name + "_z";
  for (const auto& p : scene.probes) h += "," + p.name + "_ux," + p.name + "_uy," + p.name + "_uz";
  auto columns = [&](const std::vector<int>& bodies, const char* x, const char* y, const char* z) {
    for (int i : bodies) {
      const std::string& n = scene.bodies[static_cast<std::size_t>(i)].name;
      h += "," + n + x + "," + n + y + "," + n + z;
    }
  };
  columns(reaction_bodies, "_rx", "_ry", "_rz");
  columns(pushed_bodies, "_cx", "_cy", "_cz");
  for (int i : corner_bodies) {
    const std::string& n = scene.bodies[static_cast<std::size_t>(i)].name;
    h += "," + n + "_corner_von_mises," + n + "_corner_strain";
  }
  return h + "\n";
}

double ForceCurve::largest() const {
  return y.empty() ? 0.0 : *std::max_element(y.begin(), y.end());
}

double ForceCurve::smallest() const {
  return y.empty() ? 0.0 : *std::min_element(y.begin(), y.end());
}

RunHistory::RunHistory(const Scene& scene, const Dynamics& motion) : scene_(scene) {
  const auto n = static_cast<int>(scene.bodies.size());
  // the force the holders apply to each held or gripped elastic body (the insertion-force
  // curve of a driven snap-fit)
  for (int i = 0; i < n; ++i)
    if (motion.holds(i)) {
      reaction_bodies_.push_back(i);
      reaction_curves_.push_back({i, {}, {}});
    }
  if (!scene.moves.empty()) {
    drive_ = scene.moves.front().body;
    drive_dir_ = scene.moves.front().by.normalized();
    drive_start_ = motion.states()[static_cast<std::size_t>(drive_)].position;
  }
  // FE bodies that a push (no drive) moves: the contact force against the push, against the
  // body's travel along it (the snap-fit's resistance as the paws ride over the base part
  // and snap home)
  for (int b = 0; b < n; ++b) {
    if (!motion.nodal_displacement(b) || !motion.elastic_contact()) continue;
    bool driven = false;
    for (const auto& m : scene.moves) driven = driven || m.body == b;
    Eigen::Vector3d push = Eigen::Vector3d::Zero();
    for (const auto& f : scene.forces)
      if (f.body == b && !f.region) push += f.force;
    if (driven || !(push.norm() > 0)) continue;
    PushedBody p;
    p.body = b;
    p.direction = push.normalized();
    p.start = motion.states()[static_cast<std::size_t>(b)].position;
    p.push = push.norm();
    p.curve.body = b;
    pushed_.push_back(std::move(p));
  }
  std::vector<int> pushed_bodies;
  for (const PushedBody& p : pushed_) pushed_bodies.push_back(p.body);
  // the hot-spot values at the FE bodies' sharp inside corners (a snap-fit arm's root)
  for (int b = 0; b < n; ++b)
    if (motion.reads_corners(b)) {
      corner_bodies_.push_back(b);
      corner_curves_.push_back({b, {}, {}});
    }
  out_ << history_header(scene, reaction_bodies_, pushed_bodies, corner_bodies_);
  out_.precision(17);
}

void RunHistory::record(const Dynamics& m) {
  out_ << m.time() << "," << m.steps() << "," << m.contact_points() << "," << m.contact_force()
       << "," << m.kinetic_energy() << "," << m.strain_energy() << "," << m.external_work() << ","
       << m.max_von_mises();
  auto triple = [&](const Eigen::Vector3d& v) {
    out_ << "," << v.x() << "," << v.y() << "," << v.z();
  };
  for (const auto& s : m.states()) triple(s.position);
  for (const auto& p : scene_.probes) triple(m.displacement(p.body, p.point));
  const double along =
      drive_ >= 0 ? 1e3 * (m.states()[static_cast<std::size_t>(drive_)].position - drive_start_)
                              .dot(drive_dir_)
                  : m.time();
  for (ForceCurve& c : reaction_curves_) {
    const Eigen::Vector3d r = m.reaction(c.body);
    triple(r);
    c.x.push_back(along);
    c.y.push_back(drive_ >= 0 ? r.dot(drive_dir_) : r.norm());
  }
  for (PushedBody& p : pushed_) {
    const Eigen::Vector3d c = m.contact_force_on(p.body);
    triple(c);
    p.curve.x.push_back(
        1e3 * (m.states()[static_cast<std::size_t>(p.body)].position - p.start).dot(p.direction));
    p.curve.y.push_back(-c.dot(p.direction));
  }
  for (ForceCurve& c : corner_curves_) {
    const auto [von_mises, strain] = m.corner_values(c.body);
    out_ << "," << von_mises << "," << strain;
    c.x.push_back(m.time());
    c.y.push_back(strain);
  }
  out_ << "\n";
  ++rows_;
}

}  // namespace vproto::sim
