#include "basis/core/nurbs_volume.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "basis/core/bezier_ops.hpp"
#include "basis/core/input_error.hpp"
#include "basis/core/nurbs_patch.hpp"
#include "quadrature/bernstein.hpp"

namespace knotwork {

void NurbsVolume::validate() const {
  static const char* names[3] = {"knots_u", "knots_v", "knots_w"};
  long count = 1;
  for (int d = 0; d < 3; ++d) {
    const BSplineBasis1D& b = bases[d];
    if (!b.is_open())
      throw std::invalid_argument(std::string(names[d]) + " is not open: the first and last knots must each be repeated degree+1 times");
    const auto m = b.multiplicities();
    for (size_t i = 1; i + 1 < m.size(); ++i)
      if (m[i] > b.degree())
        throw std::invalid_argument(std::string(names[d]) +
                                    " has an interior knot of multiplicity degree+1: the volume would be discontinuous");
    count *= b.num_functions();
  }
  if (control_points.rows() != count)
    throw std::invalid_argument("control_points has " + std::to_string(control_points.rows()) +
                                " points but the knot vectors need " + std::to_string(bases[0].num_functions()) + " x " +
                                std::to_string(bases[1].num_functions()) + " x " + std::to_string(bases[2].num_functions()) +
                                " = " + std::to_string(count));
  if (weights.size() != control_points.rows())
    throw std::invalid_argument("weights has " + std::to_string(weights.size()) + " entries but there are " +
                                std::to_string(control_points.rows()) + " control points");
  validate_net(control_points, weights);
}

VolumePointDerivatives volume_point_derivatives(const NurbsVolume& volume, const std::array<double, 3>& at,
                                                std::array<int, 3> span, bool second) {
  int degree[3], n[3];
  double table[3][3 * 16];  // values, first and second derivatives, of at most degree 15
  for (int d = 0; d < 3; ++d) {
    const BSplineBasis1D& b = volume.bases[d];
    degree[d] = b.degree();
    n[d] = b.num_functions();
    if (degree[d] > 15) throw std::invalid_argument("volume_point_derivatives: degree above 15");
    if (span[d] < 0) span[d] = b.find_span(at[d]);
    b.evaluate_derivatives(span[d], at[d], second ? 2 : 1, table[d]);
  }
  // Homogeneous (w x, w y, w z, w) and its derivatives, then the quotient rule.
  Eigen::Vector4d h = Eigen::Vector4d::Zero(), hd[3] = {h, h, h};
  Eigen::Vector4d hdd[3][3] = {{h, h, h}, {h, h, h}, {h, h, h}};  // with `second`: d^2 / (d a d b), a <= b
  for (int c = 0; c <= degree[2]; ++c)
    for (int b = 0; b <= degree[1]; ++b)
      for (int a = 0; a <= degree[0]; ++a) {
        const long i = (span[0] - degree[0] + a) + n[0] * ((span[1] - degree[1] + b) + static_cast<long>(n[1]) * (span[2] - degree[2] + c));
        const double w = volume.weights[i];
        const Eigen::Vector4d point(w * volume.control_points(i, 0), w * volume.control_points(i, 1),
                                    w * volume.control_points(i, 2), w);
        const double nu = table[0][a], nv = table[1][b], nw = table[2][c];
        const double du = table[0][degree[0] + 1 + a], dv = table[1][degree[1] + 1 + b], dw = table[2][degree[2] + 1 + c];
        h += point * (nu * nv * nw);
        hd[0] += point * (du * nv * nw);
        hd[1] += point * (nu * dv * nw);
        hd[2] += point * (nu * nv * dw);
        if (second) {
          const double d2[3] = {table[0][2 * (degree[0] + 1) + a], table[1][2 * (degree[1] + 1) + b],
                                table[2][2 * (degree[2] + 1) + c]};
          hdd[0][0] += point * (d2[0] * nv * nw);
          hdd[0][1] += point * (du * dv * nw);
          hdd[0][2] += point * (du * nv * dw);
          hdd[1][1] += point * (nu * d2[1] * nw);
          hdd[1][2] += point * (nu * dv * dw);
          hdd[2][2] += point * (nu * nv * d2[2]);
        }
      }
  VolumePointDerivatives out;
  out.weight = h[3];
  out.x = h.head<3>() / h[3];
  for (int d = 0; d < 3; ++d) out.jacobian.col(d) = (hd[d].head<3>() - out.x * hd[d][3]) / h[3];
  if (second)  // x = H / W: x_ab = (H_ab - x_a W_b - x_b W_a - x W_ab) / W
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b) {
        const Eigen::Vector3d x_ab = (hdd[a][b].head<3>() - out.jacobian.col(a) * hd[b][3] - out.jacobian.col(b) * hd[a][3] -
                                      out.x * hdd[a][b][3]) / h[3];
        for (int i = 0; i < 3; ++i) out.hessian[i](a, b) = out.hessian[i](b, a) = x_ab[i];
      }
  return out;
}

