#include "solver/cell_basis.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

#include "quadrature/bernstein.hpp"

namespace knotwork {

namespace {

// From Bernstein values/derivatives in reference coordinates to rational values and
// physical gradients; fills measure with weight * det J. Works in out's scratch.
void finish(const Eigen::MatrixXd& B, const Eigen::MatrixXd& Bu, const Eigen::MatrixXd& Bv,
            const Eigen::VectorXd& rule_weight, bool rational, CellBasis& out) {
  const Eigen::VectorXd& wb = out.bernstein_weights;
  const Eigen::MatrixXd* Ru = &Bu;
  const Eigen::MatrixXd* Rv = &Bv;
  if (rational) {
    out.w = (B * wb).array().inverse();  // 1 / W
    out.wu = (Bu * wb).array() * out.w;  // W_u / W
    out.wv = (Bv * wb).array() * out.w;
    out.value.noalias() = out.w.matrix().asDiagonal() * B * wb.asDiagonal();
    out.d_u.noalias() = out.w.matrix().asDiagonal() * Bu * wb.asDiagonal();
    out.d_u.noalias() -= out.wu.matrix().asDiagonal() * out.value;
    out.d_v.noalias() = out.w.matrix().asDiagonal() * Bv * wb.asDiagonal();
    out.d_v.noalias() -= out.wv.matrix().asDiagonal() * out.value;
    Ru = &out.d_u;
    Rv = &out.d_v;
  } else {
    out.value = B;
  }
  const auto& J = out.geometry.jacobian;
  out.dimension = out.geometry.dimension();
  if (out.dimension == 2) {
    out.det = J.col(0).array() * J.col(3).array() - J.col(1).array() * J.col(2).array();
    out.min_jacobian = out.det.minCoeff();
    out.inv_det = out.det.inverse();
    out.grad_x.noalias() = (J.col(3).array() * out.inv_det).matrix().asDiagonal() * *Ru;
    out.grad_x.noalias() -= (J.col(2).array() * out.inv_det).matrix().asDiagonal() * *Rv;
    out.grad_y.noalias() = (J.col(0).array() * out.inv_det).matrix().asDiagonal() * *Rv;
    out.grad_y.noalias() -= (J.col(1).array() * out.inv_det).matrix().asDiagonal() * *Ru;
    out.grad_z.resize(0, 0);
    out.measure = (rule_weight.array() * out.det.abs()).matrix();
    return;
  }
  // Surface: G = [[E, F], [F, H]] with E = x_u.x_u, F = x_u.x_v, H = x_v.x_v; G^{-1} applied to
  // the reference gradient, then mapped by J: grad = x_u (H f_u - F f_v)/det + x_v (E f_v - F f_u)/det.
  out.gu = J.col(0).array().square() + J.col(2).array().square() + J.col(4).array().square();   // E
  out.guv = J.col(0).array() * J.col(1).array() + J.col(2).array() * J.col(3).array() +
            J.col(4).array() * J.col(5).array();                                                 // F
  out.gv = J.col(1).array().square() + J.col(3).array().square() + J.col(5).array().square();   // H
  out.det = out.gu * out.gv - out.guv.square();
  out.min_jacobian = out.det.minCoeff() > 0 ? out.det.sqrt().minCoeff() : out.det.minCoeff();
  out.inv_det = out.det.inverse();
  // Coefficients of x_u and x_v in the gradient, as row scalings of Ru and Rv.
  out.s_u.noalias() = (out.gv * out.inv_det).matrix().asDiagonal() * *Ru;    // a = (H f_u - F f_v)/det
  out.s_u.noalias() -= (out.guv * out.inv_det).matrix().asDiagonal() * *Rv;
  out.s_v.noalias() = (out.gu * out.inv_det).matrix().asDiagonal() * *Rv;    // b = (E f_v - F f_u)/det
  out.s_v.noalias() -= (out.guv * out.inv_det).matrix().asDiagonal() * *Ru;
  for (int d = 0; d < 3; ++d) {
    Eigen::MatrixXd& g = d == 0 ? out.grad_x : d == 1 ? out.grad_y : out.grad_z;
    g.noalias() = J.col(2 * d).asDiagonal() * out.s_u;
    g.noalias() += J.col(2 * d + 1).asDiagonal() * out.s_v;
  }
  out.measure = (rule_weight.array() * out.det.abs().sqrt()).matrix();
}


// The same on a hexahedron: rational values and reference derivatives along u, v, w, then
// grad = J^{-T} grad_ref point by point (J = d x / d reference, 3 x 3), measure = weight |det J|.
void finish_volume(const Eigen::MatrixXd& B, const Eigen::MatrixXd& Bu, const Eigen::MatrixXd& Bv,
                   const Eigen::MatrixXd& Bw, const Eigen::VectorXd& rule_weight, bool rational, CellBasis& out) {
  const Eigen::VectorXd& wb = out.bernstein_weights;
  const Eigen::MatrixXd* R[3] = {&Bu, &Bv, &Bw};
  if (rational) {
    out.w = (B * wb).array().inverse();  // 1 / W
    out.value.noalias() = out.w.matrix().asDiagonal() * B * wb.asDiagonal();
    Eigen::MatrixXd* d[3] = {&out.d_u, &out.d_v, &out.d_w};
    Eigen::ArrayXd* wd[3] = {&out.wu, &out.wv, &out.ww};
    for (int j = 0; j < 3; ++j) {
      *wd[j] = (*R[j] * wb).array() * out.w;  // W_j / W
      d[j]->noalias() = out.w.matrix().asDiagonal() * *R[j] * wb.asDiagonal();
      d[j]->noalias() -= wd[j]->matrix().asDiagonal() * out.value;
      R[j] = d[j];
    }
  } else {
    out.value = B;
  }
  const Eigen::MatrixXd& J = out.geometry.jacobian;
  const Eigen::Index n = J.rows(), nb = B.cols();
  out.dimension = 3;
  out.det.resize(n);
  out.grad_x.resize(n, nb);
  out.grad_y.resize(n, nb);
  out.grad_z.resize(n, nb);
  Eigen::MatrixXd* grad[3] = {&out.grad_x, &out.grad_y, &out.grad_z};
  // J^{-T} per point first, then each gradient a column at a time (the tables are column-major:
  // a row per point would be read with a stride).
  thread_local Eigen::Matrix<double, Eigen::Dynamic, 9> inverse_transpose;  // kept: this runs once per cell
  inverse_transpose.resize(n, 9);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::Matrix3d Jk;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Jk(i, j) = J(k, 3 * i + j);
    out.det[k] = Jk.determinant();
    const Eigen::Matrix3d it = Jk.inverse().transpose();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) inverse_transpose(k, 3 * i + j) = it(i, j);
  }
  for (int i = 0; i < 3; ++i)
    grad[i]->noalias() = inverse_transpose.col(3 * i).asDiagonal() * *R[0] + inverse_transpose.col(3 * i + 1).asDiagonal() * *R[1] +
                         inverse_transpose.col(3 * i + 2).asDiagonal() * *R[2];
  out.min_jacobian = out.det.minCoeff();
  out.measure = (rule_weight.array() * out.det.abs()).matrix();
}

}  // namespace

