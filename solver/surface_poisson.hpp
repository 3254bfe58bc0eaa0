#pragma once
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "basis/bezier_mesh.hpp"
#include "solver/error_norms.hpp"
#include "solver/expression.hpp"
#include "solver/linear_solver.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

// One cell of a surface in R^3 as a polynomial Bezier patch: (p+1)^2 control points, index
// a + (p+1) b (a along the cell's u), on the same cells as the BezierMesh it goes with.
struct SurfaceCell {
  int degree = 1;
  Eigen::MatrixX3d points;
};

// -Laplace_Beltrami(u) + reaction u = f on a closed surface Gamma (no boundary: the
// operator alone has the constants as kernel).
// reaction = 0: u is sought with zero mean over Gamma and f is made compatible by removing
// its mean (both reported). The system is solved with one coefficient pinned to zero (the
// one with the largest weight in the representation of the constant 1, so that the reduced
// matrix is positive definite), then the constant that gives zero mean is subtracted: the
// same solution as the Lagrange multiplier formulation, with a positive definite matrix for
// CHOLMOD.
// The source: `source` as written (f(x, y, z) at the surface points), or derived from the
// exact solution on the discrete surface itself (default): for u defined around Gamma,
//   Laplace_Beltrami(u) = trace(Hessian) - n.Hessian.n - kappa (grad u . n),
// kappa = -g^{ij} (x_ij . n) the sum of the principal curvatures of the discrete surface.
// Then the exact solution of the discrete surface's problem is known, and errors measure
// the discretization alone.
struct SurfaceProblem {
  std::optional<SurfaceExactSolution> exact;
  std::optional<Expression> source;
  double reaction = 0;
};

struct SurfaceSolution {
  Eigen::VectorXd coefficients;  // one per function of the BezierMesh
  int num_functions = 0;
  long matrix_nonzeros = 0;      // stored lower triangle
  CholeskyStats cholesky;
  std::optional<ErrorNorms> errors;  // with the exact solution's mean removed when reaction = 0
  double area = 0;
  double source_mean = 0;  // removed from f (reaction = 0)
  double exact_mean = 0;   // removed from the exact solution before comparing (reaction = 0)
};

// Throws std::invalid_argument if the cells do not match the mesh or the surface is not
// regular at a quadrature point; std::runtime_error if the system cannot be factored.
SurfaceSolution solve_surface_poisson(const BezierMesh& mesh, const std::vector<SurfaceCell>& cells,
                                      const SurfaceProblem& problem, const QuadratureOptions& quadrature);

// u_h and its surface gradient at reference points of a cell: rows (value, gx, gy, gz).
Eigen::MatrixX4d evaluate_surface_solution(const BezierMesh& mesh, const std::vector<SurfaceCell>& cells,
                                           const Eigen::VectorXd& coefficients, int cell, const Eigen::VectorXd& u,
                                           const Eigen::VectorXd& v);

}  // namespace knotwork
