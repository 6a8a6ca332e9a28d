#include "vproto/sim/elastic_dynamics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "vproto/geometry/primitives.h"
#include "vproto/materials/errors.h"

namespace vproto::sim {
namespace {

// references.md: steel cantilever 1 m x 0.05 x 0.05, clamped at x = 0
constexpr double kE = 210e9, kNu = 0.3, kRho = 7850, kL = 1.0, kB = 0.05;

struct Beam {
  geometry::TetMesh mesh;
  FeMatrices fe;
  std::vector<int> clamp;
};

Beam beam(double size, bool quadratic = true) {
  geometry::TetMeshOptions o;
  o.size = size;
  o.quadratic = quadratic;
  Beam b;
  b.mesh = geometry::make_tet_mesh(geometry::make_box({kL, kB, kB}, false), o);
  b.fe = assemble(b.mesh, kE, kNu, kRho);
  b.clamp = boundary_nodes_in(b.mesh, {-1e-9, -1, -1}, {1e-9, 1, 1});
  return b;
}

// Euler-Bernoulli first bending frequency, clamped-free (references.md)
double euler_bernoulli_f1() {
  const double i = kB * kB * kB * kB / 12, a = kB * kB;
  return 1.8751 * 1.8751 / (2 * M_PI) * std::sqrt(kE * i / (kRho * a * std::pow(kL, 4)));
}

TEST(ConsistentMass, Tet10ElementMatrixIsTheKnownOne) {
  // one straight tet10: M = rho V / 420 * [6 corner diagonal, 1 corner-corner, -4 corner-mid
  // on an edge through the corner, -6 corner-mid off it, 32 mid diagonal, 16 mid-mid
  // sharing a corner, 8 mid-mid opposite]
  geometry::TetMesh m;
  m.nodes.resize(10, 3);
  m.nodes.topRows<4>() << 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 1.5;
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  m.elements.resize(1, 10);
  for (int k = 0; k < 10; ++k) m.elements(0, k) = k;
  for (int k = 0; k < 6; ++k)
    m.nodes.row(4 + k) = 0.5 * (m.nodes.row(edges[k][0]) + m.nodes.row(edges[k][1]));
  const double rho = 1000, volume = 2 * 3 * 1.5 / 6;
  const Eigen::SparseMatrix<double> mass = full_matrix(assemble(m, 1e9, 0.3, rho).mass());
  auto on_edge = [&](int corner, int mid) {
    return edges[mid][0] == corner || edges[mid][1] == corner;
  };
  auto share = [&](int p, int q) {
    return edges[p][0] == edges[q][0] || edges[p][0] == edges[q][1] || edges[p][1] == edges[q][0] ||
           edges[p][1] == edges[q][1];
  };
  for (int p = 0; p < 10; ++p)
    for (int q = 0; q < 10; ++q) {
      double expected;
      if (p < 4 && q < 4)
        expected = p == q ? 6 : 1;
      else if (p >= 4 && q >= 4)
        expected = p == q ? 32 : share(p - 4, q - 4) ? 16 : 8;
      else
        expected = p < 4 ? (on_edge(p, q - 4) ? -4 : -6) : (on_edge(q, p - 4) ? -4 : -6);
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(mass.coeff(3 * p + a, 3 * q + a), rho * volume * expected / 420, 1e-9)
            << p << " " << q;
        EXPECT_EQ(mass.coeff(3 * p + a, 3 * q + (a + 1) % 3), 0.0);
      }
    }
}

TEST(ConsistentMass, TotalMassAndBodyForceOfAMesh) {
  for (bool quadratic : {false, true}) {
    const Beam b = beam(0.025, quadratic);
    const Eigen::VectorXd f = body_force(b.fe, {0, 0, -9.81});
    const double mass = kRho * kL * kB * kB;
    EXPECT_NEAR(f.sum(), -9.81 * mass, 1e-9 * 9.81 * mass);
    // a rigid translation has no strain energy and kinetic energy m v^2 / 2
    Eigen::VectorXd v(b.fe.dofs);
    for (Eigen::Index i = 0; i < v.size(); i += 3) v.segment<3>(i) << 1, 2, 3;
    EXPECT_NEAR(0.5 * v.dot(symmetric_times(b.fe.mass(), v)), 0.5 * mass * 14, 1e-9 * mass);
    EXPECT_NEAR(symmetric_times(b.fe.stiffness(), v).norm(), 0, 1e-6 * kE * kB);
  }
}

TEST(NaturalFrequencies, CantileverFirstBendingFrequency) {
  const Beam b = beam(0.0125);
  const std::vector<double> f = natural_frequencies(b.fe, b.clamp, 2);
  // the square section bends alike about y and z: a repeated pair
  const double f1 = euler_bernoulli_f1();
  EXPECT_NEAR(f[0], f1, 0.005 * f1) << f[0] << " vs " << f1;
  EXPECT_NEAR(f[1], f[0], 1e-3 * f[0]);
}

TEST(NaturalFrequencies, AFreeBodyIsRefused) {
  const Beam b = beam(0.05);
  EXPECT_THROW(natural_frequencies(b.fe, {}, 1), SimulationError);
}

// modal coordinate of u on a mass-normalized mode
double modal(const FeMatrices& fe, const Eigen::VectorXd& mode, const Eigen::VectorXd& u) {
  return mode.dot(symmetric_times(fe.mass(), u));
}

TEST(Newmark, PeriodErrorIsAboutOmegaHSquaredOverTwelve) {
  const Beam b = beam(0.05);
  Eigen::MatrixXd modes;
  const double f1 = natural_frequencies(b.fe, b.clamp, 1, &modes)[0];
  const double omega = 2 * M_PI * f1;
  for (double wh : {0.1, 0.3}) {
    const double h = wh / omega;
    ElasticDynamics dyn(b.fe, b.clamp, h);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
    dyn.start(0, modes.col(0), zero, zero);
    // downward zero crossings of the modal coordinate, linearly interpolated
    std::vector<double> crossings;
    double previous = modal(b.fe, modes.col(0), dyn.displacement());
    while (crossings.size() < 6) {
      dyn.step(zero);
      const double q = modal(b.fe, modes.col(0), dyn.displacement());
      if (previous > 0 && q <= 0) crossings.push_back(dyn.time() - h * q / (q - previous));
      previous = q;
    }
    const double period = (crossings.back() - crossings.front()) / 5;
    const double error = period * f1 - 1;
    // exact for this scheme: T_h / T = (wh / 2) / atan(wh / 2) = 1 + (wh)^2 / 12 + O(wh^4)
    EXPECT_NEAR(error, wh * wh / 12, 0.02 * wh * wh / 12) << "wh " << wh;
    EXPECT_EQ(dyn.factor_stats().factorizations, 1);
  }
}

TEST(Newmark, UndampedFreeVibrationConservesEnergyOverTenThousandSteps) {
  // Energy does not drift (the step is exactly Newmark's for the factored matrix); what
  // remains is a bounded rounding fluctuation of about eps * w_max^2 / w_1^2: 2e-11 for
  // this beam in tet4, 2e-10 in tet10 (whose highest frequency is far higher)
  const Beam b = beam(0.05, false);
  // released from the static deflection under 1 kN at the tip
  const Eigen::VectorXd load =
      region_force(b.mesh, {kL - 1e-9, -1, -1}, {kL + 1e-9, 1, 1}, {0, 0, -1000});
  const Eigen::VectorXd u0 = solve_static(b.fe, load, b.clamp);
  const double f1 = natural_frequencies(b.fe, b.clamp, 1)[0];
  ElasticDynamics dyn(b.fe, b.clamp, 1 / (40 * f1));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  dyn.start(0, u0, zero, zero);
  const double e0 = dyn.kinetic_energy() + dyn.strain_energy();
  double worst = 0, peak_kinetic = 0;
  for (int k = 0; k < 10000; ++k) {
    dyn.step(zero);
    const double e = dyn.kinetic_energy() + dyn.strain_energy();
    worst = std::max(worst, std::abs(e - e0) / e0);
    peak_kinetic = std::max(peak_kinetic, dyn.kinetic_energy());
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_GT(peak_kinetic, 0.5 * e0);  // it did vibrate
  EXPECT_EQ(dyn.factor_stats().factorizations, 1);
}

TEST(Newmark, ConstraintResponseFromTheKeptFactorEqualsHoldingTheNode) {
  // a node pinned by a constraint force (a Lagrange multiplier on three rows, solved
  // through Y = K^^-1 C^T) moves exactly as the same node held by the factor
  const Beam b = beam(0.05);
  const auto tip = boundary_nodes_in(b.mesh, {kL - 1e-9, -1, -1}, {kL + 1e-9, 1, 1});
  const int pin = tip[tip.size() / 2];
  const double h = 1e-4;
  std::vector<int> held = b.clamp;
  held.push_back(pin);
  ElasticDynamics with_rows(b.fe, b.clamp, h), with_factor(b.fe, held, h);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  const Eigen::VectorXd gravity = body_force(b.fe, {0, 0, -9.81});
  // gravity switched on after t = 0: both start at rest with no acceleration (a node
  // pinned only from the first step on would start with g and ring at the Nyquist rate)
  with_rows.start(0, zero, zero, zero);
  with_factor.start(0, zero, zero, zero);
  Eigen::SparseMatrix<double> ct(b.fe.dofs, 3);
  for (int a = 0; a < 3; ++a) ct.insert(3 * pin + a, a) = 1;
  const Eigen::MatrixXd y = with_rows.response(ct);
  const Eigen::MatrixXd w = ct.transpose() * y;  // the 3 x 3 Delassus matrix
  for (int k = 0; k < 200; ++k) {
    const Eigen::VectorXd free = with_rows.predict(gravity);
    // gap C (u + du) = 0
    const Eigen::Vector3d lambda =
        w.ldlt().solve(-(ct.transpose() * (with_rows.displacement() + free)));
    const Eigen::VectorXd force = ct * lambda;
    with_rows.accept(free + y * lambda, &force);
    with_factor.step(gravity);
  }
  const double scale = with_factor.displacement().cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 0);
  EXPECT_LT((with_rows.displacement() - with_factor.displacement()).cwiseAbs().maxCoeff(),
            1e-9 * scale);
  // the constraint force is the reaction the factor-held node feels
  const Eigen::Vector3d reaction = with_factor.reactions().segment<3>(3 * pin);
  const Eigen::VectorXd last = with_rows.predict(gravity);
  const Eigen::Vector3d lambda =
      w.ldlt().solve(-(ct.transpose() * (with_rows.displacement() + last)));
  with_factor.step(gravity);
  EXPECT_LT((lambda - with_factor.reactions().segment<3>(3 * pin)).norm(),
            1e-7 * with_factor.reactions().segment<3>(3 * pin).norm());
  EXPECT_GT(reaction.norm(), 0);
  EXPECT_EQ(with_rows.factor_stats().factorizations, 1);
}

TEST(Newmark, GripMovedByItsFrameBalancesMomentumAndEnergy) {
  // the clamped end is gripped by a frame that accelerates sideways: the reactions R_b
  // (Eq. 25) are what change the body's momentum, and the energy they put in is what the
  // body holds
  const Beam b = beam(0.05);
  const double h = 2e-4, accel = 50;  // m/s^2 along y
  ElasticDynamics dyn(b.fe, b.clamp, h);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  auto motion = [&](double t) {
    HeldMotion m{zero, zero, zero};
    for (int v : b.clamp) {
      m.u[3 * v + 1] = 0.5 * accel * t * t;
      m.v[3 * v + 1] = accel * t;
      m.a[3 * v + 1] = accel;
    }
    return m;
  };
  HeldMotion m0 = motion(0);
  dyn.start(0, zero, zero, zero, &m0);
  Eigen::VectorXd ones_y = Eigen::VectorXd::Zero(b.fe.dofs);
  for (Eigen::Index i = 1; i < b.fe.dofs; i += 3) ones_y[i] = 1;
  const Eigen::VectorXd m_ones = symmetric_times(b.fe.mass(), ones_y);
  double impulse = 0, reaction_before = dyn.reactions().dot(ones_y);
  for (int k = 0; k < 500; ++k) {
    const HeldMotion next = motion(dyn.time() + h);
    dyn.step(zero, &next);
    const double reaction = dyn.reactions().dot(ones_y);
    impulse += 0.5 * h * (reaction_before + reaction);
    reaction_before = reaction;
  }
  const double momentum = m_ones.dot(dyn.velocity());
  const double mass = kRho * kL * kB * kB;
  // exact up to rounding, which the total-displacement step amplifies by 4 / dt^2 relative
  // to the (large, rigid) displacement
  EXPECT_NEAR(momentum, impulse, 1e-7 * momentum);
  EXPECT_NEAR(momentum, mass * accel * dyn.time(), 0.05 * momentum);  // the body follows
  const double energy = dyn.kinetic_energy() + dyn.strain_energy();
  EXPECT_NEAR(energy, dyn.external_work(), 1e-7 * energy);
}

TEST(Newmark, DampedRunSettlesOnTheStaticSolutionAndItsReactions) {
  const Beam b = beam(0.05);
  const Eigen::VectorXd load =
      region_force(b.mesh, {kL - 1e-9, -1, -1}, {kL + 1e-9, 1, 1}, {0, 0, -100});
  const Eigen::VectorXd u_static = solve_static(b.fe, load, b.clamp);
  NewmarkOptions o;
  // zeta = alpha / (2 w) + beta w / 2: half critical on the first mode (263 rad/s) and
  // above 1/2 from 10^4 rad/s up, so every mode the sudden load excites dies out
  o.rayleigh_mass = 263;
  o.rayleigh_stiffness = 1e-4;
  ElasticDynamics dyn(b.fe, b.clamp, 5e-4, o);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  dyn.start(0, zero, zero, load);
  for (int k = 0; k < 2000; ++k) dyn.step(load);
  EXPECT_LT((dyn.displacement() - u_static).norm(), 1e-6 * u_static.norm());
  EXPECT_LT(dyn.kinetic_energy(), 1e-8 * dyn.strain_energy());
  // the clamp holds the whole load
  const Eigen::VectorXd r = dyn.reactions();
  for (int a = 0; a < 3; ++a) {
    double sum = 0;
    for (Eigen::Index i = a; i < r.size(); i += 3) sum += r[i];
    EXPECT_NEAR(sum, a == 2 ? 100.0 : 0.0, 1e-4);
  }
  // work in = strain energy held + energy damped
  EXPECT_NEAR(dyn.external_work(), dyn.strain_energy() + dyn.kinetic_energy() + dyn.damped_energy(),
              1e-9 * dyn.external_work());
}

TEST(Newmark, NumericalDampingRemovesEnergy) {
  const Beam b = beam(0.05);
  const Eigen::VectorXd load =
      region_force(b.mesh, {kL - 1e-9, -1, -1}, {kL + 1e-9, 1, 1}, {0, 0, -1000});
  const Eigen::VectorXd u0 = solve_static(b.fe, load, b.clamp);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  ElasticDynamics dyn(b.fe, b.clamp, 1e-3, NewmarkOptions::with_numerical_damping(0.1));
  dyn.start(0, u0, zero, zero);
  const double e0 = dyn.strain_energy();
  for (int k = 0; k < 500; ++k) dyn.step(zero);
  EXPECT_LT(dyn.kinetic_energy() + dyn.strain_energy(), 0.5 * e0);
}

// a force spread over the beam's free end
Eigen::VectorXd tip_force(const Beam& b, const Eigen::Vector3d& f) {
  return region_force(b.mesh, {kL - 1e-9, -1, -1}, {kL + 1e-9, 1, 1}, f);
}

// every step an equilibrium K u = f
NewmarkOptions without_inertia() {
  NewmarkOptions o;
  o.inertia = false;
  return o;
}

// Without inertia the factor is K whatever the step: changing dt keeps it (a contact step
// of another length costs no factorization), and the static answer does not move; with
// inertia the factor holds M / (beta dt^2) and is redone.
TEST(Newmark, ADifferentStepRefactorsOnlyWithInertia) {
  const Beam b = beam(0.05);
  const Eigen::VectorXd load = tip_force(b, {0, 0, -100});
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  ElasticDynamics still(b.fe, b.clamp, 1e-3, without_inertia());
  still.start(0, zero, zero, load);
  still.set_time_step(3e-3);
  still.step(load);
  EXPECT_EQ(still.factor_stats().factorizations, 1);
  const Eigen::VectorXd u_static = solve_static(b.fe, load, b.clamp);
  EXPECT_LT((still.displacement() - u_static).norm(), 1e-9 * u_static.norm());
  ElasticDynamics moving(b.fe, b.clamp, 1e-3);
  moving.start(0, zero, zero, load);
  moving.set_time_step(3e-3);
  EXPECT_EQ(moving.factor_stats().factorizations, 2);
}

TEST(Newmark, AnEquilibriumsStrainEnergyIsItsLoadsWorkOnIt) {
  // without inertia a step is K u = f (+ reactions at the held dofs), and strain_energy()
  // takes u'f + u'r for u'K u: the two agree with the clamp moved and a load on the tip,
  // and again after a step with the body let go of its load
  const Beam b = beam(0.05);
  const Eigen::VectorXd load = tip_force(b, {0, 40, -100});
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(b.fe.dofs);
  ElasticDynamics dyn(b.fe, b.clamp, 1e-3, without_inertia());
  HeldMotion moved{zero, zero, zero};
  for (int v : b.clamp) moved.u[3 * v + 1] = 1e-4 * (1 + b.mesh.nodes(v, 2) / kB);  // a shear
  dyn.start(0, zero, zero, zero);
  for (const Eigen::VectorXd* f : {&load, &zero}) {
    dyn.step(*f, &moved);
    const Eigen::VectorXd& u = dyn.displacement();
    const double direct = 0.5 * u.dot(symmetric_times(b.fe.stiffness(), u));
    EXPECT_GT(direct, 0);
    EXPECT_NEAR(dyn.strain_energy(), direct, 1e-9 * direct);
  }
}

TEST(Newmark, ResponseAtSelectedRowsEqualsTheWholeResponseBlockByBlock) {
  // response_at solves 64 right-hand sides at a time and keeps only the rows asked for:
  // 150 columns (three blocks, the last one short) on free and held dofs, rows anywhere
  const Beam b = beam(0.05);
  ElasticDynamics dyn(b.fe, b.clamp, 1e-4);
  Eigen::SparseMatrix<double> ct(b.fe.dofs, 150);
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < 150; ++j) {
    entries.emplace_back((37 * j + 5) % b.fe.dofs, j, 1.0 + 0.01 * j);
    entries.emplace_back((11 * j + 3 * b.clamp[0]) % b.fe.dofs, j, -0.5);
  }
  entries.emplace_back(3 * b.clamp[0] + 1, 7, 2.0);  // a load on a held dof does nothing
  ct.setFromTriplets(entries.begin(), entries.end());
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < b.fe.dofs; i += 7) rows.push_back(i);
  rows.push_back(3 * b.clamp[1] + 2);  // a held row: zero
  const Eigen::MatrixXd whole = dyn.response(ct);
  const Eigen::MatrixXd some = dyn.response_at(ct, rows);
  ASSERT_EQ(some.rows(), static_cast<Eigen::Index>(rows.size()));
  ASSERT_EQ(some.cols(), 150);
  const double scale = whole.cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 0);
  for (std::size_t k = 0; k < rows.size(); ++k)
    EXPECT_LT((some.row(static_cast<Eigen::Index>(k)) - whole.row(rows[k])).cwiseAbs().maxCoeff(),
              1e-12 * scale);
  EXPECT_EQ(some.row(static_cast<Eigen::Index>(rows.size()) - 1).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Newmark, ResponseAtGivesTheSameBitsWhateverThreadSolvesABlock) {
  // three blocks of right-hand sides in one call (shared by two threads where the machine
  // has two cores) against each block alone (one thread): the same numbers to the last bit
  // (a block's forward sweep visits the union of its loads' paths; the supernodes one load
  // does not reach add exact zeros to its column)
  const Beam b = beam(0.05);
  ElasticDynamics dyn(b.fe, b.clamp, 1e-4);
  const int columns = 150;
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < columns; ++j) entries.emplace_back((29 * j + 4) % b.fe.dofs, j, 1.0 + j);
  Eigen::SparseMatrix<double> ct(b.fe.dofs, columns);
  ct.setFromTriplets(entries.begin(), entries.end());
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < b.fe.dofs; i += 5) rows.push_back(i);
  const Eigen::MatrixXd together = dyn.response_at(ct, rows);
  // its blocks: the columns in the elimination order of their loads, 64 at a time
  std::vector<int> order(columns);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int c) {
    return dyn.elimination_position((29 * a + 4) % b.fe.dofs) <
           dyn.elimination_position((29 * c + 4) % b.fe.dofs);
  });
  ASSERT_FALSE(std::is_sorted(order.begin(), order.end()));  // the order is the factor's
  for (int first = 0; first < columns; first += 64) {
    const int n = std::min(64, columns - first);
    Eigen::SparseMatrix<double> part(b.fe.dofs, n);
    std::vector<Eigen::Triplet<double>> block;
    for (int j = 0; j < n; ++j) {
      const int column = order[static_cast<std::size_t>(first + j)];
      block.emplace_back((29 * column + 4) % b.fe.dofs, j, 1.0 + column);
    }
    part.setFromTriplets(block.begin(), block.end());
    const Eigen::MatrixXd alone = dyn.response_at(part, rows);
    for (int j = 0; j < n; ++j)
      EXPECT_EQ(alone.col(j), together.col(order[static_cast<std::size_t>(first + j)]))
          << "block at " << first;
  }
}

}  // namespace
}  // namespace vproto::sim
