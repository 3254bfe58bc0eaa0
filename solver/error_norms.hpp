#pragma once
#include <Eigen/Core>
#include <array>

#include "basis/core/bezier_mesh.hpp"
#include "solver/expression.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

struct ErrorNorms {
  double l2 = 0;        // ||u - u_h||_L2
  double h1_semi = 0;   // |u - u_h|_H1
  double h1 = 0;        // full H1 norm: sqrt(l2^2 + h1_semi^2)
};

// Errors of the discrete solution (one coefficient per function) against the exact
// solution, by Gauss quadrature per cell (error_points, default degree+2 per direction), on
// planar domains and surfaces alike (on a surface the exact gradient is projected onto the
// tangent plane: the surface gradient). `exact_offset` is subtracted from u first (the mean
// removed when the problem fixes the solution's mean to zero).
// `h1_semi_squared_per_cell` (optional) receives |u - u_h|^2_H1 of every cell: where the
// error sits (the sum is h1_semi^2).
ErrorNorms error_norms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coefficients, const ExactSolution& exact,
                       const QuadratureOptions& quadrature, Eigen::VectorXd* h1_semi_squared_per_cell = nullptr,
                       double exact_offset = 0);

// The squares of the L2 and H1-seminorm errors summed over the cells `cells` only: one rank's
// share, summed over ranks by the caller.
// `h1_semi_squared_per_cell` (optional) as in error_norms, 0 outside `cells`.
std::array<double, 2> squared_errors(const BezierMesh& mesh, const GeometryMap& geometry,
                                    const Eigen::VectorXd& coefficients, const ExactSolution& exact,
                                    const QuadratureOptions& quadrature, CellRange cells,
                                    Eigen::VectorXd* h1_semi_squared_per_cell = nullptr, double exact_offset = 0);

// Integral of the exact solution over the domain (or surface), by the error rule.
double exact_integral(const BezierMesh& mesh, const GeometryMap& geometry, const ExactSolution& exact,
                      const QuadratureOptions& quadrature);

// u_h and its physical (surface) gradient at reference points (u, v) of one cell: rows
// (value, dx, dy) in the plane, (value, dx, dy, dz) on surfaces.
Eigen::MatrixXd evaluate_solution(const BezierMesh& mesh, const GeometryMap& geometry,
                                  const Eigen::VectorXd& coefficients, int cell,
                                  const Eigen::VectorXd& u, const Eigen::VectorXd& v);

// The same on a volume's hexahedral cell at reference points (u, v, w): rows (value, dx, dy, dz).
Eigen::MatrixXd evaluate_volume_solution(const BezierMesh& mesh, const GeometryMap& geometry,
                                         const Eigen::VectorXd& coefficients, int cell, const Eigen::VectorXd& u,
                                         const Eigen::VectorXd& v, const Eigen::VectorXd& w);

// The exact solution minus `offset` at physical point k of x (rows: points; 2 or 3 columns).
double exact_at(ExpressionEvaluator& exact, const Eigen::MatrixXd& x, Eigen::Index k, double offset);

// A cell sampled on an (n+1) x (n+1) equispaced grid of its reference square (point
// i + (n+1) j, i along u), or a hexahedron on the (n+1)^3 grid of its cube (point
// i + (n+1) (j + (n+1) k)): physical points, u_h and its gradient (evaluate_solution's rows),
// and the exact solution minus exact_offset when an evaluator is given. What the sampled
// ParaView file and the Python module's Result.sample show. Reuse one CellSamples per thread.
struct CellSamples {
  int n = 0, dimension = 0;
  Eigen::VectorXd u, v, w;  // the grid, rebuilt when n or the cells' dimension changes
  GeometryAtPoints at;
  Eigen::MatrixXd uh;
  Eigen::VectorXd exact;  // empty without an evaluator
};
void sample_cell(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients, int cell,
                 int n, ExpressionEvaluator* exact, double exact_offset, CellSamples& out);

}  // namespace knotwork
