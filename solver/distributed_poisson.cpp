#include "solver/distributed_poisson.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

#include <Eigen/SparseCore>
#include <memory>
#include <mutex>

#include <sys/resource.h>

#include "solver/assemble_poisson.hpp"
#include "basis/core/input_error.hpp"

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

// PETSc's preallocation of the rows of this rank: per owned row (local free dof d with
// row_of_dof[d] in [first_row, last_row)), the free dofs it couples with (the functions of the
// cells around it, all in the mesh) in columns of those rows and in the others. A stamp per
// column and row instead of sets: each row costs the size of its cells' function lists.
void count_row_nonzeros(const BezierMesh& mesh, const DofLayout& layout, const std::vector<int>& row_of_dof,
                        int first_row, int last_row, std::vector<int>& diagonal, std::vector<int>& off_diagonal) {
  const int rows = last_row - first_row;
  const auto owned = [&](int row) { return row >= first_row && row < last_row; };
  std::vector<std::vector<int>> cells_of_row(rows);
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int f : mesh.functions(c)) {
      const int d = layout.dof[f];
      if (d >= 0 && owned(row_of_dof[d])) cells_of_row[row_of_dof[d] - first_row].push_back(c);
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
          ++(owned(row_of_dof[d]) ? diagonal[r] : off_diagonal[r]);
        }
  }
}

// The whole mesh on every rank: its cells and functions in contiguous blocks.
MeshPart whole_mesh_part(const BezierMesh& mesh, ParallelWorld world) {
  MeshPart part;
  part.owned = cells_of_rank(mesh.num_cells(), world);
  part.global_functions = mesh.num_functions();
  part.global_cells = mesh.num_cells();
  const long n = mesh.num_functions();
  part.first_owned_function = static_cast<int>(n * world.rank / world.size);
  part.last_owned_function = static_cast<int>(n * (world.rank + 1) / world.size);
  return part;
}

// The Dirichlet projection from every rank's boundary cells, the same on every rank: the
// global numbers of the fixed functions (sorted) and their values.
std::vector<std::pair<int, double>> project_dirichlet_over_ranks(const BezierMesh& mesh, const GeometryMap& geometry,
                                                                 const PoissonProblem& problem,
                                                                 const QuadratureOptions& quadrature,
                                                                 const MeshPart& part) {
  const DirichletPieces mine = dirichlet_pieces(mesh, geometry, problem, quadrature, part.owned, part.function_offset);
  // Sent as doubles (function numbers < 2^31 are exact): counts, then functions and load, then
  // the mass entries as (row, column, value).
  std::vector<double> flat{double(mine.functions.size()), double(mine.mass.size())};
  flat.reserve(2 + 2 * mine.functions.size() + 3 * mine.mass.size());
  for (size_t k = 0; k < mine.functions.size(); ++k) flat.push_back(mine.functions[k]), flat.push_back(mine.load[k]);
  for (const auto& t : mine.mass) flat.push_back(t.row()), flat.push_back(t.col()), flat.push_back(t.value());
  const std::vector<double> all = gather_from_all_ranks(flat);
  DirichletPieces pieces;
  for (size_t at = 0; at < all.size();) {
    const size_t functions = static_cast<size_t>(all[at]), entries = static_cast<size_t>(all[at + 1]);
    at += 2;
    for (size_t k = 0; k < functions; ++k, at += 2)
      pieces.functions.push_back(static_cast<int>(all[at])), pieces.load.push_back(all[at + 1]);
    for (size_t k = 0; k < entries; ++k, at += 3)
      pieces.mass.emplace_back(static_cast<int>(all[at]), static_cast<int>(all[at + 1]), all[at + 2]);
  }
  return solve_dirichlet_projection(pieces);
}

}  // namespace

