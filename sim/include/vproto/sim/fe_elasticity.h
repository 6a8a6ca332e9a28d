#pragma once
// Linear elasticity on tetrahedral meshes (tet4 and tet10, straight-edged): stiffness and
// consistent mass assembled with quadrature exact for each element, consistent surface
// and body loads, held nodes, a static solve and natural frequencies with CHOLMOD, and
// stress recovery.

#include <Eigen/Sparse>
#include <array>
#include <optional>
#include <utility>
#include <vector>

#include "vproto/geometry/tet_mesh.h"
#include "vproto/materials/material.h"
#include "vproto/sim/sparse_cholesky.h"

namespace vproto::sim {

/// Stiffness and consistent mass of one body (dofs x, y, z per node), lower triangles in
/// compressed columns sharing one pattern: a 3x3 block for every pair of nodes that share
/// an element. Assembled in place into the pattern (no triplet list), so memory is the
/// matrices themselves.
struct FeMatrices {
  Eigen::Index dofs = 0;
  std::vector<int> outer;  ///< column starts, dofs + 1
  std::vector<int> inner;  ///< row of each entry (sorted within a column)
  std::vector<double> stiffness_values, mass_values;

  LowerView view(const std::vector<double>& values) const {
    return {dofs,         dofs,         static_cast<Eigen::Index>(inner.size()),
            outer.data(), inner.data(), values.data()};
  }
  LowerView stiffness() const { return view(stiffness_values); }
  LowerView mass() const { return view(mass_values); }
  std::size_t nonzeros() const { return inner.size(); }
};

/// Assembles K and M of a mesh of one isotropic material. Exact for straight-edged
/// tet4 and tet10. Throws SimulationError for an element that is not positively oriented.
FeMatrices assemble(const geometry::TetMesh& mesh, double youngs_modulus, double poisson_ratio,
                    double density);

/// y = A x for the symmetric matrix whose lower triangle is `lower`.
Eigen::VectorXd symmetric_times(const LowerView& lower, const Eigen::VectorXd& x);

/// x' A x for the symmetric matrix whose lower triangle is `lower`, summed in extended
/// precision: for a smooth x the terms cancel by orders of magnitude (an energy measured
/// in plain double would carry rounding of about eps * w_max^2 / w^2).
double quadratic_form(const LowerView& lower, const Eigen::VectorXd& x);

/// The whole symmetric matrix (both triangles), for tests and peers.
Eigen::SparseMatrix<double> full_matrix(const LowerView& lower);

/// Values of `lower` with the rows and columns of the held dofs replaced by the identity:
/// the same pattern, so one symbolic analysis serves any set of held nodes' values.
std::vector<double> hold_dofs(const FeMatrices& fe, const std::vector<double>& values,
                              const std::vector<char>& held_dof, double diagonal);

/// Per-dof mask (3N) of the given nodes.
std::vector<char> dof_mask(Eigen::Index dofs, const std::vector<int>& nodes);

/// A face of the mesh's boundary (a face of exactly one element), ordered so that its
/// normal (x1 - x0) x (x2 - x0) points out of the body.
struct BoundaryFace {
  std::array<int, 3> corners;
  std::array<int, 3> mids;  ///< mid nodes of edges 01, 12, 20 (tet10), or -1 (tet4)
};
std::vector<BoundaryFace> boundary_faces(const geometry::TetMesh& mesh);

/// Nodes on the mesh's boundary whose position lies inside [lo, hi].
std::vector<int> boundary_nodes_in(const geometry::TetMesh& mesh, const Eigen::Vector3d& lo,
                                   const Eigen::Vector3d& hi);

/// Nodal forces (3N) for a total force spread over the boundary faces that lie wholly in
/// [lo, hi] as a uniform traction (consistent weights: the integrals of the face shape
/// functions). Empty vector when no boundary face lies in the region.
Eigen::VectorXd region_force(const geometry::TetMesh& mesh, const Eigen::Vector3d& lo,
                             const Eigen::Vector3d& hi, const Eigen::Vector3d& total_force);

/// Consistent nodal forces (3N) of a uniform acceleration field g acting on the mass M.
Eigen::VectorXd body_force(const FeMatrices& fe, const Eigen::Vector3d& acceleration);
/// The same from the elements' masses, with no assembled M.
Eigen::VectorXd body_force(const geometry::TetMesh& mesh, double density,
                           const Eigen::Vector3d& acceleration);

/// The stiffness matrix of one element (12 x 12 or 30 x 30, its nodes' dofs in order).
/// Throws SimulationError for an element that is not positively oriented.
Eigen::MatrixXd element_stiffness(const geometry::TetMesh& mesh, Eigen::Index element,
                                  double youngs_modulus, double poisson_ratio);

/// Solves K u = f with the dofs of `fixed_nodes` held at zero, by the backend `setup`
/// asks for (null: `auto`, no coordinates); `auto` turns to PETSc's CG when CHOLMOD's
/// factor would not fit in memory. Throws SimulationError when the system is singular
/// (the body is not held against rigid motion).
Eigen::VectorXd solve_static(const FeMatrices& fe, const Eigen::VectorXd& force,
                             const std::vector<int>& fixed_nodes, SolverStats* stats = nullptr,
                             const SolverSetup* setup = nullptr);

/// The lowest `count` natural frequencies (Hz, ascending) with `held_nodes` clamped, by
/// subspace iteration on the factor of K (Rayleigh–Ritz each sweep, so repeated
/// frequencies, as a square beam's two bending modes, converge too). Mode shapes
/// (3N by count, mass-normalized) go to `modes` when given.
std::vector<double> natural_frequencies(const FeMatrices& fe, const std::vector<int>& held_nodes,
                                        int count, Eigen::MatrixXd* modes = nullptr);

/// von Mises stress at each element's centroid (Pa), from displacements u (3N).
Eigen::VectorXd element_von_mises(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                  double youngs_modulus, double poisson_ratio);

/// Per element, at its centroid: the von Mises stress (Pa) and the largest principal strain
/// (one strain evaluation for both: the step loop takes them every step).
struct ElementStressStrain {
  Eigen::VectorXd von_mises, principal_strain;
};
ElementStressStrain element_stress_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                          double youngs_modulus, double poisson_ratio);

