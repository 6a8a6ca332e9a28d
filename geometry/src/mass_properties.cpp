#include "vproto/geometry/mass_properties.h"

namespace vproto::geometry {

MassProperties mass_properties(const TriMesh& mesh) {
  MassProperties mp;
  if (mesh.F.rows() == 0) return mp;
  // a reference point inside the vertex cloud keeps the sums well conditioned
  const Eigen::Vector3d ref = mesh.V.colwise().mean().transpose();
  double volume = 0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // integral of x x^T about ref
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)).transpose() - ref;
    const Eigen::Vector3d b = mesh.V.row(mesh.F(f, 1)).transpose() - ref;
    const Eigen::Vector3d c = mesh.V.row(mesh.F(f, 2)).transpose() - ref;
    // signed tetrahedron (ref, a, b, c)
    const double v = a.dot(b.cross(c)) / 6.0;
    const Eigen::Vector3d s = a + b + c;
    volume += v;
    first += v * s / 4.0;
    // integral over a tetrahedron with one vertex at the origin:
    // v/20 (a a^T + b b^T + c c^T + s s^T)
    second +=
        v / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  mp.volume = volume;
  mp.area = surface_area(mesh);
  if (volume <= 0) return mp;
  const Eigen::Vector3d offset = first / volume;
  mp.centroid = ref + offset;
  // covariance about the centroid, then I = tr(C) 1 - C
  const Eigen::Matrix3d cov = second - volume * offset * offset.transpose();
  mp.unit_inertia = cov.trace() * Eigen::Matrix3d::Identity() - cov;
  return mp;
}

}  // namespace vproto::geometry
