#include "solver/point_location.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "basis/core/box_index.hpp"
#include "solver/cell_basis.hpp"

namespace knotwork {

struct PointLocator::Impl {
  const BezierMesh& mesh;
  const GeometryMap& geometry;
  int dim = 2;
  // Boxes in (x, y); on surfaces each cell's z-range is checked after the query.
  BoxIndex<double, int> index;
  std::vector<double> z_low, z_high;
  double diameter = 0, margin = 0;
  Impl(const BezierMesh& m, const GeometryMap& g) : mesh(m), geometry(g), dim(g.dimension()) {}
};

PointLocator::PointLocator(const BezierMesh& mesh, const GeometryMap& geometry)
    : impl_(std::make_unique<Impl>(mesh, geometry)) {
  Impl& d = *impl_;
  const int n = mesh.num_cells();
  std::vector<Eigen::VectorXd> low(n), high(n);
  Eigen::VectorXd all_low = Eigen::VectorXd::Constant(d.dim, std::numeric_limits<double>::infinity());
  Eigen::VectorXd all_high = -all_low;
  for (int c = 0; c < n; ++c) {
    const BezierGeometryCell b = geometry.bezier_cell(c);
    low[c] = b.points.colwise().minCoeff().transpose();
    high[c] = b.points.colwise().maxCoeff().transpose();
    all_low = all_low.cwiseMin(low[c]), all_high = all_high.cwiseMax(high[c]);
  }
  d.diameter = n > 0 ? (all_high - all_low).norm() : 0;
  // Points on a cell's edge must find it in spite of rounding in the boxes.
  d.margin = 1e-9 * d.diameter;
  std::vector<BoxIndex<double, int>::Entry> entries;
  entries.reserve(n);
  for (int c = 0; c < n; ++c)
    entries.emplace_back(BoxIndex<double, int>::box(low[c][0] - d.margin, low[c][1] - d.margin, high[c][0] + d.margin,
                                                    high[c][1] + d.margin),
                         c);
  d.index = BoxIndex<double, int>(entries);
  if (d.dim == 3) {
    d.z_low.resize(n), d.z_high.resize(n);
    for (int c = 0; c < n; ++c) d.z_low[c] = low[c][2], d.z_high[c] = high[c][2];
  }
}

PointLocator::~PointLocator() = default;
int PointLocator::dimension() const { return impl_->dim; }
double PointLocator::diameter() const { return impl_->diameter; }

LocatedPoint PointLocator::locate(const double* p, double max_distance) const {
  const Impl& d = *impl_;
  const int dim = d.dim;
  const Eigen::Map<const Eigen::VectorXd> target(p, dim);
  std::vector<int> candidates;
  d.index.intersecting(BoxIndex<double, int>::box(p[0], p[1], p[0], p[1]), candidates);
  std::sort(candidates.begin(), candidates.end());  // the lowest cell wins on shared edges
  const double reach = dim == 3 ? max_distance + d.margin : 0;
  LocatedPoint best;
  best.distance = std::numeric_limits<double>::infinity();
  GeometryAtPoints g;
  Eigen::VectorXd u(1), v(1);
  Eigen::MatrixXd J(dim, 2);
  for (int c : candidates) {
    if (dim == 3 && (p[2] < d.z_low[c] - reach || p[2] > d.z_high[c] + reach)) continue;
    // Newton's method on x(u, v) = p from the centre (Gauss-Newton on surfaces: the closest
    // point), steps kept within a band around the cell so that a miss cannot run away.
    double s = 0.5, t = 0.5;
    Eigen::VectorXd r(dim);
    for (int it = 0; it < 60; ++it) {
      u[0] = s, v[0] = t;
      d.geometry.evaluate(c, u, v, g);
      r = target - g.x.row(0).transpose();
      for (int k = 0; k < dim; ++k) J(k, 0) = g.jacobian(0, 2 * k), J(k, 1) = g.jacobian(0, 2 * k + 1);
      const Eigen::Vector2d step = (J.transpose() * J).ldlt().solve(J.transpose() * r);
      if (!step.allFinite()) break;
      s = std::clamp(s + step[0], -0.5, 1.5), t = std::clamp(t + step[1], -0.5, 1.5);
      if (step.norm() < 1e-14) break;
    }
    u[0] = s, v[0] = t;
    d.geometry.evaluate(c, u, v, g);
    const double distance = (target - g.x.row(0).transpose()).norm();
    // Inside the cell up to rounding (a point on an edge may land a hair outside).
    constexpr double kEdge = 1e-10;
    if (s < -kEdge || s > 1 + kEdge || t < -kEdge || t > 1 + kEdge) continue;
    const double accepted = dim == 3 ? max_distance : 1e-10 * d.diameter;
    if (distance > accepted || distance >= best.distance) continue;
    best.cell = c, best.u = std::clamp(s, 0.0, 1.0), best.v = std::clamp(t, 0.0, 1.0), best.distance = distance;
    if (dim == 2) break;  // a planar point has one preimage (up to shared edges)
  }
  return best;
}

void evaluate_at_points(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients,
                        const std::vector<LocatedPoint>& points, Eigen::VectorXd& value, Eigen::MatrixXd& gradient) {
  const int n = static_cast<int>(points.size()), dim = geometry.dimension();
  value.resize(n);
  gradient.resize(n, dim);
  CellField field;
  Eigen::VectorXd u(1), v(1);
  for (int k = 0; k < n; ++k) {
    u[0] = points[k].u, v[0] = points[k].v;
    evaluate_cell_field_at(mesh, geometry, points[k].cell, u, v, coefficients, field);
    value[k] = field.value[0];
    gradient.row(k) = field.gradient.row(0);
  }
}

}  // namespace knotwork
