// The linear-solver seam: both backends give the same answers (CHOLMOD's factor to
// round-off, PETSc's CG to its residual, MUMPS' kept factor to round-off), `auto` says
// why it chose, and a system that is not positive definite is refused by name.
#include "vproto/sim/linear_solver.h"

#include <gtest/gtest.h>

#include <Eigen/IterativeLinearSolvers>

#include "vproto/geometry/primitives.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/elastic_dynamics.h"
#include "vproto/sim/fe_elasticity.h"
#include "vproto/sim/sparse_cholesky.h"

namespace vproto::sim {
namespace {

// a steel bar 0.2 x 0.02 x 0.03 m, tet10, clamped at x = 0, pulled and bent at x = 0.2
struct Bar {
  geometry::TetMesh mesh;
  FeMatrices fe;
  std::vector<int> clamp;
  Eigen::VectorXd force;
};

const Bar& bar() {
  static const Bar b = [] {
    Bar x;
    geometry::TetMeshOptions o;
    o.size = 0.008;
    x.mesh = geometry::make_tet_mesh(geometry::make_box({0.2, 0.02, 0.03}, false), o);
    x.fe = assemble(x.mesh, 210e9, 0.3, 7850);
    x.clamp = boundary_nodes_in(x.mesh, {-1e-9, -1, -1}, {1e-9, 1, 1});
    x.force = region_force(x.mesh, {0.2 - 1e-9, -1, -1}, {1, 1, 1}, {300, -100, -200});
    return x;
  }();
  return b;
}

// Newmark options on one backend
NewmarkOptions on(SolverChoice backend) {
  NewmarkOptions o;
  o.solver = backend;
  return o;
}

// starts every body at rest and takes `steps` Newmark steps under the bar's force
void step_from_rest(const std::vector<ElasticDynamics*>& bodies, int steps) {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(bar().fe.dofs);
  for (ElasticDynamics* d : bodies) d->start(0, zero, zero, zero);
  for (int k = 0; k < steps; ++k)
    for (ElasticDynamics* d : bodies) d->step(bar().force);
}

// The sweeps of a factor large enough for subtree_solve: one right-hand side on two threads,
// several at once, and sparse ones (a unit load, whose forward sweep visits only its path to
// the root, answered at chosen rows only) give the answers of conjugate gradients run to
// 1e-15 to 1e-12, with residuals as small; the same bits solve after solve; and again after a
// numeric refactorization with new values (the partition is the analysis').
TEST(LinearSolver, CholmodsFactorSweptOnTwoThreadsAndSparseLoadsGivesTheSameAnswers) {
  geometry::TetMeshOptions o;
  o.size = 0.004;
  const geometry::TetMesh mesh =
      geometry::make_tet_mesh(geometry::make_box({0.1, 0.04, 0.03}, false), o);
  const FeMatrices fe = assemble(mesh, 210e9, 0.3, 7850);
  SparseCholesky chol(SparseCholesky::Ordering::kMetis);
  // K + c M: positive definite with no support, and with c large (a Newmark step matrix of
  // a short step) well enough conditioned for an iterative reference to 1e-15
  for (double mass_factor : {3e12, 1e13}) {
    std::vector<double> values(fe.stiffness_values.size());
    for (std::size_t k = 0; k < values.size(); ++k)
      values[k] = fe.stiffness_values[k] + mass_factor * fe.mass_values[k];
    chol.factor(fe.view(values), "K + c M", 3);  // the second time numerically only
    ASSERT_GT(chol.stats().factor_nonzeros, 2e5);
    ASSERT_NE(chol.stats().single_solve.find("two-thread"), std::string::npos)
        << chol.stats().single_solve;
    const Eigen::SparseMatrix<double> a = full_matrix(fe.view(values));
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> reference(a);
    reference.setTolerance(1e-15);
    reference.setMaxIterations(5000);
    Eigen::MatrixXd b(fe.dofs, 3);
    for (Eigen::Index i = 0; i < fe.dofs; ++i) {
      b(i, 0) = std::sin(0.37 * static_cast<double>(i)) + 0.1;
      b(i, 1) = -b(i, 0);
    }
    b.col(2).setZero();
    b(fe.dofs / 2, 2) = 1;  // a unit load
    Eigen::MatrixXd expected(fe.dofs, 3);
    for (int c = 0; c < 3; ++c) {
      expected.col(c) = reference.solve(b.col(c));
      ASSERT_EQ(reference.info(), Eigen::Success) << c;
    }
    Eigen::VectorXd single = b.col(0);
    chol.solve_in_place(single);
    Eigen::MatrixXd several = b;
    chol.solve_in_place(several);
    Eigen::VectorXd unit = b.col(2);
    chol.solve_in_place(unit);
    EXPECT_LT((single - expected.col(0)).norm(), 1e-12 * expected.col(0).norm());
    for (int c = 0; c < 3; ++c)
      EXPECT_LT((several.col(c) - expected.col(c)).norm(), 1e-12 * expected.col(c).norm()) << c;
    EXPECT_LT((unit - expected.col(2)).norm(), 1e-12 * expected.col(2).norm());
    // residuals as small as the reference's
    for (int c = 0; c < 3; ++c) {
      const double reference_residual = (a * expected.col(c) - b.col(c)).norm();
      EXPECT_LT((a * several.col(c) - b.col(c)).norm(), 4 * reference_residual + 1e-300) << c;
    }
    EXPECT_LT((a * single - b.col(0)).norm(), 4 * (a * expected.col(0) - b.col(0)).norm());
    // sparse loads answered at a few rows only (the backward sweep skips what they do not
    // need): the same answers there
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < fe.dofs; i += 97) rows.push_back(i);
    const Eigen::SparseMatrix<double> loads = b.rightCols(1).sparseView();
    const Eigen::MatrixXd at = chol.solve_sparse(loads, rows);
    ASSERT_EQ(at.rows(), static_cast<Eigen::Index>(rows.size()));
    for (std::size_t q = 0; q < rows.size(); ++q)
      EXPECT_NEAR(at(static_cast<Eigen::Index>(q), 0), expected(rows[q], 2),
                  1e-12 * expected.col(2).norm());
    Eigen::VectorXd again = b.col(0);
    chol.solve_in_place(again);
    EXPECT_EQ(again, single);  // the partition is fixed: no dependence on thread timing
  }
}

TEST(LinearSolver, TheStaticToleranceFollowsTheMeshSize) {
  EXPECT_DOUBLE_EQ(relative_tolerance_for(0.01, 1.0), 1e-8);  // 0.01 (h/l)^3
  EXPECT_LT(relative_tolerance_for(0.005, 1.0), relative_tolerance_for(0.01, 1.0));
  EXPECT_DOUBLE_EQ(relative_tolerance_for(0.5, 1.0), 1e-6);    // never looser than 1e-6
  EXPECT_DOUBLE_EQ(relative_tolerance_for(1e-6, 1.0), 1e-12);  // nor tighter than 1e-12
}

TEST(LinearSolver, AutoTakesCholmodInOneProcessAndSaysWhy) {
  SolverSetup s;
  s.use = SolveUse::kKept;
  s.dofs = 3000;
  const auto kept = make_linear_solver(s);
  EXPECT_EQ(kept->stats().backend, "cholmod");
  EXPECT_NE(kept->stats().reason.find("auto: one process"), std::string::npos)
      << kept->stats().reason;
  s.use = SolveUse::kStatic;
  s.dofs = 400000;
  EXPECT_EQ(make_linear_solver(s)->stats().backend, "cholmod");  // linear tets: no p-MG
  s.elements = Eigen::MatrixXi::Zero(1, 10);                     // quadratic ones
  const auto large = make_linear_solver(s);
  if (petsc_available()) {
    EXPECT_EQ(large->stats().backend, "petsc");
    EXPECT_NE(large->stats().reason.find("static solve of 400000 dofs"), std::string::npos)
        << large->stats().reason;
  } else {
    EXPECT_EQ(large->stats().backend, "cholmod");
  }
  EXPECT_THROW(solver_choice_from("mumps"), InputError);
}

TEST(LinearSolver, PetscConjugateGradientsAgreeWithCholmodToTheirResidual) {
  if (!petsc_available()) GTEST_SKIP() << "built without PETSc";
  const Bar& b = bar();
  SolverSetup cholmod;
  cholmod.choice = SolverChoice::kCholmod;
  SolverStats cs, ps, bare_stats;
  const Eigen::VectorXd uc = solve_static(b.fe, b.force, b.clamp, &cs, &cholmod);
  SolverSetup petsc;
  petsc.choice = SolverChoice::kPetsc;
  petsc.coordinates = b.mesh.nodes;
  petsc.relative_tolerance = 1e-10;
  const Eigen::VectorXd up = solve_static(b.fe, b.force, b.clamp, &ps, &petsc);
  EXPECT_EQ(cs.backend, "cholmod");
  EXPECT_EQ(ps.backend, "petsc");
  EXPECT_EQ(ps.method, "CG + GAMG (rigid-body near null space)");
  EXPECT_GT(ps.iterations, 0);
  EXPECT_LE(ps.relative_residual, 1e-10);
  // the true residual of PETSc's answer, computed here, is what it reports
  const Eigen::VectorXd k_up = symmetric_times(b.fe.stiffness(), up);
  std::vector<char> held = dof_mask(b.fe.dofs, b.clamp);
  double r2 = 0, f2 = 0;
  for (Eigen::Index i = 0; i < b.fe.dofs; ++i)
    if (!held[i]) {
      r2 += (b.force[i] - k_up[i]) * (b.force[i] - k_up[i]);
      f2 += b.force[i] * b.force[i];
    }
  EXPECT_LE(std::sqrt(r2 / f2), 2e-10);
  // and the displacements agree far inside any discretisation error
  EXPECT_LT((up - uc).norm() / uc.norm(), 1e-7);
  // without the rigid rotations as near null space, multigrid needs more iterations
  SolverSetup bare = petsc;
  bare.coordinates.resize(0, 3);
  const Eigen::VectorXd ub = solve_static(b.fe, b.force, b.clamp, &bare_stats, &bare);
  EXPECT_GT(bare_stats.iterations, ps.iterations);
  EXPECT_LT((ub - uc).norm() / uc.norm(), 1e-7);
}

TEST(LinearSolver, MumpsKeptFactorGivesCholmodsStepsAndConstraintColumns) {
  if (!petsc_available()) GTEST_SKIP() << "built without PETSc";
  const Bar& b = bar();
  ElasticDynamics c(b.fe, b.clamp, 1e-4, on(SolverChoice::kCholmod));
  NewmarkOptions o = on(SolverChoice::kPetsc);
  ElasticDynamics p(b.fe, b.clamp, 1e-4, o);
  EXPECT_EQ(p.factor_stats().backend, "petsc");
  EXPECT_EQ(p.factor_stats().factorizations, 1);
  EXPECT_GT(p.factor_stats().factor_nonzeros, 0);
  step_from_rest({&c, &p}, 5);
  EXPECT_LT((p.displacement() - c.displacement()).norm() / c.displacement().norm(), 1e-10);
  // 70 unit forces on free dofs: two blocks of MUMPS right-hand sides
  std::vector<char> held = dof_mask(b.fe.dofs, b.clamp);
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index i = 0, col = 0; i < b.fe.dofs && col < 70; i += 7)
    if (!held[i]) t.emplace_back(i, col++, 1.0);
  Eigen::SparseMatrix<double> ct(b.fe.dofs, 70);
  ct.setFromTriplets(t.begin(), t.end());
  const Eigen::MatrixXd yc = c.response(ct), yp = p.response(ct);
  EXPECT_LT((yp - yc).norm() / yc.norm(), 1e-10);
}

