#include "vproto/sim/linear_solver.h"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "petsc_backend.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/sparse_cholesky.h"

namespace vproto::sim {
namespace {

int environment_int(const char* name, int otherwise) {
  const char* v = std::getenv(name);
  if (!v || !*v) return otherwise;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  return end && *end == '\0' && x >= 0 ? static_cast<int>(x) : otherwise;
}

// Newmark steps on PETSc: MUMPS' kept factor, unless it would not fit in memory. Warm-
// started CG + p-multigrid (residual 1e-10 of the right-hand side) took 14-18 iterations
// a step on the steel block at dt 10 us: 0.41-0.52 s a step against the factor's 0.08 s
// at 83k dofs, 1.09 s against 0.26 s at 186k; it sets up 4-7x faster (0.55 s against
// 3.4 s, 1.4 s against 10.6 s), which pays only for runs of a few steps.
constexpr double kIterativeBytesPerDof = 3000;  // K in both triangles, 3 times over

bool g_shared = true;              // the FE solves span all MPI ranks
bool g_finished_together = false;  // every rank passed the last shared wait

// Static solves of quadratic tetrahedra at least this large go to CG + p-multigrid under
// `auto` (one process, this machine). The crossover depends on the shape, since a factor's
// cost follows its separators: on the compact steel block of bench/fe_speed.py the static
// solve took 0.80 s with CHOLMOD against 0.74 s with PETSc at 32k dofs, 2.7 / 1.6 s at
// 83k, 10.4 / 3.7 s at 186k; on the slender beam of samples/cantilever.vp (factor and
// solve) 1.1 / 1.5 s at 58k, 4.3 / 3.0 s at 157k, 19.4 / 6.7 s at 406k.
constexpr Eigen::Index kIterativeStaticDofs = 100000;

}  // namespace

SolverChoice solver_choice_from(const std::string& name) {
  if (name == "auto") return SolverChoice::kAuto;
  if (name == "cholmod") return SolverChoice::kCholmod;
  if (name == "petsc") return SolverChoice::kPetsc;
  throw InputError("unknown solver '" + name + "': use auto, cholmod or petsc");
}

std::string to_string(SolverChoice c) {
  switch (c) {
    case SolverChoice::kCholmod:
      return "cholmod";
    case SolverChoice::kPetsc:
      return "petsc";
    case SolverChoice::kAuto:
      break;
  }
  return "auto";
}

double relative_tolerance_for(double h, double l) {
  if (!(h > 0) || !(l > 0)) return 1e-8;
  const double ratio = std::min(1.0, h / l);
  return std::clamp(0.01 * ratio * ratio * ratio, 1e-12, 1e-6);
}

// Open MPI and MPICH (Hydra, PMI) tell a process its place before MPI_Init.
int launched_ranks() {
  return std::max(1, environment_int("OMPI_COMM_WORLD_SIZE", environment_int("PMI_SIZE", 1)));
}

int launched_rank() {
  return environment_int("OMPI_COMM_WORLD_RANK", environment_int("PMI_RANK", 0));
}

bool petsc_available() { return detail::petsc_built(); }

bool iterative_solve_fits(Eigen::Index dofs) {
  return kIterativeBytesPerDof * static_cast<double>(dofs) <= factor_memory_limit();
}

std::string no_petsc_message(const std::string& asked) {
  return asked +
         ": this build has no PETSc backend; install libpetsc-real-dev and build again (bash "
         "scripts/setup.sh), or use the CHOLMOD backend (solver=cholmod, one process)";
}

void start_parallel() {
  if (launched_ranks() <= 1) return;
  if (!petsc_available())
    throw InputError(no_petsc_message("vproto launched on " + std::to_string(launched_ranks()) +
                                      " MPI ranks (run it without mpirun)"));
  detail::petsc_start();
}

void finish_parallel() { detail::petsc_finish(); }

void share_solves_among_ranks(bool shared) {
  g_shared = shared;
  detail::petsc_share(shared);
}

void parallel_barrier() { detail::petsc_barrier(); }

void mark_ranks_finished_together() { g_finished_together = true; }
bool ranks_finished_together() { return g_finished_together; }

std::vector<double> peak_memory_per_rank() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double mine = 1024.0 * static_cast<double>(usage.ru_maxrss);
  if (!g_shared || launched_ranks() <= 1) return {mine};
  return detail::petsc_gather(mine);
}