void evaluate_volume_cell_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu, int nv, int nw,
                                CellBasis& out) {
  const BezierCell& c = mesh.cell(cell);
  if (c.dimension != 3) throw std::logic_error("evaluate_volume_cell_basis: not a hexahedron");
  const BernsteinTable& t = bernstein_table(c.degree_u, c.degree_v, c.degree_w, nu, nv, nw);
  rational_cell_extraction(mesh, cell, out.bernstein_weights, out.C);
  geometry.evaluate_volume_at_rule(cell, nu, nv, nw, out.geometry);
  finish_volume(t.value, t.d_u, t.d_v, t.d_w, t.weight, mesh.is_rational(), out);
}

void evaluate_volume_cell_basis_at(const BezierMesh& mesh, const GeometryMap& geometry, int cell,
                                   const Eigen::VectorXd& u, const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                   CellBasis& out) {
  const BezierCell& c = mesh.cell(cell);
  if (c.dimension != 3) throw std::logic_error("evaluate_volume_cell_basis_at: not a hexahedron");
  Eigen::MatrixXd B, Bu, Bv, Bw;
  tensor_bernstein(c.degree_u, c.degree_v, c.degree_w, u, v, w, B, Bu, Bv, Bw);
  rational_cell_extraction(mesh, cell, out.bernstein_weights, out.C);
  geometry.evaluate_volume(cell, u, v, w, out.geometry);
  finish_volume(B, Bu, Bv, Bw, Eigen::VectorXd::Ones(u.size()), mesh.is_rational(), out);
}

