#include "vproto/sim/fe_elasticity.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Eigenvalues>
#include <array>
#include <map>

#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;

// isotropic elasticity matrix, Voigt order xx yy zz yz xz xy (engineering shear strains)
Mat6 elasticity(double e, double nu) {
  const double lambda = e * nu / ((1 + nu) * (1 - 2 * nu)), mu = e / (2 * (1 + nu));
  Mat6 d = Mat6::Zero();
  d.topLeftCorner<3, 3>().setConstant(lambda);
  d.topLeftCorner<3, 3>().diagonal().array() += 2 * mu;
  d.bottomRightCorner<3, 3>().diagonal().setConstant(mu);
  return d;
}

// gradients of the barycentric coordinates of a straight tet (rows) and its volume
Eigen::Matrix<double, 4, 3> barycentric_gradients(const geometry::TetMesh& m, Eigen::Index e,
                                                  double* volume) {
  Eigen::Matrix3d j;
  const Eigen::Vector3d x0 = m.nodes.row(m.elements(e, 0)).transpose();
  for (int k = 0; k < 3; ++k) j.col(k) = m.nodes.row(m.elements(e, k + 1)).transpose() - x0;
  const double det = j.determinant();
  *volume = det / 6;
  const Eigen::Matrix3d inv_t = j.inverse().transpose();
  Eigen::Matrix<double, 4, 3> g;
  g.bottomRows<3>() = inv_t.transpose();  // grad L_{k+1} = rows of J^-1
  g.row(0) = -g.bottomRows<3>().colwise().sum();
  return g;
}

constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

// shape-function gradients (n by 3) at barycentric point l
Eigen::MatrixX3d shape_gradients(const Eigen::Matrix<double, 4, 3>& g, const Eigen::Vector4d& l,
                                 bool quadratic) {
  if (!quadratic) return g;
  Eigen::MatrixX3d d(10, 3);
  for (int i = 0; i < 4; ++i) d.row(i) = (4 * l[i] - 1) * g.row(i);
  for (int k = 0; k < 6; ++k) {
    const int a = kEdges[k][0], b = kEdges[k][1];
    d.row(4 + k) = 4 * (l[b] * g.row(a) + l[a] * g.row(b));
  }
  return d;
}

// strain-displacement matrix (6 by 3n)
Eigen::MatrixXd strain_matrix(const Eigen::MatrixX3d& dn) {
  const Eigen::Index n = dn.rows();
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(6, 3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = dn(i, 0), y = dn(i, 1), z = dn(i, 2);
    b(0, 3 * i) = x;
    b(1, 3 * i + 1) = y;
    b(2, 3 * i + 2) = z;
    b(3, 3 * i + 1) = z, b(3, 3 * i + 2) = y;
    b(4, 3 * i) = z, b(4, 3 * i + 2) = x;
    b(5, 3 * i) = y, b(5, 3 * i + 1) = x;
  }
  return b;
}

// 4-point rule, exact for quadratics: the tet10 stiffness integrand
const std::array<Eigen::Vector4d, 4>& quadrature_points() {
  static const double a = 0.5854101966249685, b = 0.1381966011250105;
  static const std::array<Eigen::Vector4d, 4> pts = {
      Eigen::Vector4d(a, b, b, b), Eigen::Vector4d(b, a, b, b), Eigen::Vector4d(b, b, a, b),
      Eigen::Vector4d(b, b, b, a)};
  return pts;
}

// engineering strains (Voigt, xx yy zz yz xz xy) at an element's centroid
Eigen::Matrix<double, 6, 1> centroid_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                            Eigen::Index el) {
  const bool quadratic = mesh.elements.cols() == 10;
  const Eigen::Index per = mesh.elements.cols();
  double volume = 0;
  const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, el, &volume);
  const Eigen::MatrixXd b =
      strain_matrix(shape_gradients(g, Eigen::Vector4d::Constant(0.25), quadratic));
  Eigen::VectorXd ue(3 * per);
  for (Eigen::Index i = 0; i < per; ++i)
    ue.segment<3>(3 * i) = u.segment<3>(3 * mesh.elements(el, i));
  return b * ue;
}

}  // namespace

Eigen::SparseMatrix<double> assemble_stiffness(const geometry::TetMesh& mesh, double e, double nu) {
  const Mat6 d = elasticity(e, nu);
  const bool quadratic = mesh.elements.cols() == 10;
  const Eigen::Index per = mesh.elements.cols(), dofs = 3 * per;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(mesh.elements.rows() * dofs * dofs));
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    double volume = 0;
    const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, el, &volume);
    Eigen::MatrixXd ke = Eigen::MatrixXd::Zero(dofs, dofs);
    if (quadratic) {
      for (const auto& l : quadrature_points()) {
        const Eigen::MatrixXd b = strain_matrix(shape_gradients(g, l, true));
        ke += (volume / 4) * b.transpose() * d * b;
      }
    } else {
      const Eigen::MatrixXd b = strain_matrix(g);
      ke = volume * b.transpose() * d * b;
    }
    for (Eigen::Index i = 0; i < per; ++i)
      for (Eigen::Index j = 0; j < per; ++j)
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c)
            triplets.emplace_back(3 * mesh.elements(el, i) + a, 3 * mesh.elements(el, j) + c,
                                  ke(3 * i + a, 3 * j + c));
  }
  const Eigen::Index n = 3 * mesh.nodes.rows();
  Eigen::SparseMatrix<double> k(n, n);
  k.setFromTriplets(triplets.begin(), triplets.end());
  return k;
}

