#pragma once
// Algebraic multigrid for every family: hypre's BoomerAMG through PETSc (Debian's petsc-dev
// carries hypre), applied as the preconditioner of knotwork's own CG, so that the stopping
// rule and the reports are those of every iterative solve (docs/SOLVERS.md).
#include <memory>
#include <string>

#include "solver/iterative_solver.hpp"

namespace knotwork {

// The name [solver] preconditioner takes for it.
inline constexpr const char* kBoomerAmgName = "boomeramg";

// BoomerAMG on K (symmetric positive definite, lower triangle stored). `petsc_options` are
// PETSc options for the preconditioner ("-pc_hypre_boomeramg_strong_threshold 0.5"), given
// to PETSc's options database before setup. Throws std::invalid_argument naming an option
// PETSc did not use or could not read, and std::runtime_error when PETSc fails.
// PETSc (and MPI, as a single process) is loaded and initialized on first use (the module
// libknotwork_petsc.so, or $KNOTWORK_PETSC_MODULE), without its signal handlers, and finalized
// at exit.
std::unique_ptr<Preconditioner> boomeramg_preconditioner(const Eigen::SparseMatrix<double>& lower,
                                                         const std::string& petsc_options);

}  // namespace knotwork