void evaluate_cell_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu,
                         int nv, CellBasis& out) {
  const BezierCell& c = mesh.cell(cell);
  if (c.dimension != 2) throw std::logic_error("evaluate_cell_basis: a hexahedron (use evaluate_volume_cell_basis)");
  const BernsteinTable& t = bernstein_table(c.degree_u, c.degree_v, nu, nv);
  rational_cell_extraction(mesh, cell, out.bernstein_weights, out.C);
  geometry.evaluate_at_rule(cell, nu, nv, out.geometry);
  finish(t.value, t.d_u, t.d_v, t.weight, mesh.is_rational(), out);
}

void evaluate_cell_basis_at(const BezierMesh& mesh, const GeometryMap& geometry, int cell, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, CellBasis& out) {
  const BezierCell& c = mesh.cell(cell);
  if (c.dimension != 2) throw std::logic_error("evaluate_cell_basis: a hexahedron (use evaluate_volume_cell_basis)");
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(c.degree_u, c.degree_v, u, v, B, Bu, Bv);
  rational_cell_extraction(mesh, cell, out.bernstein_weights, out.C);
  geometry.evaluate(cell, u, v, out.geometry);
  finish(B, Bu, Bv, Eigen::VectorXd::Ones(u.size()), mesh.is_rational(), out);
}

namespace {

// A face of a hexahedron: the reference direction held fixed and its value.
struct Face {
  int fixed = 0;
  double at = 0;
};
Face face_of(CellSide side) {
  switch (side) {
    case kSideLeft: return {0, 0.0};
    case kSideRight: return {0, 1.0};
    case kSideBottom: return {1, 0.0};
    case kSideTop: return {1, 1.0};
    case kSideFront: return {2, 0.0};
    case kSideBack: return {2, 1.0};
  }
  throw std::logic_error("face_of: not a side");
}

// The basis on one face of a hexahedron at the tensor product of two n-point rules: the
// volume's values and gradients there (finish_volume), then the face's own measure, the
// rule's weight times |x_a x x_b| for the two free directions a < b, and the outward normal,
// along +-grad(xi_fixed) = +-J^{-T} e_fixed (a face at 0 points outward against the direction).
void evaluate_face_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell, CellSide side, int n,
                         CellBasis& out) {
  const BezierCell& c = mesh.cell(cell);
  const Face face = face_of(side);
  const QuadratureRule1D rule = gauss_legendre(n);
  const int a = face.fixed == 0 ? 1 : 0, b = face.fixed == 2 ? 1 : 2;  // the free directions
  Eigen::VectorXd coordinate[3] = {Eigen::VectorXd(n * n), Eigen::VectorXd(n * n), Eigen::VectorXd(n * n)};
  Eigen::VectorXd weight(n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int k = i + n * j;
      coordinate[a][k] = rule.nodes[i];
      coordinate[b][k] = rule.nodes[j];
      coordinate[face.fixed][k] = face.at;
      weight[k] = rule.weights[i] * rule.weights[j];
    }
  Eigen::MatrixXd B, Bu, Bv, Bw;
  tensor_bernstein(c.degree_u, c.degree_v, c.degree_w, coordinate[0], coordinate[1], coordinate[2], B, Bu, Bv, Bw);
  rational_cell_extraction(mesh, cell, out.bernstein_weights, out.C);
  geometry.evaluate_volume(cell, coordinate[0], coordinate[1], coordinate[2], out.geometry);
  finish_volume(B, Bu, Bv, Bw, weight, mesh.is_rational(), out);
  const Eigen::MatrixXd& J = out.geometry.jacobian;
  out.normal.resize(n * n, 3);
  for (int k = 0; k < n * n; ++k) {
    Eigen::Matrix3d Jk;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Jk(i, j) = J(k, 3 * i + j);
    out.measure[k] = weight[k] * Jk.col(a).cross(Jk.col(b)).norm();
    const Eigen::Vector3d outward = (face.at == 0 ? -1.0 : 1.0) * Jk.inverse().row(face.fixed).transpose();
    out.normal.row(k) = outward.normalized().transpose();
  }
}

}  // namespace

