#pragma once
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "basis/bezier_mesh.hpp"
#include "basis/tensor_patch.hpp"

namespace knotwork {

// Points and Jacobians of a geometry map on one cell, at reference points of [0,1]^2.
// jacobian rows: (dx/du, dx/dv, dy/du, dy/dv), derivatives with respect to the
// cell's reference coordinates, so a cell's parameter box never enters the solver.
struct GeometryAtPoints {
  Eigen::MatrixX2d x;
  Eigen::MatrixX4d jacobian;
};

// A cell's geometry as a (rational) Bezier patch, for exact VTK output.
struct BezierGeometryCell {
  int degree_u = 1, degree_v = 1;
  Eigen::MatrixX2d points;  // (p+1)(q+1) control points, index a + (p+1) c
  Eigen::VectorXd weights;  // all 1 for polynomial cells
};

class GeometryMap {
 public:
  virtual ~GeometryMap() = default;
  // At the tensor Gauss points of an (nu x nv) rule (the fast path used per cell).
  virtual void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const = 0;
  // At arbitrary reference points.
  virtual void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                        GeometryAtPoints& out) const = 0;
  virtual BezierGeometryCell bezier_cell(int cell) const = 0;
  // Second derivatives with respect to the cell's reference coordinates at reference points,
  // rows (x_uu, x_uv, x_vv, y_uu, y_uv, y_vv), for operators that need the physical Hessian
  // (the residual error estimator). Returns false when the map cannot give them.
  virtual bool second_derivatives(int /*cell*/, const Eigen::VectorXd& /*u*/, const Eigen::VectorXd& /*v*/,
                                  Eigen::MatrixXd& /*out*/) const {
    return false;
  }
};

// The NURBS geometry of a TensorDiscretization, cell by cell through its own extraction.
class NurbsGeometryMap final : public GeometryMap {
 public:
  explicit NurbsGeometryMap(const TensorDiscretization& d);
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override;
  // Homogeneous Bezier control points (w x, w y, w) of a cell, one row per Bernstein.
  void homogeneous_bezier(int cell, Eigen::MatrixX3d& out) const;

 private:
  int pu_, pv_, nu_, elements_u_;
  std::vector<int> spans_u_, spans_v_;
  std::vector<Eigen::MatrixXd> cu_, cv_;
  Eigen::MatrixX3d net_;
};

// A NURBS patch evaluated directly at any parameter point, for cells that do not follow the
// patch's own knot grid (knot-segment and T-mesh spaces in the patch's parameter domain).
// Bezier output interpolates the map at the cell's equispaced nodes (exact for polynomial
// patches of at most the cell's degree).
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

// A map given cell by cell as polynomial Bezier patches (e.g. the coordinates of a G1 spline
// surface, `g1_cell_bernstein`): exact, with its own Bezier cells for output.
class BezierCellsGeometryMap final : public GeometryMap {
 public:
  explicit BezierCellsGeometryMap(std::vector<BezierGeometryCell> cells);
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override { return cells_[cell]; }

 private:
  std::vector<BezierGeometryCell> cells_;
};

}  // namespace knotwork
