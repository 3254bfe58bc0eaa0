#pragma once
#include <Eigen/Core>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

// Most spaces are made of functions that are, on each cell, a product f(u) g(v) of two
// univariate splines (tensor B-splines and NURBS, knot segments, T-splines and PT-splines;
// not G1 macro-patch functions). Then a row of the cell's extraction matrix is the Kronecker
// product of a u-row and a v-row, and the functions' values and gradients at the tensor Gauss
// points are products of univariate tables: O(points x functions) work instead of the dense
// O(points x Bernstein x functions) of C * B. Found from the matrices alone (no family named).

// A row factored as C(a, i + (p+1) j) = u(a, i) v(a, j).
struct SeparableExtraction {
  Eigen::MatrixXd u, v;  // functions x (p+1), functions x (q+1)
};

// Factors every row of C (functions x (p+1)(q+1)), or returns false if some row is not a
// product to rounding (|C - u v^T| <= 1e-13 max|C(a, :)| entrywise).
bool factor_separable(const Eigen::MatrixXd& C, int p, int q, SeparableExtraction& out);

// The factored rows of every pooled extraction of the mesh; empty() where a matrix does not
// factor. Indexed by BezierMesh::extraction_id.
struct SeparableMesh {
  std::vector<SeparableExtraction> rows;
  std::vector<char> separable;
  explicit SeparableMesh(const BezierMesh& mesh);
  const SeparableExtraction* of_cell(const BezierMesh& mesh, int cell) const {
    const int id = mesh.extraction_id(cell);
    return separable[id] ? &rows[id] : nullptr;
  }
};

// The alive functions of one cell at the tensor Gauss points of an (nu x nv) rule, in the
// form a Gram product wants: values (rational where the mesh is), and the physical gradients
// (planar: J^{-T}; surfaces: the surface gradient, as in CellBasis) times sqrt(measure),
// stacked by coordinate, so that sum_q m_q grad R_a . grad R_b = (G^T G)_ab.
struct CellFunctions {
  int dimension = 2;
  Eigen::MatrixXd value;             // points x functions
  Eigen::MatrixXd scaled_gradients;  // (dimension x points) x functions
  Eigen::VectorXd measure;
  GeometryAtPoints geometry;
  double min_jacobian = 0;
  Eigen::MatrixXd U, Uu, V, Vv, Ru, Rv, mu;  // scratch
  Eigen::VectorXd weights, w, wu, wv;
};
void evaluate_cell_functions(const BezierMesh& mesh, const GeometryMap& geometry, const SeparableExtraction& rows,
                             int cell, int nu, int nv, CellFunctions& out);

}  // namespace knotwork