void evaluate_side_basis(const BezierMesh& mesh, const GeometryMap& geometry, int cell,
                         CellSide side, int n, CellBasis& out) {
  if (geometry.parametric_dimension() == 3) {
    evaluate_face_basis(mesh, geometry, cell, side, n, out);
    return;
  }
  if (geometry.dimension() != 2)
    throw std::invalid_argument("boundary terms on surfaces in R^3 are not supported (closed surfaces only)");
  const BezierCell& c = mesh.cell(cell);
  if (c.dimension != 2 || side > kSideLeft) throw std::logic_error("evaluate_side_basis: a quadrilateral has four sides");
  const int p = c.degree_u, q = c.degree_v;
  const QuadratureRule1D rule = gauss_legendre(n);
  Eigen::VectorXd u(n), v(n), w(n);
  for (int k = 0; k < n; ++k) {
    const double t = rule.nodes[k];
    w[k] = rule.weights[k];
    switch (side) {
      case kSideBottom: u[k] = t; v[k] = 0; break;
      case kSideRight: u[k] = 1; v[k] = t; break;
      case kSideTop: u[k] = t; v[k] = 1; break;
      default: u[k] = 0; v[k] = t; break;  // kSideLeft
    }
  }
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(p, q, u, v, B, Bu, Bv);
  rational_cell_extraction(mesh, cell, out.bernstein_weights, out.C);
  geometry.evaluate(cell, u, v, out.geometry);
  finish(B, Bu, Bv, w, mesh.is_rational(), out);
  // Counter-clockwise tangent of the side; outward normal is it turned clockwise.
  const auto& J = out.geometry.jacobian;
  out.normal.resize(n, 2);
  for (int k = 0; k < n; ++k) {
    double tx, ty;
    switch (side) {
      case kSideBottom: tx = J(k, 0); ty = J(k, 2); break;
      case kSideRight: tx = J(k, 1); ty = J(k, 3); break;
      case kSideTop: tx = -J(k, 0); ty = -J(k, 2); break;
      default: tx = -J(k, 1); ty = -J(k, 3); break;
    }
    const double len = std::hypot(tx, ty);
    out.normal(k, 0) = ty / len;
    out.normal(k, 1) = -tx / len;
    out.measure[k] = w[k] * len;
  }
}

namespace {

// u_h and its reference derivatives from the Bernstein tables, then the physical gradient
// point by point (the formulas of finish, on one function).
// Bw: the derivatives along w on a hexahedron (null on quadrilaterals).
void finish_field(const BezierMesh& mesh, int cell, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Bu,
                  const Eigen::MatrixXd& Bv, const Eigen::MatrixXd* Bw, const Eigen::VectorXd& rule_weight,
                  const Eigen::VectorXd& coefficients, CellField& out) {
  const Eigen::MatrixXd& C = mesh.extraction(cell);
  const auto ids = mesh.functions(cell);
  out.local.resize(static_cast<Eigen::Index>(ids.size()));
  for (size_t a = 0; a < ids.size(); ++a) out.local[a] = coefficients[ids[a]];
  const Eigen::Index n = B.rows();
  if (mesh.is_rational()) {
    // R_a = w_a N_a / W with W = sum_a w_a N_a: numerator and W are polynomials in B.
    out.weights.resize(out.local.size());
    for (size_t a = 0; a < ids.size(); ++a) out.weights[a] = mesh.weights()[ids[a]];
    out.local.array() *= out.weights.array();
    out.bernstein.noalias() = C.transpose() * out.weights;
    out.w.noalias() = B * out.bernstein;
    out.w_u.noalias() = Bu * out.bernstein;
    out.w_v.noalias() = Bv * out.bernstein;
    if (Bw) out.w_w.noalias() = *Bw * out.bernstein;
  }
  out.bernstein.noalias() = C.transpose() * out.local;
  out.s.noalias() = B * out.bernstein;
  out.s_u.noalias() = Bu * out.bernstein;
  out.s_v.noalias() = Bv * out.bernstein;
  if (Bw) out.s_w.noalias() = *Bw * out.bernstein;
  if (mesh.is_rational()) {
    out.s.array() /= out.w.array();
    out.s_u.array() = (out.s_u.array() - out.s.array() * out.w_u.array()) / out.w.array();
    out.s_v.array() = (out.s_v.array() - out.s.array() * out.w_v.array()) / out.w.array();
    if (Bw) out.s_w.array() = (out.s_w.array() - out.s.array() * out.w_w.array()) / out.w.array();
  }
  out.value = out.s;
  const auto& J = out.geometry.jacobian;
  out.dimension = out.geometry.dimension();
  out.gradient.resize(n, out.dimension);
  out.measure.resize(n);
  if (Bw) {  // grad = J^{-T} (f_u, f_v, f_w), J = d x / d reference (3 x 3)
    for (Eigen::Index k = 0; k < n; ++k) {
      Eigen::Matrix3d Jk;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Jk(i, j) = J(k, 3 * i + j);
      const double det = Jk.determinant();
      const Eigen::Matrix3d it = Jk.inverse().transpose();
      for (int i = 0; i < 3; ++i) out.gradient(k, i) = it(i, 0) * out.s_u[k] + it(i, 1) * out.s_v[k] + it(i, 2) * out.s_w[k];
      out.measure[k] = rule_weight[k] * std::abs(det);
    }
    return;
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    const double fu = out.s_u[k], fv = out.s_v[k];
    if (out.dimension == 2) {
      const double det = J(k, 0) * J(k, 3) - J(k, 1) * J(k, 2);
      out.gradient(k, 0) = (J(k, 3) * fu - J(k, 2) * fv) / det;
      out.gradient(k, 1) = (J(k, 0) * fv - J(k, 1) * fu) / det;
      out.measure[k] = rule_weight[k] * std::abs(det);
    } else {
      const double E = J(k, 0) * J(k, 0) + J(k, 2) * J(k, 2) + J(k, 4) * J(k, 4);
      const double F = J(k, 0) * J(k, 1) + J(k, 2) * J(k, 3) + J(k, 4) * J(k, 5);
      const double H = J(k, 1) * J(k, 1) + J(k, 3) * J(k, 3) + J(k, 5) * J(k, 5);
      const double det = E * H - F * F;
      const double a = (H * fu - F * fv) / det, b = (E * fv - F * fu) / det;
      for (int d = 0; d < 3; ++d) out.gradient(k, d) = J(k, 2 * d) * a + J(k, 2 * d + 1) * b;
      out.measure[k] = rule_weight[k] * std::sqrt(std::abs(det));
    }
  }
}

}  // namespace

