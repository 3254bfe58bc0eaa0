#pragma once
// The Galerkin pipeline of solve_poisson on the processes mpirun started, through PETSc
// (method = "petsc"; docs/SCALING.md).
#include <functional>

#include "solver/petsc_module.hpp"
#include "solver/poisson_solver.hpp"

namespace knotwork {

// Every rank holds the whole BezierMesh and geometry (built redundantly: the space is not yet
// distributed) and the Dirichlet projection (the boundary's small system). The cells are
// split into contiguous blocks of the cell order, one per rank; each rank integrates only its
// block into the distributed matrix and load (no rank holds the global matrix), rank 0 adds
// the Neumann terms, PETSc solves, and the solution is gathered on every rank; the error
// norms are summed over the ranks' blocks. Collective: every rank calls it, and a failure on
// one rank (a bad cell, a source not finite) is thrown on all of them. A closed surface
// (zero-mean solution) is refused (std::invalid_argument).
// Runs step on every rank; a failure on any rank is thrown on all of them, the lowest failing
// rank's (InputError, GeometryError, std::invalid_argument kept as such): no rank is left
// waiting in a collective call the others never reach. Collective; also a barrier.
void on_all_ranks(const std::function<void()>& step);

// The contiguous block of the cell order rank `world.rank` integrates and writes.
CellRange cells_of_rank(int num_cells, ParallelWorld world);

PoissonSolution solve_poisson_distributed(const BezierMesh& mesh, const GeometryMap& geometry,
                                          const PoissonProblem& problem, const PoissonSolveOptions& options,
                                          const DistributedSolveOptions& petsc);

}  // namespace knotwork
