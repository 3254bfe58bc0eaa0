#pragma once
#include "basis/core/bezier_mesh.hpp"
#include "basis/pt/pt_spline.hpp"

namespace knotwork {

// The BezierMesh of PT-splines: one cell per cell of the T-mesh (parameter box, boundary ids
// bottom 0, right 1, top 2, left 3 on the rectangle's sides), and as each alive function's
// extraction row its Bernstein coefficients on the cell. The basis should have been through
// make_boundary_traces_independent when Dirichlet data are imposed.
BezierMesh pt_bezier_mesh(const RectangularPartition& mesh, const PtCellPolynomials& polynomials, int m, int n);

}  // namespace knotwork
