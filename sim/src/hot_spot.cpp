#include "vproto/sim/hot_spot.h"

#include <algorithm>
#include <cmath>

namespace vproto::sim {

namespace {

constexpr double kNear = 0.4, kFar = 1.0;  // the reads, in wall thicknesses from the edge

}  // namespace

std::vector<CornerRead> corner_reads(const geometry::TriMesh& surface, const TetLocator& locator,
                                     double spacing) {
  std::vector<CornerRead> out;
  const std::vector<geometry::Edge> edges = geometry::reentrant_edges(surface, 30);
  if (edges.empty() || !(spacing > 0)) return out;
  // candidate reads: every `spacing` along each edge, on both its faces
  std::vector<CornerRead> reads;
  std::vector<Eigen::Vector3d> origins, inward;
  for (const geometry::Edge& e : edges) {
    const double length = (e.b - e.a).norm();
    const int pieces = std::max(1, static_cast<int>(std::ceil(length / spacing)));
    for (int i = 0; i < pieces; ++i) {
      const Eigen::Vector3d p = e.a + (i + 0.5) / pieces * (e.b - e.a);
      for (std::size_t side = 0; side < 2; ++side) {
        CornerRead r;
        r.corner = p;
        r.into = e.into[side];
        reads.push_back(r);
        // the wall's thickness: a ray square to the face, from a hair inside it and a
        // twentieth of the spacing off the edge (so it does not run along the other face)
        origins.push_back(p + 0.05 * spacing * e.into[side] - 1e-6 * spacing * e.normal[side]);
        inward.push_back(-e.normal[side]);
      }
    }
  }
  const std::vector<double> depth = geometry::ray_distances(surface, origins, inward);
  // the read points, a hair inside the face
  std::vector<Eigen::Vector3d> points;
  for (std::size_t k = 0; k < reads.size(); ++k) {
    CornerRead& r = reads[k];
    r.wall = depth[k] + 1e-6 * spacing;
    const Eigen::Vector3d n = -inward[k];
    for (const double f : {kNear, kFar})
      points.push_back(r.corner + f * r.wall * r.into - 1e-6 * r.wall * n);
  }
  const std::vector<geometry::NearestFace> on = geometry::nearest_faces(surface, points);
  for (std::size_t k = 0; k < reads.size(); ++k) {
    CornerRead& r = reads[k];
    if (!std::isfinite(r.wall) || !(r.wall > 0)) continue;
    const Eigen::Vector3d n = -inward[k];
    bool on_face = true;
    for (std::size_t j = 2 * k; j < 2 * k + 2; ++j)
      on_face = on_face && on[j].distance < 1e-4 * r.wall && on[j].normal.dot(n) > 0.9999;
    if (!on_face) continue;
    const std::optional<MeshPoint> near = locator.locate(points[2 * k]);
    const std::optional<MeshPoint> far = locator.locate(points[2 * k + 1]);
    if (!near || !far) continue;
    r.near = *near;
    r.far = *far;
    out.push_back(r);
  }
  return out;
}

CornerHotSpot corner_hot_spot(const std::vector<CornerRead>& reads, const geometry::TetMesh& mesh,
                              const Eigen::VectorXd& u, double youngs_modulus, double poisson_ratio,
                              const std::vector<Eigen::Vector3d>& pressed, double reach) {
  CornerHotSpot out;
  for (std::size_t k = 0; k < reads.size(); ++k) {
    const CornerRead& r = reads[k];
    const bool pressed_near = std::any_of(pressed.begin(), pressed.end(), [&](const auto& x) {
      for (const double f : {kNear, kFar})
        if ((x - (r.corner + f * r.wall * r.into)).squaredNorm() < reach * reach) return true;
      return false;
    });
    if (pressed_near) continue;
    // the strain tensor extrapolated linearly to the edge from the two reads
    const Eigen::Matrix<double, 6, 1> near =
        element_strain_at(mesh, u, r.near.element, r.near.barycentric);
    const Eigen::Matrix<double, 6, 1> far =
        element_strain_at(mesh, u, r.far.element, r.far.barycentric);
    const Eigen::Matrix<double, 6, 1> strain =
        (kFar * near - kNear * far) / (kFar - kNear);  // 1.67 near - 0.67 far
    const double vm = von_mises_of_stress(stress_of(strain, youngs_modulus, poisson_ratio));
    const double eps = largest_principal_strain(strain);
    const int i = static_cast<int>(k);
    if (out.von_mises_read < 0 || vm > out.von_mises) out.von_mises = vm, out.von_mises_read = i;
    if (out.strain_read < 0 || eps > out.strain) out.strain = eps, out.strain_read = i;
  }
  return out;
}

void track_corner_peaks(const std::vector<CornerRead>& reads, const CornerHotSpot& now,
                        std::optional<double> yield_strength, std::optional<double> yield_strain,
                        double t, MaterialPeaks* peaks) {
  auto raise = [&](FieldPeak* peak, double value, int read) {
    if (read < 0 || !(value > peak->value)) return;
    const CornerRead& r = reads[static_cast<std::size_t>(read)];
    peak->value = value;
    peak->time = t;
    peak->at = r.corner;
    peak->element = r.near.element;
    peak->at_sharp_corner = true;
  };
  raise(&peaks->corner_von_mises, now.von_mises, now.von_mises_read);
  raise(&peaks->corner_strain, now.strain, now.strain_read);
  const bool past =
      (yield_strength && now.von_mises_read >= 0 && now.von_mises > *yield_strength) ||
      (yield_strain && now.strain_read >= 0 && now.strain > *yield_strain);
  if (peaks->corner_yielded_at < 0 && past) peaks->corner_yielded_at = t;
}

}  // namespace vproto::sim
