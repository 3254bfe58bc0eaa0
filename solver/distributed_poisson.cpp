#include "solver/distributed_poisson.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

#include <Eigen/SparseCore>
#include <memory>
#include <mutex>

#include "solver/assemble_poisson.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

namespace {
enum FailureKind { kNone = 0, kInput = 1, kGeometry = 2, kInvalid = 3, kOther = 4 };
}  // namespace

void on_all_ranks(const std::function<void()>& step) {
  int kind = kNone;
  std::string message;
  try {
    step();
  } catch (const GeometryError& e) {
    kind = kGeometry, message = e.what();
  } catch (const InputError& e) {
    kind = kInput, message = e.what();
  } catch (const std::invalid_argument& e) {
    kind = kInvalid, message = e.what();
  } catch (const std::exception& e) {
    kind = kOther, message = e.what();
  }
  const std::optional<RankFailure> f = agree_on_failure(kind, message);
  if (!f) return;
  switch (f->kind) {
    case kGeometry: throw GeometryError(f->message);
    case kInput: throw InputError(f->message);
    case kInvalid: throw std::invalid_argument(f->message);
    default: throw std::runtime_error(f->rank == 0 ? f->message : "rank " + std::to_string(f->rank) + ": " + f->message);
  }
}

CellRange cells_of_rank(int num_cells, ParallelWorld world) {
  const long n = num_cells;
  return CellRange{static_cast<int>(n * world.rank / world.size), static_cast<int>(n * (world.rank + 1) / world.size)};
}

namespace {

// PETSc's preallocation of rows [first_row, last_row): per row, the free dofs it couples with
// (the functions of the cells around it) in columns of those rows and in the others. A stamp
// per column and row instead of sets: each row costs the size of its cells' function lists.
void count_row_nonzeros(const BezierMesh& mesh, const DofLayout& layout, int first_row, int last_row,
                        std::vector<int>& diagonal, std::vector<int>& off_diagonal) {
  const int rows = last_row - first_row;
  std::vector<std::vector<int>> cells_of_row(rows);
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int f : mesh.functions(c)) {
      const int d = layout.dof[f];
      if (d >= first_row && d < last_row) cells_of_row[d - first_row].push_back(c);
    }
  diagonal.assign(rows, 0);
  off_diagonal.assign(rows, 0);
#pragma omp parallel
  {
    std::vector<int> stamp(layout.num_free(), -1);
#pragma omp for schedule(dynamic, 256)
    for (int r = 0; r < rows; ++r)
      for (int c : cells_of_row[r])
        for (int f : mesh.functions(c)) {
          const int d = layout.dof[f];
          if (d < 0 || stamp[d] == r) continue;
          stamp[d] = r;
          ++(d >= first_row && d < last_row ? diagonal[r] : off_diagonal[r]);
        }
  }
}

}  // namespace

