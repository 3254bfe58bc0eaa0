#pragma once
// The pipeline every command shares, written once against the family interface: a case's
// space (through its family), the solve, and the benchmark case.
#include <memory>
#include <string>

#include "cases/case_file.hpp"
#include "cases/spline_space.hpp"
#include "solver/poisson_solver.hpp"

namespace knotwork {

// The case's space refined `level` times uniformly (converge's level; 0: as the case says),
// through its registered family; under mpirun with method = "petsc", this rank's part of it
// where the family builds parts. Throws InputError naming the case and field.
std::unique_ptr<SplineSpace> build_space(const CaseDescription& c, int level = 0, const ProgressFunction& progress = {});

// What the reports say of the whole space when a rank holds a part: its cells, its largest
// cell diagonal (collective then); and the cells a rank writes under mpirun.
int global_num_cells(const SplineSpace& space);
double global_mesh_size(const SplineSpace& space);
struct ParallelWorld;
CellRange cells_to_write(const SplineSpace& space, ParallelWorld world);

// Solves the case's problem on the space: the family's own refusal first (check_solvable),
// then the one Galerkin pipeline. A GeometryError gets the case file and "[geometry]" in
// front of its message; a solver failure the case file.
// How the linear system was solved: [solver] method and preconditioner as resolved for this
// space ("auto" decided), and a note when the choice is not the one asked for by name.
struct SolverReport {
  std::string method, preconditioner, note;
  bool matrix_free = false;  // CG applied K without a matrix ([solver] matrix)
  // Under PETSc, what knotwork's PCShell was built from: "diagonal" (K's diagonal),
  // "operator" (the space's operator, no matrix) or "whole_matrix" (gathered on every process).
  std::string shell_built_from;
  // The PETSc options BoomerAMG runs with in knotwork's CG: on a volume the options for 3D
  // (kBoomerAmgVolumeOptions) followed by the user's, which win; elsewhere the user's.
  std::string petsc_options;
};
// An adaptive loop's solves (studies/adaptive.cpp) on a family that keeps prolongations
// (SplineSpace::keep_prolongations), with [solver] preconditioner = "multigrid" or "auto":
// multigrid over the steps, each step's matrix a level (NestedMultigrid), and CG from the
// previous solution prolonged. solve_case then takes CG with it whatever the space offers.
class NestedMultigrid;
struct AdaptiveSolve {
  std::shared_ptr<NestedMultigrid> multigrid;  // the earlier steps' levels; the solve adds its own
  Eigen::VectorXd initial;                     // the previous step's solution prolonged (empty: 0)
  double energy_tolerance = 0;                 // PoissonSolveOptions::energy_tolerance (0: none)
};
PoissonSolution solve_case(const CaseDescription& c, const SplineSpace& space, Ordering ordering,
                           const ProgressFunction& progress = {}, SolverReport* report = nullptr,
                           AdaptiveSolve* adaptive = nullptr);

// The space's operator (SplineSpace::matrix_free_operator), or null where it has none or refuses
// this rule (its documented refusals: a degree or rule beyond its tables).
std::shared_ptr<const MatrixFreePoisson> space_operator(const SplineSpace& space, double stiffness, double reaction,
                                                        const QuadratureOptions& quadrature);

// Lets a serial solve that assembles its matrix take it from the space's operator where that
// operator writes it itself (a tensor patch with one affine map: its Kronecker form, the same
// matrix as the element loop's to rounding, docs/SOLVERS.md); solve_poisson decides per problem.
void assemble_by_operator_where_possible(const CaseDescription& c, const SplineSpace& space, PoissonSolveOptions& so);

// Inside a catch block: the exception being handled again, as the user's error. A solve that
// did not converge names [solver], a degenerate geometry "[geometry]", and another
// std::invalid_argument the case file; an InputError, and anything else, as it is.
[[noreturn]] void rethrow_as_case_error(const CaseDescription& c);

// The benchmark problem: unit square, u = sin(pi x) sin(pi y), degree p, n x n elements.
CaseDescription unit_square_benchmark_case(int p, int n);
CaseDescription unit_cube_benchmark_case(int p, int n);

}  // namespace knotwork
