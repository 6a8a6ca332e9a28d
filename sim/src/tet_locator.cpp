#include "vproto/sim/tet_locator.h"

#include <cmath>

#include "vproto/materials/errors.h"

namespace vproto::sim {

Eigen::VectorXd shape_values(const Eigen::Vector4d& l, bool quadratic) {
  if (!quadratic) return l;
  static constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  Eigen::VectorXd n(10);
  for (int i = 0; i < 4; ++i) n[i] = l[i] * (2 * l[i] - 1);
  for (int k = 0; k < 6; ++k) n[4 + k] = 4 * l[kEdges[k][0]] * l[kEdges[k][1]];
  return n;
}

TetLocator::TetLocator(const geometry::TetMesh& mesh) : mesh_(mesh) {
  origin_ = mesh.nodes.colwise().minCoeff().transpose();
  cell_ = mesh.mesh_size > 0 ? mesh.mesh_size : 1.0;
  for (Eigen::Index e = 0; e < mesh.elements.rows(); ++e) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (int k = 0; k < 4; ++k) {
      lo = lo.cwiseMin(mesh.nodes.row(mesh.elements(e, k)).transpose());
      hi = hi.cwiseMax(mesh.nodes.row(mesh.elements(e, k)).transpose());
    }
    const Eigen::Vector3i a = ((lo - origin_) / cell_).array().floor().cast<int>();
    const Eigen::Vector3i b = ((hi - origin_) / cell_).array().floor().cast<int>();
    for (int i = a.x(); i <= b.x(); ++i)
      for (int j = a.y(); j <= b.y(); ++j)
        for (int k = a.z(); k <= b.z(); ++k) buckets_[key(i, j, k)].push_back(static_cast<int>(e));
  }
}

std::optional<MeshPoint> TetLocator::locate(const Eigen::Vector3d& p) const {
  const Eigen::Vector3i c = ((p - origin_) / cell_).array().floor().cast<int>();
  MeshPoint best;
  double best_min = -1e300;
  // the point's cell and its neighbours (points on a cell face may sit in either)
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj)
      for (int dk = -1; dk <= 1; ++dk) {
        const auto it = buckets_.find(key(c.x() + di, c.y() + dj, c.z() + dk));
        if (it == buckets_.end()) continue;
        for (int e : it->second) {
          Eigen::Matrix3d j;
          const Eigen::Vector3d x0 = mesh_.nodes.row(mesh_.elements(e, 0)).transpose();
          for (int k = 0; k < 3; ++k)
            j.col(k) = mesh_.nodes.row(mesh_.elements(e, k + 1)).transpose() - x0;
          const Eigen::Vector3d l123 = j.partialPivLu().solve(p - x0);
          const Eigen::Vector4d l(1 - l123.sum(), l123.x(), l123.y(), l123.z());
          const double worst = l.minCoeff();
          if (worst > best_min) {
            best_min = worst;
            best.element = e;
            best.barycentric = l;
          }
          if (worst >= -1e-12) return best;
        }
      }
  if (best.element < 0 || best_min < -0.5) return std::nullopt;
  // nearest candidate: clamp onto the element
  best.barycentric = best.barycentric.cwiseMax(0.0);
  best.barycentric /= best.barycentric.sum();
  return best;
}

Eigen::RowVectorXd TetLocator::interpolate(const MeshPoint& at,
                                           const Eigen::MatrixXd& nodal) const {
  const bool quadratic = mesh_.elements.cols() == 10;
  const Eigen::VectorXd n = shape_values(at.barycentric, quadratic);
  Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(nodal.cols());
  for (Eigen::Index k = 0; k < n.size(); ++k)
    out += n[k] * nodal.row(mesh_.elements(at.element, k));
  return out;
}

Eigen::SparseMatrix<double> interpolation_matrix(const geometry::TetMesh& mesh,
                                                 const TetLocator& locator,
                                                 const Eigen::MatrixX3d& points) {
  const bool quadratic = mesh.elements.cols() == 10;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(points.rows() * mesh.elements.cols()));
  for (Eigen::Index p = 0; p < points.rows(); ++p) {
    const auto at = locator.locate(points.row(p).transpose());
    if (!at)
      throw SimulationError("a surface point lies outside the body's tetrahedral mesh (point " +
                            std::to_string(p) + ")");
    const Eigen::VectorXd n = shape_values(at->barycentric, quadratic);
    for (Eigen::Index k = 0; k < n.size(); ++k)
      t.emplace_back(static_cast<int>(p), mesh.elements(at->element, k), n[k]);
  }
  Eigen::SparseMatrix<double> m(points.rows(), mesh.nodes.rows());
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

}  // namespace vproto::sim
