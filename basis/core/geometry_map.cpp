#include "basis/core/geometry_map.hpp"

#include <algorithm>
#include <sstream>

#include "basis/core/bezier_ops.hpp"
#include "basis/core/input_error.hpp"
#include "quadrature/bernstein.hpp"

namespace knotwork {

void dehomogenize_point(const double h[3], const double hu[3], const double hv[3], GeometryAtPoints& out,
                        Eigen::Index k) {
  const double w = h[2], x = h[0] / w, y = h[1] / w;
  out.x(k, 0) = x;
  out.x(k, 1) = y;
  out.jacobian(k, 0) = (hu[0] - x * hu[2]) / w;
  out.jacobian(k, 1) = (hv[0] - x * hv[2]) / w;
  out.jacobian(k, 2) = (hu[1] - y * hu[2]) / w;
  out.jacobian(k, 3) = (hv[1] - y * hv[2]) / w;
}

void dehomogenize_map(const Eigen::MatrixX3d& h, const Eigen::MatrixX3d& hu, const Eigen::MatrixX3d& hv,
                      GeometryAtPoints& out) {
  const Eigen::Index n = h.rows();
  out.x.resize(n, 2);
  out.jacobian.resize(n, 4);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double hk[3] = {h(k, 0), h(k, 1), h(k, 2)}, huk[3] = {hu(k, 0), hu(k, 1), hu(k, 2)},
                 hvk[3] = {hv(k, 0), hv(k, 1), hv(k, 2)};
    dehomogenize_point(hk, huk, hvk, out, k);
  }
}

namespace {
// Bezier control points interpolating a map at the cell's equispaced nodes.
BezierGeometryCell interpolated_bezier_cell(const GeometryMap& map, const BezierCell& c, int cell) {
  BezierGeometryCell g;
  g.degree_u = c.degree_u;
  g.degree_v = c.degree_v;
  const int n = (c.degree_u + 1) * (c.degree_v + 1);
  Eigen::VectorXd u(n), v(n);
  for (int j = 0; j <= c.degree_v; ++j)
    for (int i = 0; i <= c.degree_u; ++i) {
      u[i + (c.degree_u + 1) * j] = double(i) / c.degree_u;
      v[i + (c.degree_u + 1) * j] = double(j) / c.degree_v;
    }
  GeometryAtPoints at;
  map.evaluate(cell, u, v, at);
  g.points = bernstein_interpolation_inverse(c.degree_u, c.degree_v) * at.x;
  g.weights.setOnes(n);
  return g;
}
}  // namespace

AnalyticGeometryMap::AnalyticGeometryMap(const BezierMesh& mesh, Function map)
    : mesh_(mesh), map_(std::move(map)) {}

void AnalyticGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                   GeometryAtPoints& out) const {
  const BezierCell& c = mesh_.cell(cell);
  const double hu = c.u1 - c.u0, hv = c.v1 - c.v0;
  out.x.resize(u.size(), 2);
  out.jacobian.resize(u.size(), 4);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    double x[2], J[4];
    map_(c.u0 + hu * u[k], c.v0 + hv * v[k], x, J);
    out.x(k, 0) = x[0];
    out.x(k, 1) = x[1];
    out.jacobian(k, 0) = J[0] * hu;
    out.jacobian(k, 1) = J[1] * hv;
    out.jacobian(k, 2) = J[2] * hu;
    out.jacobian(k, 3) = J[3] * hv;
  }
}

void AnalyticGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  const BernsteinTable& t = bernstein_table(1, 1, nu, nv);
  evaluate(cell, t.point_u, t.point_v, out);
}

BezierGeometryCell AnalyticGeometryMap::bezier_cell(int cell) const {
  return interpolated_bezier_cell(*this, mesh_.cell(cell), cell);
}

BezierCellsGeometryMap::BezierCellsGeometryMap(std::vector<BezierGeometryCell> cells) : cells_(std::move(cells)) {
  if (!cells_.empty()) dimension_ = static_cast<int>(cells_[0].points.cols());
  if (dimension_ != 2 && dimension_ != 3)
    throw std::invalid_argument("Bezier geometry cells: points in R^2 or R^3 needed, got " + std::to_string(dimension_) +
                                " coordinates");
  for (size_t c = 0; c < cells_.size(); ++c) {
    const auto& g = cells_[c];
    if (g.points.rows() != (g.degree_u + 1) * (g.degree_v + 1))
      throw std::invalid_argument("Bezier geometry cell " + std::to_string(c) + ": (p+1)(q+1) control points needed");
    if (g.points.cols() != dimension_)
      throw std::invalid_argument("Bezier geometry cell " + std::to_string(c) + ": " + std::to_string(g.points.cols()) +
                                  " coordinates, the first cell has " + std::to_string(dimension_));
    if (g.weights.size() == 0) cells_[c].weights = Eigen::VectorXd::Ones(g.points.rows());
  }
}

namespace {
// Point and Jacobian (dx/du, dx/dv, dy/du, dy/dv[, dz/du, dz/dv]) from tabulated Bernstein values.
void bezier_map(const Eigen::MatrixXd& points, const Eigen::MatrixXd& value, const Eigen::MatrixXd& d_u,
                const Eigen::MatrixXd& d_v, GeometryAtPoints& out) {
  out.x.noalias() = value * points;
  out.jacobian.resize(value.rows(), 2 * points.cols());
  for (Eigen::Index d = 0; d < points.cols(); ++d) {
    out.jacobian.col(2 * d).noalias() = d_u * points.col(d);
    out.jacobian.col(2 * d + 1).noalias() = d_v * points.col(d);
  }
}
}  // namespace

void BezierCellsGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                      GeometryAtPoints& out) const {
  const BezierGeometryCell& g = cells_[cell];
  Eigen::MatrixXd value, d_u, d_v;
  tensor_bernstein(g.degree_u, g.degree_v, u, v, value, d_u, d_v);
  bezier_map(g.points, value, d_u, d_v, out);
}

void BezierCellsGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  const BezierGeometryCell& g = cells_[cell];
  const BernsteinTable& t = bernstein_table(g.degree_u, g.degree_v, nu, nv);
  bezier_map(g.points, t.value, t.d_u, t.d_v, out);
}

bool BezierCellsGeometryMap::second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                                Eigen::MatrixXd& out) const {
  const BezierGeometryCell& g = cells_[cell];
  Eigen::MatrixXd uu, uv, vv;
  tensor_bernstein_second(g.degree_u, g.degree_v, u, v, uu, uv, vv);
  out.resize(u.size(), 3 * g.points.cols());
  for (Eigen::Index d = 0; d < g.points.cols(); ++d) {
    out.col(3 * d).noalias() = uu * g.points.col(d);
    out.col(3 * d + 1).noalias() = uv * g.points.col(d);
    out.col(3 * d + 2).noalias() = vv * g.points.col(d);
  }
  return true;
}

}  // namespace knotwork
