#pragma once
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/nurbs_patch.hpp"

namespace knotwork {

// Points and Jacobians of a geometry map on one cell, at reference points of [0,1]^2, in a
// physical space of dimension 2 (planar domains) or 3 (surfaces; MFEM's sdim != dim).
// x: points x dimension. jacobian: points x 2 dimension, columns (dx/du, dx/dv, dy/du, dy/dv
// [, dz/du, dz/dv]), derivatives with respect to the cell's reference coordinates, so a
// cell's parameter box never enters the solver. The first fundamental form is J^T J.
struct GeometryAtPoints {
  Eigen::MatrixXd x;
  Eigen::MatrixXd jacobian;
  int dimension() const { return static_cast<int>(x.cols()); }
};

// A cell's geometry as a (rational) Bezier patch, for exact VTK output.
struct BezierGeometryCell {
  int degree_u = 1, degree_v = 1;
  Eigen::MatrixXd points;   // (p+1)(q+1) control points x dimension, index a + (p+1) c
  Eigen::VectorXd weights;  // all 1 for polynomial cells
};

class GeometryMap {
 public:
  virtual ~GeometryMap() = default;
  // 2 for planar domains, 3 for surfaces in R^3.
  virtual int dimension() const { return 2; }
  // At the tensor Gauss points of an (nu x nv) rule (the fast path used per cell).
  virtual void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const = 0;
  // At arbitrary reference points.
  virtual void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                        GeometryAtPoints& out) const = 0;
  virtual BezierGeometryCell bezier_cell(int cell) const = 0;
  // Second derivatives with respect to the cell's reference coordinates at reference points,
  // columns (x_uu, x_uv, x_vv, y_uu, y_uv, y_vv[, z_uu, z_uv, z_vv]), for operators that need
  // the physical Hessian (the residual error estimator) or the curvature of a surface.
  // Returns false when the map cannot give them.
  virtual bool second_derivatives(int /*cell*/, const Eigen::VectorXd& /*u*/, const Eigen::VectorXd& /*v*/,
                                  Eigen::MatrixXd& /*out*/) const {
    return false;
  }
};

// x = (w x, w y) / w and its reference derivatives by the quotient rule, from homogeneous
// points h = (w x, w y, w) and their derivatives (rational maps).
void dehomogenize_map(const Eigen::MatrixX3d& h, const Eigen::MatrixX3d& hu, const Eigen::MatrixX3d& hv,
                      GeometryAtPoints& out);

// A NURBS patch evaluated directly at any parameter point, for cells that do not follow the
// patch's own knot grid (locally refined spaces in the patch's parameter domain).
// Bezier output interpolates the map at the cell's equispaced nodes (exact for polynomial
// patches of at most the cell's degree). Every cell must lie inside one knot span of the
// patch: the constructor throws GeometryError naming the first cell that straddles a knot.
class PatchGeometryMap final : public GeometryMap {
 public:
  PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch);
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override;
  bool second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                          Eigen::MatrixXd& out) const override;

 private:
  const BezierMesh& mesh_;
  NurbsPatch patch_;
};

// A map given by a function of the patch parameters (tests and manufactured maps).
// `map(u, v, x[2], J[4])` fills the point and the Jacobian (dx/du, dx/dv, dy/du, dy/dv).
class AnalyticGeometryMap final : public GeometryMap {
 public:
  using Function = std::function<void(double u, double v, double* x, double* jacobian)>;
  AnalyticGeometryMap(const BezierMesh& mesh, Function map);
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                GeometryAtPoints& out) const override;
  // Interpolates the map at equispaced nodes: exact only for polynomial maps of that degree.
  BezierGeometryCell bezier_cell(int cell) const override;

 private:
  const BezierMesh& mesh_;
  Function map_;
};

// A map given cell by cell as polynomial Bezier patches in R^2 or R^3 (e.g. the coordinates
// of a spline surface built by a family): exact, with its own Bezier cells for output.
// Every cell must have the same number of point columns (the dimension).
class BezierCellsGeometryMap final : public GeometryMap {
 public:
  explicit BezierCellsGeometryMap(std::vector<BezierGeometryCell> cells);
  int dimension() const override { return dimension_; }
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override { return cells_[cell]; }
  bool second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                          Eigen::MatrixXd& out) const override;
  int num_cells() const { return static_cast<int>(cells_.size()); }

 private:
  std::vector<BezierGeometryCell> cells_;
  int dimension_ = 2;
};

}  // namespace knotwork