PoissonSolution solve_poisson_distributed(const BezierMesh& mesh, const GeometryMap& geometry,
                                          const PoissonProblem& problem, const PoissonSolveOptions& options,
                                          const DistributedSolveOptions& petsc) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  if (problem.reaction < 0) throw std::invalid_argument("reaction must be >= 0");
  if (problem.reaction == 0 && !has_boundary(mesh))
    throw std::invalid_argument("[solver] method = \"petsc\" does not solve closed surfaces yet (their zero-mean "
                                "solution needs the whole mass matrix); use method = \"direct\" or \"iterative\"");
  const ParallelWorld world = parallel_world();
  PoissonSolution sol;
  sol.num_functions = mesh.num_functions();
  sol.distributed.ranks = world.size;
  PoissonForm form;
  form.reaction = problem.reaction;
  form.source_reaction = problem.reaction;
  form.source = problem.source.empty() ? nullptr : &problem.source;
  form.exact = problem.exact ? &*problem.exact : nullptr;

  say("setup");
  auto t = clock::now();
  std::vector<bool> fixed;
  Eigen::VectorXd fixed_values;
  on_all_ranks([&] { fixed_values = project_dirichlet_data(mesh, geometry, problem, options.quadrature, fixed); });
  const DofLayout layout = make_dof_layout(mesh.num_functions(), fixed);
  sol.num_free = layout.num_free();
  const CellRange mine = cells_of_rank(mesh.num_cells(), world);
  sol.timings.setup = seconds_since(t);

  sol.coefficients = fixed_values;
  if (layout.num_free() > 0) {
    say("assembly");
    t = clock::now();
    const int n = layout.num_free();
    const int first_row = static_cast<int>(long(n) * world.rank / world.size);
    const int last_row = static_cast<int>(long(n) * (world.rank + 1) / world.size);
    std::vector<int> diagonal_nonzeros, off_diagonal_nonzeros;
    count_row_nonzeros(mesh, layout, first_row, last_row, diagonal_nonzeros, off_diagonal_nonzeros);
    std::unique_ptr<DistributedSystem> system;
    on_all_ranks([&] {
      system = make_distributed_system(n, first_row, last_row, diagonal_nonzeros, off_diagonal_nonzeros);
    });
    diagonal_nonzeros = off_diagonal_nonzeros = {};
    // The cells' blocks go to PETSc one at a time (MatSetValues is not thread-safe); the
    // threads integrate the next cells meanwhile.
    std::mutex into_petsc;
    on_all_ranks([&] {
      assemble_poisson_elements(
          mesh, geometry, form, layout, fixed_values, options.quadrature, mine,
          [&](const std::vector<std::pair<int, int>>& order, const Eigen::MatrixXd& Ke, const Eigen::VectorXd& Fe) {
            // Per thread, reused from cell to cell (no allocation per cell once sizes settle).
            thread_local std::vector<int> dofs;
            thread_local Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> block;
            thread_local Eigen::VectorXd load;
            const int m = static_cast<int>(order.size());
            dofs.resize(m);
            block.resize(m, m);
            load.resize(m);
            for (int a = 0; a < m; ++a) {
              dofs[a] = order[a].first;
              load[a] = Fe[order[a].second];
              for (int b = 0; b < m; ++b) block(a, b) = Ke(order[a].second, order[b].second);
            }
            const std::lock_guard<std::mutex> one_at_a_time(into_petsc);
            system->add(m, dofs.data(), block.data(), load.data());
          });
      if (world.rank == 0) {  // the boundary's few terms, once
        Eigen::VectorXd neumann = Eigen::VectorXd::Zero(n);
        add_neumann_terms(mesh, geometry, problem, layout, options.quadrature, neumann);
        std::vector<int> rows;
        std::vector<double> values;
        for (int d = 0; d < n; ++d)
          if (neumann[d] != 0) rows.push_back(d), values.push_back(neumann[d]);
        system->add_load(static_cast<int>(rows.size()), rows.data(), values.data());
      }
    });
    on_all_ranks([&] { system->finish_assembly(); });
    sol.timings.assembly = seconds_since(t);

    // knotwork's own preconditioner as a PCShell: built on every rank from what it needs of
    // the matrix, the diagonal.
    std::unique_ptr<Preconditioner> shell;
    DistributedSolveOptions solve_options = petsc;
    if (petsc.preconditioner == "shell") {
      say("preconditioner");
      t = clock::now();
      Eigen::VectorXd diagonal;
      on_all_ranks([&] { diagonal = system->diagonal(); });
      Eigen::SparseMatrix<double> diagonal_matrix(n, n);
      std::vector<Eigen::Triplet<double>> d;
      for (int i = 0; i < n; ++i) d.emplace_back(i, i, diagonal[i]);
      diagonal_matrix.setFromTriplets(d.begin(), d.end());
      on_all_ranks([&] {
        if (options.preconditioner) shell = options.preconditioner(layout, diagonal_matrix);
        if (!shell) throw std::invalid_argument("[solver] preconditioner: the space's own preconditioner does not "
                                                "apply to this problem's unknowns");
      });
      solve_options.shell = shell.get();
      sol.timings.preconditioner = seconds_since(t);
    }
    say("PETSc solve");
    DistributedSolveResult r;
    on_all_ranks([&] {
      try {
        r = system->solve(solve_options);
      } catch (const std::invalid_argument& e) {  // the user's options
        throw std::invalid_argument(std::string("[solver] petsc_options: ") + e.what());
      }
    });
    system.reset();
    sol.matrix_nonzeros = r.global_nonzeros;
    sol.timings.preconditioner += r.setup_seconds;
    sol.timings.iterations = r.solve_seconds;
    sol.iterative.iterations = r.iterations;
    sol.iterative.relative_residual = r.relative_residual;
    sol.iterative.converged = r.converged;
    sol.distributed.ksp = r.ksp_type;
    sol.distributed.pc = r.pc_type;
    sol.distributed.package = r.factor_package;
    sol.distributed.reason = r.reason;
    if (!r.converged) {
      char b[300];
      std::snprintf(b, sizeof b, "PETSc's %s + %s stopped after %d iterations (%s) at relative residual %.3e, tolerance %.1e",
                    r.ksp_type.c_str(), r.pc_type.c_str(), r.iterations, r.reason.c_str(), r.relative_residual,
                    petsc.tolerance);
      throw NotConverged(b);
    }
    for (int d = 0; d < layout.num_free(); ++d) sol.coefficients[layout.function_of_dof[d]] = r.solution[d];
  }
  if (!sol.coefficients.allFinite()) throw std::runtime_error("the discrete solution has non-finite values");

  if (options.compute_errors && problem.exact) {
    say("error norms");
    t = clock::now();
    std::array<double, 2> squares{0, 0};
    on_all_ranks([&] {
      squares = squared_errors(mesh, geometry, sol.coefficients, *problem.exact, options.quadrature, mine,
                               options.cell_errors ? &sol.cell_h1_squared : nullptr);
    });
    sum_over_ranks(squares.data(), 2);
    if (options.cell_errors) sum_over_ranks(sol.cell_h1_squared.data(), static_cast<int>(sol.cell_h1_squared.size()));
    ErrorNorms n;
    n.l2 = std::sqrt(squares[0]);
    n.h1_semi = std::sqrt(squares[1]);
    n.h1 = std::sqrt(squares[0] + squares[1]);
    sol.errors = n;
    sol.timings.errors = seconds_since(t);
  }
  // Each phase as long as its slowest rank.
  double phases[3] = {sol.timings.setup, sol.timings.assembly, sol.timings.errors};
  max_over_ranks(phases, 3);
  sol.timings.setup = phases[0], sol.timings.assembly = phases[1], sol.timings.errors = phases[2];
  return sol;
}

}  // namespace knotwork
