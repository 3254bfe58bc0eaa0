#include "solver/poisson_solver.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "solver/assemble_poisson.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

bool has_boundary(const BezierMesh& mesh) {
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int b : mesh.cell(c).boundary)
      if (b >= 0) return true;
  return false;
}

ZeroMeanData zero_mean_data(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& load_form,
                            const QuadratureOptions& quadrature, Ordering ordering) {
  const int n = mesh.num_functions();
  const DofLayout all = make_dof_layout(n, std::vector<bool>(n, false));
  Eigen::SparseMatrix<double> M = lower_pattern_matrix(mesh, all);
  PoissonForm mass = load_form;
  mass.stiffness = 0;
  mass.reaction = 1;
  mass.coefficients = nullptr;  // the plain mass matrix, whatever A is
  ZeroMeanData z;
  assemble_poisson(mesh, geometry, mass, all, Eigen::VectorXd::Zero(n), quadrature, M, z.load, &z.integrals);
  SparseCholesky chol(ordering);
  chol.factorize(M);
  z.one = chol.solve(z.integrals);
  z.area = z.one.dot(z.integrals);
  z.source_mean = z.one.dot(z.load) / z.area;
  // The pinned coefficient x_p = 0 leaves x = one - one_p e_p nearly in the kernel, with energy
  // one_p^2 K_pp: pin where one_p^2 times the function's size is largest (M_pp standing in for
  // K_pp, which is not assembled yet). With argmax |one_p| alone, a basis whose constant has
  // coefficients 1 on almost every function pinned a small one (G1 prism sphere: condition
  // 1.5e8 instead of 8e2).
  Eigen::Index pin;
  (z.one.array().square() * M.diagonal().array()).maxCoeff(&pin);
  z.pin = static_cast<int>(pin);
  return z;
}

PoissonSolution solve_poisson(const BezierMesh& mesh, const GeometryMap& geometry,
                              const PoissonProblem& problem, const PoissonSolveOptions& options) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) {
    return std::chrono::duration<double>(clock::now() - t).count();
  };
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  if (problem.reaction < 0) throw std::invalid_argument("reaction must be >= 0");
  PoissonSolution sol;
  sol.num_functions = mesh.num_functions();
  const PoissonForm form = poisson_form(problem);
  sol.zero_mean = without_reaction(problem) && !has_boundary(mesh);

  say("setup");
  auto t = clock::now();
  std::vector<bool> fixed;
  Eigen::VectorXd fixed_values = project_dirichlet_data(mesh, geometry, problem, options.quadrature, fixed);
  ZeroMeanData zero_mean;
  if (sol.zero_mean) {
    zero_mean = zero_mean_data(mesh, geometry, form, options.quadrature, options.ordering);
    fixed[zero_mean.pin] = true;
    sol.area = zero_mean.area;
    sol.source_mean = zero_mean.source_mean;
  }
  const DofLayout layout = make_dof_layout(mesh.num_functions(), fixed);
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(mesh, layout);
  sol.num_free = layout.num_free();
  sol.matrix_nonzeros = K.nonZeros();
  sol.timings.setup = seconds_since(t);

  say("assembly");
  t = clock::now();
  Eigen::VectorXd rhs;
  if (sol.zero_mean) {
    // The load, with f's mean removed, comes from the mass pass.
    PoissonForm stiffness = form;
    stiffness.load = false;
    assemble_poisson(mesh, geometry, stiffness, layout, fixed_values, options.quadrature, K, rhs);
    for (int d = 0; d < layout.num_free(); ++d) rhs[d] = zero_mean.compatible_load(layout.function_of_dof[d]);
  } else {
    assemble_poisson(mesh, geometry, form, layout, fixed_values, options.quadrature, K, rhs);
    add_neumann_terms(mesh, geometry, problem, layout, options.quadrature, rhs);
  }
  sol.timings.assembly = seconds_since(t);
  if (options.on_system) options.on_system(K, rhs);
  if (options.estimate_condition) {
    say("condition estimates");
    sol.stiffness_spectrum = jacobi_scaled_spectrum(K);
    // The mass matrix over the same free dofs (the matrix a reaction term would add).
    PoissonForm mass = form;
    mass.stiffness = 0;
    mass.reaction = 1;
    mass.load = false;
    mass.nitsche = nullptr;
    mass.coefficients = nullptr;
    Eigen::SparseMatrix<double> M = lower_pattern_matrix(mesh, layout);
    Eigen::VectorXd unused;
    assemble_poisson(mesh, geometry, mass, layout, Eigen::VectorXd::Zero(mesh.num_functions()), options.quadrature, M,
                     unused);
    sol.mass_spectrum = jacobi_scaled_spectrum(M);
  }

  sol.coefficients = fixed_values;
  if (layout.num_free() > 0 && options.iterative) {
    say("preconditioner");
    t = clock::now();
    std::unique_ptr<Preconditioner> pc = options.preconditioner ? options.preconditioner(layout, K) : nullptr;
    if (!pc) pc = jacobi_preconditioner(K);
    sol.timings.preconditioner = seconds_since(t);
    say("iterations");
    t = clock::now();
    const Eigen::VectorXd x = preconditioned_cg(K, rhs, *pc, options.tolerance, options.max_iterations, sol.iterative);
    sol.timings.iterations = seconds_since(t);
    if (!sol.iterative.converged) {
      char b[400];
      std::snprintf(b, sizeof b, "CG stopped after %d iterations (%s) at backward error %.3e (relative residual %.3e), above the tolerance %.1e",
                    sol.iterative.iterations, sol.iterative.stop_reason().c_str(),
                    sol.iterative.backward_error, sol.iterative.relative_residual, options.tolerance);
      throw NotConverged(b);
    }
    for (int d = 0; d < layout.num_free(); ++d) sol.coefficients[layout.function_of_dof[d]] = x[d];
  } else if (layout.num_free() > 0) {
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
  if (sol.zero_mean) zero_mean.remove_mean(sol.coefficients);
  if (!sol.coefficients.allFinite())
    throw std::runtime_error("the discrete solution has non-finite values");

  if (options.compute_errors && problem.exact) {
    say("error norms");
    t = clock::now();
    if (sol.zero_mean) {
      // Over the area the mass matrix measured (as the solution's mean is).
      sol.exact_mean = exact_integral(mesh, geometry, *problem.exact, options.quadrature) / sol.area;
    }
    sol.errors = error_norms(mesh, geometry, sol.coefficients, *problem.exact, options.quadrature,
                             options.cell_errors ? &sol.cell_h1_squared : nullptr, sol.exact_mean);
    sol.timings.errors = seconds_since(t);
  }
  return sol;
}

}  // namespace knotwork
