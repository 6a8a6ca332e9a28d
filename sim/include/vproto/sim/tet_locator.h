#pragma once
// Finding the element of a tetrahedral mesh that holds a point, and interpolating nodal
// values there with the element's shape functions (probes, surfaces for rendering).

#include <Eigen/SparseCore>
#include <optional>
#include <unordered_map>
#include <vector>

#include "vproto/geometry/tet_mesh.h"

namespace vproto::sim {

struct MeshPoint {
  int element = -1;
  Eigen::Vector4d barycentric = Eigen::Vector4d::Zero();
};

/// Shape-function values (4 or 10) at barycentric coordinates, VTK node order.
Eigen::VectorXd shape_values(const Eigen::Vector4d& barycentric, bool quadratic);

class TetLocator {
 public:
  /// Buckets the elements in a uniform grid of about the mesh size.
  explicit TetLocator(const geometry::TetMesh& mesh);

  /// The element holding `p` (within a relative tolerance, so points on the boundary are
  /// found); when none does, the element whose barycentric coordinates are least negative
  /// among the nearby ones, or nullopt when `p` is far from the mesh.
  std::optional<MeshPoint> locate(const Eigen::Vector3d& p) const;

  /// Interpolates per-node values (#N by k) at a located point.
  Eigen::RowVectorXd interpolate(const MeshPoint& at, const Eigen::MatrixXd& nodal) const;

 private:
  long key(int i, int j, int k) const {
    return (static_cast<long>(i) * 73856093L) ^ (static_cast<long>(j) * 19349663L) ^
           (static_cast<long>(k) * 83492791L);
  }
  const geometry::TetMesh& mesh_;
  Eigen::Vector3d origin_;
  double cell_ = 1;
  std::unordered_map<long, std::vector<int>> buckets_;
};

/// The sparse matrix (#points by #nodes) that interpolates nodal values at the points with
/// the shape functions of the elements holding them (surface vertices of an elastic body,
/// probes). Throws SimulationError for a point far from the mesh.
Eigen::SparseMatrix<double> interpolation_matrix(const geometry::TetMesh& mesh,
                                                 const TetLocator& locator,
                                                 const Eigen::MatrixX3d& points);

}  // namespace vproto::sim
