#include "studies/bench_study.hpp"

#include <chrono>
#include <cstdio>

#include "solver/poisson_solver.hpp"
#include "studies/pipeline.hpp"

namespace knotwork {

// The benchmark problem: unit square, u = sin(pi x) sin(pi y), or the unit cube, u = sin(pi x)
// sin(pi y) sin(pi z); homogeneous Dirichlet.
BenchResult bench_configuration(int p, int n, Ordering ordering, bool with_errors, bool floor, const std::string& solver,
                                double tolerance, const std::string& preconditioner, const std::string& matrix, bool cube) {
  CaseDescription c = cube ? unit_cube_benchmark_case(p, n) : unit_square_benchmark_case(p, n);
  const auto t0 = std::chrono::steady_clock::now();
  const std::unique_ptr<SplineSpace> d = build_space(c);
  const double t_space = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double floor_seconds = NAN;
  PoissonSolution s;
  SolverReport report;
  if (solver == "iterative") {
    c.solver.method = "iterative";
    c.solver.tolerance = tolerance;
    c.solver.preconditioner = preconditioner;
    c.solver.matrix = matrix;
    if (!with_errors) {  // no exact solution, so no error norms: the boundary data it gave (u = 0) stated instead
      for (BoundaryCondition& side : c.problem.boundary) side.from_exact = false, side.value = Expression::constant(0);
      c.problem.exact.reset();
    }
    s = solve_case(c, *d, ordering, {}, &report);
  } else {
    PoissonSolveOptions so;
    so.ordering = ordering;
    so.compute_errors = with_errors;
    assemble_by_operator_where_possible(c, *d, so);  // as `run` assembles
    if (floor)
      so.on_system = [&](const Eigen::SparseMatrix<double>& K, const Eigen::VectorXd& F) {
        const auto t = std::chrono::steady_clock::now();
        SparseCholesky bare(Ordering::kCholmodDefault);
        bare.factorize(K);
        const Eigen::VectorXd x = bare.solve(F);
        floor_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
      };
    s = solve_poisson(d->mesh(), d->geometry(), c.problem, so);
  }
  BenchResult r;
  std::snprintf(r.assembly_name, sizeof r.assembly_name, "%s", s.assembly.c_str());
  std::snprintf(r.preconditioner_name, sizeof r.preconditioner_name, "%s", report.preconditioner.c_str());
  r.floor_seconds = floor_seconds;
  r.degree = p;
  r.elements = n;
  r.dofs = s.num_functions;
  r.free_dofs = s.num_free;
  r.matrix_nonzeros = s.matrix_nonzeros;
  r.factor_nonzeros = s.cholesky.factor_nonzeros;
  r.flops = s.cholesky.flops;
  r.setup = s.timings.setup + t_space;
  r.assembly = s.timings.assembly;
  r.analysis = s.timings.analysis;
  r.factorization = s.timings.factorization;
  r.solve = s.timings.solve;
  r.preconditioner = s.timings.preconditioner;
  r.cg = s.timings.iterations;
  r.iterations = s.iterative.iterations;
  r.relative_residual = s.iterative.relative_residual;
  r.errors = s.timings.errors;
  r.total = r.setup + r.assembly + r.analysis + r.factorization + r.solve + r.preconditioner + r.cg + r.errors;
  r.cholmod_peak_bytes = s.cholesky.peak_bytes;
  r.l2 = s.errors ? s.errors->l2 : NAN;
  return r;
}

}  // namespace knotwork