/// The strain (Voigt: xx yy zz, then the engineering shears yz xz xy) of one element's own
/// field at barycentric coordinates `l` in it (a tet10's is linear, a tet4's constant).
Eigen::Matrix<double, 6, 1> element_strain_at(const geometry::TetMesh& mesh,
                                              const Eigen::VectorXd& u, Eigen::Index element,
                                              const Eigen::Vector4d& l);

/// The stress (Voigt, Pa) of a strain, isotropic linear elasticity.
Eigen::Matrix<double, 6, 1> stress_of(const Eigen::Matrix<double, 6, 1>& strain,
                                      double youngs_modulus, double poisson_ratio);

/// The von Mises stress of a stress, and the largest principal strain of a strain (Voigt).
double von_mises_of_stress(const Eigen::Matrix<double, 6, 1>& stress);
double largest_principal_strain(const Eigen::Matrix<double, 6, 1>& strain);

/// The largest value of an element field (at the elements' centroids) over a run so far.
struct FieldPeak {
  double value = 0;
  double time = -1;  ///< s; -1: no step yet
  /// m, the element's centroid where the body starts
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  Eigen::Index element = -1;  ///< the element's index in its mesh
  /// The element lies at a sharp inside corner of its body (elements_at_sharp_corners).
  bool at_sharp_corner = false;
};

