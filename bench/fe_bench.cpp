// FE speed, stage by stage, for one mesh (issue 3): mesh, assemble, analyse + factor,
// static solve, and a Newmark step on its kept factor against the memory-bandwidth bound of
// two triangular solves (16 bytes per entry of L / measured read bandwidth). Writes the
// same problem as a CalculiX deck so bench/fe_speed.py can time ccx on the very same mesh.
//
//   fe_bench --size H [--length L] [--tet4] [--ordering auto|amd|metis|nesdis]
//            [--inp FILE] [--solution FILE] [--steps N]
// prints one JSON object on stdout.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "vproto/geometry/primitives.h"
#include "vproto/geometry/tet_mesh.h"
#include "vproto/sim/elastic_dynamics.h"
#include "vproto/sim/fe_elasticity.h"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// peak resident memory of this process so far, bytes
double peak_memory() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return 1024.0 * std::stod(line.substr(6));
  return 0;
}

// read bandwidth of one core, bytes/s: the best of a few passes over 512 MB
double read_bandwidth() {
  const std::size_t n = 64u << 20;  // doubles
  std::vector<double> a(n, 1.0);
  double best = 0, sink = 0;
  for (int pass = 0; pass < 4; ++pass) {
    const auto t = Clock::now();
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (std::size_t i = 0; i < n; i += 4) {
      s0 += a[i];
      s1 += a[i + 1];
      s2 += a[i + 2];
      s3 += a[i + 3];
    }
    sink += s0 + s1 + s2 + s3;
    best = std::max(best, 8.0 * n / since(t));
  }
  if (sink == 42) std::puts("");  // keep the loop
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace vproto;
  double size = 0.02, length = 0.4;
  bool quadratic = true;
  int steps = 20;
  bool kept = false;      // --kept: the Newmark steps as if contact asked for columns
  bool cg_steps = false;  // --cg-steps: PETSc's warm-started CG even where a factor fits
  std::string inp, solution, ordering_name = "auto", solver_name = "cholmod";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--size")
      size = std::stod(next());
    else if (a == "--length")
      length = std::stod(next());
    else if (a == "--tet4")
      quadratic = false;
    else if (a == "--ordering")
      ordering_name = next();
    else if (a == "--solver")
      solver_name = next();
    else if (a == "--kept")
      kept = true;
    else if (a == "--cg-steps")
      cg_steps = true;
    else if (a == "--inp")
      inp = next();
    else if (a == "--solution")
      solution = next();
    else if (a == "--steps")
      steps = std::stoi(next());
    else {
      std::cerr << "unknown argument " << a << "\n";
      return 2;
    }
  }
  const auto ordering = ordering_name == "amd"      ? sim::SparseCholesky::Ordering::kAmd
                        : ordering_name == "metis"  ? sim::SparseCholesky::Ordering::kMetis
                        : ordering_name == "nesdis" ? sim::SparseCholesky::Ordering::kNesdis
                                                    : sim::SparseCholesky::Ordering::kAutomatic;
  // a steel block L x 0.1 x 0.1 m clamped at x = 0, 10 kN down on its far face
  const double e = 210e9, nu = 0.3, rho = 7850;
  auto t = Clock::now();
  geometry::TetMeshOptions mo;
  mo.size = size;
  mo.quadratic = quadratic;
  const geometry::TetMesh mesh =
      geometry::make_tet_mesh(geometry::make_box({length, 0.1, 0.1}, false), mo);
  const double mesh_s = since(t);

  t = Clock::now();
  const sim::FeMatrices fe = sim::assemble(mesh, e, nu, rho);
  const double assemble_s = since(t);
  const auto clamp = sim::boundary_nodes_in(mesh, {-1e-9, -1, -1}, {1e-9, 1, 1});
  const Eigen::VectorXd f =
      sim::region_force(mesh, {length - 1e-9, -1, -1}, {length + 1e-9, 1, 1}, {0, 0, -1e4});

  // static: hold, analyse, factor (or set up the preconditioner), solve: the path of
  // `vproto run` in mode=static, by the backend --solver names
  t = Clock::now();
  sim::SolverSetup setup;
  setup.choice = sim::solver_choice_from(solver_name);
  setup.ordering = ordering;
  setup.coordinates = mesh.nodes;
  setup.elements = mesh.elements;
  setup.relative_tolerance = sim::relative_tolerance_for(size, std::sqrt(length * length + 0.02));
  sim::SolverStats st;
  const Eigen::VectorXd u = sim::solve_static(fe, f, clamp, &st, &setup);
  const double static_s = since(t);
  const double static_memory = peak_memory();

  // dynamic: one factor of K + 4M/dt^2, then steps (--steps 0: none)
  double dyn_factor_s = 0, step_s = 0, nnz_l = 0;
  std::string single_solve;
  if (steps > 0) {
    const double dt = 1e-5;
    t = Clock::now();
    sim::NewmarkOptions no;
    no.ordering = ordering;
    no.solver = sim::solver_choice_from(solver_name);
    no.constraint_columns = kept;
    no.iterative_steps = cg_steps;
    no.mesh = &mesh;
    sim::ElasticDynamics dyn(fe, clamp, dt, no);
    dyn_factor_s = since(t);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(fe.dofs);
    dyn.start(0, zero, zero, zero);
    dyn.step(f);  // warm-up (workspace)
    t = Clock::now();
    for (int s = 0; s < steps; ++s) dyn.step(f);
    step_s = since(t) / steps;
    nnz_l = dyn.factor_stats().factor_nonzeros;
    single_solve = dyn.factor_stats().single_solve;
    if (sim::launched_rank() == 0)
      std::fprintf(stderr, "dynamic: %s, %d iterations in the last step\n",
                   dyn.factor_stats().method.c_str(), dyn.factor_stats().iterations);
  }
  const double bandwidth = read_bandwidth();
  const double bound_s = 16 * nnz_l / bandwidth;

  // under mpirun every rank computes; rank 0 alone writes and reports
  const bool writer = sim::launched_rank() == 0;
  if (writer && !inp.empty()) {
    // the same problem for CalculiX (C3D4/C3D10 share VTK's node order)
    std::ofstream out(inp);
    out.precision(17);
    out << "*NODE, NSET=NALL\n";
    for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i)
      out << i + 1 << ", " << mesh.nodes(i, 0) << ", " << mesh.nodes(i, 1) << ", "
          << mesh.nodes(i, 2) << "\n";
    out << "*ELEMENT, TYPE=" << (quadratic ? "C3D10" : "C3D4") << ", ELSET=EALL\n";
    for (Eigen::Index el = 0; el < mesh.elements.rows(); ++el) {
      out << el + 1;
      for (Eigen::Index c = 0; c < mesh.elements.cols(); ++c)
        out << ", " << mesh.elements(el, c) + 1;
      out << "\n";
    }
    out << "*NSET, NSET=HELD\n";
    for (int v : clamp) out << v + 1 << ",\n";
    out << "*MATERIAL, NAME=M\n*ELASTIC\n"
        << e << ", " << nu
        << "\n*SOLID SECTION, ELSET=EALL, MATERIAL=M\n*STEP\n*STATIC\n*BOUNDARY\nHELD, 1, 3, "
           "0.\n*CLOAD\n";
    for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i)
      for (int c = 0; c < 3; ++c)
        if (f[3 * i + c] != 0) out << i + 1 << ", " << c + 1 << ", " << f[3 * i + c] << "\n";
    out << "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
  }
  if (writer && !solution.empty()) {
    std::ofstream out(solution);
    out.precision(17);
    for (Eigen::Index i = 0; i < u.size(); ++i) out << u[i] << "\n";
  }

  if (writer)
    std::printf(
        "{\"size\": %g, \"element\": \"%s\", \"nodes\": %ld, \"elements\": %ld, \"dofs\": %ld,\n"
        " \"nnz_K_lower\": %zu, \"backend\": \"%s\", \"method\": \"%s\", \"ranks\": %d,\n"
        " \"iterations\": %d, \"relative_residual\": %.3g, \"relative_tolerance\": %.3g,\n"
        " \"ordering\": \"%s\", \"nnz_L\": %.0f, \"factor_flops\": %.4g,\n"
        " \"mesh_s\": %.4f, \"assemble_s\": %.4f, \"analyze_s\": %.4f, \"factor_s\": %.4f,\n"
        " \"solve_s\": %.5f, \"static_total_s\": %.4f,\n"
        " \"peak_memory_static_bytes\": %.0f, \"peak_memory_bytes\": %.0f,\n"
        " \"dynamic_factor_s\": %.4f, \"dynamic_step_s\": %.6f, \"single_solve\": \"%s\",\n"
        " \"read_bandwidth_GBps\": %.2f, \"bound_two_solves_s\": %.6f,\n"
        " \"step_over_bound\": %.3f, \"max_u\": %.10g}\n",
        size, quadratic ? "tet10" : "tet4", static_cast<long>(mesh.nodes.rows()),
        static_cast<long>(mesh.elements.rows()), static_cast<long>(fe.dofs), fe.nonzeros(),
        st.backend.c_str(), st.method.c_str(), st.ranks, st.iterations, st.relative_residual,
        st.relative_tolerance, st.ordering.c_str(), st.factor_nonzeros, st.flops, mesh_s,
        assemble_s, st.analyze_seconds, st.factor_seconds,
        std::max(0.0, static_s - st.analyze_seconds - st.factor_seconds), assemble_s + static_s,
        static_memory, peak_memory(), dyn_factor_s, step_s, single_solve.c_str(), bandwidth / 1e9,
        bound_s, bound_s > 0 ? step_s / bound_s : 0.0, u.cwiseAbs().maxCoeff());
  sim::finish_parallel();  // PETSc, when the solve started it (and its -log_view)
  return 0;
}
