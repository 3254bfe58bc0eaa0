#pragma once
#include <Eigen/Core>

#include "basis/bezier_mesh.hpp"
#include "solver/geometry_map.hpp"

namespace knotwork {

// The basis of one cell at quadrature points, in the form every integrator uses:
// the alive functions are R = C * Btilde, with Btilde the (rational) Bernstein
// polynomials of the cell, whose values and physical gradients are tabulated here.
struct CellBasis {
  Eigen::MatrixXd C;                    // alive functions x Bernstein (rational-adjusted)
  Eigen::VectorXd bernstein_weights;    // 1 for polynomial cells
  Eigen::MatrixXd value, grad_x, grad_y;  // points x Bernstein
  Eigen::VectorXd measure;              // quadrature weight * |det J| (or |tangent| on a side)
  GeometryAtPoints geometry;
  Eigen::MatrixX2d normal;              // outward unit normal (sides only)
  double min_jacobian = 0;              // smallest det J at the points (volume only)
  // Scratch reused from cell to cell (no allocation per cell once sizes settle).
  Eigen::MatrixXd d_u, d_v;
  Eigen::ArrayXd det, inv_det, w, wu, wv;
};

// At the tensor Gauss points of an (nu x nv) rule on the cell.
void evaluate_cell_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu,
                         int nv, CellBasis& out);

// At an n-point Gauss rule along one side of the cell (a boundary edge).
void evaluate_side_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell,
                         CellSide side, int n, CellBasis& out);

// Bernstein indices (a + (p+1) c) whose trace on the side is not identically zero.
std::vector<int> side_bernstein_indices(int p, int q, CellSide side);

}  // namespace knotwork
