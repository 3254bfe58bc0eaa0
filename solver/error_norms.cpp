#include "solver/error_norms.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <string>

#include "solver/assemble_poisson.hpp"
#include "solver/cell_basis.hpp"

namespace knotwork {

namespace {

// |u - u_h|^2 in L2 and H1-seminorm of every cell of [first, last) (the others: 0).
void cell_squared_errors(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients,
                         const ExactSolution& exact, const QuadratureOptions& quadrature, double exact_offset,
                         int first, int last, Eigen::VectorXd& cell_l2, Eigen::VectorXd& cell_semi_all) {
  const bool volume = geometry.parametric_dimension() == 3;
  if (geometry.dimension() == 3 && !exact.on_surface())
    throw std::invalid_argument(std::string("error norms on a ") + (volume ? "volume" : "surface") +
                                " need the exact solution as a function of (x, y, z)");
  cell_l2 = Eigen::VectorXd::Zero(mesh.num_cells());
  cell_semi_all = cell_l2;
  const bool surface = geometry.dimension() == 3 && !volume;
  std::vector<Expression> wanted{exact.u, exact.u_x, exact.u_y};
  if (geometry.dimension() == 3) wanted.push_back(exact.u_z);
  const ExpressionBatch compiled(wanted);  // merged once; each thread runs its own copy
#pragma omp parallel
  {
    ExpressionBatch ex(compiled);
    CellField field;
#pragma omp for schedule(dynamic, 64)
    for (int c = first; c < last; ++c) {
      const BezierCell& cell = mesh.cell(c);
      if (volume) {
        evaluate_volume_cell_field(mesh, geometry, c, rule_points(quadrature.error_points_u, cell.degree_u, 2),
                                   rule_points(quadrature.error_points_v, cell.degree_v, 2),
                                   rule_points(quadrature.error_points_w, cell.degree_w, 2), coefficients, field);
        const Eigen::MatrixXd& x = field.geometry.x;
        ex.evaluate(x.col(0).data(), x.col(1).data(), x.col(2).data(), x.rows());
        const Eigen::MatrixXd& grad_h = field.gradient;
        double l2 = 0, semi = 0;
        for (Eigen::Index k = 0; k < field.measure.size(); ++k) {
          const double e = ex.result(0)[k] - exact_offset - field.value[k];
          const double gx = ex.result(1)[k] - grad_h(k, 0), gy = ex.result(2)[k] - grad_h(k, 1),
                       gz = ex.result(3)[k] - grad_h(k, 2);
          l2 += field.measure[k] * e * e;
          semi += field.measure[k] * (gx * gx + gy * gy + gz * gz);
        }
        cell_l2[c] = l2;
        cell_semi_all[c] = semi;
        continue;
      }
      evaluate_cell_field(mesh, geometry, c, rule_points(quadrature.error_points_u, cell.degree_u, 2),
                          rule_points(quadrature.error_points_v, cell.degree_v, 2), coefficients, field);
      const Eigen::VectorXd& uh = field.value;
      const Eigen::MatrixXd& grad_h = field.gradient;
      const Eigen::VectorXd& measure = field.measure;
      const Eigen::MatrixXd& x = field.geometry.x;
      ex.evaluate(x.col(0).data(), x.col(1).data(), surface ? x.col(2).data() : nullptr, x.rows());
      const double *u = ex.result(0), *ux = ex.result(1), *uy = ex.result(2);
      double cell_semi = 0, l2 = 0;
      if (!surface) {
        for (Eigen::Index k = 0; k < measure.size(); ++k) {
          const double e = u[k] - exact_offset - uh[k];
          const double gx = ux[k] - grad_h(k, 0), gy = uy[k] - grad_h(k, 1);
          l2 += measure[k] * e * e;
          cell_semi += measure[k] * (gx * gx + gy * gy);
        }
      } else {
        // The ambient gradient projected onto the tangent plane of the discrete surface.
        const double* uz = ex.result(3);
        const auto& J = field.geometry.jacobian;
        for (Eigen::Index k = 0; k < measure.size(); ++k) {
          const double e = u[k] - exact_offset - uh[k];
          const Eigen::Vector3d n =
              Eigen::Vector3d(J(k, 0), J(k, 2), J(k, 4)).cross(Eigen::Vector3d(J(k, 1), J(k, 3), J(k, 5))).normalized();
          Eigen::Vector3d grad(ux[k], uy[k], uz[k]);
          grad -= grad.dot(n) * n;
          const Eigen::Vector3d g = grad - grad_h.row(k).transpose();
          l2 += measure[k] * e * e;
          cell_semi += measure[k] * g.squaredNorm();
        }
      }
      cell_l2[c] = l2;
      cell_semi_all[c] = cell_semi;
    }
  }
}

}  // namespace

ErrorNorms error_norms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coefficients, const ExactSolution& exact,
                       const QuadratureOptions& quadrature, Eigen::VectorXd* h1_semi_squared_per_cell,
                       double exact_offset) {
  // Per-cell contributions, summed in cell order afterwards: the norms are bitwise the same
  // whatever the number of threads and however the cells were shared among them.
  Eigen::VectorXd cell_l2, cell_semi_all;
  cell_squared_errors(mesh, geometry, coefficients, exact, quadrature, exact_offset, 0, mesh.num_cells(), cell_l2,
                      cell_semi_all);
  double l2 = 0, semi = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) l2 += cell_l2[c], semi += cell_semi_all[c];
  if (h1_semi_squared_per_cell) *h1_semi_squared_per_cell = std::move(cell_semi_all);
  ErrorNorms n;
  n.l2 = std::sqrt(l2);
  n.h1_semi = std::sqrt(semi);
  n.h1 = std::sqrt(l2 + semi);
  return n;
}

