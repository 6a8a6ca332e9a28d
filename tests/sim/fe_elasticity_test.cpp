#include "vproto/sim/fe_elasticity.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "vproto/geometry/primitives.h"
#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

geometry::TetMesh beam_mesh(double size, bool quadratic) {
  geometry::TetMeshOptions o;
  o.size = size;
  o.quadratic = quadratic;
  return geometry::make_tet_mesh(geometry::make_box({1.0, 0.05, 0.05}, false), o);
}

// mean z displacement of the nodes on the free end
double tip_deflection(const geometry::TetMesh& m, const Eigen::VectorXd& u) {
  const auto tip = boundary_nodes_in(m, {1 - 1e-9, -1, -1}, {1 + 1e-9, 1, 1});
  double sum = 0;
  for (int v : tip) sum += u[3 * v + 2];
  return sum / static_cast<double>(tip.size());
}

double cantilever(double size, bool quadratic) {
  const geometry::TetMesh m = beam_mesh(size, quadratic);
  const FeMatrices fe = assemble(m, 210e9, 0.3, 7850);
  const auto clamp = boundary_nodes_in(m, {-1e-9, -1, -1}, {1e-9, 1, 1});
  const Eigen::VectorXd f = region_force(m, {1 - 1e-9, -1, -1}, {1 + 1e-9, 1, 1}, {0, 0, -100});
  return -tip_deflection(m, solve_static(fe, f, clamp));
}

TEST(FeElasticity, PatchTestUniformTensionIsExact) {
  for (bool quadratic : {false, true}) {
    geometry::TetMeshOptions o;
    o.size = 0.02;
    o.quadratic = quadratic;
    const geometry::TetMesh m =
        geometry::make_tet_mesh(geometry::make_box({0.1, 0.04, 0.04}, false), o);
    const double e = 70e9, nu = 0.33, force = 1000, area = 0.04 * 0.04;
    const Eigen::SparseMatrix<double> k = full_matrix(assemble(m, e, nu, 2700).stiffness());
    const Eigen::VectorXd f = region_force(m, {0.1 - 1e-9, -1, -1}, {1, 1, 1}, {force, 0, 0});
    ASSERT_NEAR(f.sum(), force, 1e-9);
    // a support that lets the bar contract freely: u_x = 0 on the left face, and just
    // enough more (u_y, u_z at one corner, u_z at another) to stop rigid motion; the
    // exact solution u_x = F x / (E A), u_y = -nu F y / (E A) is then linear, which both
    // elements must reproduce at every node
    const auto left = boundary_nodes_in(m, {-1e-9, -1, -1}, {1e-9, 1, 1});
    std::vector<char> fix_dof(static_cast<std::size_t>(k.rows()), 0);
    int corner = -1, other = -1;
    for (int v : left) {
      fix_dof[3 * v] = 1;
      const Eigen::Vector3d p = m.nodes.row(v);
      if (p.norm() < 1e-12) corner = v;
      if ((p - Eigen::Vector3d(0, 0.04, 0)).norm() < 1e-12) other = v;
    }
    ASSERT_GE(corner, 0);
    ASSERT_GE(other, 0);
    fix_dof[3 * corner + 1] = fix_dof[3 * corner + 2] = fix_dof[3 * other + 2] = 1;
    std::vector<Eigen::Index> map(fix_dof.size());
    Eigen::Index n = 0;
    for (std::size_t i = 0; i < fix_dof.size(); ++i) map[i] = fix_dof[i] ? -1 : n++;
    std::vector<Eigen::Triplet<double>> t;
    for (Eigen::Index c = 0; c < k.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(k, c); it; ++it)
        if (map[it.row()] >= 0 && map[c] >= 0) t.emplace_back(map[it.row()], map[c], it.value());
    Eigen::SparseMatrix<double> kr(n, n);
    kr.setFromTriplets(t.begin(), t.end());
    Eigen::VectorXd fr(n);
    for (std::size_t i = 0; i < map.size(); ++i)
      if (map[i] >= 0) fr[map[i]] = f[static_cast<Eigen::Index>(i)];
    const Eigen::VectorXd ur = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(kr).solve(fr);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(k.rows());
    for (std::size_t i = 0; i < map.size(); ++i)
      if (map[i] >= 0) u[static_cast<Eigen::Index>(i)] = ur[map[i]];
    const double strain = force / (e * area);
    for (Eigen::Index v = 0; v < m.nodes.rows(); ++v) {
      EXPECT_NEAR(u[3 * v], strain * m.nodes(v, 0), 1e-9 * strain * 0.1)
          << "quadratic " << quadratic;
      EXPECT_NEAR(u[3 * v + 1], -nu * strain * m.nodes(v, 1), 1e-9 * strain * 0.1);
    }
    const Eigen::VectorXd vm = element_von_mises(m, u, e, nu);
    EXPECT_NEAR(vm.minCoeff(), force / area, 1e-6 * force / area);
    EXPECT_NEAR(vm.maxCoeff(), force / area, 1e-6 * force / area);
  }
}

