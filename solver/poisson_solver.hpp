#pragma once
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "basis/bezier_mesh.hpp"
#include "solver/error_norms.hpp"
#include "solver/geometry_map.hpp"
#include "solver/linear_solver.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

struct PoissonTimings {
  double setup = 0;          // Dirichlet projection, dof numbering, sparsity pattern
  double assembly = 0;       // stiffness, load, Neumann terms
  double analysis = 0;       // CHOLMOD symbolic analysis (0 when reused)
  double factorization = 0;  // CHOLMOD numeric factorization
  double solve = 0;          // triangular solves
  double errors = 0;         // error norms
};

struct PoissonSolveOptions {
  QuadratureOptions quadrature;
  Ordering ordering = Ordering::kAmd;  // measured fastest on IGA matrices: docs/PERFORMANCE.md
  bool compute_errors = true;  // when the problem has an exact solution
  std::function<void(const std::string&)> progress;  // called at the start of each phase
  // Keep one solver across solves on the same mesh (other sources or boundary data): its
  // symbolic analysis is reused while the matrix pattern stays the same. Null: a new one.
  std::shared_ptr<SparseCholesky> solver;
  // Called with the assembled system (lower triangle of K over the free dofs, and F)
  // before it is factored: for inspecting or exporting it, or benchmarking solvers on it.
  std::function<void(const Eigen::SparseMatrix<double>&, const Eigen::VectorXd&)> on_system;
};

struct PoissonSolution {
  Eigen::VectorXd coefficients;  // one per basis function (Dirichlet ones included)
  int num_functions = 0;         // dimension of the discrete space
  int num_free = 0;              // unknowns of the linear system
  long matrix_nonzeros = 0;      // stored (lower triangle)
  CholeskyStats cholesky;
  std::optional<ErrorNorms> errors;
  PoissonTimings timings;
};

// The whole Galerkin pipeline on one BezierMesh: Dirichlet projection, assembly with
// lifting, Neumann terms, CHOLMOD, error norms.
PoissonSolution solve_poisson(const BezierMesh& mesh, const GeometryMap& geometry,
                              const PoissonProblem& problem, const PoissonSolveOptions& options);

}  // namespace knotwork
