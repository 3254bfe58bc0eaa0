#include "basis/core/nurbs_volume.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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

namespace {

// The homogeneous control points (w x, w y, w z, w) of the net's block over `span`, a then b
// then c (the order the sums below take them).
void gather_block(const NurbsVolume& volume, const std::array<int, 3>& span, const int* degree, double* block) {
  const long n0 = volume.bases[0].num_functions(), n1 = volume.bases[1].num_functions();
  for (int c = 0; c <= degree[2]; ++c)
    for (int b = 0; b <= degree[1]; ++b)
      for (int a = 0; a <= degree[0]; ++a, block += 4) {
        const long i = (span[0] - degree[0] + a) + n0 * ((span[1] - degree[1] + b) + n1 * (span[2] - degree[2] + c));
        const double w = volume.weights[i];
        block[0] = w * volume.control_points(i, 0);
        block[1] = w * volume.control_points(i, 1);
        block[2] = w * volume.control_points(i, 2);
        block[3] = w;
      }
}

// The map and its derivatives at one point from the net's block and the univariate tables of
// the three directions there (table[d]: the g + 1 values, then the first derivatives, then with
// `second` the second derivatives, of the functions alive on the cell's span): the homogeneous
// form and its derivatives summed over the block, then the quotient rule.
VolumePointDerivatives combine_tables(const double* block, const int* degree, const double* const* table, bool second) {
  double h[4] = {0, 0, 0, 0}, hd[3][4] = {}, hdd[3][3][4] = {};  // with `second`: d^2 / (d a d b), a <= b
  for (int c = 0; c <= degree[2]; ++c)
    for (int b = 0; b <= degree[1]; ++b)
      for (int a = 0; a <= degree[0]; ++a, block += 4) {
        const double nu = table[0][a], nv = table[1][b], nw = table[2][c];
        const double du = table[0][degree[0] + 1 + a], dv = table[1][degree[1] + 1 + b], dw = table[2][degree[2] + 1 + c];
        const double s = nu * nv * nw, su = du * nv * nw, sv = nu * dv * nw, sw = nu * nv * dw;
        for (int e = 0; e < 4; ++e) {
          h[e] += block[e] * s;
          hd[0][e] += block[e] * su;
          hd[1][e] += block[e] * sv;
          hd[2][e] += block[e] * sw;
        }
        if (second) {
          const double d2[3] = {table[0][2 * (degree[0] + 1) + a], table[1][2 * (degree[1] + 1) + b],
                                table[2][2 * (degree[2] + 1) + c]};
          const double s00 = d2[0] * nv * nw, s01 = du * dv * nw, s02 = du * nv * dw, s11 = nu * d2[1] * nw,
                       s12 = nu * dv * dw, s22 = nu * nv * d2[2];
          for (int e = 0; e < 4; ++e) {
            hdd[0][0][e] += block[e] * s00;
            hdd[0][1][e] += block[e] * s01;
            hdd[0][2][e] += block[e] * s02;
            hdd[1][1][e] += block[e] * s11;
            hdd[1][2][e] += block[e] * s12;
            hdd[2][2][e] += block[e] * s22;
          }
        }
      }
  VolumePointDerivatives out;
  out.weight = h[3];
  for (int e = 0; e < 3; ++e) out.x[e] = h[e] / h[3];
  for (int d = 0; d < 3; ++d)
    for (int e = 0; e < 3; ++e) out.jacobian(e, d) = (hd[d][e] - out.x[e] * hd[d][3]) / h[3];
  if (second)  // x = H / W: x_ab = (H_ab - x_a W_b - x_b W_a - x W_ab) / W
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b)
        for (int i = 0; i < 3; ++i)
          out.hessian[i](a, b) = out.hessian[i](b, a) =
              (hdd[a][b][i] - out.jacobian(i, a) * hd[b][3] - out.jacobian(i, b) * hd[a][3] - out.x[i] * hdd[a][b][3]) / h[3];
  return out;
}

}  // namespace