TEST(FeElasticity, Tet10CantileverMatchesCalculix) {
  // references.md: steel 1 x 0.05 x 0.05 m, 100 N over the free end, clamped: C3D10 3.043e-4 m
  const double delta = cantilever(0.01, true);
  EXPECT_NEAR(delta, 3.043e-4, 0.003 * 3.043e-4) << delta;
}

TEST(FeElasticity, Tet4LocksAndConvergesWithRefinement) {
  const double coarse = cantilever(0.02, false), fine = cantilever(0.01, false);
  EXPECT_LT(coarse, 0.9 * 3.043e-4);  // linear tets are far too stiff in bending
  EXPECT_GT(fine, coarse);            // and approach the answer as the mesh refines
  EXPECT_LT(fine, 3.043e-4);
}

// The nodal fields frames and meshes show: a tet10's strain field evaluated at its own
// nodes. Pure bending, u_x = a x z, u_z = -a x^2 / 2 (strain e_xx = a z and nothing else),
// is quadratic, so tet10 nodes carry it exactly: the largest principal strain max(a z, 0)
// and von Mises E |a z| (uniaxial) at every node, the surface's included, where the
// elements' centroid values averaged fell short by a quarter element.
TEST(FeElasticity, NodalFieldsOfATet10MeshAreExactForPureBending) {
  const geometry::TetMesh m = beam_mesh(0.02, true);
  const double a = 1e-3, e = 210e9;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * m.nodes.rows());
  for (Eigen::Index v = 0; v < m.nodes.rows(); ++v) {
    const double x = m.nodes(v, 0), z = m.nodes(v, 2) - 0.025;  // from the middle plane
    u[3 * v] = a * x * z;
    u[3 * v + 2] = -a * x * x / 2;
  }
  // (with nu = 0 the lateral strains stay zero and the stress is uniaxial)
  const ElementStressStrain f = nodal_stress_strain(m, u, e, 0.0);
  double worst_strain = 0, worst_stress = 0;
  for (Eigen::Index v = 0; v < m.nodes.rows(); ++v) {
    const double z = m.nodes(v, 2) - 0.025;
    worst_strain = std::max(worst_strain, std::abs(f.principal_strain[v] - std::max(a * z, 0.0)));
    worst_stress = std::max(worst_stress, std::abs(f.von_mises[v] - e * std::abs(a * z)));
  }
  EXPECT_LT(worst_strain, 1e-9 * a);  // round-off
  EXPECT_LT(worst_stress, 1e-9 * e * a);
  // the centroids' values averaged do not reach the surface's
  const ElementStressStrain c = element_stress_strain(m, u, e, 0.0);
  EXPECT_LT(nodal_average(m, c.principal_strain).maxCoeff(), 0.95 * a * 0.025);
  EXPECT_NEAR(f.principal_strain.maxCoeff(), a * 0.025, 1e-9 * a);
}

