#include "solver/error_norms.hpp"

#include <cmath>

#include "quadrature/bernstein.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/cell_basis.hpp"

namespace knotwork {

ErrorNorms error_norms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coefficients, const ExactSolution& exact,
                       const QuadratureOptions& quadrature, Eigen::VectorXd* h1_semi_squared_per_cell) {
  double l2 = 0, semi = 0;
  if (h1_semi_squared_per_cell) h1_semi_squared_per_cell->setZero(mesh.num_cells());
#pragma omp parallel reduction(+ : l2, semi)
  {
    ExpressionEvaluator u(exact.u), ux(exact.u_x), uy(exact.u_y);
    CellBasis cb;
    Eigen::VectorXd local, beta, uh, uhx, uhy;
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
      uhx.noalias() = cb.grad_x * beta;
      uhy.noalias() = cb.grad_y * beta;
      double cell_semi = 0;
      for (Eigen::Index k = 0; k < cb.measure.size(); ++k) {
        const double x = cb.geometry.x(k, 0), y = cb.geometry.x(k, 1);
        const double e = u(x, y) - uh[k];
        const double ex = ux(x, y) - uhx[k], ey = uy(x, y) - uhy[k];
        l2 += cb.measure[k] * e * e;
        cell_semi += cb.measure[k] * (ex * ex + ey * ey);
      }
      semi += cell_semi;
      if (h1_semi_squared_per_cell) (*h1_semi_squared_per_cell)[c] = cell_semi;
    }
  }
  ErrorNorms n;
  n.l2 = std::sqrt(l2);
  n.h1_semi = std::sqrt(semi);
  n.h1 = std::sqrt(l2 + semi);
  return n;
}

Eigen::MatrixX3d evaluate_solution(const BezierMesh& mesh, const GeometryMap& geometry,
                                   const Eigen::VectorXd& coefficients, int c,
                                   const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  const BezierCell& cell = mesh.cell(c);
  const Eigen::Index n = u.size();
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(cell.degree_u, cell.degree_v, u, v, B, Bu, Bv);
  Eigen::VectorXd wb;
  Eigen::MatrixXd C;
  rational_cell_extraction(mesh, c, wb, C);
  const auto ids = mesh.functions(c);
  Eigen::VectorXd local(ids.size());
  for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
  const Eigen::VectorXd beta = wb.asDiagonal() * (C.transpose() * local);  // weighted Bernstein coeffs
  GeometryAtPoints g;
  geometry.evaluate(c, u, v, g);
  Eigen::MatrixX3d out(n, 3);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double W = B.row(k).dot(wb), Wu = Bu.row(k).dot(wb), Wv = Bv.row(k).dot(wb);
    const double val = B.row(k).dot(beta) / W;
    const double du_ = (Bu.row(k).dot(beta) - val * Wu) / W;
    const double dv_ = (Bv.row(k).dot(beta) - val * Wv) / W;
    const auto& J = g.jacobian;
    const double det = J(k, 0) * J(k, 3) - J(k, 1) * J(k, 2);
    out(k, 0) = val;
    out(k, 1) = (J(k, 3) * du_ - J(k, 2) * dv_) / det;
    out(k, 2) = (J(k, 0) * dv_ - J(k, 1) * du_) / det;
  }
  return out;
}

}  // namespace knotwork
