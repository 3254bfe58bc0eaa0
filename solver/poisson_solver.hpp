#pragma once
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "basis/core/bezier_mesh.hpp"
#include "solver/error_norms.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/condition_estimate.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/matrix_free.hpp"
#include "solver/linear_solver.hpp"
#include "solver/poisson_problem.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

struct PoissonTimings {
  double setup = 0;          // Dirichlet projection, dof numbering, sparsity pattern
  double assembly = 0;       // stiffness, load, Neumann terms
  double analysis = 0;       // CHOLMOD symbolic analysis (0 when reused)
  double factorization = 0;  // CHOLMOD numeric factorization
  double solve = 0;          // triangular solves
  double preconditioner = 0;  // iterative path: building the preconditioner
  double iterations = 0;      // iterative path: the CG iterations
  double errors = 0;         // error norms
};

struct PoissonSolveOptions {
  QuadratureOptions quadrature;
  // AMD on planar domains and surfaces, METIS on volumes: measured fastest (docs/PERFORMANCE.md,
  // docs/VOLUMES.md).
  Ordering ordering = Ordering::kAuto;
  bool compute_errors = true;  // when the problem has an exact solution
  bool cell_errors = false;    // also |u - u_h|^2_H1 per cell (PoissonSolution::cell_h1_squared)
  std::function<void(const std::string&)> progress;  // called at the start of each phase
  // Keep one solver across solves on the same mesh (other sources or boundary data): its
  // symbolic analysis is reused while the matrix pattern stays the same. Null: a new one.
  std::shared_ptr<SparseCholesky> solver;
  // The linear solve: CHOLMOD, or preconditioned CG to `tolerance` (relative residual) in at
  // most `max_iterations`, with the preconditioner `preconditioner` builds (null: Jacobi).
  bool iterative = false;
  double tolerance = 1e-15;  // on the backward error (IterativeStats)
  int max_iterations = 1000;
  std::function<std::unique_ptr<Preconditioner>(const DofLayout&, const Eigen::SparseMatrix<double>&)> preconditioner;
  // With `iterative` (serial): CG starts from these coefficients (one per function, their free
  // ones taken; an adaptive step's previous solution prolonged). Empty: from 0.
  Eigen::VectorXd initial;
  // With `iterative` (serial), > 0: CG also stops once its estimate of the algebraic error's
  // energy norm is at most this (preconditioned_cg's energy_tolerance; an adaptive step's
  // fraction of its error estimator). 0: the backward error `tolerance` alone.
  double energy_tolerance = 0;
  // With `iterative`: K applied without a matrix (nothing assembled: the load and the Dirichlet
  // lifting come from the operator, and `preconditioner` gets a matrix holding only K's
  // diagonal). Planar problems and volumes with constant coefficients, a given source and no
  // Nitsche terms, solved serially, without on_system or estimate_condition: solve_poisson
  // refuses others.
  std::function<std::shared_ptr<const MatrixFreePoisson>()> matrix_free;
  // Where the matrix is assembled, an operator that may write it itself
  // (MatrixFreePoisson::assembles_lower: a tensor patch or volume with one affine map) instead of the
  // element loop; its load, Dirichlet lifting and error norms are then used too. Taken only for
  // the problems `matrix_free` serves (and on_system, estimate_condition). For the others, or
  // where it cannot write the matrix, its pattern (gives_pattern) replaces the mesh's.
  // Distributed (called on every process; the operator over the process's mesh), each process
  // writes its owned rows and their load from it when every process can, else none does; no
  // pattern is taken from it there.
  std::function<std::shared_ptr<const MatrixFreePoisson>()> matrix_from_operator;
  // Called with the assembled system (lower triangle of K over the free dofs, and F)
  // before it is factored: for inspecting or exporting it, or benchmarking solvers on it.
  std::function<void(const Eigen::SparseMatrix<double>&, const Eigen::VectorXd&)> on_system;
  // Also estimate the extreme eigenvalues of the Jacobi-scaled stiffness and mass matrices
  // over the free dofs (PoissonSolution::stiffness_spectrum, mass_spectrum): two Lanczos
  // runs and a factorization each, so off by default.
  bool estimate_condition = false;
};