TEST(FeElasticity, AFreeBodyIsSingular) {
  const geometry::TetMesh m = beam_mesh(0.025, false);
  const FeMatrices fe = assemble(m, 210e9, 0.3, 7850);
  const Eigen::VectorXd f = Eigen::VectorXd::Zero(fe.dofs);
  EXPECT_THROW(solve_static(fe, f, {}), SimulationError);
}

// The run's stress and strain peaks: where (the element's centroid) and when; away from
// contacts the elements within `reach` of a pressed point are left out; the first time past
// the material's yield is kept, and a later, lower state changes nothing.
TEST(FeElasticity, MaterialPeaksKeepWhereAndWhenAndLeaveOutThePressedElements) {
  geometry::TetMesh m;  // two unit tets side by side along x
  m.nodes.resize(6, 3);
  m.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 3, 0, 0, 3, 1, 0;
  m.elements.resize(2, 4);
  m.elements << 0, 1, 2, 3, 1, 4, 5, 3;
  auto centroid = [&](int el) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += 0.25 * m.nodes.row(m.elements(el, k)).transpose();
    return c;
  };
  ElementStressStrain f;
  f.von_mises = Eigen::Vector2d(5e6, 2e6);  // element 0 the more stressed
  f.principal_strain = Eigen::Vector2d(0.01, 0.03);
  MaterialPeaks p;
  const std::vector<Eigen::Vector3d> pressed{Eigen::Vector3d(0, 0, 0)};
  auto now = track_material_peaks(m, f, pressed, 1.0, {}, 4e6, 0.04, 0.5, &p);
  EXPECT_EQ(now.first, 5e6);
  EXPECT_EQ(now.second, 0.03);
  EXPECT_EQ(p.von_mises.value, 5e6);
  EXPECT_EQ(p.von_mises.time, 0.5);
  EXPECT_TRUE(p.von_mises.at.isApprox(centroid(0)));
  // element 0's centroid is within 1 of the pressed point: away from it, element 1
  EXPECT_EQ(p.bulk_von_mises.value, 2e6);
  EXPECT_TRUE(p.bulk_von_mises.at.isApprox(centroid(1)));
  EXPECT_EQ(p.strain.value, 0.03);
  EXPECT_TRUE(p.strain.at.isApprox(centroid(1)));
  EXPECT_EQ(p.yielded_at, 0.5);      // 5 MPa past 4 MPa
  EXPECT_EQ(p.bulk_yielded_at, -1);  // 2 MPa and 3 % strain: below both
  // later: lower stress, the strain past 4 % away from the contact (nothing pressed)
  f.von_mises = Eigen::Vector2d(1e6, 1e6);
  f.principal_strain = Eigen::Vector2d(0.01, 0.05);
  now = track_material_peaks(m, f, {}, 1.0, {}, 4e6, 0.04, 0.75, &p);
  EXPECT_EQ(now.first, 1e6);
  EXPECT_EQ(p.von_mises.value, 5e6);
  EXPECT_EQ(p.von_mises.time, 0.5);
  EXPECT_EQ(p.strain.value, 0.05);
  EXPECT_EQ(p.strain.time, 0.75);
  EXPECT_EQ(p.yielded_at, 0.5);
  EXPECT_EQ(p.bulk_yielded_at, 0.75);
  // element 0 at a sharp inside corner: away from contacts and corners, element 1
  MaterialPeaks c;
  f.von_mises = Eigen::Vector2d(5e6, 2e6);
  track_material_peaks(m, f, {}, 1.0, {1, 0}, 4e6, 0.04, 0.5, &c);
  EXPECT_TRUE(c.bulk_von_mises.at_sharp_corner);
  EXPECT_EQ(c.bulk_von_mises.element, 0);
  EXPECT_EQ(c.regular_von_mises.value, 2e6);
  EXPECT_EQ(c.regular_von_mises.element, 1);
  EXPECT_FALSE(c.regular_von_mises.at_sharp_corner);
  EXPECT_EQ(c.bulk_yielded_at, 0.5);
  EXPECT_EQ(c.regular_yielded_at, 0.5);  // strain 5 % at element 1
  f.principal_strain = Eigen::Vector2d(0.05, 0.01);
  MaterialPeaks d;
  track_material_peaks(m, f, {}, 1.0, {1, 0}, 4e6, 0.04, 0.5, &d);
  EXPECT_EQ(d.bulk_yielded_at, 0.5);
  EXPECT_EQ(d.regular_yielded_at, -1);  // past the yield only at the corner
  // a material without yield values never yields
  MaterialPeaks q;
  track_material_peaks(m, f, {}, 1.0, {}, std::nullopt, std::nullopt, 1.0, &q);
  EXPECT_EQ(q.yielded_at, -1);
  EXPECT_EQ(q.strain.value, 0.05);
}