// Newmark steps with no constraint columns: MUMPS' kept factor where it fits (faster a
// step), warm-started CG + p-multigrid when asked; both give CHOLMOD's steps.
TEST(LinearSolver, NewmarkStepsOnPetscPickAFactorOrWarmStartedCg) {
  if (!petsc_available()) GTEST_SKIP() << "built without PETSc";
  const Bar& b = bar();
  ElasticDynamics c(b.fe, b.clamp, 1e-4, on(SolverChoice::kCholmod));
  NewmarkOptions o = on(SolverChoice::kPetsc);
  o.constraint_columns = false;
  o.mesh = &b.mesh;
  ElasticDynamics f(b.fe, b.clamp, 1e-4, o);
  o.iterative_steps = true;
  ElasticDynamics g(b.fe, b.clamp, 1e-4, o);
  EXPECT_EQ(f.factor_stats().method, "MUMPS Cholesky (distributed factor, kept)");
  EXPECT_NE(f.factor_stats().reason.find("4-6x faster a step"), std::string::npos)
      << f.factor_stats().reason;
  EXPECT_EQ(g.factor_stats().method,
            "CG + p-multigrid (tet10 to tet4, MUMPS on tet4), warm started from the last step");
  step_from_rest({&c, &f, &g}, 8);
  EXPECT_LT((f.displacement() - c.displacement()).norm() / c.displacement().norm(), 1e-10);
  // CG stops at 1e-10 of the right-hand side: the steps agree far inside Newmark's error
  EXPECT_LT((g.displacement() - c.displacement()).norm() / c.displacement().norm(), 1e-7);
  EXPECT_NEAR(g.kinetic_energy() + g.strain_energy(), g.external_work(), 1e-6 * g.external_work());
  EXPECT_GT(g.factor_stats().iterations, 0);
  EXPECT_LE(g.factor_stats().relative_residual, 1e-10);
}