void evaluate_cell_field(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu, int nv,
                         const Eigen::VectorXd& coefficients, CellField& out) {
  const BezierCell& c = mesh.cell(cell);
  const BernsteinTable& t = bernstein_table(c.degree_u, c.degree_v, nu, nv);
  geometry.evaluate_at_rule(cell, nu, nv, out.geometry);
  finish_field(mesh, cell, t.value, t.d_u, t.d_v, nullptr, t.weight, coefficients, out);
}

void evaluate_volume_cell_field(const BezierMesh& mesh, const GeometryMap& geometry, int cell, int nu, int nv, int nw,
                                const Eigen::VectorXd& coefficients, CellField& out) {
  const BezierCell& c = mesh.cell(cell);
  if (c.dimension != 3) throw std::logic_error("evaluate_volume_cell_field: not a hexahedron");
  const BernsteinTable& t = bernstein_table(c.degree_u, c.degree_v, c.degree_w, nu, nv, nw);
  geometry.evaluate_volume_at_rule(cell, nu, nv, nw, out.geometry);
  finish_field(mesh, cell, t.value, t.d_u, t.d_v, &t.d_w, t.weight, coefficients, out);
}

void evaluate_cell_field_at(const BezierMesh& mesh, const GeometryMap& geometry, int cell, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, const Eigen::VectorXd& coefficients, CellField& out) {
  const BezierCell& c = mesh.cell(cell);
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(c.degree_u, c.degree_v, u, v, B, Bu, Bv);
  geometry.evaluate(cell, u, v, out.geometry);
  finish_field(mesh, cell, B, Bu, Bv, nullptr, Eigen::VectorXd::Ones(u.size()), coefficients, out);
}

std::vector<int> side_bernstein_indices(int p, int q, int r, CellSide side) {
  const Face face = face_of(side);
  const int degree[3] = {p, q, r}, last = face.at == 0 ? 0 : degree[face.fixed];
  std::vector<int> idx;
  for (int c = 0; c <= r; ++c)
    for (int b = 0; b <= q; ++b)
      for (int a = 0; a <= p; ++a) {
        const int index[3] = {a, b, c};
        if (index[face.fixed] == last) idx.push_back(a + (p + 1) * (b + (q + 1) * c));
      }
  return idx;
}

std::vector<int> side_bernstein_indices(int p, int q, CellSide side) {
  std::vector<int> idx;
  if (side == kSideBottom || side == kSideTop) {
    const int c = side == kSideBottom ? 0 : q;
    for (int a = 0; a <= p; ++a) idx.push_back(a + (p + 1) * c);
  } else {
    const int a = side == kSideLeft ? 0 : p;
    for (int c = 0; c <= q; ++c) idx.push_back(a + (p + 1) * c);
  }
  return idx;
}

}  // namespace knotwork
