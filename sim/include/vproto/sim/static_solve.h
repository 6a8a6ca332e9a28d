#pragma once
// mode=static for elastic bodies: each elastic body's equilibrium K u = f under its
// region forces, point forces and gravity, with `fix ... region=` and `grip` nodes held
// (in a static solve the gripper's frame does not move).

#include <vector>

#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/scene.h"
#include "vproto/sim/sparse_cholesky.h"

namespace vproto::sim {

struct ElasticSolution {
  int body = 0;
  Eigen::VectorXd displacement;     ///< 3N, m, node order of the body's tet mesh
  Eigen::VectorXd nodal_von_mises;  ///< N, Pa, averaged over the elements at each node
  Eigen::VectorXd nodal_strain;     ///< N, the largest principal strain, averaged likewise
  /// N: the node's stress is a sharp inside corner's concentration (concentration_nodes)
  std::vector<char> concentrated_nodes;
  double max_von_mises = 0;         ///< Pa, over element centroids
  double max_principal_strain = 0;  ///< over element centroids
  /// The same with where; times are load factors (1: the full load), and as the response is
  /// linear in the load, the yield is passed at the load factor 1 / the larger ratio.
  MaterialPeaks peaks;
  double strain_energy = 0;     ///< J
  double external_work = 0;     ///< J (twice the strain energy at equilibrium)
  Eigen::VectorXd load;         ///< 3N nodal forces, N (for peers and reports)
  std::vector<int> held_nodes;  ///< nodes held at zero displacement
  Eigen::Vector3d reaction = Eigen::Vector3d::Zero();  ///< N, the holders on the body
  SparseCholesky::Stats factor;                        ///< ordering, nnz(L), flops, times
  double assemble_seconds = 0;                         ///< K, M and the loads
  double solve_seconds = 0;   ///< the triangular solves (the factor's times are in `factor`)
  double stress_seconds = 0;  ///< reactions, energies, stresses and strains
};

/// Throws InputError at the first statement a static solve cannot honour (joints, drives,
/// velocities, loads on free rigid bodies), at elastic bodies that nothing holds, and at
/// materials too close to incompressible for these elements.
void check_static_supported(const Scene& scene);

/// Solves every elastic body (they must be meshed). Throws InputError for a region that
/// selects no node, SimulationError when a system is singular.
std::vector<ElasticSolution> solve_static_scene(const Scene& scene);

}  // namespace vproto::sim