/// An FE body's stress and strain over a run, against its material's yield: over all its
/// elements, and away from contacts, over those whose centroids lie farther than a reach
/// (the step loop: two mesh sizes) from every node a contact pressed in that step (a sharp
/// edge or corner pressing a face concentrates them under it over about two elements, and
/// there a linear-elastic value grows as the mesh is refined).
struct MaterialPeaks {
  FieldPeak von_mises, strain;            ///< Pa; the largest principal strain
  FieldPeak bulk_von_mises, bulk_strain;  ///< away from contacts
  /// Away from contacts and from the body's sharp inside corners: where a linear-elastic
  /// value converges as the mesh is refined (at a re-entrant edge with no fillet it is
  /// singular, as under a sharp contact).
  FieldPeak regular_von_mises, regular_strain;
  /// When the stress or the strain first passed the material's yield_strength or
  /// yield_strain (s; -1: never, or the material gives neither), anywhere / away from
  /// contacts / away from contacts and sharp corners.
  double yielded_at = -1, bulk_yielded_at = -1, regular_yielded_at = -1;
  /// At the body's sharp inside corners: the hot-spot values extrapolated to them from the
  /// faces (hot_spot.h; `at` the corner, `element` the element of the read at 0.4 t), and
  /// when they first passed the yield.
  FieldPeak corner_von_mises, corner_strain;
  double corner_yielded_at = -1;
};

/// Per element of `mesh`: whether it lies at a sharp inside corner of the body's `surface`
/// (its re-entrant edges whose faces turn by more than 30 degrees, the mesher's feature
/// angle, geometry::reentrant_edges): its centroid within two of its sizes (its longest
/// edge), or within `reach` (m), of one. The stress there is singular: as the elements
/// shrink the value two of them away grows too, and one read `reach` away converges
/// (the step loop: 0.4 of the body's thinnest wall, where the hot-spot method of the IIW's
/// fatigue recommendations reads a weld toe's nearest reference stress).
std::vector<char> elements_at_sharp_corners(const geometry::TetMesh& mesh,
                                            const geometry::TriMesh& surface, double reach);

/// Raises `peaks` with the element fields of one state at time t (s): over all elements,
/// over those whose centroids are farther than `reach` from every point of `pressed`
/// (positions in the reference mesh), and over those of them not `at_corner` (per element;
/// empty: none); sets the first times past the material's yield. Returns the fields'
/// largest values in this state (von Mises, strain).
std::pair<double, double> track_material_peaks(const geometry::TetMesh& mesh,
                                               const ElementStressStrain& fields,
                                               const std::vector<Eigen::Vector3d>& pressed,
                                               double reach, const std::vector<char>& at_corner,
                                               std::optional<double> yield_strength,
                                               std::optional<double> yield_strain, double t,
                                               MaterialPeaks* peaks);

/// Per node of `mesh`: whether its stress is a local concentration rather than the body's
/// own field, the elements the peaks away from contacts and corners leave out
/// (track_material_peaks): the node belongs to an element `at_corner` or one whose centroid
/// lies within `reach` (m) of a point of `pressed` (positions in the reference mesh). Frames
/// top their colour scale with the largest value of the other nodes.
std::vector<char> concentration_nodes(const geometry::TetMesh& mesh,
                                      const std::vector<Eigen::Vector3d>& pressed, double reach,
                                      const std::vector<char>& at_corner);

/// Per point of an interpolation (tet_locator.h's interpolation_matrix, points by nodes):
/// whether any node it takes a share of 1e-3 or more from is flagged.
std::vector<char> flagged_points(const Eigen::SparseMatrix<double>& interpolation,
                                 const std::vector<char>& node_flags);

/// materials::yield_ratio at each entry of two fields of the same points.
Eigen::VectorXd yield_ratios(const materials::Material& m, const Eigen::VectorXd& von_mises,
                             const Eigen::VectorXd& principal_strain);

/// The von Mises stress (Pa) and the largest principal strain at each node (N each): each
/// element's strain field evaluated at its own nodes (a tet10's is linear: its value at the
/// surface, not a quarter element inside as at the centroid; a tet4's is constant),
/// averaged over the elements around the node, then the invariants taken. What frames and
/// exported meshes show.
ElementStressStrain nodal_stress_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                        double youngs_modulus, double poisson_ratio);

/// Element values averaged over the elements around each node.
Eigen::VectorXd nodal_average(const geometry::TetMesh& mesh, const Eigen::VectorXd& per_element);

/// Largest principal strain over the element centroids.
double max_principal_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u);

}  // namespace vproto::sim
