#pragma once
#include <optional>
#include <string>
#include <vector>

#include "basis/core/mesh_part.hpp"
#include "solver/expression.hpp"

namespace knotwork {

enum class BoundaryKind { kDirichlet, kNeumann };

// One condition per boundary id of the BezierMesh (for a single patch: bottom, right,
// top, left). With from_exact the data come from the exact solution: u itself for
// Dirichlet, its normal derivative grad(u).n for Neumann.
struct BoundaryCondition {
  BoundaryKind kind = BoundaryKind::kDirichlet;
  bool from_exact = true;
  Expression value;  // g (Dirichlet) or h = du/dn (Neumann) when not from_exact
  // Neumann data given as a flux vector F, two entries in the plane: h = F.n with the outward
  // unit normal n (G+Smo's vector-valued Neumann functions). `value` is then unused.
  std::vector<Expression> flux;
};

// How Dirichlet sides are imposed. kProjection: strongly, the functions whose trace does not
// vanish there are fixed by the L2 projection of g onto their traces. kNitsche: weakly, by
// Nitsche's method (every function stays free; a penalty per boundary cell, from a local
// eigenvalue bound, keeps the form coercive). A C1 space ties the gradient at a boundary vertex
// to its boundary traces, so the projection's derivative error there enters the solution;
// Nitsche's method lets the Galerkin solution choose its trace (docs/MATH.md §4).
enum class DirichletMethod { kProjection, kNitsche };

// The variable coefficients of -div(A grad u) + c u = f. A is symmetric positive definite at
// every point: the identity (no entries), a scalar function a times the identity (one entry),
// in the plane the matrix [[a11, a12], [a12, a22]] (three entries, in that order), on a surface
// a 3x3 matrix (six entries a11 a12 a13 a22 a23 a33) whose tangential part P A P acts and must
// be positive definite on the tangent plane. c >= 0: the constant
// PoissonProblem::reaction, or a function (`reaction`, when given). The assembly refuses, naming
// the field and the point, an A that is not positive definite or a c that is negative at a
// quadrature point.
struct PoissonCoefficients {
  std::vector<Expression> diffusion;
  std::string diffusion_where;  // "file: [problem] coefficient", for messages about A as a whole
  Expression reaction;
  bool constant() const { return diffusion.empty() && reaction.empty(); }
};

// -div(A grad u) + c u = f in the domain or -div_G(A grad_G u) + c u = f on a surface (A and c as
// PoissonCoefficients say), with the boundary conditions above;
// Neumann data are the flux (A grad u).n. On a closed surface with c = 0 the operator has
// the constants as kernel: u is sought with zero mean and f is made compatible by removing its
// mean (solve_poisson reports both).
struct PoissonProblem {
  Expression source;  // empty on a surface: derived from `exact` on the discrete surface (PoissonForm)
  std::optional<ExactSolution> exact;
  std::vector<BoundaryCondition> boundary;
  double reaction = 0;
  PoissonCoefficients coefficients;
  DirichletMethod dirichlet_method = DirichletMethod::kProjection;
  // Nitsche's penalty on a boundary cell is nitsche_penalty * 2 lambda, with lambda the largest
  // ratio of the squared normal derivative on the cell's Dirichlet sides to the squared
  // gradient over the cell: > 1 makes the form coercive.
  double nitsche_penalty = 2;
};

struct QuadratureOptions {
  int points_u = 0, points_v = 0, points_w = 0;                    // matrix and load; 0 means degree+1
  int error_points_u = 0, error_points_v = 0, error_points_w = 0;  // error norms; 0 means degree+2
  // (w: the third direction of a volume's hexahedra)
  // Boundary integrals (the Dirichlet projection, Neumann data, Nitsche's terms): points per
  // side; 0 means one more than the interior rule has, -1 the interior rule's own number (as
  // GeoPDEs and G+Smo integrate: their discretizations to the last digit).
  int boundary_points = 0;
  // Cells whose functions are products f(u) g(v) are integrated from univariate tables
  // (solver/separable_cells); false forces the dense C * B path on every cell (the tests
  // compare the two).
  bool separable_cells = true;
};

// "projection" or "nitsche" when the problem has a Dirichlet side, else null (for reports).
inline const char* dirichlet_method_name(const PoissonProblem& p) {
  for (const BoundaryCondition& bc : p.boundary)
    if (bc.kind == BoundaryKind::kDirichlet)
      return p.dirichlet_method == DirichletMethod::kNitsche ? "nitsche" : "projection";
  return nullptr;
}

}  // namespace knotwork
