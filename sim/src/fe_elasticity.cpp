#include "vproto/sim/fe_elasticity.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>

#include "two_threads.h"
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

// quadratic shape-function gradients (10 by 3) at barycentric point l
Eigen::Matrix<double, 10, 3> shape_gradients(const Eigen::Matrix<double, 4, 3>& g,
                                             const Eigen::Vector4d& l) {
  Eigen::Matrix<double, 10, 3> d;
  for (int i = 0; i < 4; ++i) d.row(i) = (4 * l[i] - 1) * g.row(i);
  for (int k = 0; k < 6; ++k) {
    const int a = kEdges[k][0], b = kEdges[k][1];
    d.row(4 + k) = 4 * (l[b] * g.row(a) + l[a] * g.row(b));
  }
  return d;
}

// strain-displacement matrix (6 by 3n)
template <typename Gradients>
Eigen::Matrix<double, 6, 3 * Gradients::RowsAtCompileTime> strain_matrix(const Gradients& dn) {
  constexpr int n = Gradients::RowsAtCompileTime;
  Eigen::Matrix<double, 6, 3 * n> b = Eigen::Matrix<double, 6, 3 * n>::Zero();
  for (int i = 0; i < n; ++i) {
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

// engineering strains (Voigt, xx yy zz yz xz xy) at an element's centroid: the symmetric
// gradient of sum_i u_i N_i. At the centroid a tet10's corner functions have no gradient
// (4 L - 1 = 0) and the mid-edge node of edge (a, b) has grad L_a + grad L_b; computed here
// without the 6 x 30 strain matrix or a heap vector (the stresses are taken every step)
Eigen::Matrix<double, 6, 1> centroid_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                            Eigen::Index el) {
  double volume = 0;
  const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, el, &volume);
  Eigen::Matrix3d grad = Eigen::Matrix3d::Zero();  // grad(u)(i, j) = d u_i / d x_j
  auto add = [&](Eigen::Index node, const Eigen::RowVector3d& dn) {
    grad.noalias() += u.segment<3>(3 * node) * dn;
  };
  if (mesh.elements.cols() == 10) {
    for (int k = 0; k < 6; ++k)
      add(mesh.elements(el, 4 + k), g.row(kEdges[k][0]) + g.row(kEdges[k][1]));
  } else {
    for (int k = 0; k < 4; ++k) add(mesh.elements(el, k), g.row(k));
  }
  Eigen::Matrix<double, 6, 1> e;
  e << grad(0, 0), grad(1, 1), grad(2, 2), grad(1, 2) + grad(2, 1), grad(0, 2) + grad(2, 0),
      grad(0, 1) + grad(1, 0);
  return e;
}

}  // namespace

namespace {

// integral over a tet of volume V of L0^a L1^b L2^c L3^d, divided by V
double monomial_integral(const std::array<int, 4>& e) {
  auto fact = [](int n) {
    double f = 1;
    for (int k = 2; k <= n; ++k) f *= k;
    return f;
  };
  return 6 * fact(e[0]) * fact(e[1]) * fact(e[2]) * fact(e[3]) /
         fact(e[0] + e[1] + e[2] + e[3] + 3);
}

// the shape functions as polynomials in the barycentric coordinates
using Polynomial = std::map<std::array<int, 4>, double>;

std::vector<Polynomial> shape_polynomials(bool quadratic) {
  std::vector<Polynomial> n;
  for (int i = 0; i < 4; ++i) {
    std::array<int, 4> one{}, two{};
    one[i] = 1;
    two[i] = 2;
    n.push_back(quadratic ? Polynomial{{two, 2.0}, {one, -1.0}} : Polynomial{{one, 1.0}});
  }
  if (quadratic)
    for (const auto& edge : kEdges) {
      std::array<int, 4> e{};
      e[edge[0]] = e[edge[1]] = 1;
      n.push_back(Polynomial{{e, 4.0}});
    }
  return n;
}

// (1/V) * integral of N_p N_q over a straight tet: the same for every element
Eigen::MatrixXd reference_mass(bool quadratic) {
  const std::vector<Polynomial> n = shape_polynomials(quadratic);
  const auto size = static_cast<Eigen::Index>(n.size());
  Eigen::MatrixXd m(size, size);
  for (Eigen::Index p = 0; p < size; ++p)
    for (Eigen::Index q = 0; q < size; ++q) {
      double sum = 0;
      for (const auto& [ep, cp] : n[p])
        for (const auto& [eq, cq] : n[q]) {
          std::array<int, 4> e{};
          for (int k = 0; k < 4; ++k) e[k] = ep[k] + eq[k];
          sum += cp * cq * monomial_integral(e);
        }
      m(p, q) = sum;
    }
  return m;
}

// The lower-triangle pattern: for every node, the sorted nodes >= it that share an
// element with it (itself first).
std::vector<std::vector<int>> node_neighbours(const geometry::TetMesh& mesh) {
  std::vector<std::vector<int>> adj(static_cast<std::size_t>(mesh.nodes.rows()));
  const Eigen::Index per = mesh.elements.cols();
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el)
    for (Eigen::Index i = 0; i < per; ++i)
      for (Eigen::Index j = 0; j < per; ++j) {
        const int a = mesh.elements(el, i), b = mesh.elements(el, j);
        if (a <= b) adj[a].push_back(b);
      }
  for (auto& list : adj) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return adj;
}