VolumeGeometryMap::VolumeGeometryMap(const BezierMesh& mesh, NurbsVolume volume)
    : VolumeGeometryMap(mesh, std::vector<NurbsVolume>{std::move(volume)}) {}

VolumeGeometryMap::VolumeGeometryMap(const BezierMesh& mesh, std::vector<NurbsVolume> volumes)
    : mesh_(mesh), volumes_(std::move(volumes)) {
  if (volumes_.empty()) throw std::logic_error("VolumeGeometryMap: no volume");
  for (const NurbsVolume& v : volumes_) v.validate();
  span_of_cell_.resize(mesh.num_cells());
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    if (cell.dimension != 3) throw std::logic_error("VolumeGeometryMap: the mesh's cells are not hexahedra");
    if (volumes_.size() > 1 && (cell.patch < 0 || cell.patch >= static_cast<int>(volumes_.size())))
      throw std::logic_error("VolumeGeometryMap: a cell of a volume that is not given");
    const double lo[3] = {cell.u0, cell.v0, cell.w0}, hi[3] = {cell.u1, cell.v1, cell.w1};
    for (int d = 0; d < 3; ++d) {
      const BSplineBasis1D& b = volume_of(c).bases[d];
      // The span of the cell's midpoint, so that a cell's faces use the cell's own polynomial.
      const int s = b.find_span(0.5 * (lo[d] + hi[d]));
      const auto& knots = b.knots();
      if (!(lo[d] >= knots[s] && hi[d] <= knots[s + 1]) || lo[d] < b.domain_begin() || hi[d] > b.domain_end()) {
        std::ostringstream m;
        m << "cell " << c << " ([" << lo[d] << ", " << hi[d] << "] along " << "uvw"[d]
          << ") does not lie inside one knot span of the volume";
        throw GeometryError(m.str());
      }
      span_of_cell_[c][d] = s;
    }
  }
}

void VolumeGeometryMap::evaluate_volume(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                        const Eigen::VectorXd& w, GeometryAtPoints& out) const {
  const BezierCell& c = mesh_.cell(cell);
  const double lo[3] = {c.u0, c.v0, c.w0}, size[3] = {c.u1 - c.u0, c.v1 - c.v0, c.w1 - c.w0};
  const Eigen::Index n = u.size();
  out.x.resize(n, 3);
  out.jacobian.resize(n, 9);
  for (Eigen::Index k = 0; k < n; ++k) {
    const std::array<double, 3> at{lo[0] + size[0] * u[k], lo[1] + size[1] * v[k], lo[2] + size[2] * w[k]};
    const VolumePointDerivatives p = volume_point_derivatives(volume_of(cell), at, span_of_cell_[cell]);
    for (int i = 0; i < 3; ++i) {
      out.x(k, i) = p.x[i];
      for (int j = 0; j < 3; ++j) out.jacobian(k, 3 * i + j) = p.jacobian(i, j) * size[j];  // d/d(reference)
    }
  }
}

