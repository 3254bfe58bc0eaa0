#pragma once
// Physical points to cells: which cell of a BezierMesh holds a point, and where in the cell's
// reference square [0,1]^2 (the inverse of the geometry map), for point probes and line plots
// of a solution (Python's Result.evaluate). Planar domains: the point's preimage. Surfaces:
// the closest point of the surface, accepted within a distance.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

struct LocatedPoint {
  int cell = -1;          // -1: not in the domain (nor within `distance` of the surface)
  double u = 0, v = 0;    // reference coordinates in the cell
  double distance = 0;    // |x(u, v) - p|: rounding in the plane, the distance to a surface
};

class PointLocator {
 public:
  // Indexes the cells by the boxes of their Bezier control points (each cell's image lies in
  // their convex hull), in the R-tree of basis/core/box_index.hpp.
  PointLocator(const BezierMesh& mesh, const GeometryMap& geometry);
  ~PointLocator();
  // p: dimension() coordinates. max_distance: on surfaces, the largest distance from the
  // surface accepted (planar domains ignore it: a point is inside or not). Thread-safe.
  LocatedPoint locate(const double* p, double max_distance) const;
  int dimension() const;
  // The diagonal of the box around every cell: a length scale for tolerances.
  double diameter() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A discrete function u_h = sum_i coefficients_i R_i and its physical gradient (the surface
// gradient on surfaces) at located points (every cell >= 0): value (n), gradient (n x dimension).
void evaluate_at_points(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients,
                        const std::vector<LocatedPoint>& points, Eigen::VectorXd& value, Eigen::MatrixXd& gradient);

}  // namespace knotwork
