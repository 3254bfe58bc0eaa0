#include "app/discretize.hpp"

#include <cmath>
#include <stdexcept>

#include "cases/geometries.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

Discretization discretize(const CaseDescription& c) {
  Discretization d;
  try {
    d.tensor = build_tensor_discretization(c.geometry, c.space);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
  d.geometry = std::make_unique<NurbsGeometryMap>(d.tensor);
  return d;
}

PoissonSolution solve_case(const CaseDescription& c, const Discretization& d, Ordering ordering,
                           const std::function<void(const std::string&)>& progress) {
  PoissonSolveOptions so;
  so.quadrature = c.quadrature;
  so.ordering = ordering;
  so.progress = progress;
  try {
    return solve_poisson(d.mesh(), *d.geometry, c.problem, so);
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry]: " + e.what());
  }
}

CaseDescription unit_square_benchmark_case(int p, int n) {
  CaseDescription c;
  c.path = "bench";
  c.name = "bench";
  c.geometry = rectangle_patch(0, 0, 1, 1);
  c.space.degree = {p, p};
  c.space.elements_per_span = {n, n};
  c.problem.exact = differentiate_exact_solution(Expression::parse("sin(pi*x)*sin(pi*y)", "bench"));
  c.problem.source = c.problem.exact->minus_laplacian;
  c.problem.boundary.assign(4, BoundaryCondition{});
  return c;
}

double mesh_size(const Discretization& d) {
  Eigen::VectorXd u(4), v(4);
  u << 0, 1, 1, 0;
  v << 0, 0, 1, 1;
  double h = 0;
  GeometryAtPoints g;
  for (int c = 0; c < d.mesh().num_cells(); ++c) {
    d.geometry->evaluate(c, u, v, g);
    h = std::max({h, (g.x.row(0) - g.x.row(2)).norm(), (g.x.row(1) - g.x.row(3)).norm()});
  }
  return h;
}

std::string describe_space(const CaseDescription& c) {
  const auto& s = c.space;
  const int ru = s.continuity[0] < 0 ? s.degree[0] - 1 : s.continuity[0];
  const int rv = s.continuity[1] < 0 ? s.degree[1] - 1 : s.continuity[1];
  std::string r = std::string(s.rational ? "NURBS" : "B-spline") + ", degree " +
                  std::to_string(s.degree[0]) + "x" + std::to_string(s.degree[1]) + ", C^" +
                  std::to_string(ru);
  if (rv != ru) r += "/C^" + std::to_string(rv);
  return r + " at new knots";
}

}  // namespace knotwork
