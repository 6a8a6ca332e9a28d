#pragma once
// The structural ("hot-spot") stress at a body's sharp inside corners. At a re-entrant edge
// with no fillet a linear-elastic solid's stress is singular: the value at the corner grows
// without bound as the mesh is refined, so it says that the corner concentrates stress, not
// how much. The hot-spot method (IIW fatigue recommendations, Hobbacher 2016, type "a"
// points on fine meshes) reads the surface stress along each face square to the edge at
// 0.4 t and 1.0 t from it, t the wall's thickness there, and extrapolates linearly to the
// edge: 1.67 s(0.4 t) - 0.67 s(1.0 t). Those reads lie outside the singular zone and
// converge with the mesh, and for a wall in bending (a snap-fit arm on its base) the
// extrapolation gives the beam's stress at its root, M c / I: Bayer's root strain
// 1.5 h y / l^2 for an arm deflected by y, which the designer compares with the material's
// permissible strain, a fillet's concentration factor applied to it.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "vproto/geometry/tet_mesh.h"
#include "vproto/geometry/tri_mesh.h"
#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/tet_locator.h"

namespace vproto::sim {

/// One place where the hot-spot stress is read: a point on a re-entrant edge and one of the
/// edge's two faces.
struct CornerRead {
  Eigen::Vector3d corner = Eigen::Vector3d::Zero();  ///< m, on the edge (reference mesh)
  Eigen::Vector3d into = Eigen::Vector3d::Zero();    ///< unit, along the face, off the edge
  double wall = 0;      ///< m, the face's wall thickness t there (inward, square to the face)
  MeshPoint near, far;  ///< at 0.4 t and 1.0 t from the edge along the face
};

/// The reads of a body's re-entrant edges whose faces turn by more than 30 degrees (the
/// mesher's feature angle, as elements_at_sharp_corners): along each edge every `spacing`
/// (m; at least its middle), on each face whose plane runs on, unbent, for 1.0 t from the
/// edge (a face that ends or bends sooner has no reads: its value would not be the wall's).
std::vector<CornerRead> corner_reads(const geometry::TriMesh& surface, const TetLocator& locator,
                                     double spacing);

/// The largest hot-spot von Mises stress and largest principal strain over the reads of one
/// state (each the extrapolated tensor's; -1: no read).
struct CornerHotSpot {
  double von_mises = 0, strain = 0;  ///< Pa; dimensionless
  int von_mises_read = -1, strain_read = -1;
};

/// The hot-spot values of displacements u (3N) over the reads, leaving out those with a read
/// point within `reach` (m) of a point of `pressed` (positions in the reference mesh: a
/// contact there makes the surface stress its own).
CornerHotSpot corner_hot_spot(const std::vector<CornerRead>& reads, const geometry::TetMesh& mesh,
                              const Eigen::VectorXd& u, double youngs_modulus, double poisson_ratio,
                              const std::vector<Eigen::Vector3d>& pressed = {}, double reach = 0);

/// Raises the peaks' hot-spot values (MaterialPeaks::corner_*) with one state's at time t
/// (s), and sets the first time they pass the material's yield.
void track_corner_peaks(const std::vector<CornerRead>& reads, const CornerHotSpot& now,
                        std::optional<double> yield_strength, std::optional<double> yield_strain,
                        double t, MaterialPeaks* peaks);

}  // namespace vproto::sim
