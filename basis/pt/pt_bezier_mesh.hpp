#pragma once
#include <functional>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/pt/pt_spline.hpp"

namespace knotwork {

// The BezierMesh of PT-splines: one cell per cell of the T-mesh (parameter box, boundary ids
// bottom 0, right 1, top 2, left 3 on the rectangle's sides), and as each alive function's
// extraction row its Bernstein coefficients on the cell. The basis should have been through
// make_boundary_traces_independent when Dirichlet data are imposed.
BezierMesh pt_bezier_mesh(const RectangularPartition& mesh, const PtCellPolynomials& polynomials, int m, int n);

// The same mesh from the basis itself, with the exact Bernstein coefficients rounded once
// (the numbers of pt_bezier_mesh(mesh, to_double(pt_cell_polynomials_exact(...)), m, n)),
// computed a cell at a time: no cell's exact coefficients, and no function-by-function copy
// of the rounded ones, outlive the cell. Used for the spaces that are solved on.
BezierMesh pt_bezier_mesh(const PtSplineBasis& basis, const RectangularPartition& mesh);

namespace pt_detail {
// Calls visit(cell, functions, coefficients) for each cell of T in order: the functions not
// zero on it, increasing, and their exact Bernstein coefficients rounded once (one row per
// function, index a + (m + 1) b). pt_cell_polynomials.cpp.
void for_each_cell_polynomials_rounded(
    const PtSplineBasis& basis, const RectangularPartition& mesh,
    const std::function<void(int cell, const std::vector<int>& functions, Eigen::MatrixXd& coefficients)>& visit);
}  // namespace pt_detail

}  // namespace knotwork
