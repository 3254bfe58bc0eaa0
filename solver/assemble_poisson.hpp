#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "basis/bezier_mesh.hpp"
#include "solver/geometry_map.hpp"
#include "solver/poisson_problem.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

// Stiffness (grad phi_i . grad phi_j) and load (f phi_i) over the free dofs, cell by cell
// through the BezierMesh, threaded with OpenMP. The Dirichlet lifting -K_{free,fixed} u_fixed
// goes to the right-hand side at the element level, so the full matrix never exists.
// `matrix` must hold the lower pattern (lower_pattern_matrix); its values are overwritten. Throws InputError when the
// geometry Jacobian is not positive at a quadrature point (naming the cell) or f is not finite.
void assemble_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const Expression& source,
                      const DofLayout& layout, const Eigen::VectorXd& fixed_values,
                      const QuadratureOptions& quadrature, Eigen::SparseMatrix<double>& matrix,
                      Eigen::VectorXd& rhs);

// Adds the Neumann terms (h phi_i over the Neumann sides) to rhs (free dofs).
void add_neumann_terms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const PoissonProblem& problem, const DofLayout& layout,
                       const QuadratureOptions& quadrature, Eigen::VectorXd& rhs);

// L2 projection of the Dirichlet data onto the traces of the functions that do not
// vanish on the Dirichlet sides. Returns one value per function (0 for the others) and
// marks those functions in `fixed`.
Eigen::VectorXd project_dirichlet_data(const BezierMesh& mesh, const GeometryMap& geometry,
                                       const PoissonProblem& problem,
                                       const QuadratureOptions& quadrature, std::vector<bool>& fixed);

// Number of quadrature points along u and v for a cell (0 in options means degree + extra).
inline int rule_points(int requested, int degree, int extra) {
  return requested > 0 ? requested : degree + extra;
}

}  // namespace knotwork