// The nodes whose stress frames leave out of their colour scale are those of the elements
// track_material_peaks leaves out: at a sharp corner, or with the centroid within the reach
// of a pressed point (checked against every element by brute force, the pressed points
// on both sides of the lookup's cells and of the origin), and a surface point is flagged
// when it takes a share from a flagged node.
TEST(FeElasticity, ConcentrationNodesAreThoseOfTheElementsThePeaksLeaveOut) {
  geometry::TetMeshOptions o;
  o.size = 0.05;
  o.quadratic = true;  // the mid-edge nodes go with their elements too
  const geometry::TetMesh m =
      geometry::make_tet_mesh(geometry::make_box({0.4, 0.2, 0.1}, true), o);  // centred
  const double reach = 0.07;
  const std::vector<Eigen::Vector3d> pressed{
      {-0.2, -0.1, 0.05}, {0.0, 0.0, 0.05}, {0.13, 0.07, -0.05}, {0.2, -0.03, 0.0}};
  std::vector<char> corner(static_cast<std::size_t>(m.elements.rows()), 0);
  corner[7] = 1;
  const std::vector<char> got = concentration_nodes(m, pressed, reach, corner);
  std::vector<char> want(static_cast<std::size_t>(m.nodes.rows()), 0);
  for (Eigen::Index el = 0; el < m.elements.rows(); ++el) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += 0.25 * m.nodes.row(m.elements(el, k)).transpose();
    bool near = el == 7;
    for (const Eigen::Vector3d& x : pressed) near = near || (x - c).norm() < reach;
    if (near)
      for (Eigen::Index k = 0; k < m.elements.cols(); ++k)
        want[static_cast<std::size_t>(m.elements(el, k))] = 1;
  }
  EXPECT_EQ(got, want);
  const auto flagged = std::count(got.begin(), got.end(), 1);
  EXPECT_GT(flagged, 10);
  EXPECT_LT(flagged, m.nodes.rows() / 2);
  // nothing pressed and no corner: nothing flagged
  const std::vector<char> none = concentration_nodes(m, {}, reach, {});
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
  // points: the first at node 0 alone, the second half-way between nodes 1 and 2
  Eigen::SparseMatrix<double> at(2, m.nodes.rows());
  at.insert(0, 0) = 1;
  at.insert(1, 1) = 0.5;
  at.insert(1, 2) = 0.5;
  std::vector<char> flags(static_cast<std::size_t>(m.nodes.rows()), 0);
  flags[2] = 1;
  EXPECT_EQ(flagged_points(at, flags), (std::vector<char>{0, 1}));
  flags[2] = 0;
  flags[0] = 1;
  EXPECT_EQ(flagged_points(at, flags), (std::vector<char>{1, 0}));
}

}  // namespace
}  // namespace vproto::sim
