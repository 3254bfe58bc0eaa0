#pragma once
// The PETSc module (libknotwork_petsc.so, loaded on first use by solver/petsc_loader.cpp):
// MPI through PETSc, hypre's BoomerAMG as a preconditioner of knotwork's CG
// (solver/amg_preconditioner.hpp), and the distributed solve of `method = "petsc"`. Nothing
// here names a PETSc type: only the module links PETSc and MPI, and only runs that ask for
// them load their ~85 libraries.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "solver/assemble_poisson.hpp"
#include "solver/iterative_solver.hpp"

namespace knotwork {

// This process among the processes mpirun started (rank 0 of 1 without mpirun). The first
// call initializes PETSc and MPI.
struct ParallelWorld {
  int rank = 0, size = 1;
};
ParallelWorld parallel_world();

// The rank and size mpirun gave this process, read from OpenMPI's environment without loading
// anything (rank 0 of 1 when not started by mpirun).
ParallelWorld launched_world();

// Sums (or maximum) over all ranks, in place; every rank calls it.
void sum_over_ranks(double* values, int n);
void max_over_ranks(double* values, int n);

// Every rank calls it after a step some rank may have failed (kind 0: not failed). Returns the
// failure of the lowest failing rank, the same on every rank, or nothing: so that all ranks
// throw the same error instead of some waiting forever in the next collective call.
struct RankFailure {
  int rank = 0, kind = 0;
  std::string message;
};
std::optional<RankFailure> agree_on_failure(int kind, const std::string& message);
// Every rank's values one after the other (rank 0's first), on every rank; every rank calls it.
std::vector<double> gather_from_all_ranks(const std::vector<double>& mine);
// Rank 0's text on every rank; every rank calls it.
void broadcast_from_first(std::string& text);

// Whether agree_on_failure has returned a failure in this process (every rank then throws it).
bool failure_shared_by_all_ranks();

struct DistributedSolveOptions {
  // PETSc options for the KSP and its PC, after the defaults (CG + BoomerAMG); refused when
  // PETSc does not use one (std::invalid_argument).
  std::string petsc_options;
  // The normwise backward error ||b - A x||_inf / (||A||_inf ||x||_inf + ||b||_inf) at which
  // the KSP stops, as serial CG's (PETSc's own relative test where the options give -ksp_rtol
  // or -ksp_atol).
  double tolerance = 1e-15;
  int max_iterations = 1000;
  // The preconditioner: "boomeramg" (hypre), "jacobi" (PETSc's), or "shell": `shell`, one of
  // knotwork's, over all free dofs, applied on every rank to the gathered residual (each rank
  // keeps its rows): a PCShell.
  std::string preconditioner = "boomeramg";
  const Preconditioner* shell = nullptr;
  // Whether the shell is built from the whole matrix, gathered on every rank (whole_lower),
  // rather than from its diagonal alone.
  bool shell_reads_matrix = false;
  // The solution's entries this rank wants back (global rows, any order); null: all of them.
  const std::vector<int>* wanted_rows = nullptr;
};

struct DistributedSolveResult {
  Eigen::VectorXd solution;  // the wanted rows' values (DistributedSolveOptions), or every free dof
  int iterations = 0;
  double relative_residual = 0;  // ||b - A x|| / ||b||, computed after the solve
  double backward_error = 0;     // ||b - A x||_inf / (||A||_inf ||x||_inf + ||b||_inf), after the solve
  std::string tolerance_kind;    // "backward_error" (knotwork's stop) or "relative_residual" (PETSc's)
  bool converged = false;
  std::string reason;            // PETSc's KSPConvergedReason
  std::string ksp_type, pc_type, factor_package;  // what ran (after the user's options)
  long global_nonzeros = 0;                        // of the distributed matrix
  double matrix_seconds = 0, setup_seconds = 0, solve_seconds = 0;  // max over ranks
};

// The distributed matrix and load (a MATMPIAIJ and its vector), owned rows
// [first_row, last_row) on this rank. The rank gives its owned rows whole (their pattern and
// the values its own cells put there; PETSc keeps the arrays as they are, no copy, no count,
// no sort), then adds what its cells put in rows other ranks own, which finish_assembly sends
// there. No lock: every call comes from one thread.
class DistributedSystem {
 public:
  virtual ~DistributedSystem() = default;
  // Collective, once: the owned rows (solver/sparsity.hpp; the system keeps them for the
  // matrix's lifetime).
  virtual void set_owned_rows(OwnedRows&& rows) = 0;
  // After set_owned_rows: adds n entries to a row another rank owns (inside its pattern).
  virtual void add_to_row(int row, int n, const int* cols, const double* values) = 0;
  virtual void add_load(int n, const int* dofs, const double* values) = 0;
  // Collective: sends the entries of rows owned elsewhere; afterwards nothing can be added.
  virtual void finish_assembly() = 0;
  // Collective: the matrix's diagonal, every free dof, on every rank.
  virtual Eigen::VectorXd diagonal() = 0;
  // Collective: the whole matrix's lower triangle (its upper rows read as columns) on every
  // rank, for a preconditioner that every rank applies to the whole residual: as much memory
  // per rank as the serial matrix.
  virtual Eigen::SparseMatrix<double> whole_lower() = 0;
  // Collective: solves, and gathers the solution's wanted rows on each rank.
  virtual DistributedSolveResult solve(const DistributedSolveOptions& options) = 0;
  // Seconds this rank spent in set_owned_rows, add_to_row and finish_assembly (PETSc's share of assembly).
  virtual double assembly_seconds() const = 0;
};

// Collective. Throws std::runtime_error when PETSc fails (naming what it was doing).
std::unique_ptr<DistributedSystem> make_distributed_system(int num_free, int first_row, int last_row);

}  // namespace knotwork
