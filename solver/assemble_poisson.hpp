#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/mesh_part.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/poisson_problem.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

// What assemble_poisson integrates: the form
//   a(u, v) = stiffness (A grad u, grad v) + reaction (c u, v),   l(v) = (f, v),
// with A = I and c = 1 unless `coefficients` gives them (on a surface, A's tangential part),
// with grad the physical gradient of a planar domain or the surface gradient of a surface
// (Laplace-Beltrami): one routine for both, through the GeometryMap's dimension.
struct PoissonForm {
  double stiffness = 1;
  double reaction = 0;
  // Null or constant(): A = I and c = 1 (times `reaction`). Otherwise A and c are evaluated at
  // every quadrature point, and `reaction` must be 1 when c is a function.
  const PoissonCoefficients* coefficients = nullptr;
  // f(x, y[, z]). Null: derived from `exact` on the discrete surface itself,
  // f = -Laplace_Beltrami(u) + source_reaction u, with
  //   Laplace_Beltrami(u) = trace(Hess u) - n.(Hess u) n - kappa (grad u . n),
  // kappa = -G^{ij} (x_ij . n) the sum of the principal curvatures, so that the discrete
  // surface's problem has `exact` as its solution (needs the exact Hessian and a geometry
  // with second derivatives).
  const Expression* source = nullptr;
  const ExactSolution* exact = nullptr;
  double source_reaction = 0;  // the problem's reaction in the derived f (the matrix's may differ: a mass pass)
  // A and c in the derived f on a surface, -div_G(A grad_G u) + c u (null: A = I and c the
  // constant source_reaction); kept when a mass pass drops `coefficients` from the matrix.
  const PoissonCoefficients* source_coefficients = nullptr;
  bool load = true;  // false: the right-hand side gets only the Dirichlet lifting
  // Non-null: this problem's Dirichlet sides are imposed weakly by Nitsche's method, adding
  //   - (du/dn, v)_D - (u, dv/dn)_D + gamma (u, v)_D   to a(u, v),
  //   - (g, dv/dn)_D + gamma (g, v)_D                   to l(v),
  // with gamma constant on each boundary cell (PoissonProblem::nitsche_penalty).
  const PoissonProblem* nitsche = nullptr;
};

// How refusals name a cell: "cell c (u in [u0, u1], v in [v0, v1])", its parameter box.
std::string describe_cell(int c, double u0, double u1, double v0, double v1);

// The form of a problem: its coefficients, source (or exact solution to derive it from on a
// surface) and Nitsche data.
PoissonForm poisson_form(const PoissonProblem& problem);
// The plain mass matrix's form, (u, v), from a problem's form: no stiffness, coefficients,
// boundary terms or load, whatever the problem's.
PoissonForm mass_form(const PoissonForm& form);
// True when the problem has no reaction term (constant or variable).
bool without_reaction(const PoissonProblem& problem);

// Matrix and load of the form over the free dofs, cell by cell through the BezierMesh,
// threaded with OpenMP. The Dirichlet lifting -A_{free,fixed} u_fixed goes to the
// right-hand side at the element level, so the full matrix never exists.
// `matrix` must hold the lower pattern (lower_pattern_matrix); its values are overwritten.
// `integrals` (optional) receives the integral of every basis function (all functions).
// Throws GeometryError when det J (planar) or the area element (surfaces) is not positive at
// a quadrature point (naming the cell), InputError when f is not finite.
// `cells` restricts the integration to a block of cells (a process's share under mpirun).
void assemble_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& form,
                      const DofLayout& layout, const Eigen::VectorXd& fixed_values,
                      const QuadratureOptions& quadrature, Eigen::SparseMatrix<double>& matrix,
                      Eigen::VectorXd& rhs, Eigen::VectorXd* integrals = nullptr, CellRange cells = {});
// The same into a rank's rows of the distributed matrix (rank_rows_pattern; its values are
// overwritten): every cell of `cells` adds its rows whole, owned rows into PETSc's two blocks,
// the others into the halo rows.
void assemble_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& form,
                      const DofLayout& layout, const Eigen::VectorXd& fixed_values,
                      const QuadratureOptions& quadrature, RankRows& rows, Eigen::VectorXd& rhs, CellRange cells);

// Adds the Neumann terms (h phi_i over the Neumann sides of `cells`) to rhs (free dofs).
void add_neumann_terms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const PoissonProblem& problem, const DofLayout& layout,
                       const QuadratureOptions& quadrature, Eigen::VectorXd& rhs, CellRange cells = {});

// Nitsche's terms of the cells of `cells` that have a Dirichlet side, over each cell's alive
// functions (mesh.functions(cell) order): the boundary part of the matrix and of the load.
// Cells whose map is not regular are skipped (the element loop refuses them); throws
// GeometryError when a cell's stiffness matrix is numerically singular all the same.
struct NitscheCellTerms {
  int cell = -1;
  Eigen::MatrixXd matrix;
  Eigen::VectorXd load;
};
std::vector<NitscheCellTerms> nitsche_terms(const BezierMesh& mesh, const GeometryMap& geometry,
                                            const PoissonProblem& problem, const QuadratureOptions& quadrature,
                                            CellRange cells);

// L2 projection of the Dirichlet data onto the traces of the functions that do not vanish on
// the Dirichlet sides (none with DirichletMethod::kNitsche). Returns one value per function
// (0 for the others) and marks those functions in `fixed`.
Eigen::VectorXd project_dirichlet_data(const BezierMesh& mesh, const GeometryMap& geometry,
                                       const PoissonProblem& problem,
                                       const QuadratureOptions& quadrature, std::vector<bool>& fixed);

// The Dirichlet projection in two steps, so that ranks holding parts of a mesh can each bring
// their cells' share: the functions of `cells` whose trace on a Dirichlet side is not zero
// (numbered globally: part.global), and their boundary mass matrix and load entries
// there (function numbers; entries of the same pair add up).
struct DirichletPieces {
  std::vector<int> functions;
  std::vector<double> load;  // per entry of `functions`
  std::vector<Eigen::Triplet<double>> mass;
};
DirichletPieces dirichlet_pieces(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonProblem& problem,
                                 const QuadratureOptions& quadrature, CellRange cells, const MeshPart& part);
// The projected value of every function of the pieces (sorted by function number). Throws
// std::runtime_error when the traces are linearly dependent. The pieces are taken (their
// entries freed once the matrix's are made: on a volume they are most of the set-up's peak).
std::vector<std::pair<int, double>> solve_dirichlet_projection(DirichletPieces pieces);

// Number of quadrature points along u and v for a cell (0 in options means degree + extra).
inline int rule_points(int requested, int degree, int extra) {
  return requested > 0 ? requested : degree + extra;
}

}  // namespace knotwork