// An element's stiffness from its barycentric gradients: B^T D B at four quadrature points
// (tet10, exact for straight edges) or once (tet4, constant strain).
template <int N>
void stiffness_of(const Mat6& d, const Eigen::Matrix<double, 4, 3>& g, double volume,
                  Eigen::Matrix<double, 3 * N, 3 * N>* ke) {
  using B = Eigen::Matrix<double, 6, 3 * N>;
  if constexpr (N == 10) {
    ke->setZero();
    for (const auto& l : quadrature_points()) {
      const B b = strain_matrix(shape_gradients(g, l));
      ke->noalias() += (volume / 4) * b.transpose() * d * b;
    }
  } else {
    const B b = strain_matrix(g);
    ke->noalias() = volume * b.transpose() * d * b;
  }
}

// In batches on two threads: the element matrices (four quadrature points of B^T D B for a
// tet10) split by element, then their sums split by column, each entry summed in element
// order by one thread, so the values have the same bits on any number of threads. A
// 284k-dof tet10 block (66k elements, bench/fe_bench --size 0.007 --length 0.5): the
// whole assembly 1.10-1.17 s on one thread, 0.79-0.83 s on two.
template <int N>
void assemble_elements(const geometry::TetMesh& mesh, const Mat6& d, double density,
                       const std::vector<std::vector<int>>& adj, FeMatrices& fe) {
  constexpr int kDofs = 3 * N;
  using Ke = Eigen::Matrix<double, kDofs, kDofs>;
  const Eigen::MatrixXd mref = reference_mass(N == 10);
  constexpr Eigen::Index kBatch = 2048;  // elements: 15 MB of tet10 matrices
  const Eigen::Index elements = mesh.elements.rows();
  std::vector<Ke, Eigen::aligned_allocator<Ke>> ke(
      static_cast<std::size_t>(std::min(kBatch, elements)));
  std::vector<double> volume(ke.size());
  // the column node where half the matrix's entries lie before (summing threads' boundary)
  const auto half = std::lower_bound(fe.outer.begin(), fe.outer.end(), fe.outer.back() / 2);
  const int split_node = static_cast<int>((half - fe.outer.begin()) / 3);
  for (Eigen::Index first = 0; first < elements; first += kBatch) {
    const Eigen::Index count = std::min(kBatch, elements - first);
    in_two_threads(count >= 64, [&](int start, int stride) {
      for (Eigen::Index k = start; k < count; k += stride) {
        const auto at = static_cast<std::size_t>(k);
        const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, first + k, &volume[at]);
        if (!(volume[at] > 0)) continue;  // refused below, in element order
        stiffness_of<N>(d, g, volume[at], &ke[at]);
      }
    });
    for (Eigen::Index k = 0; k < count; ++k)
      if (!(volume[static_cast<std::size_t>(k)] > 0))
        throw SimulationError(
            "tet element " + std::to_string(first + k) + " is inverted or flat (volume " +
            std::to_string(volume[static_cast<std::size_t>(k)]) + " m^3): the mesh is invalid");
    // summed in element order, each thread into the columns of its half of the entries
    in_two_threads(count >= 64, [&](int part, int parts) {
      const int from = parts == 1  ? 0
                       : part == 0 ? 0
                                   : split_node,
                to = parts == 1 || part == 1 ? std::numeric_limits<int>::max() : split_node;
      for (Eigen::Index k = 0; k < count; ++k) {
        const Eigen::Index el = first + k;
        const Ke& m = ke[static_cast<std::size_t>(k)];
        const double mass_scale = density * volume[static_cast<std::size_t>(k)];
        int node[N];
        for (int i = 0; i < N; ++i) node[i] = mesh.elements(el, i);
        for (int p = 0; p < N; ++p) {
          const int col_node = node[p];
          if (col_node < from || col_node >= to) continue;
          const auto& list = adj[static_cast<std::size_t>(col_node)];
          for (int q = 0; q < N; ++q) {
            const int row_node = node[q];
            if (row_node < col_node) continue;  // the (q, p) pair fills the lower triangle
            const auto rank = std::lower_bound(list.begin(), list.end(), row_node) - list.begin();
            const double mass = mass_scale * mref(p, q);
            for (int a = 0; a < 3; ++a) {
              const int col = 3 * col_node + a;
              for (int c = row_node == col_node ? a : 0; c < 3; ++c) {
                const auto at = static_cast<std::size_t>(
                    fe.outer[col] + (row_node == col_node ? c - a : 3 - a + 3 * (rank - 1) + c));
                fe.stiffness_values[at] += m(3 * q + c, 3 * p + a);
                if (a == c) fe.mass_values[at] += mass;
              }
            }
          }
        }
      }
    });
  }
}

}  // namespace

