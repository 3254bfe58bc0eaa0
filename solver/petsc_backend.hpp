#pragma once
// The distributed steps of solve_poisson under mpirun (method = "petsc"; docs/SCALING.md) and
// its PETSc backend. solve_poisson (poisson_solver.hpp) is the one driver; these are the
// pieces it runs when a Distribution is given.
#include <functional>
#include <utility>
#include <vector>

#include "solver/petsc_module.hpp"
#include "solver/poisson_solver.hpp"

namespace knotwork {

// Runs step on every rank; a failure on any rank is thrown on all of them, the lowest failing
// rank's (InputError, GeometryError, std::invalid_argument kept as such): no rank is left
// waiting in a collective call the others never reach. Collective; also a barrier.
void on_all_ranks(const std::function<void()>& step);

// The contiguous block of the cell order rank `world.rank` integrates and writes.
CellRange cells_of_rank(int num_cells, ParallelWorld world);

// The whole mesh on every rank: its cells and functions split into contiguous blocks (one
// block, the whole mesh, for a world of one).
MeshPart whole_mesh_part(const BezierMesh& mesh, ParallelWorld world);

// The Dirichlet projection from every rank's boundary cells, the same on every rank: the
// global numbers of the fixed functions (sorted) and their values. Collective.
std::vector<std::pair<int, double>> project_dirichlet_over_ranks(const BezierMesh& mesh, const GeometryMap& geometry,
                                                                 const PoissonProblem& problem,
                                                                 const QuadratureOptions& quadrature,
                                                                 const MeshPart& part);

// The PETSc backend: the rank's assembled rows (rank_rows_pattern, filled by assemble_poisson;
// consumed) and load (per local free dof), this rank owning [first_row, last_row) of the n
// global unknowns, become PETSc's distributed matrix and load (owned rows handed over as
// PETSc's two blocks, without a copy; the halo rows added to their owners'), are solved with
// the KSP/PC `petsc` names, and the rank's free values are written into sol.coefficients.
// Collective. Throws NotConverged when PETSc stops above its tolerance.
void solve_with_petsc(RankRows&& rows, const Eigen::VectorXd& load, const DofLayout& layout, int first_row,
                      int last_row, int n, const std::vector<int>& fixed_functions, const MeshPart& part,
                      const PoissonSolveOptions& options, const DistributedSolveOptions& petsc, PoissonSolution& sol);

}  // namespace knotwork
