#pragma once
// Analytic volumes of the faceted primitives, computed independently of the mesh code.

#include <cmath>

namespace vproto::testing {

constexpr double kPi = 3.14159265358979323846;

/// Area of a regular N-gon inscribed in a circle of radius r.
inline double ngon_area(double r, int n) { return 0.5 * n * r * r * std::sin(2 * kPi / n); }

/// Frustum of two similar regular N-gons.
inline double ngon_frustum_volume(double h, double r1, double r2, int n) {
  const double a1 = ngon_area(r1, n), a2 = ngon_area(r2, n);
  return h / 3 * (a1 + a2 + std::sqrt(a1 * a2));
}

/// OpenSCAD-style faceted sphere: (n+1)/2 rings at polar angles 180 (i + 1/2) / rings.
inline double faceted_sphere_volume(double r, int n) {
  const int rings = (n + 1) / 2;
  double v = 0;
  for (int i = 0; i + 1 < rings; ++i) {
    const double p0 = kPi * (i + 0.5) / rings, p1 = kPi * (i + 1.5) / rings;
    const double h = r * (std::cos(p0) - std::cos(p1));
    const double a0 = ngon_area(r * std::sin(p0), n), a1 = ngon_area(r * std::sin(p1), n);
    v += h / 3 * (a0 + a1 + std::sqrt(a0 * a1));
  }
  return v;
}

}  // namespace vproto::testing
