#pragma once
// The PETSc backend of the linear-solver seam (linear_solver.h), behind a wall: only
// petsc_solver.cpp includes PETSc's and MPI's headers.

#include <memory>
#include <string>
#include <vector>

#include "vproto/sim/linear_solver.h"

namespace vproto::sim::detail {

bool petsc_built();
/// PetscInitialize (and MPI_Init); idempotent.
void petsc_start();
/// PetscFinalize (and MPI_Finalize) when started; idempotent.
void petsc_finish();
void petsc_abort(int code);
/// PETSc solvers made from now on span all ranks (true) or this rank alone.
void petsc_share(bool shared);
void petsc_barrier();
/// Every rank's `value`, in rank order (MPI_Allgather; this rank's alone without MPI).
std::vector<double> petsc_gather(double value);
std::unique_ptr<LinearSolver> make_petsc_solver(const SolverSetup& setup,
                                                const std::string& reason);

}  // namespace vproto::sim::detail