void abort_parallel(int code) { detail::petsc_abort(code); }

std::unique_ptr<LinearSolver> make_linear_solver(const SolverSetup& setup) {
  const int ranks = g_shared ? launched_ranks() : 1;
  std::string reason;
  bool petsc = false;
  switch (setup.choice) {
    case SolverChoice::kPetsc:
      if (!petsc_available()) throw InputError(no_petsc_message("solver=petsc"));
      petsc = true;
      reason = "asked for (solver=petsc)";
      break;
    case SolverChoice::kCholmod:
      reason = "asked for (solver=cholmod)";
      if (ranks > 1) reason += "; every rank repeats the whole solve";
      break;
    case SolverChoice::kAuto:
      if (ranks > 1 && petsc_available()) {
        petsc = true;
        reason = "auto: " + std::to_string(ranks) + " MPI ranks share the solve";
      } else if (setup.use == SolveUse::kStatic && petsc_available() &&
                 setup.dofs >= kIterativeStaticDofs && setup.elements.cols() == 10) {
        petsc = true;
        reason = "auto: a static solve of " + std::to_string(setup.dofs) +
                 " dofs (>= " + std::to_string(kIterativeStaticDofs) +
                 ") on quadratic tetrahedra, where CG + p-multigrid beats a factor";
      } else if (setup.use == SolveUse::kSteps && petsc_available() &&
                 estimated_factor_bytes(static_cast<double>(setup.dofs)) > factor_memory_limit() &&
                 iterative_solve_fits(setup.dofs)) {
        petsc = true;
        reason = "auto: a factor of " + std::to_string(setup.dofs) +
                 " dofs would not fit in memory, so CG needing none";
      } else {
        reason = "auto: one process";
        if (setup.use == SolveUse::kStatic && setup.elements.cols() != 10)
          reason += ", a static solve of linear tetrahedra (no p-multigrid)";
        else if (setup.use == SolveUse::kStatic)
          reason += ", a static solve of " + std::to_string(setup.dofs) + " dofs (< " +
                    std::to_string(kIterativeStaticDofs) + ")";
        else
          reason += ", a factor kept for every step";
        if (!petsc_available()) reason += "; this build has no PETSc";
      }
      break;
  }
  if (!setup.reason.empty()) reason = setup.reason;
  if (petsc && setup.use == SolveUse::kSteps) {
    // per case: the kept factor is faster a step; CG only when the factor would not fit
    const double factor = estimated_factor_bytes(static_cast<double>(setup.dofs));
    if (factor <= factor_memory_limit() && !setup.iterative_steps) {
      SolverSetup kept = setup;
      kept.use = SolveUse::kKept;
      return detail::make_petsc_solver(
          kept, reason + "; MUMPS' kept factor, 4-6x faster a step than warm-started CG");
    }
    return detail::make_petsc_solver(
        setup, reason + (setup.iterative_steps
                             ? std::string("; warm-started CG, as asked")
                             : "; warm-started CG, since a factor (about " +
                                   std::to_string(static_cast<long>(factor / 1e9 + 0.5)) +
                                   " GB) would not fit"));
  }
  if (petsc) return detail::make_petsc_solver(setup, reason);
  auto cholmod = std::make_unique<SparseCholesky>(setup.ordering);
  cholmod->set_reason(reason);
  return cholmod;
}

}  // namespace vproto::sim
