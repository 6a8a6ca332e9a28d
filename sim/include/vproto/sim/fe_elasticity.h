#pragma once
// Linear elasticity on tetrahedral meshes (tet4 and tet10, straight-edged): stiffness
// assembled with quadrature exact for each element, consistent surface loads, clamped
// nodes, a static solve with CHOLMOD (supernodal Cholesky), and stress recovery.

#include <Eigen/Sparse>
#include <vector>

#include "vproto/geometry/tet_mesh.h"

namespace vproto::sim {

/// The 3N by 3N stiffness matrix (dofs ordered x, y, z per node) of a mesh of one
/// isotropic material. Exact for straight-edged tet4 and tet10.
Eigen::SparseMatrix<double> assemble_stiffness(const geometry::TetMesh& mesh, double youngs_modulus,
                                               double poisson_ratio);

/// Nodes on the mesh's boundary whose position lies inside [lo, hi].
std::vector<int> boundary_nodes_in(const geometry::TetMesh& mesh, const Eigen::Vector3d& lo,
                                   const Eigen::Vector3d& hi);

/// Nodal forces (3N) for a total force spread over the boundary faces that lie wholly in
/// [lo, hi] as a uniform traction (consistent weights: the integrals of the face shape
/// functions). Empty vector when no boundary face lies in the region.
Eigen::VectorXd region_force(const geometry::TetMesh& mesh, const Eigen::Vector3d& lo,
                             const Eigen::Vector3d& hi, const Eigen::Vector3d& total_force);

/// Solves K u = f with the dofs of `fixed_nodes` held at zero. Throws SimulationError
/// when the system is singular (the body is not held against rigid motion).
Eigen::VectorXd solve_static(const Eigen::SparseMatrix<double>& stiffness,
                             const Eigen::VectorXd& force, const std::vector<int>& fixed_nodes);

/// von Mises stress at each element's centroid (Pa), from displacements u (3N).
Eigen::VectorXd element_von_mises(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                  double youngs_modulus, double poisson_ratio);

/// Largest principal strain over the element centroids.
double max_principal_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u);

}  // namespace vproto::sim
