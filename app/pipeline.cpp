#include "app/pipeline.hpp"

#include "cases/geometries.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

std::unique_ptr<SplineSpace> build_space(const CaseDescription& c, int level, const ProgressFunction& progress) {
  return space_family(c).build(c, level, progress);
}

PoissonSolution solve_case(const CaseDescription& c, const SplineSpace& space, Ordering ordering,
                           const ProgressFunction& progress) {
  space.check_solvable();
  PoissonSolveOptions so;
  so.quadrature = c.quadrature;
  so.ordering = ordering;
  so.progress = progress;
  so.cell_errors = true;
  try {
    return solve_poisson(space.mesh(), space.geometry(), c.problem, so);
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry]: " + e.what());
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": " + e.what());
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

}  // namespace knotwork
