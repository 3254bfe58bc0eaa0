#pragma once
// The Galerkin pipeline of solve_poisson on the processes mpirun started, through PETSc
// (method = "petsc"; docs/SCALING.md).
#include <functional>

#include "solver/petsc_module.hpp"
#include "solver/poisson_solver.hpp"

namespace knotwork {

// Each rank holds either its part of the space (`part`: the cells it integrates and the halo
// its matrix rows need, with their own function numbers; families that split their spaces build these) or,
// when `part` is null, the whole BezierMesh and geometry, built redundantly, whose cells are
// then split into contiguous blocks of the cell order and whose functions into contiguous
// blocks of rows. The Dirichlet projection is assembled from every rank's boundary cells and
// solved on every rank (a boundary-sized system). Each rank integrates its cells into the
// distributed matrix and load, Neumann terms included (no rank holds the global matrix),
// PETSc solves, and each rank gets back the values of its mesh's functions (with a whole mesh:
// all of them); the error norms are summed over the ranks' cells. The returned coefficients
// are per function of `mesh`. Collective: every rank calls it, and a failure on one rank (a bad
// cell, a source not finite) is thrown on all of them. A closed surface (zero-mean solution)
// is solved as solve_poisson does (the mass matrix's solve for the constant 1 on every rank, so
// a whole mesh only: with a part it is refused, std::invalid_argument).
// Runs step on every rank; a failure on any rank is thrown on all of them, the lowest failing
// rank's (InputError, GeometryError, std::invalid_argument kept as such): no rank is left
// waiting in a collective call the others never reach. Collective; also a barrier.
void on_all_ranks(const std::function<void()>& step);

// The contiguous block of the cell order rank `world.rank` integrates and writes.
CellRange cells_of_rank(int num_cells, ParallelWorld world);

PoissonSolution solve_poisson_distributed(const BezierMesh& mesh, const GeometryMap& geometry, const MeshPart* part,
                                          const PoissonProblem& problem, const PoissonSolveOptions& options,
                                          const DistributedSolveOptions& petsc);

}  // namespace knotwork
