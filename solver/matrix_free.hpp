#pragma once
// A Poisson operator applied without a matrix, over all of a space's functions: what a
// family with such an operator gives the driver (SplineSpace::matrix_free_operator), which
// then assembles nothing (docs/SOLVERS.md, "Without a matrix").
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <vector>

#include "basis/core/mesh_part.hpp"
#include "solver/expression.hpp"

namespace knotwork {

struct DofLayout;

class MatrixFreePoisson {
 public:
  virtual ~MatrixFreePoisson() = default;
  virtual int num_functions() const = 0;
  // y = K x (y overwritten).
  virtual void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const = 0;
  virtual Eigen::VectorXd diagonal() const = 0;
  // Whether apply_free serves `layout`: K applied to vectors over its free dofs alone, without
  // embedding them in vectors over all the functions (checked once by the caller).
  virtual bool applies_free(const DofLayout& /*layout*/) const { return false; }
  // y = K x over the free dofs of a layout that applies_free accepted (x and y by dof).
  virtual void apply_free(const DofLayout& /*layout*/, const Eigen::VectorXd& /*x*/, Eigen::VectorXd& /*y*/) const {}
  // F_a = int f R_a, f a planar source f(x, y).
  virtual Eigen::VectorXd load(const Expression& source) const = 0;
  // The most functions one function couples with (itself included): the attainable accuracy.
  virtual int max_row_nonzeros() const = 0;
  // Whether every element's map is affine: then a product costs a few small univariate
  // products per element, and CG without a matrix was measured faster than with one
  // (docs/SOLVERS.md, "Without a matrix"): what [solver] matrix = "auto" asks.
  virtual bool all_elements_affine() const { return false; }
  // The squared L2 and H1-seminorm errors of u_h = sum_a c_a R_a against the exact solution
  // (planar), by Gauss rules of points_u x points_v per cell (0: degree + 2, as error_norms),
  // and |u - u_h|^2_H1 per cell of the space's mesh in `h1_per_cell` when given. Over the
  // mesh's cells `cells` only (a process's own, in the mesh's cell order; 0 per cell outside),
  // as error_norms' squared_errors. False when the operator does not compute them (then
  // error_norms does).
  virtual bool squared_errors(const Eigen::VectorXd& /*coefficients*/, const ExactSolution& /*exact*/, int /*points_u*/,
                              int /*points_v*/, std::array<double, 2>& /*squares*/, Eigen::VectorXd* /*h1_per_cell*/,
                              CellRange /*cells*/ = {}) const {
    return false;
  }
  // Whether lower_matrix() can write K without the element loop: a tensor patch, from its
  // Kronecker form where the map is one affine map (O(1) work per entry) and by sum
  // factorization elsewhere (O(p^4) per function in 2D, not the element loop's O(p^6) per
  // cell): docs/SOLVERS.md, "The matrix from the Kronecker form" and "... by sum factorization".
  virtual bool assembles_lower() const { return false; }
  // Whether row_entries() serves: any row alone, at O(1) per entry (a distributed solve's
  // owned rows). A row by sum factorization would cost a whole band of element rows.
  virtual bool writes_rows() const { return false; }
  // How lower_matrix() writes K, as --json reports it (solver.assembly_method).
  virtual const char* assembly_method() const { return "kronecker_form"; }
  // K's lower triangle over the free dofs of `layout` (dof order is function order), with the
  // pattern lower_pattern_matrix gives the space's mesh (functions that share a cell), in
  // CHOLMOD's layout. Only where assembles_lower(); throws std::logic_error elsewhere.
  virtual Eigen::SparseMatrix<double> lower_matrix(const DofLayout& layout) const;
  // K's entries (row, columns[k]) into values[k], functions numbered as the operator's, by the
  // same sums: a distributed solve's owned rows, each written whole by its process. Only where
  // writes_rows(); throws std::logic_error elsewhere.
  virtual void row_entries(int row, int count, const int* columns, double* values) const;
  // Whether lower_pattern() gives that pattern (zero values) for any problem on the space, also
  // where the element loop must fill it (a curved or rational patch, variable coefficients):
  // a tensor patch's from its two univariate bases, O(1) per entry, where the mesh's walks
  // the cells of every function.
  virtual bool gives_pattern() const { return false; }
  virtual Eigen::SparseMatrix<double> lower_pattern(const DofLayout& layout) const;
  // Where gives_pattern(): the functions that share an element with `function` (itself
  // included), appended to `out` in ascending order: a distributed solve's owned rows.
  virtual void coupled_functions(int function, std::vector<int>& out) const;
};

}  // namespace knotwork