bool VolumeGeometryMap::volume_second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                                  const Eigen::VectorXd& w, Eigen::MatrixXd& out, GeometryAtPoints* first) const {
  const BezierCell& c = mesh_.cell(cell);
  const double lo[3] = {c.u0, c.v0, c.w0}, size[3] = {c.u1 - c.u0, c.v1 - c.v0, c.w1 - c.w0};
  out.resize(u.size(), 18);
  if (first) {
    first->x.resize(u.size(), 3);
    first->jacobian.resize(u.size(), 9);
  }
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const std::array<double, 3> at{lo[0] + size[0] * u[k], lo[1] + size[1] * v[k], lo[2] + size[2] * w[k]};
    const VolumePointDerivatives p = volume_point_derivatives(volume_of(cell), at, span_of_cell_[cell], true);
    if (first)
      for (int i = 0; i < 3; ++i) {
        first->x(k, i) = p.x[i];
        for (int j = 0; j < 3; ++j) first->jacobian(k, 3 * i + j) = p.jacobian(i, j) * size[j];
      }
    for (int i = 0; i < 3; ++i) {
      int column = 6 * i;
      for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) out(k, column++) = p.hessian[i](a, b) * size[a] * size[b];  // d^2/d(reference)^2
    }
  }
  return true;
}

void VolumeGeometryMap::evaluate_volume_at_rule(int cell, int nu, int nv, int nw, GeometryAtPoints& out) const {
  // The rule's points, as the cell basis tabulates them (kept per rule: no Gauss rule per cell).
  const BernsteinTable& rule = bernstein_table(0, 0, 0, nu, nv, nw);
  evaluate_volume(cell, rule.point_u, rule.point_v, rule.point_w, out);
}

void VolumeGeometryMap::evaluate_at_rule(int, int, int, GeometryAtPoints&) const {
  throw std::logic_error("VolumeGeometryMap: a volume's cells take three reference coordinates");
}

void VolumeGeometryMap::evaluate(int, const Eigen::VectorXd&, const Eigen::VectorXd&, GeometryAtPoints&) const {
  throw std::logic_error("VolumeGeometryMap: a volume's cells take three reference coordinates");
}

BezierGeometryCell VolumeGeometryMap::bezier_cell(int cell) const {
  // On the cell (inside one knot span in each direction) the volume is a rational Bezier
  // hexahedron of its degrees, or of the cell's where those are higher (the same map, elevated):
  // its homogeneous form (w x, w y, w z, w) is polynomial, so interpolating it at the nodes of
  // that degree gives its Bernstein coefficients exactly.
  const BezierCell& c = mesh_.cell(cell);
  BezierGeometryCell g;
  const NurbsVolume& volume = volume_of(cell);
  g.degree_u = std::max<int>(c.degree_u, volume.bases[0].degree());
  g.degree_v = std::max<int>(c.degree_v, volume.bases[1].degree());
  g.degree_w = std::max<int>(c.degree_w, volume.bases[2].degree());
  const int nu = g.degree_u + 1, nv = g.degree_v + 1, nw = g.degree_w + 1;
  Eigen::MatrixXd homogeneous(nu * nv * nw, 4);
  const double lo[3] = {c.u0, c.v0, c.w0}, size[3] = {c.u1 - c.u0, c.v1 - c.v0, c.w1 - c.w0};
  for (int k = 0; k < nw; ++k)
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const std::array<double, 3> at{lo[0] + size[0] * i / g.degree_u, lo[1] + size[1] * j / g.degree_v,
                                       lo[2] + size[2] * k / g.degree_w};
        const VolumePointDerivatives p = volume_point_derivatives(volume_of(cell), at, span_of_cell_[cell]);
        homogeneous.row(i + nu * (j + nv * k)) << p.weight * p.x.transpose(), p.weight;
      }
  const Eigen::MatrixXd coefficients = bernstein_interpolant(g.degree_u, g.degree_v, g.degree_w, homogeneous);
  g.weights = coefficients.col(3);
  g.points = coefficients.leftCols(3).array().colwise() / g.weights.array();
  return g;
}

}  // namespace knotwork
