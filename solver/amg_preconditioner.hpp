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

// The options a volume's BoomerAMG starts from, before the user's (which override them):
// aggressive coarsening on the first level, HMIS, extended+i interpolation with at most 4
// entries per row. With hypre's defaults (made for 2D stencils) a trivariate stencil of
// (2p + 1)^3 entries builds coarse operators that fill up: measured on the cube at p = 2, these
// options take 3.0-3.9x less time and 0.43-0.54x the memory at 64^3 and 96^3 elements, the same
// errors and 19-20 iterations (docs/VOLUMES.md). Planar domains and surfaces keep the defaults.
inline constexpr const char* kBoomerAmgVolumeOptions =
    "-pc_hypre_boomeramg_agg_nl 1 -pc_hypre_boomeramg_coarsen_type HMIS -pc_hypre_boomeramg_interp_type ext+i "
    "-pc_hypre_boomeramg_P_max 4";

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