std::array<double, 2> squared_errors(const BezierMesh& mesh, const GeometryMap& geometry,
                                    const Eigen::VectorXd& coefficients, const ExactSolution& exact,
                                    const QuadratureOptions& quadrature, CellRange cells,
                                    Eigen::VectorXd* h1_semi_squared_per_cell, double exact_offset) {
  Eigen::VectorXd cell_l2, cell_semi;
  const int last = cells.last < 0 ? mesh.num_cells() : cells.last;
  cell_squared_errors(mesh, geometry, coefficients, exact, quadrature, exact_offset, cells.first, last, cell_l2, cell_semi);
  double l2 = 0, semi = 0;
  for (int c = cells.first; c < last; ++c) l2 += cell_l2[c], semi += cell_semi[c];
  if (h1_semi_squared_per_cell) *h1_semi_squared_per_cell = std::move(cell_semi);
  return {l2, semi};
}

double exact_integral(const BezierMesh& mesh, const GeometryMap& geometry, const ExactSolution& exact,
                      const QuadratureOptions& quadrature) {
  Eigen::VectorXd per_cell = Eigen::VectorXd::Zero(mesh.num_cells());  // summed in cell order below
#pragma omp parallel
  {
    ExpressionEvaluator u(exact.u);
    CellBasis cb;
#pragma omp for schedule(dynamic, 64)
    for (int c = 0; c < mesh.num_cells(); ++c) {
      const BezierCell& cell = mesh.cell(c);
      evaluate_cell_basis(mesh, geometry, c, rule_points(quadrature.error_points_u, cell.degree_u, 2),
                          rule_points(quadrature.error_points_v, cell.degree_v, 2), cb);
      double integral = 0;
      for (Eigen::Index k = 0; k < cb.measure.size(); ++k) integral += cb.measure[k] * exact_at(u, cb.geometry.x, k, 0.0);
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
  CellField field;
  evaluate_cell_field_at(mesh, geometry, c, u, v, coefficients, field);
  Eigen::MatrixXd out(u.size(), 1 + field.dimension);
  out.col(0) = field.value;
  out.rightCols(field.dimension) = field.gradient;
  return out;
}

Eigen::MatrixXd evaluate_volume_solution(const BezierMesh& mesh, const GeometryMap& geometry,
                                         const Eigen::VectorXd& coefficients, int c, const Eigen::VectorXd& u,
                                         const Eigen::VectorXd& v, const Eigen::VectorXd& w) {
  CellBasis cb;
  evaluate_volume_cell_basis_at(mesh, geometry, c, u, v, w, cb);
  const auto ids = mesh.functions(c);
  Eigen::VectorXd local(static_cast<Eigen::Index>(ids.size()));
  for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
  const Eigen::VectorXd bernstein = cb.C.transpose() * local;
  Eigen::MatrixXd out(u.size(), 4);
  out.col(0) = cb.value * bernstein;
  for (int d = 0; d < 3; ++d) out.col(1 + d) = cb.grad(d) * bernstein;
  return out;
}

double exact_at(ExpressionEvaluator& exact, const Eigen::MatrixXd& x, Eigen::Index k, double offset) {
  return (x.cols() == 2 ? exact(x(k, 0), x(k, 1)) : exact(x(k, 0), x(k, 1), x(k, 2))) - offset;
}

void sample_cell(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients, int cell,
                 int n, ExpressionEvaluator* exact, double exact_offset, CellSamples& out) {
  const int m = n + 1, dimension = geometry.parametric_dimension(), points = dimension == 3 ? m * m * m : m * m;
  if (out.n != n || out.dimension != dimension) {
    out.n = n;
    out.dimension = dimension;
    out.u.resize(points);
    out.v.resize(points);
    out.w.setZero(dimension == 3 ? points : 0);
    for (int k = 0; k < points; ++k) {
      out.u[k] = double(k % m) / n, out.v[k] = double((k / m) % m) / n;
      if (dimension == 3) out.w[k] = double(k / (m * m)) / n;
    }
  }
  if (dimension == 3) {
    geometry.evaluate_volume(cell, out.u, out.v, out.w, out.at);
    out.uh = evaluate_volume_solution(mesh, geometry, coefficients, cell, out.u, out.v, out.w);
  } else {
    geometry.evaluate(cell, out.u, out.v, out.at);
    out.uh = evaluate_solution(mesh, geometry, coefficients, cell, out.u, out.v);
  }
  out.exact.resize(exact ? points : 0);
  for (Eigen::Index k = 0; k < out.exact.size(); ++k) out.exact[k] = exact_at(*exact, out.at.x, k, exact_offset);
}

}  // namespace knotwork