TEST(LinearSolver, PetscRefusesAMatrixThatIsNotPositiveDefinite) {
  if (!petsc_available()) GTEST_SKIP() << "built without PETSc";
  // a chain of springs, tridiag(-1, 2, -1), shifted by -1/2: a tenth of its eigenvalues
  // are negative
  constexpr int n = 60;
  Eigen::SparseMatrix<double> lower(n, n);
  for (int i = 0; i < n; ++i) {
    lower.insert(i, i) = 1.5;
    if (i + 1 < n) lower.insert(i + 1, i) = -1;
  }
  lower.makeCompressed();
  for (SolveUse use : {SolveUse::kStatic, SolveUse::kKept}) {
    SolverSetup s;
    s.choice = SolverChoice::kPetsc;
    s.use = use;
    s.dofs = n;
    s.relative_tolerance = 1e-10;
    const auto solver = make_linear_solver(s);
    try {
      solver->factor(view_of(lower), "the test matrix", 3);
      Eigen::VectorXd x = Eigen::VectorXd::Ones(n);
      solver->solve_in_place(x);
      ADD_FAILURE() << "solved an indefinite matrix: " << x.transpose();
    } catch (const SimulationError& e) {
      EXPECT_NE(std::string(e.what()).find("the test matrix is not positive definite"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace vproto::sim