PoissonSolution solve_poisson_distributed(const BezierMesh& mesh, const GeometryMap& geometry, const MeshPart* given,
                                          const PoissonProblem& problem, const PoissonSolveOptions& options,
                                          const DistributedSolveOptions& petsc) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  if (problem.reaction < 0) throw std::invalid_argument("reaction must be >= 0");
  const ParallelWorld world = parallel_world();
  const MeshPart part = given ? *given : whole_mesh_part(mesh, world);
  // A closed surface has no boundary cell anywhere; a part may simply hold none.
  double boundary_sides = has_boundary(mesh) ? 1 : 0;
  sum_over_ranks(&boundary_sides, 1);
  const bool zero_mean = without_reaction(problem) && boundary_sides == 0;
  if (zero_mean && given)
    throw std::invalid_argument("[solver] method = \"petsc\" solves closed surfaces only with the space built whole on "
                                "every rank (their zero-mean solution needs the whole mass matrix), and this family "
                                "split it; use method = \"direct\" or \"iterative\"");
  PoissonSolution sol;
  sol.zero_mean = zero_mean;
  sol.num_functions = part.global_functions;
  sol.distributed.ranks = world.size;
  PoissonForm form = poisson_form(problem);

  say("setup");
  auto t = clock::now();
  std::vector<std::pair<int, double>> dirichlet;  // global function, value; sorted
  on_all_ranks([&] { dirichlet = project_dirichlet_over_ranks(mesh, geometry, problem, options.quadrature, part); });
  // A closed surface: as solve_poisson does, on every rank (each holds the whole mesh): the
  // constant 1 from the mass matrix, one coefficient pinned to 0, the load with f's mean removed.
  ZeroMeanData mean;
  if (zero_mean) {
    on_all_ranks([&] { mean = zero_mean_data(mesh, geometry, form, options.quadrature, options.ordering); });
    dirichlet = {{mean.pin, 0.0}};
    sol.area = mean.area;
    sol.source_mean = mean.source_mean;
    form.load = false;
  }
  std::vector<int> fixed_functions(dirichlet.size());
  for (size_t k = 0; k < dirichlet.size(); ++k) fixed_functions[k] = dirichlet[k].first;
  // Free dofs are numbered globally in function order: a free function's row is its number
  // less the fixed functions before it.
  const auto fixed_below = [&](int g) {
    return static_cast<int>(std::lower_bound(fixed_functions.begin(), fixed_functions.end(), g) - fixed_functions.begin());
  };
  const int n = part.global_functions - static_cast<int>(fixed_functions.size());
  std::vector<bool> fixed(mesh.num_functions(), false);
  Eigen::VectorXd fixed_values = Eigen::VectorXd::Zero(mesh.num_functions());
  for (int f = 0; f < mesh.num_functions(); ++f) {
    const int g = f + part.function_offset, k = fixed_below(g);
    if (k < static_cast<int>(fixed_functions.size()) && fixed_functions[k] == g)
      fixed[f] = true, fixed_values[f] = dirichlet[k].second;
  }
  const DofLayout layout = make_dof_layout(mesh.num_functions(), fixed);
  std::vector<int> row_of_dof(layout.num_free());
  for (int d = 0; d < layout.num_free(); ++d) {
    const int g = layout.function_of_dof[d] + part.function_offset;
    row_of_dof[d] = g - fixed_below(g);
  }
  sol.num_free = n;
  const CellRange mine = part.owned;
  sol.timings.setup = seconds_since(t);

  sol.coefficients = fixed_values;
  if (n > 0) {  // global: every rank takes part in the collective calls, with or without rows of its own
    say("assembly");
    t = clock::now();
    const int first_row = part.first_owned_function - fixed_below(part.first_owned_function);
    const int last_row = part.last_owned_function - fixed_below(part.last_owned_function);
    std::vector<int> diagonal_nonzeros, off_diagonal_nonzeros;
    count_row_nonzeros(mesh, layout, row_of_dof, first_row, last_row, diagonal_nonzeros, off_diagonal_nonzeros);
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
              dofs[a] = row_of_dof[order[a].first];
              load[a] = Fe[order[a].second];
              for (int b = 0; b < m; ++b) block(a, b) = Ke(order[a].second, order[b].second);
            }
            const std::lock_guard<std::mutex> one_at_a_time(into_petsc);
            system->add(m, dofs.data(), block.data(), load.data());
          });
      // The Neumann terms of the rank's cells.
      Eigen::VectorXd neumann = Eigen::VectorXd::Zero(layout.num_free());
      add_neumann_terms(mesh, geometry, problem, layout, options.quadrature, neumann, mine);
      if (zero_mean)  // the compatible load, once: each rank adds its own rows
        for (int d = 0; d < layout.num_free(); ++d) {
          const int g = layout.function_of_dof[d];
          if (g >= part.first_owned_function && g < part.last_owned_function)
            neumann[d] += mean.compatible_load(g);
        }
      std::vector<int> rows;
      std::vector<double> values;
      for (int d = 0; d < layout.num_free(); ++d)
        if (neumann[d] != 0) rows.push_back(row_of_dof[d]), values.push_back(neumann[d]);
      system->add_load(static_cast<int>(rows.size()), rows.data(), values.data());
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
      // It acts on every free dof of the global space (its numbering is the rows').
      std::vector<bool> fixed_globally(part.global_functions, false);
      for (int g : fixed_functions) fixed_globally[g] = true;
      const DofLayout global_layout = make_dof_layout(part.global_functions, fixed_globally);
      on_all_ranks([&] {
        if (options.preconditioner) shell = options.preconditioner(global_layout, diagonal_matrix);
        if (!shell) throw std::invalid_argument("[solver] preconditioner: the space's own preconditioner does not "
                                                "apply to this problem's unknowns");
      });
      solve_options.shell = shell.get();
      sol.timings.preconditioner = seconds_since(t);
    }
    say("PETSc solve");
    DistributedSolveResult r;
    solve_options.wanted_rows = &row_of_dof;
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
  if (zero_mean) mean.remove_mean(sol.coefficients);
  if (!sol.coefficients.allFinite()) throw std::runtime_error("the discrete solution has non-finite values");

  if (options.compute_errors && problem.exact) {
    say("error norms");
    t = clock::now();
    if (zero_mean) {
      double integral = 0;
      on_all_ranks([&] { integral = exact_integral(mesh, geometry, *problem.exact, options.quadrature); });
      sol.exact_mean = integral / sol.area;
    }
    std::array<double, 2> squares{0, 0};
    on_all_ranks([&] {
      squares = squared_errors(mesh, geometry, sol.coefficients, *problem.exact, options.quadrature, mine,
                               options.cell_errors ? &sol.cell_h1_squared : nullptr, sol.exact_mean);
    });
    sum_over_ranks(squares.data(), 2);
    // A whole mesh on every rank gets every cell's error (a part has only its own cells').
    if (options.cell_errors && !given)
      sum_over_ranks(sol.cell_h1_squared.data(), static_cast<int>(sol.cell_h1_squared.size()));
    ErrorNorms n;
    n.l2 = std::sqrt(squares[0]);
    n.h1_semi = std::sqrt(squares[1]);
    n.h1 = std::sqrt(squares[0] + squares[1]);
    sol.errors = n;
    sol.timings.errors = seconds_since(t);
  }
  // Each phase as long as its slowest rank; the most cells and memory of any rank.
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  double phases[5] = {sol.timings.setup, sol.timings.assembly, sol.timings.errors, double(mesh.num_cells()),
                      usage.ru_maxrss / 1024.0};
  max_over_ranks(phases, 5);
  sol.timings.setup = phases[0], sol.timings.assembly = phases[1], sol.timings.errors = phases[2];
  sol.distributed.cells_held = static_cast<int>(phases[3]);
  sol.distributed.peak_memory_mb = phases[4];
  return sol;
}

}  // namespace knotwork
