#include "solver/poisson_solver.hpp"

#include <chrono>

#include "solver/assemble_poisson.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

PoissonSolution solve_poisson(const BezierMesh& mesh, const GeometryMap& geometry,
                              const PoissonProblem& problem, const PoissonSolveOptions& options) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) {
    return std::chrono::duration<double>(clock::now() - t).count();
  };
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  PoissonSolution sol;
  sol.num_functions = mesh.num_functions();

  say("setup");
  auto t = clock::now();
  std::vector<bool> fixed;
  const Eigen::VectorXd fixed_values =
      project_dirichlet_data(mesh, geometry, problem, options.quadrature, fixed);
  const DofLayout layout = make_dof_layout(mesh.num_functions(), fixed);
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(mesh, layout);
  sol.num_free = layout.num_free();
  sol.matrix_nonzeros = K.nonZeros();
  sol.timings.setup = seconds_since(t);

  say("assembly");
  t = clock::now();
  Eigen::VectorXd rhs;
  assemble_poisson(mesh, geometry, problem.source, layout, fixed_values, options.quadrature, K, rhs);
  add_neumann_terms(mesh, geometry, problem, layout, options.quadrature, rhs);
  sol.timings.assembly = seconds_since(t);
  if (options.on_system) options.on_system(K, rhs);

  sol.coefficients = fixed_values;
  if (layout.num_free() > 0) {
    say("factorization");
    const std::shared_ptr<SparseCholesky> cholesky =
        options.solver ? options.solver : std::make_shared<SparseCholesky>(options.ordering);
    cholesky->factorize(K);
    say("solve");
    const Eigen::VectorXd x = cholesky->solve(rhs);
    sol.cholesky = cholesky->stats();
    sol.timings.analysis = sol.cholesky.analyze_seconds;
    sol.timings.factorization = sol.cholesky.factorize_seconds;
    sol.timings.solve = sol.cholesky.solve_seconds;
    for (int d = 0; d < layout.num_free(); ++d) sol.coefficients[layout.function_of_dof[d]] = x[d];
  }
  if (!sol.coefficients.allFinite())
    throw std::runtime_error("the discrete solution has non-finite values");

  if (options.compute_errors && problem.exact) {
    say("error norms");
    t = clock::now();
    sol.errors = error_norms(mesh, geometry, sol.coefficients, *problem.exact, options.quadrature);
    sol.timings.errors = seconds_since(t);
  }
  return sol;
}

}  // namespace knotwork
