#include "solver/poisson_solver.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include <sys/resource.h>

#include <algorithm>
#include <optional>
#include <array>

#include "basis/core/input_error.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/petsc_backend.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

namespace {

// K over the free dofs of `layout`, from an operator over all functions: the fixed ones are
// zero in x and dropped from y. Its ||K||_inf is a lower bound (no matrix to sum rows of):
// the largest of the diagonal and |K s|_inf for s = +-1 alternating, so CG's backward errors
// are upper bounds of the true ones.
class FreeDofsOperator final : public SymmetricOperator {
 public:
  FreeDofsOperator(const MatrixFreePoisson& op, const DofLayout& layout, const Eigen::VectorXd& diagonal)
      : op_(op), layout_(layout), direct_(op.applies_free(layout)) {
    if (!direct_) x_ = Eigen::VectorXd::Zero(op.num_functions());
    norm_ = diagonal.size() > 0 ? diagonal.maxCoeff() : 0;
    Eigen::VectorXd s(diagonal.size()), y;
    for (Eigen::Index d = 0; d < s.size(); ++d) s[d] = d % 2 ? -1.0 : 1.0;
    apply(s, y);
    if (y.size() > 0) norm_ = std::max(norm_, y.lpNorm<Eigen::Infinity>());
  }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override {
    if (direct_) return op_.apply_free(layout_, x, y);
    const int n = layout_.num_free();
    for (int d = 0; d < n; ++d) x_[layout_.function_of_dof[d]] = x[d];
    op_.apply(x_, all_);
    y.resize(n);
    for (int d = 0; d < n; ++d) y[d] = all_[layout_.function_of_dof[d]];
  }
  double inf_norm() const override { return norm_; }
  int max_row_nonzeros() const override { return op_.max_row_nonzeros(); }

 private:
  const MatrixFreePoisson& op_;
  const DofLayout& layout_;
  const bool direct_;                // the operator applies itself to the free dofs (no x_, all_)
  mutable Eigen::VectorXd x_, all_;  // fixed entries of x_ stay zero
  double norm_ = 0;
};

// The rows this process owns (owned_rows_pattern: no halo), whole, from an operator over its
// mesh's functions (MatrixFreePoisson::row_entries): what the other processes' cells add to
// those rows is in the operator's rows already, and their own rows are written by them. The
// diagonal block's upper triangle is written and mirrored (half its entries), the other block whole.
// `entries(row, count, columns, values)` as MatrixFreePoisson::row_entries.
template <class Entries>
void write_owned_rows(Entries entries, const DofLayout& layout, RankRows& rows) {
  OwnedRows& owned = rows.owned;
  const long diagonal_entries = owned.diagonal_nonzeros();
  if (rows.halo_start.back() != 0) throw std::logic_error("write_owned_rows: rows with a halo to send");
  const std::vector<int> diagonal = diagonal_positions(owned);
  const int count = rows.last - rows.first;
#pragma omp parallel
  {
    std::vector<int> columns;
#pragma omp for schedule(static)
    for (int r = 0; r < count; ++r) {
      const int row = layout.function_of_dof[rows.first + r];
      // The diagonal block's columns count from the first owned row, the others are global rows.
      const int begin = diagonal[r], end = owned.diagonal_start[r + 1];
      columns.clear();
      for (int k = begin; k < end; ++k) columns.push_back(layout.function_of_dof[rows.first + owned.diagonal_cols[k]]);
      entries(row, end - begin, columns.data(), owned.values.data() + begin);
      const int off_begin = owned.off_start[r], off_end = owned.off_start[r + 1];
      columns.clear();
      for (int k = off_begin; k < off_end; ++k) {
        const auto at = std::lower_bound(rows.global_row.begin(), rows.global_row.end(), owned.off_cols[k]);
        columns.push_back(layout.function_of_dof[at - rows.global_row.begin()]);
      }
      entries(row, off_end - off_begin, columns.data(), owned.values.data() + diagonal_entries + off_begin);
    }
  }
  mirror_diagonal_block(owned, diagonal);
}

// The owned rows from the operator: row by row where it writes rows alone (the Kronecker form);
// elsewhere looked up in its lower triangle over all its functions (sum factorization over
// the process's element rows, which hold every element of an owned function: those rows are
// whole), O(log) per entry.
void write_owned_rows(const MatrixFreePoisson& op, const DofLayout& layout, RankRows& rows) {
  if (op.writes_rows()) {
    write_owned_rows([&op](int row, int count, const int* columns, double* values) {
      op.row_entries(row, count, columns, values);
    }, layout, rows);
    return;
  }
  const int n = op.num_functions();
  const Eigen::SparseMatrix<double> lower = op.lower_matrix(make_dof_layout(n, std::vector<bool>(n, false)));
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  const double* stored = lower.valuePtr();
  write_owned_rows([&](int row, int count, const int* columns, double* values) {
    for (int k = 0; k < count; ++k) {
      const int column = std::min(row, columns[k]), r = std::max(row, columns[k]);
      const int* at = std::lower_bound(inner + outer[column], inner + outer[column + 1], r);
      values[k] = at != inner + outer[column + 1] && *at == r ? stored[at - inner] : 0.0;
    }
  }, layout, rows);
}

}  // namespace

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
  PoissonForm mass = mass_form(load_form);
  mass.load = load_form.load;  // and the load (f, v), in the same pass
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

