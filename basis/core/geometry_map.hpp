#pragma once
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/nurbs_patch.hpp"

namespace knotwork {

// Points and Jacobians of a geometry map on one cell, at reference points of [0,1]^2, in a
// physical space of dimension 2 (planar domains) or 3 (surfaces; MFEM's sdim != dim).
// x: points x dimension. jacobian: points x 2 dimension, columns (dx/du, dx/dv, dy/du, dy/dv
// [, dz/du, dz/dv]), derivatives with respect to the cell's reference coordinates, so a
// cell's parameter box never enters the solver. The first fundamental form is J^T J.
// On a volume's hexahedral cells (parametric dimension 3) the jacobian has nine columns,
// (dx/du, dx/dv, dx/dw, dy/du, ..., dz/dw): column i*d + j is the derivative of coordinate i
// along reference direction j in every case.
struct GeometryAtPoints {
  Eigen::MatrixXd x;
  Eigen::MatrixXd jacobian;
  int dimension() const { return static_cast<int>(x.cols()); }
  int parametric_dimension() const { return x.cols() > 0 ? static_cast<int>(jacobian.cols() / x.cols()) : 2; }
};

// A cell's geometry as a (rational) Bezier patch, for exact VTK output.
struct BezierGeometryCell {
  int degree_u = 1, degree_v = 1;
  int degree_w = 0;         // a hexahedron's (0: a quadrilateral)
  // (p+1)(q+1)(r+1) control points x dimension, index a + (p+1) b + (p+1)(q+1) c
  Eigen::MatrixXd points;
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
  // 2 for the quadrilateral cells of planar domains and surfaces, 3 for the hexahedra of a
  // volume, whose maps evaluate at three reference coordinates (the two calls below; the
  // two-coordinate calls above then throw std::logic_error).
  virtual int parametric_dimension() const { return 2; }
  virtual void evaluate_volume_at_rule(int /*cell*/, int /*nu*/, int /*nv*/, int /*nw*/, GeometryAtPoints& /*out*/) const {
    throw std::logic_error("evaluate_volume_at_rule: this map is not a volume's");
  }
  virtual void evaluate_volume(int /*cell*/, const Eigen::VectorXd& /*u*/, const Eigen::VectorXd& /*v*/,
                               const Eigen::VectorXd& /*w*/, GeometryAtPoints& /*out*/) const {
    throw std::logic_error("evaluate_volume: this map is not a volume's");
  }
  // Second derivatives with respect to the cell's reference coordinates at reference points,
  // columns (x_uu, x_uv, x_vv, y_uu, y_uv, y_vv[, z_uu, z_uv, z_vv]), for operators that need
  // the physical Hessian (the residual error estimator) or the curvature of a surface.
  // Returns false when the map cannot give them.
  virtual bool second_derivatives(int /*cell*/, const Eigen::VectorXd& /*u*/, const Eigen::VectorXd& /*v*/,
                                  Eigen::MatrixXd& /*out*/) const {
    return false;
  }
  // A volume's: columns (x_uu, x_uv, x_uw, x_vv, x_vw, x_ww, then y's, then z's), and with
  // `first` the points and Jacobians there too (one evaluation of the map for both). False
  // when the map cannot give them.
  virtual bool volume_second_derivatives(int /*cell*/, const Eigen::VectorXd& /*u*/, const Eigen::VectorXd& /*v*/,
                                         const Eigen::VectorXd& /*w*/, Eigen::MatrixXd& /*out*/,
                                         GeometryAtPoints* /*first*/ = nullptr) const {
    return false;
  }
};

// x = (w x, w y) / w and its reference derivatives by the quotient rule, from homogeneous
// points h = (w x, w y, w) and their derivatives (rational maps).
void dehomogenize_map(const Eigen::MatrixX3d& h, const Eigen::MatrixX3d& hu, const Eigen::MatrixX3d& hv,
                      GeometryAtPoints& out);
// The same at one point k of `out` (sized already), from h, h_u, h_v of that point.
void dehomogenize_point(const double h[3], const double hu[3], const double hv[3], GeometryAtPoints& out,
                        Eigen::Index k);

// The one NURBS map: a patch as the geometry of a space in its parameter domain (a tensor
// space's elements, or the cells of a locally refined space). Every cell must lie inside one
// knot span of the patch: the constructor throws GeometryError naming the first cell (or
// element) that straddles a knot. At quadrature points the patch is evaluated as given, of its
// own (low) degree, one direction at a time, from univariate tables made once per distinct
// cell interval and rule (thread-safe, kept); at other points directly; a cell's Bezier form
// is exact: the patch restricted to the cell, rational, raised to the cell's degree when that
// is higher.
class PatchGeometryMap final : public GeometryMap {
 public:
  PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch);
  // Cells that are a grid of elements: cell c is element (c % (u.size() - 1), first_row +
  // c / (u.size() - 1)) of the element boundaries u x v (the whole space's, also when the mesh
  // holds a part of it: a few rows from first_row on). No per-cell lookup.
  struct ElementGrid {
    std::vector<double> u, v;
    int first_row = 0;
  };
  PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch, ElementGrid grid);
  ~PatchGeometryMap() override;
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override;
  bool second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                          Eigen::MatrixXd& out) const override;
  // A grid map only: evaluate_at_rule on element (eu, ev) of the whole grid, whether or not
  // the mesh (a part) holds it.
  void evaluate_element_at_rule(int eu, int ev, int nu, int nv, GeometryAtPoints& out) const;

 private:
  PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch, const ElementGrid* grid);  // both public ones
  struct Interval {
    int span, element;  // the patch's knot span and its index among the patch's elements
    double from, length;
  };
  struct RuleTables;
  struct Lookup;
  void find_intervals();
  void check_intervals();
  void interval_at_rule(int iu, int iv, int nu, int nv, GeometryAtPoints& out) const;
  std::pair<int, int> intervals_of(int cell) const;
  const RuleTables& tables(bool along_u, int n) const;

  const BezierMesh& mesh_;
  NurbsPatch patch_;
  Eigen::MatrixX3d net_;  // homogeneous control points (w x, w y, w), numbered as the patch's
  // The patch's Bezier extraction per element and its breakpoints, per direction (Bezier cells).
  std::vector<Eigen::MatrixXd> extraction_u_, extraction_v_;
  std::vector<double> breaks_u_, breaks_v_;
  std::vector<Interval> intervals_u_, intervals_v_;
  int grid_columns_ = 0, first_row_ = 0;      // a grid map: its columns (else 0)
  std::vector<int> cell_u_, cell_v_;          // otherwise: each cell's intervals
  std::unique_ptr<Lookup> lookup_;
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

// Several maps side by side: the cells of piece k are cells first_cell[k] .. first_cell[k+1]-1
// of the whole mesh, and cell c of the whole is cell c - first_cell[k] of piece k (a multipatch
// domain: one patch map per patch, each over its own patch's mesh).
class PiecewiseGeometryMap final : public GeometryMap {
 public:
  PiecewiseGeometryMap(std::vector<std::unique_ptr<GeometryMap>> pieces, std::vector<int> first_cell);
  int dimension() const override { return pieces_.front()->dimension(); }
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override;
  bool second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                          Eigen::MatrixXd& out) const override;

 private:
  std::pair<const GeometryMap*, int> piece_of(int cell) const;
  std::vector<std::unique_ptr<GeometryMap>> pieces_;
  std::vector<int> first_cell_;
};

}  // namespace knotwork
