#include "studies/system_study.hpp"

#include <memory>
#include <stdexcept>

#include "solver/assemble_poisson.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

namespace {

Eigen::SparseMatrix<double, Eigen::RowMajor> whole(const Eigen::SparseMatrix<double>& lower) {
  Eigen::SparseMatrix<double, Eigen::RowMajor> full = lower.selfadjointView<Eigen::Lower>();
  full.makeCompressed();
  return full;
}

// The lower triangle solve_poisson assembles, into a copy of `pattern` (every function free), as
// a whole symmetric matrix.
Eigen::SparseMatrix<double, Eigen::RowMajor> whole(const BezierMesh& mesh, const GeometryMap& geometry,
                                                   const PoissonForm& form, const QuadratureOptions& quadrature,
                                                   const DofLayout& all, Eigen::SparseMatrix<double> lower,
                                                   Eigen::VectorXd& load) {
  assemble_poisson(mesh, geometry, form, all, Eigen::VectorXd::Zero(mesh.num_functions()), quadrature, lower, load);
  return whole(lower);
}

}  // namespace

AssembledSystem assemble_system(const CaseDescription& c, const SplineSpace& space, const ProgressFunction& progress) {
  const auto say = [&](const std::string& what) {
    if (progress) progress(what);
  };
  space.check_solvable();
  const BezierMesh& mesh = space.mesh();
  const GeometryMap& geometry = space.geometry();
  const PoissonProblem& problem = c.problem;
  const int n = mesh.num_functions();
  AssembledSystem s;
  try {
    say("Dirichlet projection");
    std::vector<bool> fixed;
    const Eigen::VectorXd g = project_dirichlet_data(mesh, geometry, problem, c.quadrature, fixed);
    for (int f = 0; f < n; ++f)
      if (fixed[f]) s.dirichlet.push_back(f);
    s.dirichlet_values.resize(static_cast<Eigen::Index>(s.dirichlet.size()));
    for (size_t k = 0; k < s.dirichlet.size(); ++k) s.dirichlet_values[static_cast<Eigen::Index>(k)] = g[s.dirichlet[k]];
    s.zero_mean = without_reaction(problem) && !has_boundary(mesh);

    say("stiffness and load");
    const PoissonForm form = poisson_form(problem);
    const DofLayout all = make_dof_layout(n, std::vector<bool>(n, false));
    // The space's operator, where it has one: a tensor patch's gives the pattern, and on one
    // affine map writes the matrices themselves (docs/SOLVERS.md).
    const std::shared_ptr<const MatrixFreePoisson> op = space_operator(space, 1.0, problem.reaction, c.quadrature);
    if (op && op->num_functions() != n) throw std::logic_error("assemble_system: an operator of another space");
    if (op && op->assembles_lower() && !s.zero_mean && operator_serves(problem, geometry)) {
      s.stiffness = whole(op->lower_matrix(all));
      s.load = op->load(problem.source);
      add_neumann_terms(mesh, geometry, problem, all, c.quadrature, s.load);
      say("mass");
      const std::shared_ptr<const MatrixFreePoisson> mass = space_operator(space, 0.0, 1.0, c.quadrature);
      if (!mass || !mass->assembles_lower())
        throw std::logic_error("assemble_system: the operator wrote the stiffness but not the mass matrix");
      s.mass = whole(mass->lower_matrix(all));
      return s;
    }
    const Eigen::SparseMatrix<double> pattern =
        op && op->gives_pattern() ? op->lower_pattern(all) : lower_pattern_matrix(mesh, all);
    s.stiffness = whole(mesh, geometry, form, c.quadrature, all, pattern, s.load);
    add_neumann_terms(mesh, geometry, problem, all, c.quadrature, s.load);

    say("mass");
    Eigen::VectorXd unused;
    s.mass = whole(mesh, geometry, mass_form(form), c.quadrature, all, pattern, unused);
  } catch (...) {
    rethrow_as_case_error(c);
  }
  return s;
}

}  // namespace knotwork
