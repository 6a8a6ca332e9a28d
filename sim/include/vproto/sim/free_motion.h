#pragma once
// The step loop for what this version can simulate: rigid bodies moving freely under
// initial velocities, forces, torques and gravity, with `fix` holding bodies to the
// ground. Contact is not handled yet: when the bounds of two bodies that may meet
// overlap, the run stops with a SimulationError naming them and the time, instead of
// letting them pass through each other. Everything else (joints, drives, grips, loads on
// elastic bodies) is refused up front with the statement's place.

#include <functional>
#include <string>
#include <vector>

#include "vproto/sim/frame.h"
#include "vproto/sim/rigid_body.h"
#include "vproto/sim/scene.h"

namespace vproto::sim {

/// Throws InputError at the first statement of `scene` this step loop cannot honour.
void check_free_motion_supported(const Scene& scene);

class FreeMotion {
 public:
  /// The scene's bodies must have their mass properties. `time_step` > 0.
  FreeMotion(const Scene& scene, double time_step);

  /// Advances to time `t` (>= the current time) in steps of at most the time step.
  /// Throws SimulationError when bodies' bounds meet or the state stops being finite.
  void advance_to(double t);

  double time() const { return time_; }
  long steps() const { return steps_; }
  /// Bodies' states; fixed bodies never change.
  const std::vector<RigidState>& states() const { return states_; }
  /// Kinetic energy of all bodies, and the work done on them by loads and gravity, J.
  double kinetic_energy() const;
  double external_work() const { return external_work_; }

  /// The frame at the current time (poses only; fields are the caller's).
  Frame frame(int index) const;
  /// Displacement of the material point that started at `point` on `body`, m.
  Eigen::Vector3d displacement(int body, const Eigen::Vector3d& point) const;

  /// Called after every step (for history rows).
  void on_step(std::function<void(const FreeMotion&)> callback) { on_step_ = std::move(callback); }

 private:
  void step(double dt);
  void check_overlaps() const;

  const Scene& scene_;
  double time_step_;
  double time_ = 0;
  long steps_ = 0;
  double external_work_ = 0;
  std::vector<RigidState> states_;
  std::vector<RigidInertia> inertias_;
  std::vector<bool> fixed_;
  std::vector<bool> moves_;  ///< anything acts on it
  std::function<void(const FreeMotion&)> on_step_;
};

}  // namespace vproto::sim