struct PoissonSolution {
  Eigen::VectorXd coefficients;  // one per basis function (Dirichlet ones included)
  int num_functions = 0;         // dimension of the discrete space
  int num_free = 0;              // unknowns of the linear system
  long matrix_nonzeros = 0;      // stored (lower triangle)
  CholeskyStats cholesky;
  IterativeStats iterative;  // the iterative path's count and final relative residual
  SpectrumEstimate stiffness_spectrum, mass_spectrum;  // with estimate_condition
  std::optional<ErrorNorms> errors;
  Eigen::VectorXd cell_h1_squared;  // with cell_errors: where the error sits (sums to h1_semi^2)
  PoissonTimings timings;
  // How K was made: "kronecker_form" or "sum_factorization" (the operator wrote it),
  // "element_loop", or "none" (CG applied K without a matrix).
  std::string assembly = "element_loop";
  // method = "petsc" (solver/petsc_backend.hpp): the processes, and what PETSc ran
  // (the KSP, the PC, the factorization package when a direct one) and why it stopped.
  struct Distributed {
    int ranks = 0;  // 0: not a PETSc solve
    int cells_held = 0;  // the most cells one rank held (its part, or the whole mesh)
    double peak_memory_mb = 0;  // the largest peak resident size of a rank, after the solve
    std::string ksp, pc, package, reason;
    // What stopped the KSP: "backward_error" (knotwork's test, as serial CG's) or
    // "relative_residual" (PETSc's own, where the options give -ksp_rtol or -ksp_atol).
    std::string stop;
  } distributed;
  // Closed surfaces with reaction = 0 (zero-mean solution): the surface's area, the mean
  // removed from f, and the exact solution's mean, removed before the errors are measured.
  bool zero_mean = false;
  double area = 0, source_mean = 0, exact_mean = 0;
};

// The whole Galerkin pipeline on one BezierMesh, planar or on a surface: Dirichlet projection,
// assembly with lifting, Neumann terms, CHOLMOD, error norms. A mesh without boundary sides
// (a closed surface) and reaction = 0 is solved for the zero-mean solution: one coefficient
// is pinned (the one with the largest weight in the representation of the constant 1, so the
// reduced matrix is positive definite), then the constant that gives zero mean is subtracted;
// the same solution as the Lagrange multiplier formulation.
// The iterative path stopped at max_iterations above the tolerance (or broke down): the
// message has the residual reached; no solution is returned.
struct NotConverged : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Whether some cell side lies on the boundary (false: a closed surface).
bool has_boundary(const BezierMesh& mesh);

// Whether a space's operator (MatrixFreePoisson) can stand for the element loop on this problem:
// planar or a volume (not a surface), constant coefficients, a given source, Dirichlet data by
// projection; the driver also asks for a boundary (no zero-mean solve).
bool operator_serves(const PoissonProblem& problem, const GeometryMap& geometry);

// Closed surface, reaction 0: the mass matrix gives the constant 1 in the basis (M one = the
// integrals of the functions), hence the area and the mean of f; the stiffness matrix with
// one coefficient pinned (`pin`, the largest entry of `one`) gives a solution, shifted to zero
// mean. `load` is the load of `load_form`'s source over every function. The whole mesh.
struct ZeroMeanData {
  Eigen::VectorXd one, integrals, load;
  double area = 0, source_mean = 0;
  int pin = 0;
  // The load of function f with f's mean removed (compatible with the pinned system).
  double compatible_load(int f) const { return load[f] - source_mean * integrals[f]; }
  // The coefficients shifted by a constant to zero mean.
  void remove_mean(Eigen::VectorXd& coefficients) const { coefficients -= (integrals.dot(coefficients) / area) * one; }
};
struct PoissonForm;
ZeroMeanData zero_mean_data(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& load_form,
                            const QuadratureOptions& quadrature, Ordering ordering);

// Under mpirun with method = "petsc": this rank's part of the space (null: every rank holds the
// whole mesh, built redundantly, whose cells and functions are then split into contiguous
// blocks) and PETSc's solver settings (solver/petsc_module.hpp).
struct DistributedSolveOptions;
struct Distribution {
  const MeshPart* part = nullptr;
  const DistributedSolveOptions* petsc = nullptr;
};

// The one driver: serial (distribution null: CHOLMOD, or CG with options.preconditioner) or on
// the processes mpirun started (PETSc), planar or on a surface, closed surfaces included. The
// same steps either way: the Dirichlet projection (from every rank's boundary cells), the
// zero-mean pin, the dof numbering, the assembly of this process's cells, the backend's solve,
// the mean removed, the error norms (summed over the ranks). Distributed, every rank calls it,
// a failure on one rank is thrown on all, the returned coefficients are per function of `mesh`
// (a part's own), and each phase's time is its slowest rank's. A closed surface needs the whole
// mesh on every rank (the constant's representation needs the whole mass matrix): with a part
// it is refused (std::invalid_argument).
PoissonSolution solve_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonProblem& problem,
                              const PoissonSolveOptions& options, const Distribution* distribution = nullptr);

}  // namespace knotwork
