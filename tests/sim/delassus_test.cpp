// The Delassus matrix of rows from their sides (sim/src/delassus.h) against the matrix
// written out whole: W = G A G', G the rows' Jacobian on every body's motions (each side's
// block, signed) and A the bodies' responses side by side (mobilities with their
// mechanisms' couplings, compliances).
#include "delassus.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace vproto::sim {
namespace {

Eigen::MatrixXd random_spd(int n, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a(i, j) = normal(rng);
  return a * a.transpose() + n * Eigen::MatrixXd::Identity(n, n);
}

// W formed column by column (LazyDelassus) holds the same values, bit for bit, as W formed
// whole: its diagonal blocks at once, each column when asked for.
void expect_lazy_matches(const std::vector<RowSides>& rows, const FrameMobility& mobility,
                         const Eigen::MatrixXd& w) {
  double asked = 0;
  LazyDelassus lazy(rows, mobility, {}, 1e-3, [&](double bytes) { asked = bytes; });
  const auto m = static_cast<Eigen::Index>(rows.size());
  ASSERT_EQ(lazy.points(), m);
  for (Eigen::Index i = 0; i < m; ++i)
    EXPECT_EQ(lazy.diagonal(i), w.block(3 * i, 3 * i, 3, 3).eval()) << i;
  lazy.prepare({m - 1, 0});
  EXPECT_EQ(lazy.formed(), 2);
  EXPECT_EQ(asked, 72.0 * static_cast<double>(m) * 2);
  std::vector<Eigen::Index> all(static_cast<std::size_t>(m));
  for (Eigen::Index j = 0; j < m; ++j) all[static_cast<std::size_t>(j)] = j;
  lazy.prepare(all);
  EXPECT_EQ(lazy.formed(), m);
  for (Eigen::Index j = 0; j < m; ++j)
    EXPECT_EQ(Eigen::Map<const Eigen::MatrixXd>(lazy.column(j), 3 * m, 3),
              w.middleCols(3 * j, 3).eval())
        << j;
}

Eigen::Matrix3d random_basis(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Matrix3d a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a(i, j) = normal(rng);
  return Eigen::HouseholderQR<Eigen::Matrix3d>(a).householderQ();
}

// Rows on three rigid bodies, the second and third jointed together (their mobility has a
// coupling block): row 0 between bodies 0 (+) and 1 (-), row 1 on body 0 alone, row 2
// between bodies 1 (+) and 2 (-), row 3 between 2 (+) and 0 (-).
TEST(Delassus, RowsOnRigidBodiesGiveGPGt) {
  std::mt19937 rng(7);
  const Eigen::MatrixXd p = random_spd(18, rng);  // the three bodies' mobility, whole
  Eigen::MatrixXd mobility = p;
  mobility.block<6, 6>(0, 6).setZero();  // body 0 is not jointed to the others
  mobility.block<6, 6>(6, 0).setZero();
  mobility.block<6, 6>(0, 12).setZero();
  mobility.block<6, 6>(12, 0).setZero();
  std::normal_distribution<double> normal;
  auto random_jac = [&] {
    Eigen::Matrix<double, 3, 6> j;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 6; ++b) j(a, b) = normal(rng);
    return j;
  };
  const std::vector<std::vector<std::pair<int, double>>> touches = {
      {{0, 1}, {1, -1}}, {{0, 1}}, {{1, 1}, {2, -1}}, {{2, 1}, {0, -1}}};
  std::vector<RowSides> rows(touches.size());
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(rows.size()), 18);
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (const auto& [body, sign] : touches[r]) {
      FrameSide side;
      side.id = body;
      side.sign = sign;
      side.jac = random_jac();
      rows[r].add(side);
      g.block<3, 6>(3 * static_cast<Eigen::Index>(r), 6 * body) += sign * side.jac;
    }
  const FrameMobility of = [&](int q, int r) -> std::optional<Eigen::Matrix<double, 6, 6>> {
    const Eigen::Matrix<double, 6, 6> block = mobility.block<6, 6>(6 * q, 6 * r);
    if (block.isZero(0)) return std::nullopt;
    return block;
  };
  Eigen::MatrixXd w;
  assemble_delassus(rows, of, {}, 1e-3, &w);
  expect_lazy_matches(rows, of, w);
  const Eigen::MatrixXd expected = g * mobility * g.transpose();
  EXPECT_LT((w - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  // (the coupling of bodies 1 and 2 is in it: without it rows 2 and 3 would not couple
  // through body 2 alone as they do)
  Eigen::MatrixXd uncoupled = mobility;
  uncoupled.block<6, 6>(6, 12).setZero();
  uncoupled.block<6, 6>(12, 6).setZero();
  EXPECT_GT((w - g * uncoupled * g.transpose()).cwiseAbs().maxCoeff(),
            1e-3 * expected.cwiseAbs().maxCoeff());
}

// Rows on the surface nodes of two elastic bodies: row 0 a point of body A (three nodes)
// against a point of body B (two nodes), row 1 a node of A against a rigid body, row 2 a
// point of B against one of A. Each body's compliance (its surface nodes' 3 x 3 blocks:
// the kept factor's columns, stored by rows) couples its own sides only. Each node's columns
// hold the blocks of the nodes solved before it and its own only, as the contact stage keeps
// them: a block they lack comes from the later node's columns, transposed.
TEST(Delassus, NodeSidesReadEachBodysComplianceColumns) {
  std::mt19937 rng(11);
  constexpr int kNodes = 4;
  std::array<Dynamics::ElasticBody, 2> bodies;
  std::array<Eigen::MatrixXd, 2> compliance;
  for (std::size_t b = 0; b < 2; ++b) {
    compliance[b] = random_spd(3 * kNodes, rng);
    Dynamics::ElasticBody& eb = bodies[b];
    eb.column_row.resize(kNodes);
    // (solved in the order 2, 0, 3, 1)
    const std::array<int, kNodes> order{2, 0, 3, 1};
    for (int row = 0; row < kNodes; ++row) {
      const int k = order[static_cast<std::size_t>(row)];
      eb.column_row[static_cast<std::size_t>(k)] = row;
      eb.column_nodes.push_back(k);
      Dynamics::ElasticBody::NodeColumns& column = eb.columns[k];
      column.resize(3 * (row + 1), 3);
      for (int held = 0; held <= row; ++held)
        column.block<3, 3>(3 * held, 0) =
            compliance[b].block<3, 3>(3 * order[static_cast<std::size_t>(held)], 3 * k);
    }
  }
  struct Point {
    int body;
    double sign;
    std::array<int, 3> nodes;
    std::array<double, 3> weights;
  };
  const std::vector<std::vector<Point>> points = {
      {{0, 1, {0, 1, 2}, {0.2, 0.3, 0.5}}, {1, -1, {3, -1, 1}, {0.6, 0, 0.4}}},
      {{0, 1, {2, -1, -1}, {1, 0, 0}}},
      {{1, 1, {0, 2, 3}, {0.1, 0.7, 0.2}}, {0, -1, {3, 1, -1}, {0.5, 0.5, 0}}}};
  std::vector<RowSides> rows(points.size());
  const auto m = static_cast<Eigen::Index>(rows.size());
  // the rows' operator on both bodies' nodal forces (body axes), and the compliances whole
  Eigen::MatrixXd n = Eigen::MatrixXd::Zero(3 * m, 6 * kNodes);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(6 * kNodes, 6 * kNodes);
  c.topLeftCorner(3 * kNodes, 3 * kNodes) = compliance[0];
  c.bottomRightCorner(3 * kNodes, 3 * kNodes) = compliance[1];
  for (std::size_t r = 0; r < points.size(); ++r)
    for (const Point& pt : points[r]) {
      NodeSide side;
      side.body = &bodies[static_cast<std::size_t>(pt.body)];
      side.id = pt.body;
      side.sign = pt.sign;
      side.nodes = pt.nodes;
      side.weights = pt.weights;
      side.basis = random_basis(rng);
      for (std::size_t k = 0; k < 3; ++k) {
        if (pt.nodes[k] < 0) continue;
        side.columns[k] = &side.body->columns.at(pt.nodes[k]);
        n.block<3, 3>(3 * static_cast<Eigen::Index>(r), 3 * kNodes * pt.body + 3 * pt.nodes[k]) +=
            pt.sign * pt.weights[k] * side.basis.transpose();
      }
      rows[r].add(side);
    }
  Eigen::MatrixXd w;
  const FrameMobility none = [](int, int) -> std::optional<Eigen::Matrix<double, 6, 6>> {
    return std::nullopt;
  };
  assemble_delassus(rows, none, {}, 1e-3, &w);
  expect_lazy_matches(rows, none, w);
  const Eigen::MatrixXd expected = n * c * n.transpose();
  EXPECT_LT((w - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  EXPECT_LT((w - w.transpose()).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace vproto::sim