FeMatrices assemble(const geometry::TetMesh& mesh, double e, double nu, double density) {
  const Mat6 d = elasticity(e, nu);
  const std::vector<std::vector<int>> adj = node_neighbours(mesh);
  FeMatrices fe;
  fe.dofs = 3 * mesh.nodes.rows();
  fe.outer.resize(static_cast<std::size_t>(fe.dofs) + 1);
  std::size_t count = 0;
  for (std::size_t v = 0; v < adj.size(); ++v) {
    const std::size_t below = 3 * (adj[v].size() - 1);  // rows in the nodes after v
    for (std::size_t a = 0; a < 3; ++a) {
      fe.outer[3 * v + a] = static_cast<int>(count);
      count += (3 - a) + below;
    }
  }
  if (count > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw SimulationError("the stiffness matrix would have " + std::to_string(count) +
                          " entries, more than this solver indexes; use a coarser mesh_size");
  fe.outer.back() = static_cast<int>(count);
  fe.inner.resize(count);
  for (std::size_t v = 0; v < adj.size(); ++v)
    for (int a = 0; a < 3; ++a) {
      auto at = static_cast<std::size_t>(fe.outer[3 * v + a]);
      for (int c = a; c < 3; ++c) fe.inner[at++] = static_cast<int>(3 * v) + c;
      for (std::size_t k = 1; k < adj[v].size(); ++k)
        for (int c = 0; c < 3; ++c) fe.inner[at++] = 3 * adj[v][k] + c;
    }
  fe.stiffness_values.assign(count, 0.0);
  fe.mass_values.assign(count, 0.0);
  if (mesh.elements.cols() == 10)
    assemble_elements<10>(mesh, d, density, adj, fe);
  else
    assemble_elements<4>(mesh, d, density, adj, fe);
  return fe;
}

Eigen::VectorXd symmetric_times(const LowerView& a, const Eigen::VectorXd& x) {
  VPROTO_DEMAND(x.size() == a.cols());
  Eigen::VectorXd y = Eigen::VectorXd::Zero(a.rows());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  for (Eigen::Index col = 0; col < a.cols(); ++col) {
    const double xc = x[col];
    double sum = 0;
    for (int k = outer[col]; k < outer[col + 1]; ++k) {
      const int row = inner[k];
      const double v = values[k];
      y[row] += v * xc;
      if (row != col) sum += v * x[row];
    }
    y[col] += sum;
  }
  return y;
}

double quadratic_form(const LowerView& a, const Eigen::VectorXd& x) {
  VPROTO_DEMAND(x.size() == a.cols());
  // (a body that deforms quasi-statically has no velocity: its kinetic energy costs nothing)
  if (x.isZero(0)) return 0;
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  // two halves of the entries, summed apart and then added (on two threads where one is
  // free; the same sums either way): x87's extended precision does not vectorize, and the
  // snap-fit's strain energy, every contact step, was 3 % of its run on the step's thread
  const Eigen::Index cols = a.cols();
  const Eigen::Index half = std::upper_bound(outer, outer + cols, outer[cols] / 2) - outer - 1;
  std::array<long double, 2> part{0, 0};
  in_two_threads(outer[cols] >= 200000, [&](int first, int stride) {
    for (int c = first; c < 2; c += stride) {
      long double sum = 0;
      for (Eigen::Index col = c == 0 ? 0 : half; col < (c == 0 ? half : cols); ++col) {
        long double column = 0;
        for (int k = outer[col]; k < outer[col + 1]; ++k) {
          const int row = inner[k];
          column += (row == col ? 1.0L : 2.0L) * values[k] * x[row];
        }
        sum += column * x[col];
      }
      part[static_cast<std::size_t>(c)] = sum;
    }
  });
  return static_cast<double>(part[0] + part[1]);
}

Eigen::SparseMatrix<double> full_matrix(const LowerView& lower) {
  Eigen::SparseMatrix<double> l = lower;
  Eigen::SparseMatrix<double> full = l.selfadjointView<Eigen::Lower>();
  return full;
}

std::vector<char> dof_mask(Eigen::Index dofs, const std::vector<int>& nodes) {
  std::vector<char> mask(static_cast<std::size_t>(dofs), 0);
  for (int v : nodes)
    for (int a = 0; a < 3; ++a) mask[static_cast<std::size_t>(3 * v + a)] = 1;
  return mask;
}

std::vector<double> hold_dofs(const FeMatrices& fe, const std::vector<double>& values,
                              const std::vector<char>& held, double diagonal) {
  std::vector<double> out = values;
  for (Eigen::Index col = 0; col < fe.dofs; ++col)
    for (int k = fe.outer[col]; k < fe.outer[col + 1]; ++k) {
      const int row = fe.inner[k];
      if (held[col] || held[row]) out[k] = row == col ? diagonal : 0.0;
    }
  return out;
}

Eigen::VectorXd body_force(const FeMatrices& fe, const Eigen::Vector3d& g) {
  Eigen::VectorXd field(fe.dofs);
  for (Eigen::Index i = 0; i < fe.dofs / 3; ++i) field.segment<3>(3 * i) = g;
  return symmetric_times(fe.mass(), field);
}

Eigen::VectorXd body_force(const geometry::TetMesh& mesh, double density,
                           const Eigen::Vector3d& g) {
  const Eigen::Index per = mesh.elements.cols();
  const Eigen::MatrixXd mref = reference_mass(per == 10);
  const Eigen::VectorXd weights = mref.rowwise().sum();  // each node's share of the mass
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * mesh.nodes.rows());
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    double volume = 0;
    barycentric_gradients(mesh, el, &volume);
    for (Eigen::Index k = 0; k < per; ++k)
      f.segment<3>(3 * mesh.elements(el, k)) += density * volume * weights[k] * g;
  }
  return f;
}

