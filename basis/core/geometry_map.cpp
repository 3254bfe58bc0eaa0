#include "basis/core/geometry_map.hpp"

#include <algorithm>
#include <sstream>

#include "basis/core/bezier_ops.hpp"
#include "basis/core/input_error.hpp"
#include "quadrature/bernstein.hpp"

namespace knotwork {

void dehomogenize_map(const Eigen::MatrixX3d& h, const Eigen::MatrixX3d& hu, const Eigen::MatrixX3d& hv,
                      GeometryAtPoints& out) {
  const Eigen::Index n = h.rows();
  out.x.resize(n, 2);
  out.jacobian.resize(n, 4);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double w = h(k, 2);
    const double x = h(k, 0) / w, y = h(k, 1) / w;
    out.x(k, 0) = x;
    out.x(k, 1) = y;
    out.jacobian(k, 0) = (hu(k, 0) - x * hu(k, 2)) / w;
    out.jacobian(k, 1) = (hv(k, 0) - x * hv(k, 2)) / w;
    out.jacobian(k, 2) = (hu(k, 1) - y * hu(k, 2)) / w;
    out.jacobian(k, 3) = (hv(k, 1) - y * hv(k, 2)) / w;
  }
}

PatchGeometryMap::PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch) : mesh_(mesh), patch_(std::move(patch)) {
  // Each cell is mapped by the patch's polynomial on the span that holds the cell's middle:
  // a cell across a knot of the patch would be mapped wrongly on one side of it.
  const std::vector<double> bu = patch_.basis_u.breakpoints(), bv = patch_.basis_v.breakpoints();
  const double eu = 1e-12 * (bu.back() - bu.front()), ev = 1e-12 * (bv.back() - bv.front());
  auto straddled = [](const std::vector<double>& b, double lo, double hi, double eps) -> const double* {
    const auto it = std::upper_bound(b.begin(), b.end(), lo + eps);
    return it != b.end() && *it < hi - eps ? &*it : nullptr;
  };
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    const double* u = straddled(bu, cell.u0, cell.u1, eu);
    const double* v = straddled(bv, cell.v0, cell.v1, ev);
    if (!u && !v) continue;
    std::ostringstream s;
    s << "cell " << c << " ([" << cell.u0 << ", " << cell.u1 << "] x [" << cell.v0 << ", " << cell.v1
      << "]) straddles the geometry's knot " << (u ? "u = " : "v = ") << (u ? *u : *v)
      << ": the map is a different polynomial on each side, so every cell must lie inside one knot span "
         "(put a knot there)";
    throw GeometryError(s.str());
  }
}

namespace {
// B-spline values and derivatives at the distinct parameters of one call: quadrature rules are
// tensor products, so a cell's points repeat a few u and v values (the estimator evaluates
// the map at every point of every cell and side: per point, it was 25% slower).
class DerivativeCache {
 public:
  DerivativeCache(const BSplineBasis1D& basis, int span, int order)
      : basis_(basis), span_(span), order_(order), size_((order + 1) * (basis.degree() + 1)) {}
  const double* at(double t) {
    for (size_t k = 0; k < params_.size(); ++k)
      if (params_[k] == t) return values_.data() + k * size_;
    params_.push_back(t);
    values_.resize(params_.size() * size_);
    basis_.evaluate_derivatives(span_, t, order_, values_.data() + (params_.size() - 1) * size_);
    return values_.data() + (params_.size() - 1) * size_;
  }

 private:
  const BSplineBasis1D& basis_;
  int span_, order_;
  size_t size_;
  std::vector<double> params_, values_;
};
}  // namespace

void PatchGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                GeometryAtPoints& out) const {
  const BezierCell& c = mesh_.cell(cell);
  const int p = patch_.basis_u.degree(), q = patch_.basis_v.degree(), nu = patch_.basis_u.num_functions();
  Eigen::MatrixX3d h(u.size(), 3), hu(u.size(), 3), hv(u.size(), 3);
  // Span from the cell's middle, so a point on a cell edge uses the cell's own polynomial.
  const int su = patch_.basis_u.find_span(0.5 * (c.u0 + c.u1)), sv = patch_.basis_v.find_span(0.5 * (c.v0 + c.v1));
  DerivativeCache cu(patch_.basis_u, su, 1), cv(patch_.basis_v, sv, 1);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double* du = cu.at(c.u0 + u[k] * (c.u1 - c.u0));
    const double* dv = cv.at(c.v0 + v[k] * (c.v1 - c.v0));
    h.row(k).setZero();
    hu.row(k).setZero();
    hv.row(k).setZero();
    for (int b = 0; b <= q; ++b)
      for (int a = 0; a <= p; ++a) {
        const int i = (su - p + a) + nu * (sv - q + b);
        const double w = patch_.weights[i];
        const Eigen::RowVector3d P(w * patch_.control_points(i, 0), w * patch_.control_points(i, 1), w);
        h.row(k) += du[a] * dv[b] * P;
        hu.row(k) += du[p + 1 + a] * dv[b] * P * (c.u1 - c.u0);  // derivative in the cell's reference u
        hv.row(k) += du[a] * dv[q + 1 + b] * P * (c.v1 - c.v0);
      }
  }
  dehomogenize_map(h, hu, hv, out);
}

bool PatchGeometryMap::second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                          Eigen::MatrixXd& out) const {
  const BezierCell& c = mesh_.cell(cell);
  const int p = patch_.basis_u.degree(), q = patch_.basis_v.degree(), nu = patch_.basis_u.num_functions();
  const double su_len = c.u1 - c.u0, sv_len = c.v1 - c.v0;
  const int su = patch_.basis_u.find_span(0.5 * (c.u0 + c.u1)), sv = patch_.basis_v.find_span(0.5 * (c.v0 + c.v1));
  DerivativeCache cu(patch_.basis_u, su, 2), cv(patch_.basis_v, sv, 2);
  out.resize(u.size(), 6);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double* du = cu.at(c.u0 + u[k] * su_len);
    const double* dv = cv.at(c.v0 + v[k] * sv_len);
    // Homogeneous map H = (w x, w y, w) and its derivatives in the cell's reference coordinates.
    Eigen::RowVector3d H = Eigen::RowVector3d::Zero(), Hu = H, Hv = H, Huu = H, Huv = H, Hvv = H;
    for (int b = 0; b <= q; ++b)
      for (int a = 0; a <= p; ++a) {
        const int i = (su - p + a) + nu * (sv - q + b);
        const double w = patch_.weights[i];
        const Eigen::RowVector3d P(w * patch_.control_points(i, 0), w * patch_.control_points(i, 1), w);
        const double n0 = du[a], n1 = du[p + 1 + a] * su_len, n2 = du[2 * (p + 1) + a] * su_len * su_len;
        const double m0 = dv[b], m1 = dv[q + 1 + b] * sv_len, m2 = dv[2 * (q + 1) + b] * sv_len * sv_len;
        H += n0 * m0 * P;
        Hu += n1 * m0 * P;
        Hv += n0 * m1 * P;
        Huu += n2 * m0 * P;
        Huv += n1 * m1 * P;
        Hvv += n0 * m2 * P;
      }
    // Quotient rule for g = h / w, one coordinate at a time.
    const double w = H[2];
    for (int d = 0; d < 2; ++d) {
      const double g = H[d] / w;
      const double gu = (Hu[d] - g * Hu[2]) / w, gv = (Hv[d] - g * Hv[2]) / w;
      out(k, 3 * d + 0) = (Huu[d] - 2 * gu * Hu[2] - g * Huu[2]) / w;
      out(k, 3 * d + 1) = (Huv[d] - gu * Hv[2] - gv * Hu[2] - g * Huv[2]) / w;
      out(k, 3 * d + 2) = (Hvv[d] - 2 * gv * Hv[2] - g * Hvv[2]) / w;
    }
  }
  return true;
}

void PatchGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  const BernsteinTable& t = bernstein_table(1, 1, nu, nv);
  evaluate(cell, t.point_u, t.point_v, out);
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

BezierGeometryCell PatchGeometryMap::bezier_cell(int cell) const {
  return interpolated_bezier_cell(*this, mesh_.cell(cell), cell);
}

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
