#pragma once
// One elastic body's finite-element problem as a scene states it: its matrices, the nodes
// its `fix ... region=` clamps hold to the ground, the nodes its `grip` holds to its
// reference frame, and its loads (region and point forces with their ramps, gravity).
// Static and dynamic solves both start from this.

#include <vector>

#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/scene.h"

namespace vproto::sim {

struct ElasticModel {
  int body = 0;
  FeMatrices fe;
  std::vector<int> fixed_nodes;  ///< held at zero displacement
  std::vector<int> grip_nodes;   ///< moved rigidly with the reference frame
  /// The grip is vproto's own, not the scene's: a floating body that nothing holds has its
  /// reference frame carried by the corner nodes of the element at its centroid (the
  /// frame's choice does not change the deformation, only where it is measured from), and
  /// nothing holds it, so it has no reaction to report.
  bool frame_grip = false;
  struct Load {
    Eigen::VectorXd nodal;  ///< 3N, N, at full strength
    double ramp = 0;        ///< s over which it grows linearly from zero; 0: at once
    /// Its moment about the body's centroid (undeformed, body axes), N m.
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  };
  std::vector<Load> loads;

  /// Nodal forces at time t (a static solve asks for t = infinity).
  Eigen::VectorXd load_at(double t) const;
  /// Fixed and gripped nodes together, sorted, without repeats.
  std::vector<int> held_nodes() const;
};

/// Throws InputError when the body's material is too close to incompressible for
/// displacement-based tetrahedra (nu >= 0.495: they lock).
void check_element_material(const Body& body);

class FactorMemoryError;
/// A body whose factor would not fit in memory, as an InputError at its statement naming
/// the mesh size that would fit (a factor's size grows about as h^-4).
[[noreturn]] void refuse_factor(const Body& body, const FactorMemoryError& error);

/// Throws InputError for a region that selects no node or no boundary face and for a
/// point force outside the body. The body must be meshed. A `floating` body's point forces
/// and gravity act on its reference frame (the caller loads the nodes with the frame's
/// acceleration instead), so only region forces become nodal loads; when nothing clamps or
/// grips a floating body, its frame grip is chosen (`frame_grip`).
/// `matrices` false: K and M are not assembled (fe holds the dofs only; a solver that
/// computes the elements itself, PETSc over MPI ranks, needs no whole matrix).
ElasticModel make_elastic_model(const Scene& scene, int body, bool floating = false,
                                bool matrices = true);

}  // namespace vproto::sim