VolumePointDerivatives volume_point_derivatives(const NurbsVolume& volume, const std::array<double, 3>& at,
                                                std::array<int, 3> span, bool second) {
  int degree[3];
  double table[3][3 * 16];  // values, first and second derivatives, of at most degree 15
  for (int d = 0; d < 3; ++d) {
    const BSplineBasis1D& b = volume.bases[d];
    degree[d] = b.degree();
    if (degree[d] > 15) throw std::invalid_argument("volume_point_derivatives: degree above 15");
    if (span[d] < 0) span[d] = b.find_span(at[d]);
    b.evaluate_derivatives(span[d], at[d], second ? 2 : 1, table[d]);
  }
  const double* tables[3] = {table[0], table[1], table[2]};
  thread_local std::vector<double> block;  // kept: this runs once per point
  block.resize(size_t(4) * (degree[0] + 1) * (degree[1] + 1) * (degree[2] + 1));
  gather_block(volume, span, degree, block.data());
  return combine_tables(block.data(), degree, tables, second);
}

std::optional<AffineVolumeMap> affine_map(const NurbsVolume& volume) {
  const Eigen::VectorXd& w = volume.weights;
  if (w.size() == 0 || (w.array() - w[0]).abs().maxCoeff() > 64 * std::numeric_limits<double>::epsilon() * std::abs(w[0]))
    return std::nullopt;
  std::array<std::vector<double>, 3> g;
  std::array<long, 3> n;
  for (int d = 0; d < 3; ++d) {
    if (volume.bases[d].degree() < 1) return std::nullopt;
    g[d] = greville_abscissae(volume.bases[d]);
    n[d] = volume.bases[d].num_functions();
  }
  const Eigen::MatrixX3d& P = volume.control_points;
  const auto at = [&](long i, long j, long k) -> Eigen::Vector3d { return P.row(i + n[0] * (j + n[1] * k)).transpose(); };
  AffineVolumeMap m;
  m.jacobian.col(0) = (at(n[0] - 1, 0, 0) - at(0, 0, 0)) / (g[0].back() - g[0].front());
  m.jacobian.col(1) = (at(0, n[1] - 1, 0) - at(0, 0, 0)) / (g[1].back() - g[1].front());
  m.jacobian.col(2) = (at(0, 0, n[2] - 1) - at(0, 0, 0)) / (g[2].back() - g[2].front());
  m.origin = at(0, 0, 0) - m.jacobian * Eigen::Vector3d(g[0].front(), g[1].front(), g[2].front());
  const double size = P.cwiseAbs().maxCoeff() + m.jacobian.cwiseAbs().maxCoeff();
  const double tolerance = 64 * std::numeric_limits<double>::epsilon() * size;
  for (long k = 0; k < n[2]; ++k)
    for (long j = 0; j < n[1]; ++j)
      for (long i = 0; i < n[0]; ++i)
        if ((at(i, j, k) - m.origin - m.jacobian * Eigen::Vector3d(g[0][i], g[1][j], g[2][k])).cwiseAbs().maxCoeff() > tolerance)
          return std::nullopt;
  return m;
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
  // The rule's points (as the cell basis tabulates them: point i + nu (j + nv l)) form a grid, so
  // each direction's univariate functions are evaluated once per node, not once per point, and
  // the net's block is contracted one direction at a time (the same map as evaluate_volume's,
  // summed in another order: equal to rounding).
  const BernsteinTable& rule = bernstein_table(0, 0, 0, nu, nv, nw);
  const BezierCell& c = mesh_.cell(cell);
  const double lo[3] = {c.u0, c.v0, c.w0}, size[3] = {c.u1 - c.u0, c.v1 - c.v0, c.w1 - c.w0};
  const NurbsVolume& volume = volume_of(cell);
  const std::array<int, 3>& span = span_of_cell_[cell];
  const QuadratureRule1D* rules[3] = {&rule.rule_u, &rule.rule_v, &rule.rule_w};
  const int count[3] = {nu, nv, nw};
  int degree[3];
  thread_local std::vector<double> tables[3];  // per direction and node: the g + 1 values, then the derivatives
  for (int d = 0; d < 3; ++d) {
    const BSplineBasis1D& b = volume.bases[d];
    degree[d] = b.degree();
    if (degree[d] > 15) throw std::invalid_argument("evaluate_volume_at_rule: degree above 15");
    const int width = 2 * (degree[d] + 1);
    tables[d].resize(size_t(width) * count[d]);
    for (int i = 0; i < count[d]; ++i)
      b.evaluate_derivatives(span[d], lo[d] + size[d] * rules[d]->nodes[i], 1, tables[d].data() + size_t(width) * i);
  }
  const int g0 = degree[0] + 1, g1 = degree[1] + 1, g2 = degree[2] + 1;
  thread_local std::vector<double> block, along_u, along_uv;
  block.resize(size_t(4) * g0 * g1 * g2);
  gather_block(volume, span, degree, block.data());
  // Sum factorization, one direction at a time: O(n g^3) flops per cell rather than O(n g^3)
  // per point. Along u: (value, d/du) at node i for each (b, c), 4 homogeneous components.
  along_u.assign(size_t(8) * nu * g1 * g2, 0.0);
  for (int bc = 0; bc < g1 * g2; ++bc)
    for (int i = 0; i < nu; ++i) {
      const double* t = tables[0].data() + size_t(2 * g0) * i;
      double* o = along_u.data() + size_t(8) * (i + size_t(nu) * bc);
      for (int a = 0; a < g0; ++a) {
        const double* q = block.data() + size_t(4) * (a + size_t(g0) * bc);
        for (int e = 0; e < 4; ++e) o[e] += t[a] * q[e], o[4 + e] += t[g0 + a] * q[e];
      }
    }
  // Along v: (value, d/du, d/dv) at nodes (i, j) for each c.
  along_uv.assign(size_t(12) * nu * nv * g2, 0.0);
  for (int c2 = 0; c2 < g2; ++c2)
    for (int j = 0; j < nv; ++j) {
      const double* t = tables[1].data() + size_t(2 * g1) * j;
      for (int i = 0; i < nu; ++i) {
        double* o = along_uv.data() + size_t(12) * (i + size_t(nu) * (j + size_t(nv) * c2));
        for (int b2 = 0; b2 < g1; ++b2) {
          const double* q = along_u.data() + size_t(8) * (i + size_t(nu) * (b2 + size_t(g1) * c2));
          for (int e = 0; e < 4; ++e) {
            o[e] += t[b2] * q[e];
            o[4 + e] += t[b2] * q[4 + e];
            o[8 + e] += t[g1 + b2] * q[e];
          }
        }
      }
    }
  // Along w, then the quotient rule at each point: x = H / W, dx/da = (H_a - x W_a) / W.
  const Eigen::Index n = Eigen::Index(nu) * nv * nw;
  out.x.resize(n, 3);
  out.jacobian.resize(n, 9);
  for (int l = 0; l < nw; ++l) {
    const double* t = tables[2].data() + size_t(2 * g2) * l;
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        double h[4] = {}, hd[3][4] = {};
        for (int c2 = 0; c2 < g2; ++c2) {
          const double* q = along_uv.data() + size_t(12) * (i + size_t(nu) * (j + size_t(nv) * c2));
          for (int e = 0; e < 4; ++e) {
            h[e] += t[c2] * q[e];
            hd[0][e] += t[c2] * q[4 + e];
            hd[1][e] += t[c2] * q[8 + e];
            hd[2][e] += t[g2 + c2] * q[e];
          }
        }
        const Eigen::Index k = i + Eigen::Index(nu) * (j + Eigen::Index(nv) * l);
        for (int a = 0; a < 3; ++a) {
          const double x = h[a] / h[3];
          out.x(k, a) = x;
          for (int e = 0; e < 3; ++e) out.jacobian(k, 3 * a + e) = (hd[e][a] - x * hd[e][3]) / h[3] * size[e];  // d/d(reference)
        }
      }
  }
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