Eigen::MatrixXd element_stiffness(const geometry::TetMesh& mesh, Eigen::Index el,
                                  double youngs_modulus, double poisson_ratio) {
  const Mat6 d = elasticity(youngs_modulus, poisson_ratio);
  double volume = 0;
  const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, el, &volume);
  if (!(volume > 0))
    throw SimulationError("tet element " + std::to_string(el) + " is inverted or flat (volume " +
                          std::to_string(volume) + " m^3): the mesh is invalid");
  if (mesh.elements.cols() == 10) {
    Eigen::Matrix<double, 30, 30> ke;
    stiffness_of<10>(d, g, volume, &ke);
    return ke;
  }
  Eigen::Matrix<double, 12, 12> ke;
  stiffness_of<4>(d, g, volume, &ke);
  return ke;
}

namespace {

bool inside(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

}  // namespace

std::vector<BoundaryFace> boundary_faces(const geometry::TetMesh& m) {
  using Face = BoundaryFace;
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

std::vector<int> boundary_nodes_in(const geometry::TetMesh& m, const Eigen::Vector3d& lo,
                                   const Eigen::Vector3d& hi) {
  std::vector<char> mark(static_cast<std::size_t>(m.nodes.rows()), 0);
  for (const BoundaryFace& f : boundary_faces(m)) {
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
  for (const BoundaryFace& f : boundary_faces(m)) {
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

Eigen::VectorXd solve_static(const FeMatrices& fe, const Eigen::VectorXd& f,
                             const std::vector<int>& fixed_nodes, SolverStats* stats,
                             const SolverSetup* given) {
  VPROTO_DEMAND(f.size() == fe.dofs);
  const std::vector<char> held = dof_mask(fe.dofs, fixed_nodes);
  const std::vector<double> k = hold_dofs(fe, fe.stiffness_values, held, 1.0);
  SolverSetup setup = given ? *given : SolverSetup{};
  setup.use = SolveUse::kStatic;
  setup.dofs = fe.dofs;
  std::unique_ptr<LinearSolver> solver = make_linear_solver(setup);
  try {
    try {
      solver->factor(fe.view(k), "the stiffness matrix", 3);
    } catch (const FactorMemoryError& e) {
      // too large for a factor: `auto` turns to conjugate gradients, which need no factor
      if (setup.choice != SolverChoice::kAuto || !petsc_available() ||
          !iterative_solve_fits(fe.dofs))
        throw;
      setup.choice = SolverChoice::kPetsc;
      setup.reason = std::string("auto: ") + e.what() + ", so PETSc's CG, which needs none";
      solver = make_linear_solver(setup);
      solver->factor(fe.view(k), "the stiffness matrix", 3);
    }
  } catch (const FactorMemoryError&) {
    throw;  // too large, not singular
  } catch (const SimulationError& e) {
    // a backend that failed for its own reasons says so; a singular matrix is the body's
    if (std::string(e.what()).find("not positive definite") == std::string::npos) throw;
    throw SimulationError(
        "the stiffness matrix is singular: the body is not held against rigid "
        "motion; fix or grip a region of it");
  }
  Eigen::VectorXd u = f;
  for (Eigen::Index i = 0; i < fe.dofs; ++i)
    if (held[i]) u[i] = 0;
  solver->solve_in_place(u);
  if (!u.allFinite()) throw SimulationError("the static solve gave non-finite displacements");
  if (stats) *stats = solver->stats();
  return u;
}

std::vector<double> natural_frequencies(const FeMatrices& fe, const std::vector<int>& held_nodes,
                                        int count, Eigen::MatrixXd* modes) {
  VPROTO_DEMAND(count > 0);
  const std::vector<char> held = dof_mask(fe.dofs, held_nodes);
  const std::vector<double> kv = hold_dofs(fe, fe.stiffness_values, held, 1.0);
  const std::vector<double> mv = hold_dofs(fe, fe.mass_values, held, 0.0);
  const LowerView k = fe.view(kv), m = fe.view(mv);
  SparseCholesky llt;
  llt.factor(k, "the stiffness matrix (is the body held?)", 3);
  // subspace iteration with a few guard vectors; convergence rate (w_count / w_p)^2
  const int p = std::min<Eigen::Index>(std::max(2 * count, count + 8), fe.dofs);
  Eigen::MatrixXd x(fe.dofs, p);
  std::uint64_t seed = 0x9E3779B97F4A7C15ull;  // fixed: the same answer every run
  for (Eigen::Index j = 0; j < p; ++j)
    for (Eigen::Index i = 0; i < fe.dofs; ++i) {
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      x(i, j) = held[i] ? 0.0 : static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5;
    }
  Eigen::VectorXd previous = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd lambda;
  for (int sweep = 0; sweep < 200; ++sweep) {
    Eigen::MatrixXd mx(fe.dofs, p), kx(fe.dofs, p);
    for (Eigen::Index j = 0; j < p; ++j) mx.col(j) = symmetric_times(m, x.col(j));
    const Eigen::MatrixXd y = llt.solve(mx);
    for (Eigen::Index j = 0; j < p; ++j) {
      kx.col(j) = symmetric_times(k, y.col(j));
      mx.col(j) = symmetric_times(m, y.col(j));
    }
    Eigen::MatrixXd kr = y.transpose() * kx, mr = y.transpose() * mx;
    kr = 0.5 * (kr + kr.transpose()).eval();
    mr = 0.5 * (mr + mr.transpose()).eval();
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ritz(kr, mr);
    if (ritz.info() != Eigen::Success)
      throw SimulationError("the eigenvalue iteration broke down (is the mass matrix singular?)");
    lambda = ritz.eigenvalues();
    x = y * ritz.eigenvectors();  // M-orthonormal Ritz vectors
    const double change =
        ((lambda - previous).head(count).array() / lambda.head(count).array()).abs().maxCoeff();
    previous = lambda;
    // the Rayleigh quotients carry rounding of about eps * w_max^2 / w^2 (1e-10 on a
    // slender beam), so a change below 1e-9 is convergence
    if (sweep > 1 && change < 1e-9) break;
  }
  std::vector<double> hz;
  for (int j = 0; j < count; ++j) hz.push_back(std::sqrt(std::max(lambda[j], 0.0)) / (2 * M_PI));
  if (modes) *modes = x.leftCols(count);
  return hz;
}

Eigen::VectorXd yield_ratios(const materials::Material& m, const Eigen::VectorXd& von_mises,
                             const Eigen::VectorXd& principal_strain) {
  Eigen::VectorXd r(von_mises.size());
  for (Eigen::Index i = 0; i < r.size(); ++i)
    r[i] = materials::yield_ratio(m, von_mises[i], principal_strain[i]);
  return r;
}

Eigen::VectorXd nodal_average(const geometry::TetMesh& mesh, const Eigen::VectorXd& per_element) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(mesh.nodes.rows());
  Eigen::VectorXd count = Eigen::VectorXd::Zero(mesh.nodes.rows());
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el)
    for (Eigen::Index k = 0; k < mesh.elements.cols(); ++k) {
      sum[mesh.elements(el, k)] += per_element[el];
      count[mesh.elements(el, k)] += 1;
    }
  return sum.cwiseQuotient(count.cwiseMax(1.0));
}

namespace {

double von_mises_of(const Eigen::Matrix<double, 6, 1>& s) {
  return std::sqrt(0.5 * ((s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) +
                          (s[2] - s[0]) * (s[2] - s[0])) +
                   3 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

// the largest eigenvalue of the strain tensor of engineering strains v (Voigt)
double largest_principal(const Eigen::Matrix<double, 6, 1>& v) {
  Eigen::Matrix3d eps;
  eps << v[0], v[5] / 2, v[4] / 2, v[5] / 2, v[1], v[3] / 2, v[4] / 2, v[3] / 2, v[2];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(eps, Eigen::EigenvaluesOnly);
  return solver.eigenvalues().maxCoeff();
}

}  // namespace

double von_mises_of_stress(const Eigen::Matrix<double, 6, 1>& stress) {
  return von_mises_of(stress);
}

double largest_principal_strain(const Eigen::Matrix<double, 6, 1>& strain) {
  return largest_principal(strain);
}

Eigen::Matrix<double, 6, 1> stress_of(const Eigen::Matrix<double, 6, 1>& strain, double e,
                                      double nu) {
  return elasticity(e, nu) * strain;
}

Eigen::Matrix<double, 6, 1> element_strain_at(const geometry::TetMesh& mesh,
                                              const Eigen::VectorXd& u, Eigen::Index el,
                                              const Eigen::Vector4d& l) {
  if (mesh.elements.cols() != 10) return centroid_strain(mesh, u, el);  // constant
  double volume = 0;
  const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, el, &volume);
  Eigen::Matrix<double, 30, 1> ue;
  for (int k = 0; k < 10; ++k) ue.segment<3>(3 * k) = u.segment<3>(3 * mesh.elements(el, k));
  return strain_matrix(shape_gradients(g, l)) * ue;
}

Eigen::VectorXd element_von_mises(const geometry::TetMesh& mesh, const Eigen::VectorXd& u, double e,
                                  double nu) {
  const Mat6 d = elasticity(e, nu);
  Eigen::VectorXd out(mesh.elements.rows());
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el)
    out[el] = von_mises_of(d * centroid_strain(mesh, u, el));
  return out;
}

ElementStressStrain element_stress_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                          double e, double nu) {
  const Mat6 d = elasticity(e, nu);
  ElementStressStrain out;
  out.von_mises.resize(mesh.elements.rows());
  out.principal_strain.resize(mesh.elements.rows());
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    const Eigen::Matrix<double, 6, 1> v = centroid_strain(mesh, u, el);
    out.von_mises[el] = von_mises_of(d * v);
    out.principal_strain[el] = largest_principal(v);
  }
  return out;
}

ElementStressStrain nodal_stress_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u,
                                        double e, double nu) {
  const Eigen::Index n = mesh.nodes.rows();
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(6, n);  // strains summed per node
  Eigen::VectorXd count = Eigen::VectorXd::Zero(n);
  const bool quadratic = mesh.elements.cols() == 10;
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    if (!quadratic) {
      const Eigen::Matrix<double, 6, 1> v = centroid_strain(mesh, u, el);  // constant
      for (int k = 0; k < 4; ++k) {
        sum.col(mesh.elements(el, k)) += v;
        count[mesh.elements(el, k)] += 1;
      }
      continue;
    }
    double volume = 0;
    const Eigen::Matrix<double, 4, 3> g = barycentric_gradients(mesh, el, &volume);
    Eigen::Matrix<double, 30, 1> ue;
    for (int k = 0; k < 10; ++k) ue.segment<3>(3 * k) = u.segment<3>(3 * mesh.elements(el, k));
    for (int k = 0; k < 10; ++k) {
      // the node's barycentric coordinates: a corner's, or the middle of an edge
      Eigen::Vector4d l = Eigen::Vector4d::Zero();
      if (k < 4) {
        l[k] = 1;
      } else {
        l[kEdges[k - 4][0]] = 0.5;
        l[kEdges[k - 4][1]] = 0.5;
      }
      sum.col(mesh.elements(el, k)) += strain_matrix(shape_gradients(g, l)) * ue;
      count[mesh.elements(el, k)] += 1;
    }
  }
  const Mat6 d = elasticity(e, nu);
  ElementStressStrain out;
  out.von_mises.resize(n);
  out.principal_strain.resize(n);
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Matrix<double, 6, 1> strain = sum.col(v) / std::max(count[v], 1.0);
    out.von_mises[v] = von_mises_of(d * strain);
    out.principal_strain[v] = largest_principal(strain);
  }
  return out;
}

