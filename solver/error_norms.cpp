#include "solver/error_norms.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "solver/assemble_poisson.hpp"
#include "solver/cell_basis.hpp"

namespace knotwork {

namespace {

// The exact solution at a cell's points, and on surfaces its ambient gradient projected onto
// the tangent plane.
struct ExactAtPoints {
  ExpressionEvaluator u, ux, uy;
  std::optional<ExpressionEvaluator> uz;
  explicit ExactAtPoints(const ExactSolution& e) : u(e.u), ux(e.u_x), uy(e.u_y) {
    if (e.on_surface()) uz.emplace(e.u_z);
  }
  double value(const GeometryAtPoints& g, Eigen::Index k) {
    return g.dimension() == 2 ? u(g.x(k, 0), g.x(k, 1)) : u(g.x(k, 0), g.x(k, 1), g.x(k, 2));
  }
  // Surfaces only (the planar loop evaluates u_x, u_y itself).
  Eigen::Vector3d surface_gradient(const GeometryAtPoints& g, Eigen::Index k) {
    const double x = g.x(k, 0), y = g.x(k, 1), z = g.x(k, 2);
    Eigen::Vector3d grad(ux(x, y, z), uy(x, y, z), (*uz)(x, y, z));
    const auto& J = g.jacobian;
    const Eigen::Vector3d n = Eigen::Vector3d(J(k, 0), J(k, 2), J(k, 4)).cross(Eigen::Vector3d(J(k, 1), J(k, 3), J(k, 5))).normalized();
    return grad - grad.dot(n) * n;
  }
};

}  // namespace

ErrorNorms error_norms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coefficients, const ExactSolution& exact,
                       const QuadratureOptions& quadrature, Eigen::VectorXd* h1_semi_squared_per_cell,
                       double exact_offset) {
  if (geometry.dimension() == 3 && !exact.on_surface())
    throw std::invalid_argument("error norms on a surface need the exact solution as a function of (x, y, z)");
  // Per-cell contributions, summed in cell order afterwards: the norms are bitwise the same
  // whatever the number of threads and however the cells were shared among them.
  Eigen::VectorXd cell_l2 = Eigen::VectorXd::Zero(mesh.num_cells()), cell_semi_all = cell_l2;
#pragma omp parallel
  {
    ExactAtPoints ex(exact);
    CellBasis cb;
    Eigen::VectorXd local, beta, uh;
    Eigen::MatrixXd grad_h;
#pragma omp for schedule(dynamic, 64)
    for (int c = 0; c < mesh.num_cells(); ++c) {
      const BezierCell& cell = mesh.cell(c);
      evaluate_cell_basis(mesh, geometry, c, rule_points(quadrature.error_points_u, cell.degree_u, 2),
                          rule_points(quadrature.error_points_v, cell.degree_v, 2), cb);
      const auto ids = mesh.functions(c);
      local.resize(ids.size());
      for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
      beta.noalias() = cb.C.transpose() * local;  // coefficients in the (rational) Bernstein basis
      uh.noalias() = cb.value * beta;
      grad_h.resize(cb.measure.size(), cb.dimension);  // (n x 2) in the plane, (n x 3) on surfaces
      for (int d = 0; d < cb.dimension; ++d) grad_h.col(d).noalias() = cb.grad(d) * beta;
      double cell_semi = 0, l2 = 0;
      if (cb.dimension == 2) {
        for (Eigen::Index k = 0; k < cb.measure.size(); ++k) {
          const double x = cb.geometry.x(k, 0), y = cb.geometry.x(k, 1);
          const double e = ex.u(x, y) - exact_offset - uh[k];
          const double gx = ex.ux(x, y) - grad_h(k, 0), gy = ex.uy(x, y) - grad_h(k, 1);
          l2 += cb.measure[k] * e * e;
          cell_semi += cb.measure[k] * (gx * gx + gy * gy);
        }
      } else {
        for (Eigen::Index k = 0; k < cb.measure.size(); ++k) {
          const double e = ex.value(cb.geometry, k) - exact_offset - uh[k];
          const Eigen::Vector3d g = ex.surface_gradient(cb.geometry, k) - grad_h.row(k).transpose();
          l2 += cb.measure[k] * e * e;
          cell_semi += cb.measure[k] * g.squaredNorm();
        }
      }
      cell_l2[c] = l2;
      cell_semi_all[c] = cell_semi;
    }
  }
  double l2 = 0, semi = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) l2 += cell_l2[c], semi += cell_semi_all[c];
  if (h1_semi_squared_per_cell) *h1_semi_squared_per_cell = std::move(cell_semi_all);
  ErrorNorms n;
  n.l2 = std::sqrt(l2);
  n.h1_semi = std::sqrt(semi);
  n.h1 = std::sqrt(l2 + semi);
  return n;
}

double exact_integral(const BezierMesh& mesh, const GeometryMap& geometry, const ExactSolution& exact,
                      const QuadratureOptions& quadrature) {
  Eigen::VectorXd per_cell = Eigen::VectorXd::Zero(mesh.num_cells());  // summed in cell order below
#pragma omp parallel
  {
    ExactAtPoints ex(exact);
    CellBasis cb;
#pragma omp for schedule(dynamic, 64)
    for (int c = 0; c < mesh.num_cells(); ++c) {
      const BezierCell& cell = mesh.cell(c);
      evaluate_cell_basis(mesh, geometry, c, rule_points(quadrature.error_points_u, cell.degree_u, 2),
                          rule_points(quadrature.error_points_v, cell.degree_v, 2), cb);
      double integral = 0;
      for (Eigen::Index k = 0; k < cb.measure.size(); ++k) integral += cb.measure[k] * ex.value(cb.geometry, k);
      per_cell[c] = integral;
    }
  }
  double integral = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) integral += per_cell[c];
  return integral;
}

Eigen::MatrixXd evaluate_solution(const BezierMesh& mesh, const GeometryMap& geometry,
                                  const Eigen::VectorXd& coefficients, int c,
                                  const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  CellBasis cb;
  evaluate_cell_basis_at(mesh, geometry, c, u, v, cb);
  const auto ids = mesh.functions(c);
  Eigen::VectorXd local(ids.size());
  for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
  const Eigen::VectorXd beta = cb.C.transpose() * local;
  Eigen::MatrixXd out(u.size(), 1 + cb.dimension);
  out.col(0).noalias() = cb.value * beta;
  for (int d = 0; d < cb.dimension; ++d) out.col(1 + d).noalias() = cb.grad(d) * beta;
  return out;
}

double exact_at(ExpressionEvaluator& exact, const Eigen::MatrixXd& x, Eigen::Index k, double offset) {
  return (x.cols() == 2 ? exact(x(k, 0), x(k, 1)) : exact(x(k, 0), x(k, 1), x(k, 2))) - offset;
}

void sample_cell(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients, int cell,
                 int n, ExpressionEvaluator* exact, double exact_offset, CellSamples& out) {
  const int m = n + 1;
  if (out.n != n) {
    out.n = n;
    out.u.resize(m * m);
    out.v.resize(m * m);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) out.u[i + m * j] = double(i) / n, out.v[i + m * j] = double(j) / n;
  }
  geometry.evaluate(cell, out.u, out.v, out.at);
  out.uh = evaluate_solution(mesh, geometry, coefficients, cell, out.u, out.v);
  out.exact.resize(exact ? m * m : 0);
  for (Eigen::Index k = 0; k < out.exact.size(); ++k) out.exact[k] = exact_at(*exact, out.at.x, k, exact_offset);
}

}  // namespace knotwork
