#pragma once
// A trivariate NURBS (a volume) and the map it gives the hexahedral cells of a space in its
// parameter domain (docs/VOLUMES.md). At a cell's Gauss rule the map is evaluated one direction
// at a time from univariate tables; at other points, point by point.
#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

// Open knot vectors in u, v and w; control points in R^3 numbered i + n_u j + n_u n_v k (u
// fastest); positive weights (all equal: a polynomial volume).
struct NurbsVolume {
  std::array<BSplineBasis1D, 3> bases;
  Eigen::MatrixX3d control_points;
  Eigen::VectorXd weights;
  // Throws std::invalid_argument naming what is wrong (counts, weights, open knots).
  void validate() const;
};

// x = origin + jacobian (u, v, w) in the volume's parameters.
struct AffineVolumeMap {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Matrix3d jacobian = Eigen::Matrix3d::Identity();
};
// The volume's map when it is one affine map (equal weights, and every control point the affine
// map of its Greville abscissae, to 64 eps of the net's size: linear precision makes those its
// only coefficients); none otherwise.
std::optional<AffineVolumeMap> affine_map(const NurbsVolume& volume);

// The volume's point and its derivatives (columns x_u, x_v, x_w) at the parameters (u, v, w),
// in the knot spans `span` (one per direction; -1: the span holding the parameter).
// With `second`, also the Hessians: hessian[i](a, b) = d^2 x_i / (d a d b), a, b in (u, v, w).
struct VolumePointDerivatives {
  Eigen::Vector3d x;
  Eigen::Matrix3d jacobian;
  double weight = 1;
  std::array<Eigen::Matrix3d, 3> hessian;
};
VolumePointDerivatives volume_point_derivatives(const NurbsVolume& volume, const std::array<double, 3>& at,
                                                std::array<int, 3> span = {-1, -1, -1}, bool second = false);

// The volume as the geometry of a mesh of hexahedra in its parameter domain. Every cell must
// lie inside one knot span of the volume in each direction: the constructor throws
// GeometryError naming the first that does not. Reference coordinates are the cell's [0,1]^3.
class VolumeGeometryMap final : public GeometryMap {
 public:
  VolumeGeometryMap(const BezierMesh& mesh, NurbsVolume volume);
  // Several volumes (a multipatch domain): cell c lies in volumes[cell(c).patch].
  VolumeGeometryMap(const BezierMesh& mesh, std::vector<NurbsVolume> volumes);
  int dimension() const override { return 3; }
  int parametric_dimension() const override { return 3; }
  void evaluate_volume_at_rule(int cell, int nu, int nv, int nw, GeometryAtPoints& out) const override;
  void evaluate_volume(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                       GeometryAtPoints& out) const override;
  // The two-coordinate calls of planar and surface maps: refused (std::logic_error).
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override;
  bool volume_second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                 Eigen::MatrixXd& out, GeometryAtPoints* first = nullptr) const override;

 private:
  const NurbsVolume& volume_of(int cell) const { return volumes_[volumes_.size() == 1 ? 0 : mesh_.cell(cell).patch]; }

  const BezierMesh& mesh_;
  std::vector<NurbsVolume> volumes_;
  std::vector<std::array<int, 3>> span_of_cell_;
};

}  // namespace knotwork