bool operator_serves(const PoissonProblem& problem, const GeometryMap& geometry) {
  const bool planar_or_volume = geometry.dimension() == 2 || geometry.parametric_dimension() == 3;
  return planar_or_volume && problem.coefficients.constant() && !problem.source.empty() &&
         problem.dirichlet_method != DirichletMethod::kNitsche;
}

PoissonSolution solve_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonProblem& problem,
                              const PoissonSolveOptions& options, const Distribution* distribution) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) {
    return std::chrono::duration<double>(clock::now() - t).count();
  };
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  if (problem.reaction < 0) throw std::invalid_argument("reaction must be >= 0");
  const bool volume = geometry.parametric_dimension() == 3;
  if (volume != (mesh.num_cells() > 0 && mesh.cell(0).dimension == 3))
    throw std::invalid_argument("the geometry's parametric dimension is not the mesh's cells'");
  // A gradient given by the caller (a Python exact solution) has as many components as it was given.
  if (problem.exact && problem.exact->on_surface() != (geometry.dimension() == 3))
    throw InputError(problem.exact->u.where() + ": the exact solution's gradient has " +
                     (problem.exact->on_surface() ? "3 components on a planar domain (give u_x, u_y)"
                                                  : "2 components on a surface (give u_x, u_y, u_z)"));
  const bool distributed = distribution != nullptr;
  // Serially a step's exception is the caller's as it is; distributed, every rank agrees on it.
  const auto step = [&](const std::function<void()>& f) {
    if (distributed) on_all_ranks(f);
    else f();
  };
  const ParallelWorld world = distributed ? parallel_world() : ParallelWorld{};
  const MeshPart* given = distributed ? distribution->part : nullptr;
  const MeshPart part = given ? *given : whole_mesh_part(mesh, world);
  // A closed surface has no boundary cell anywhere; a part may simply hold none.
  double boundary_sides = has_boundary(mesh) ? 1 : 0;
  if (distributed) sum_over_ranks(&boundary_sides, 1);
  PoissonSolution sol;
  sol.zero_mean = without_reaction(problem) && boundary_sides == 0;
  if (sol.zero_mean && given)
    throw std::invalid_argument("[solver] method = \"petsc\" solves closed surfaces only with the space built whole on "
                                "every rank (their zero-mean solution needs the whole mass matrix), and this family "
                                "split it; use method = \"direct\" or \"iterative\"");
  sol.num_functions = part.global_functions;
  if (distributed) sol.distributed.ranks = world.size;
  PoissonForm form = poisson_form(problem);

  say("setup");
  auto t = clock::now();
  std::vector<std::pair<int, double>> dirichlet;  // global function, value; sorted
  step([&] { dirichlet = project_dirichlet_over_ranks(mesh, geometry, problem, options.quadrature, part); });
  // A closed surface: the constant 1 from the mass matrix (on every rank: each holds the whole
  // mesh), one coefficient pinned to 0, the load with f's mean removed (added below).
  ZeroMeanData mean;
  if (sol.zero_mean) {
    step([&] { mean = zero_mean_data(mesh, geometry, form, options.quadrature, options.ordering); });
    dirichlet = {{mean.pin, 0.0}};
    sol.area = mean.area;
    sol.source_mean = mean.source_mean;
    form.load = false;
  }
  std::vector<int> fixed_functions(dirichlet.size());
  for (size_t k = 0; k < dirichlet.size(); ++k) fixed_functions[k] = dirichlet[k].first;
  // Free dofs are numbered globally in function order: a free function's row is its number
  // less the fixed functions before it (serially, its dof number).
  const auto fixed_below = [&](int g) {
    return static_cast<int>(std::lower_bound(fixed_functions.begin(), fixed_functions.end(), g) - fixed_functions.begin());
  };
  const int n = part.global_functions - static_cast<int>(fixed_functions.size());
  std::vector<bool> fixed(mesh.num_functions(), false);
  Eigen::VectorXd fixed_values = Eigen::VectorXd::Zero(mesh.num_functions());
  for (int f = 0; f < mesh.num_functions(); ++f) {
    const int g = part.global(f), k = fixed_below(g);
    if (k < static_cast<int>(fixed_functions.size()) && fixed_functions[k] == g)
      fixed[f] = true, fixed_values[f] = dirichlet[k].second;
  }
  const DofLayout layout = make_dof_layout(mesh.num_functions(), fixed);
  const CellRange mine = part.owned;
  // Serially the lower triangle CHOLMOD reads; distributed, this rank's rows as PETSc takes them.
  // (Built in place: Eigen 3.4's SparseMatrix has no move assignment, and a copy costs.)
  const bool matrix_free = options.matrix_free != nullptr;
  // What an operator's load and lifting serve: the problems without a matrix and, where one
  // is assembled, those whose operator writes it from its Kronecker form.
  const bool operator_problem = !sol.zero_mean && operator_serves(problem, geometry);
  if (matrix_free && (distributed || !operator_problem || !options.iterative || options.on_system || options.estimate_condition))
    throw std::logic_error("solve_poisson: the matrix-free path serves serial CG on planar problems and volumes with "
                           "constant coefficients, a given source and no Nitsche terms");
  // An operator that writes the matrix (then its load, lifting and errors are used too), or
  // one that gives only its pattern, for the element loop to fill. Distributed, each process
  // writes its owned rows whole from its operator, or none does (a process that adds its
  // cells' entries to rows another one wrote whole would count them twice), or gives the
  // pattern of its owned rows.
  std::shared_ptr<const MatrixFreePoisson> op, pattern_from;
  if (!matrix_free && options.matrix_from_operator) {
    std::shared_ptr<const MatrixFreePoisson> given;
    step([&] {
      given = options.matrix_from_operator();
      if (given && given->num_functions() != mesh.num_functions())
        throw std::logic_error("solve_poisson: matrix_from_operator gave an operator of another space");
    });
    const bool writes = given && operator_problem && given->assembles_lower();
    if (distributed) {
      double some_cannot = writes ? 0 : 1;
      max_over_ranks(&some_cannot, 1);
      if (some_cannot == 0) op = std::move(given);
      else if (given && given->gives_pattern()) pattern_from = std::move(given);
    } else if (writes) {
      op = std::move(given);
    } else if (given && given->gives_pattern()) {
      pattern_from = std::move(given);
    }
  }
  const bool matrix_by_operator = op != nullptr;
  Eigen::SparseMatrix<double> K = distributed || matrix_free || matrix_by_operator ? Eigen::SparseMatrix<double>()
                                  : pattern_from                                  ? pattern_from->lower_pattern(layout)
                                                                                  : lower_pattern_matrix(mesh, layout);
  RankRows rows;
  const int first_row = part.first_owned_function - fixed_below(part.first_owned_function);
  const int last_row = part.last_owned_function - fixed_below(part.last_owned_function);
  if (distributed) {
    std::vector<int> row_of_dof(layout.num_free());
    for (int d = 0; d < layout.num_free(); ++d) {
      const int g = part.global(layout.function_of_dof[d]);
      row_of_dof[d] = g - fixed_below(g);
    }
    // Rows the operator writes whole need no halo, and their pattern comes from it; where the
    // element loop fills them, the owned rows' pattern may still come from the operator.
    const MatrixFreePoisson* couplings_from = op ? op.get() : pattern_from.get();
    const CoupledFunctions coupled = [couplings_from](int f, std::vector<int>& out) {
      couplings_from->coupled_functions(f, out);
    };
    step([&] {
      rows = op ? owned_rows_pattern(layout, std::move(row_of_dof), first_row, last_row, coupled)
                : rank_rows_pattern(mesh, layout, std::move(row_of_dof), first_row, last_row, mine,
                                    pattern_from ? &coupled : nullptr);
    });
    sol.matrix_nonzeros = rows.owned.diagonal_nonzeros() + rows.owned.off_nonzeros();
  } else {
    sol.matrix_nonzeros = K.nonZeros();  // none stored without a matrix
  }
  sol.num_free = n;
  sol.timings.setup = seconds_since(t);

  // This process's cells (serially, all of them), threaded, into the lower triangle over its
  // free dofs; Neumann terms of the same cells; on a closed surface the compatible load.
  say("assembly");
  t = clock::now();
  Eigen::VectorXd rhs;
  Eigen::VectorXd free_diagonal;
  if (matrix_free || matrix_by_operator)
  step([&] {
    // F over the free dofs, less K g for the Dirichlet values g; Neumann terms as assembled.
    // Distributed, the owned rows of F and K g (whole: the operator covers their elements).
    sol.assembly = matrix_free ? "none" : op->assembly_method();
    if (distributed && !matrix_free) {  // one word for all processes: sum factorization where any used it
      double summed = sol.assembly == "sum_factorization" ? 1 : 0;
      max_over_ranks(&summed, 1);
      if (summed != 0) sol.assembly = "sum_factorization";
    }
    if (matrix_free) {
      op = options.matrix_free();
      if (!op || op->num_functions() != mesh.num_functions())
        throw std::logic_error("solve_poisson: matrix_free gave no operator, or one of another space");
    }
    else if (distributed) write_owned_rows(*op, layout, rows);
    else {
      Eigen::SparseMatrix<double> written = op->lower_matrix(layout);
      K.swap(written);  // (no copy: Eigen 3.4's SparseMatrix has no move assignment)
      sol.matrix_nonzeros = K.nonZeros();
    }
    const Eigen::VectorXd load = form.load ? op->load(*form.source) : Eigen::VectorXd::Zero(mesh.num_functions());
    Eigen::VectorXd lifting;
    if (fixed_values.lpNorm<Eigen::Infinity>() > 0) op->apply(fixed_values, lifting);
    rhs.setZero(layout.num_free());
    const int first = distributed ? rows.first : 0, last = distributed ? rows.last : layout.num_free();
    for (int d = first; d < last; ++d) {
      const int f = layout.function_of_dof[d];
      rhs[d] = load[f] - (lifting.size() > 0 ? lifting[f] : 0.0);
    }
    if (matrix_free) {
      const Eigen::VectorXd diagonal = op->diagonal();
      free_diagonal.resize(layout.num_free());
      for (int d = 0; d < layout.num_free(); ++d) free_diagonal[d] = diagonal[layout.function_of_dof[d]];
    }
    add_neumann_terms(mesh, geometry, problem, layout, options.quadrature, rhs, mine);
  });
  else
  step([&] {
    if (distributed) assemble_poisson(mesh, geometry, form, layout, fixed_values, options.quadrature, rows, rhs, mine);
    else assemble_poisson(mesh, geometry, form, layout, fixed_values, options.quadrature, K, rhs, nullptr, mine);
    add_neumann_terms(mesh, geometry, problem, layout, options.quadrature, rhs, mine);
    if (sol.zero_mean)  // each rank adds its own rows
      for (int d = 0; d < layout.num_free(); ++d) {
        const int g = layout.function_of_dof[d];
        if (part.global(g) >= part.first_owned_function && part.global(g) < part.last_owned_function) rhs[d] += mean.compatible_load(g);
      }
  });
  sol.timings.assembly = seconds_since(t);
  if (options.on_system && !distributed) options.on_system(K, rhs);
  if (options.estimate_condition && !distributed) {
    say("condition estimates");
    sol.stiffness_spectrum = jacobi_scaled_spectrum(K);
    // The mass matrix over the same free dofs (the matrix a reaction term would add).
    Eigen::SparseMatrix<double> M = K;  // the same pattern; its values are overwritten
    Eigen::VectorXd unused;
    assemble_poisson(mesh, geometry, mass_form(form), layout, Eigen::VectorXd::Zero(mesh.num_functions()), options.quadrature, M,
                     unused);
    sol.mass_spectrum = jacobi_scaled_spectrum(M);
  }

  // The backend.
  sol.coefficients = fixed_values;
  if (n > 0 && distributed) {  // global: every rank takes part, with or without rows of its own
    solve_with_petsc(std::move(rows), rhs, layout, first_row, last_row, n, fixed_functions, part, options,
                     *distribution->petsc, sol);
  } else if (n > 0 && options.iterative) {
    say("preconditioner");
    t = clock::now();
    if (matrix_free) {  // the preconditioner's matrix: K's diagonal alone
      K.resize(layout.num_free(), layout.num_free());
      K.reserve(Eigen::VectorXi::Ones(layout.num_free()));
      for (int d = 0; d < layout.num_free(); ++d) K.insert(d, d) = free_diagonal[d];
      K.makeCompressed();
    }
    std::unique_ptr<Preconditioner> pc = options.preconditioner ? options.preconditioner(layout, K) : nullptr;
    if (!pc) pc = jacobi_preconditioner(K);
    std::optional<FreeDofsOperator> free_op;
    if (matrix_free) {
      free_op.emplace(*op, layout, free_diagonal);
      // The preconditioner and the operator took what they need of K's diagonal; CG needs
      // neither copy (403 MB at 4096^2, p = 2: 8% of the run's peak).
      Eigen::SparseMatrix<double>().swap(K);
      Eigen::VectorXd().swap(free_diagonal);
    }
    sol.timings.preconditioner = seconds_since(t);
    say("iterations");
    t = clock::now();
    Eigen::VectorXd initial;
    if (options.initial.size() > 0) {
      if (options.initial.size() != mesh.num_functions())
        throw std::invalid_argument("an initial guess of " + std::to_string(options.initial.size()) + " coefficients for " +
                                    std::to_string(mesh.num_functions()) + " functions");
      initial.resize(layout.num_free());
      for (int d = 0; d < layout.num_free(); ++d) initial[d] = options.initial[layout.function_of_dof[d]];
    }
    const Eigen::VectorXd x =
        matrix_free ? preconditioned_cg(*free_op, rhs, *pc, options.tolerance, options.max_iterations, sol.iterative, &initial,
                                        options.energy_tolerance)
                    : preconditioned_cg(K, rhs, *pc, options.tolerance, options.max_iterations, sol.iterative, &initial,
                                        options.energy_tolerance);
    sol.timings.iterations = seconds_since(t);
    if (!sol.iterative.converged) {
      char b[400];
      std::snprintf(b, sizeof b, "CG stopped after %d iterations (%s) at backward error %.3e (relative residual %.3e), above the tolerance %.1e",
                    sol.iterative.iterations, sol.iterative.stop_reason().c_str(),
                    sol.iterative.backward_error, sol.iterative.relative_residual, options.tolerance);
      throw NotConverged(b);
    }
    for (int d = 0; d < layout.num_free(); ++d) sol.coefficients[layout.function_of_dof[d]] = x[d];
  } else if (n > 0) {
    say("factorization");
    const std::shared_ptr<SparseCholesky> cholesky =
        options.solver ? options.solver : std::make_shared<SparseCholesky>(resolve_ordering(options.ordering, volume));
    cholesky->factorize(K);
    say("solve");
    const Eigen::VectorXd x = cholesky->solve(rhs);
    sol.cholesky = cholesky->stats();
    sol.timings.analysis = sol.cholesky.analyze_seconds;
    sol.timings.factorization = sol.cholesky.factorize_seconds;
    sol.timings.solve = sol.cholesky.solve_seconds;
    for (int d = 0; d < layout.num_free(); ++d) sol.coefficients[layout.function_of_dof[d]] = x[d];
  }
  if (sol.zero_mean) mean.remove_mean(sol.coefficients);
  if (!sol.coefficients.allFinite()) throw std::runtime_error("the discrete solution has non-finite values");

  if (options.compute_errors && problem.exact) {
    say("error norms");
    t = clock::now();
    if (sol.zero_mean) {
      // Over the area the mass matrix measured (as the solution's mean is).
      double integral = 0;
      step([&] { integral = exact_integral(mesh, geometry, *problem.exact, options.quadrature); });
      sol.exact_mean = integral / sol.area;
    }
    std::array<double, 2> squares{0, 0};
    // Without a matrix the operator's own sum-factorized pass where it has one (the same rule
    // and integrand, about half the time: docs/SOLVERS.md), over this process's own cells
    // when distributed; else cell by cell.
    Eigen::VectorXd* per_cell = options.cell_errors ? &sol.cell_h1_squared : nullptr;
    bool by_operator = false;
    const MatrixFreePoisson* error_operator = op ? op.get() : pattern_from.get();
    if (error_operator && !sol.zero_mean)
      step([&] {
        by_operator = error_operator->squared_errors(sol.coefficients, *problem.exact, options.quadrature.error_points_u,
                                         options.quadrature.error_points_v, squares, per_cell, mine);
      });
    if (by_operator && per_cell && per_cell->size() != mesh.num_cells())
      throw std::logic_error("solve_poisson: the operator's errors are not one per cell of the mesh");
    if (!by_operator)
      step([&] {
        squares = squared_errors(mesh, geometry, sol.coefficients, *problem.exact, options.quadrature, mine, per_cell,
                                 sol.exact_mean);
      });
    if (distributed) {
      sum_over_ranks(squares.data(), 2);
      // A whole mesh on every rank gets every cell's error (a part has only its own cells').
      if (options.cell_errors && !given)
        sum_over_ranks(sol.cell_h1_squared.data(), static_cast<int>(sol.cell_h1_squared.size()));
    }
    ErrorNorms e;
    e.l2 = std::sqrt(squares[0]);
    e.h1_semi = std::sqrt(squares[1]);
    e.h1 = std::sqrt(squares[0] + squares[1]);
    sol.errors = e;
    sol.timings.errors = seconds_since(t);
  }
  if (distributed) {
    // Each phase as long as its slowest rank; the most cells and memory of any rank.
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    double phases[5] = {sol.timings.setup, sol.timings.assembly, sol.timings.errors, double(mesh.num_cells()),
                        usage.ru_maxrss / 1024.0};
    max_over_ranks(phases, 5);
    sol.timings.setup = phases[0], sol.timings.assembly = phases[1], sol.timings.errors = phases[2];
    sol.distributed.cells_held = static_cast<int>(phases[3]);
    sol.distributed.peak_memory_mb = phases[4];
  }
  return sol;
}

}  // namespace knotwork