std::vector<char> elements_at_sharp_corners(const geometry::TetMesh& mesh,
                                            const geometry::TriMesh& surface, double reach) {
  const std::vector<geometry::Edge> corners = geometry::reentrant_edges(surface, 30);
  std::vector<char> at(static_cast<std::size_t>(mesh.elements.rows()), 0);
  if (corners.empty()) return at;
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    double size = 0;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d p = mesh.nodes.row(mesh.elements(el, i)).transpose();
      c += 0.25 * p;
      for (int j = i + 1; j < 4; ++j)
        size = std::max(size, (p - mesh.nodes.row(mesh.elements(el, j)).transpose()).norm());
    }
    at[static_cast<std::size_t>(el)] =
        geometry::distance_to_edges(corners, c) <= std::max(2 * size, reach);
  }
  return at;
}

std::vector<char> concentration_nodes(const geometry::TetMesh& mesh,
                                      const std::vector<Eigen::Vector3d>& pressed, double reach,
                                      const std::vector<char>& at_corner) {
  std::vector<char> out(static_cast<std::size_t>(mesh.nodes.rows()), 0);
  // the pressed points in cells of the reach's size: an element's centroid need only be
  // compared with those of the 27 cells around its own
  const bool near_contacts = !pressed.empty() && reach > 0;
  using Cell = std::array<std::int64_t, 3>;
  auto cell_of = [&](const Eigen::Vector3d& x) {
    return Cell{static_cast<std::int64_t>(std::floor(x.x() / reach)),
                static_cast<std::int64_t>(std::floor(x.y() / reach)),
                static_cast<std::int64_t>(std::floor(x.z() / reach))};
  };
  std::map<Cell, std::vector<Eigen::Vector3d>> cells;
  if (near_contacts)
    for (const Eigen::Vector3d& x : pressed) cells[cell_of(x)].push_back(x);
  auto near_a_contact = [&](const Eigen::Vector3d& c) {
    const Cell at = cell_of(c);
    for (std::int64_t i = -1; i <= 1; ++i)
      for (std::int64_t j = -1; j <= 1; ++j)
        for (std::int64_t k = -1; k <= 1; ++k) {
          const auto found = cells.find(Cell{at[0] + i, at[1] + j, at[2] + k});
          if (found == cells.end()) continue;
          for (const Eigen::Vector3d& x : found->second)
            if ((x - c).squaredNorm() < reach * reach) return true;
        }
    return false;
  };
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
    bool concentrated = !at_corner.empty() && at_corner[static_cast<std::size_t>(el)];
    if (!concentrated && near_contacts) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (Eigen::Index k = 0; k < 4; ++k)
        c += 0.25 * mesh.nodes.row(mesh.elements(el, k)).transpose();
      concentrated = near_a_contact(c);
    }
    if (concentrated)
      for (Eigen::Index k = 0; k < mesh.elements.cols(); ++k)
        out[static_cast<std::size_t>(mesh.elements(el, k))] = 1;
  }
  return out;
}

