#pragma once
#include <Eigen/Core>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

// The basis of one cell at quadrature points, in the form every integrator uses:
// the alive functions are R = C * Btilde, with Btilde the (rational) Bernstein
// polynomials of the cell, whose values and physical gradients are tabulated here.
// Planar cells (dimension 2): grad = J^{-T} grad_ref and measure = w |det J|. Surface cells
// (dimension 3): grad = J G^{-1} grad_ref with G = J^T J the first fundamental form (the
// surface gradient, tangent to the surface) and measure = w sqrt(det G). One formula for both:
// in the plane J G^{-1} = J^{-T}.
// Volume cells (hexahedra, parametric dimension 3): grad = J^{-T} grad_ref, measure = w |det J|.
struct CellBasis {
  int dimension = 2;  // of the physical space (the parametric one: geometry.parametric_dimension())
  Eigen::MatrixXd C;                    // alive functions x Bernstein (rational-adjusted)
  Eigen::VectorXd bernstein_weights;    // 1 for polynomial cells
  Eigen::MatrixXd value, grad_x, grad_y, grad_z;  // points x Bernstein (grad_z: surfaces only)
  Eigen::VectorXd measure;              // quadrature weight * |det J| or area element (|tangent| on a side)
  GeometryAtPoints geometry;
  Eigen::MatrixXd normal;               // outward unit normal (planar sides: 2 columns; a hexahedron's faces: 3)
  // Smallest det J at the points (planar: signed, <= 0 means the map folds; surfaces: the
  // area element sqrt(det G), <= 0 means it degenerates). Volume only.
  double min_jacobian = 0;
  // Physical gradient rows of Bernstein b at point k: grad(d) for d < dimension.
  const Eigen::MatrixXd& grad(int d) const { return d == 0 ? grad_x : d == 1 ? grad_y : grad_z; }
  // Scratch reused from cell to cell (no allocation per cell once sizes settle).
  Eigen::MatrixXd d_u, d_v, d_w, s_u, s_v;
  Eigen::ArrayXd det, inv_det, w, wu, wv, ww, gu, gv, guv;
};

// At the tensor Gauss points of an (nu x nv) rule on the cell.
void evaluate_cell_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu,
                         int nv, CellBasis& out);

// At arbitrary reference points (u_k, v_k) of the cell; measure holds the area element alone
// (no quadrature weight).
void evaluate_cell_basis_at(const BezierMesh& mesh, const GeometryMap& geometry, int cell, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, CellBasis& out);

// On a volume's hexahedral cell: at the tensor Gauss points of an (nu x nv x nw) rule, and at
// arbitrary reference points (u_k, v_k, w_k), where measure holds |det J| alone.
void evaluate_volume_cell_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu, int nv, int nw,
                                CellBasis& out);
void evaluate_volume_cell_basis_at(const BezierMesh& mesh, const GeometryMap& geometry, int cell,
                                   const Eigen::VectorXd& u, const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                   CellBasis& out);

// At an n-point Gauss rule along one side of the cell (a boundary edge), or on a hexahedron at
// the n x n-point rule of one face (kSideLeft/Right: u = 0/1, kSideBottom/Top: v = 0/1,
// kSideFront/Back: w = 0/1), with the face's area element and outward normal.
void evaluate_side_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell,
                         CellSide side, int n, CellBasis& out);

// One discrete function u_h = sum_i coefficient_i R_i on a cell, with its physical gradient
// (the surface gradient on surfaces): what error norms and sampling need. Cheaper than
// CellBasis, which tabulates every function: here the coefficients are taken to the
// Bernstein basis first (C^T) and only matrix-vector products remain.
struct CellField {
  int dimension = 2;
  Eigen::VectorXd value;
  Eigen::MatrixXd gradient;  // points x dimension
  Eigen::VectorXd measure;   // as in CellBasis
  GeometryAtPoints geometry;
  Eigen::VectorXd local, bernstein, weights, s, s_u, s_v, s_w, w, w_u, w_v, w_w;  // scratch
};

// At the tensor Gauss points of an (nu x nv) rule, for the global coefficient vector.
void evaluate_cell_field(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu, int nv,
                         const Eigen::VectorXd& coefficients, CellField& out);
// On a hexahedron, at the tensor Gauss points of an (nu x nv x nw) rule: u_h and its gradient
// from the cell's Bernstein coefficients of u_h (the functions' values are never formed).
void evaluate_volume_cell_field(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu, int nv, int nw,
                                const Eigen::VectorXd& coefficients, CellField& out);
// At arbitrary reference points (measure = the area element alone).
void evaluate_cell_field_at(const BezierMesh& mesh, const GeometryMap& geometry, int cell, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, const Eigen::VectorXd& coefficients, CellField& out);

// Bernstein indices (a + (p+1) c) whose trace on the side is not identically zero; on a
// hexahedron of degrees (p, q, r) (a + (p+1) b + (p+1)(q+1) c) those on the face.
std::vector<int> side_bernstein_indices(int p, int q, CellSide side);
std::vector<int> side_bernstein_indices(int p, int q, int r, CellSide side);

}  // namespace knotwork