namespace {

// boundary faces: (corner nodes, mid nodes or -1) of faces that belong to one element
struct Face {
  std::array<int, 3> corners;
  std::array<int, 3> mids;  // edges 01, 12, 20 of the face, or -1 (tet4)
};

std::vector<Face> boundary_faces(const geometry::TetMesh& m) {
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  const bool quadratic = m.elements.cols() == 10;
  std::map<std::array<int, 3>, std::pair<int, Face>> seen;
  for (Eigen::Index e = 0; e < m.elements.rows(); ++e)
    for (const auto& f : kFaces) {
      Face face;
      for (int k = 0; k < 3; ++k) face.corners[k] = m.elements(e, f[k]);
      face.mids = {-1, -1, -1};
      if (quadratic)
        for (int k = 0; k < 3; ++k) {
          const int a = f[k], b = f[(k + 1) % 3];
          for (int q = 0; q < 6; ++q)
            if ((kEdges[q][0] == a && kEdges[q][1] == b) ||
                (kEdges[q][0] == b && kEdges[q][1] == a))
              face.mids[k] = m.elements(e, 4 + q);
        }
      std::array<int, 3> key = face.corners;
      std::sort(key.begin(), key.end());
      auto [it, added] = seen.try_emplace(key, std::make_pair(1, face));
      if (!added) ++it->second.first;
    }
  std::vector<Face> out;
  for (const auto& [key, v] : seen)
    if (v.first == 1) out.push_back(v.second);
  return out;
}

bool inside(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

}  // namespace

std::vector<int> boundary_nodes_in(const geometry::TetMesh& m, const Eigen::Vector3d& lo,
                                   const Eigen::Vector3d& hi) {
  std::vector<char> mark(static_cast<std::size_t>(m.nodes.rows()), 0);
  for (const Face& f : boundary_faces(m)) {
    for (int v : f.corners) mark[v] = 1;
    for (int v : f.mids)
      if (v >= 0) mark[v] = 1;
  }
  std::vector<int> out;
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i)
    if (mark[i] && inside(m.nodes.row(i).transpose(), lo, hi)) out.push_back(static_cast<int>(i));
  return out;
}

Eigen::VectorXd region_force(const geometry::TetMesh& m, const Eigen::Vector3d& lo,
                             const Eigen::Vector3d& hi, const Eigen::Vector3d& total) {
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(m.nodes.rows());
  double area_sum = 0;
  for (const Face& f : boundary_faces(m)) {
    bool all_in = true;
    for (int v : f.corners) all_in = all_in && inside(m.nodes.row(v).transpose(), lo, hi);
    if (!all_in) continue;
    const Eigen::Vector3d a = m.nodes.row(f.corners[0]), b = m.nodes.row(f.corners[1]),
                          c = m.nodes.row(f.corners[2]);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    area_sum += area;
    // integrals of the face shape functions: linear A/3 per corner; quadratic 0 per
    // corner and A/3 per mid-edge node
    if (f.mids[0] < 0) {
      for (int v : f.corners) weight[v] += area / 3;
    } else {
      for (int v : f.mids) weight[v] += area / 3;
    }
  }
  if (area_sum <= 0) return {};
  Eigen::VectorXd out = Eigen::VectorXd::Zero(3 * m.nodes.rows());
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i)
    if (weight[i] != 0) out.segment<3>(3 * i) = total * (weight[i] / area_sum);
  return out;
}

Eigen::VectorXd solve_static(const Eigen::SparseMatrix<double>& k, const Eigen::VectorXd& f,
                             const std::vector<int>& fixed_nodes) {
  const Eigen::Index n = k.rows();
  // free dofs renumbered; the held ones are dropped
  std::vector<Eigen::Index> map(static_cast<std::size_t>(n), 0);
  for (int v : fixed_nodes)
    for (int a = 0; a < 3; ++a) map[3 * v + a] = -1;
  Eigen::Index free = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (map[i] == 0)
      map[i] = free++;
    else
      map[i] = -1;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(k.nonZeros()));
  for (Eigen::Index col = 0; col < k.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, col); it; ++it)
      if (map[it.row()] >= 0 && map[col] >= 0 && map[it.row()] >= map[col])  // lower triangle
        t.emplace_back(map[it.row()], map[col], it.value());
  Eigen::SparseMatrix<double> kr(free, free);
  kr.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd fr(free);
  for (Eigen::Index i = 0; i < n; ++i)
    if (map[i] >= 0) fr[map[i]] = f[i];
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  llt.compute(kr);
  if (llt.info() != Eigen::Success)
    throw SimulationError(
        "the stiffness matrix is singular: the body is not held against rigid "
        "motion; fix or grip a region of it");
  const Eigen::VectorXd ur = llt.solve(fr);
  if (!ur.allFinite()) throw SimulationError("the static solve gave non-finite displacements");
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i)
    if (map[i] >= 0) u[i] = ur[map[i]];
  return u;
}

Eigen::VectorXd element_von_mises(const geometry::TetMesh& mesh, const Eigen::VectorXd& u, double e,
                                  double nu) {
  const Mat6 d = elasticity(e, nu);
  Eigen::VectorXd out(mesh.elements.rows());
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    const Eigen::Matrix<double, 6, 1> s = d * centroid_strain(mesh, u, el);
    out[el] = std::sqrt(0.5 * ((s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) +
                               (s[2] - s[0]) * (s[2] - s[0])) +
                        3 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
  }
  return out;
}

double max_principal_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u) {
  double worst = 0;
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    const Eigen::Matrix<double, 6, 1> v = centroid_strain(mesh, u, el);
    Eigen::Matrix3d eps;
    eps << v[0], v[5] / 2, v[4] / 2, v[5] / 2, v[1], v[3] / 2, v[4] / 2, v[3] / 2, v[2];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(eps, Eigen::EigenvaluesOnly);
    worst = std::max(worst, solver.eigenvalues().maxCoeff());
  }
  return worst;
}

}  // namespace vproto::sim