std::vector<char> flagged_points(const Eigen::SparseMatrix<double>& interpolation,
                                 const std::vector<char>& node_flags) {
  std::vector<char> out(static_cast<std::size_t>(interpolation.rows()), 0);
  for (Eigen::Index outer = 0; outer < interpolation.outerSize(); ++outer)
    for (Eigen::SparseMatrix<double>::InnerIterator it(interpolation, outer); it; ++it)
      if (std::abs(it.value()) >= 1e-3 && node_flags[static_cast<std::size_t>(it.col())])
        out[static_cast<std::size_t>(it.row())] = 1;
  return out;
}

std::pair<double, double> track_material_peaks(const geometry::TetMesh& mesh,
                                               const ElementStressStrain& fields,
                                               const std::vector<Eigen::Vector3d>& pressed,
                                               double reach, const std::vector<char>& at_corner,
                                               std::optional<double> yield_strength,
                                               std::optional<double> yield_strain, double t,
                                               MaterialPeaks* peaks) {
  auto centroid = [&](Eigen::Index el) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (Eigen::Index k = 0; k < 4; ++k)
      c += 0.25 * mesh.nodes.row(mesh.elements(el, k)).transpose();
    return c;
  };
  // (asked only of elements above the running largest away from contacts: a few a state)
  auto touched = [&](Eigen::Index el) {
    const Eigen::Vector3d c = centroid(el);
    return std::any_of(pressed.begin(), pressed.end(), [&](const Eigen::Vector3d& x) {
      return (x - c).squaredNorm() < reach * reach;
    });
  };
  auto corner = [&](Eigen::Index el) {
    return !at_corner.empty() && at_corner[static_cast<std::size_t>(el)];
  };
  auto raise = [&](FieldPeak* peak, double value, Eigen::Index el) {
    if (el < 0 || !(value > peak->value)) return;
    peak->value = value;
    peak->time = t;
    peak->at = centroid(el);
    peak->element = el;
    peak->at_sharp_corner = corner(el);
  };
  // a field's largest value, anywhere, away from contacts, and away from them and corners
  struct Top {
    double all = 0, bulk = 0, regular = 0;
  };
  auto track = [&](const Eigen::VectorXd& field, FieldPeak* all, FieldPeak* bulk,
                   FieldPeak* regular) {
    Top top;
    Eigen::Index at = -1, bulk_at = -1, regular_at = -1;
    for (Eigen::Index el = 0; el < field.size(); ++el) {
      if (field[el] > top.all || at < 0) top.all = field[el], at = el;
      const bool above_bulk = field[el] > top.bulk || bulk_at < 0;
      const bool above_regular = (field[el] > top.regular || regular_at < 0) && !corner(el);
      if (!(above_bulk || above_regular) || touched(el)) continue;
      if (above_bulk) top.bulk = field[el], bulk_at = el;
      if (above_regular) top.regular = field[el], regular_at = el;
    }
    raise(all, top.all, at);
    raise(bulk, top.bulk, bulk_at);
    raise(regular, top.regular, regular_at);
    return top;
  };
  const Top stress =
      track(fields.von_mises, &peaks->von_mises, &peaks->bulk_von_mises, &peaks->regular_von_mises);
  const Top strain =
      track(fields.principal_strain, &peaks->strain, &peaks->bulk_strain, &peaks->regular_strain);
  auto past = [&](double s, double eps) {
    return (yield_strength && s > *yield_strength) || (yield_strain && eps > *yield_strain);
  };
  if (peaks->yielded_at < 0 && past(stress.all, strain.all)) peaks->yielded_at = t;
  if (peaks->bulk_yielded_at < 0 && past(stress.bulk, strain.bulk)) peaks->bulk_yielded_at = t;
  if (peaks->regular_yielded_at < 0 && past(stress.regular, strain.regular))
    peaks->regular_yielded_at = t;
  return {stress.all, strain.all};
}

double max_principal_strain(const geometry::TetMesh& mesh, const Eigen::VectorXd& u) {
  double worst = 0;
  for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el)
    worst = std::max(worst, largest_principal(centroid_strain(mesh, u, el)));
  return worst;
}

}  // namespace vproto::sim
