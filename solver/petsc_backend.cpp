#include "solver/petsc_backend.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

#include <Eigen/SparseCore>
#include <memory>

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
  const DirichletPieces mine = dirichlet_pieces(mesh, geometry, problem, quadrature, part.owned, part);
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

void solve_with_petsc(Eigen::SparseMatrix<double>& K, const Eigen::VectorXd& load, const DofLayout& layout,
                    const std::vector<int>& row_of_dof, int first_row, int last_row, int n,
                    const std::vector<int>& fixed_functions, const MeshPart& part, const PoissonSolveOptions& options,
                    const DistributedSolveOptions& petsc, PoissonSolution& sol) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  auto say = [&](const std::string& s) {
  if (options.progress) options.progress(s);
  };
  auto t = clock::now();
  std::unique_ptr<DistributedSystem> system;
  on_all_ranks([&] { system = make_distributed_system(n, first_row, last_row); });
  on_all_ranks([&] {
    // Both triangles, row by row, straight from the lower CSC: sweeping its columns j in
    // order, row i >= j gets (j, v) and row j gets (i, v), so every row fills in ascending
    // column order (row_of_dof is increasing). Owned rows go to PETSc as its two blocks
    // (columns this rank owns, and the others); the other rows, what this rank's cells put
    // there, are added to their owners' rows.
    const int nd = layout.num_free();
    const auto owned = [&](int d) { return row_of_dof[d] >= first_row && row_of_dof[d] < last_row; };
    const auto owned_column = [&](int d) { return owned(d); };  // same ranges: square blocks
    const int* outer = K.outerIndexPtr();
    const int* inner = K.innerIndexPtr();
    const double* value = K.valuePtr();
    // This rank's owned dofs are one contiguous run [first, last) of its local dofs.
    int first = 0;
    while (first < nd && !owned(first)) ++first;
    int last = first;
    while (last < nd && owned(last)) ++last;
    if (last - first != last_row - first_row)
      throw std::logic_error("distributed assembly: this rank's mesh does not hold all of its rows");
    // Pass 1: the length of every row's part in each block (other rows: one count).
    std::vector<int> diagonal_count(nd + 1, 0), off_count(nd + 1, 0);
    const auto count = [&](int row, int col) { ++(owned(row) && owned_column(col) ? diagonal_count : off_count)[row + 1]; };
    for (int j = 0; j < nd; ++j)
      for (int p = outer[j]; p < outer[j + 1]; ++p) {
        count(inner[p], j);
        if (inner[p] != j) count(j, inner[p]);
      }
    OwnedRows rows;
    rows.diagonal_start.assign(diagonal_count.begin() + first, diagonal_count.begin() + last + 1);
    rows.off_start.assign(off_count.begin() + first, off_count.begin() + last + 1);
    rows.diagonal_start[0] = rows.off_start[0] = 0;
    for (int r = 0; r < last - first; ++r)
      rows.diagonal_start[r + 1] += rows.diagonal_start[r], rows.off_start[r + 1] += rows.off_start[r];
    std::vector<int> other_start(nd + 1, 0);  // rows owned elsewhere: all their entries
    for (int d = 0; d < nd; ++d) other_start[d + 1] = other_start[d] + (d >= first && d < last ? 0 : off_count[d + 1]);
    diagonal_count = off_count = {};
    rows.diagonal_cols.resize(rows.diagonal_start.back()), rows.diagonal_values.resize(rows.diagonal_start.back());
    rows.off_cols.resize(rows.off_start.back()), rows.off_values.resize(rows.off_start.back());
    std::vector<int> other_cols(other_start[nd]);
    std::vector<double> other_values(other_start[nd]);
    // Pass 2: fill.
    std::vector<int> next_diagonal(rows.diagonal_start.begin(), rows.diagonal_start.end() - 1);
    std::vector<int> next_off(rows.off_start.begin(), rows.off_start.end() - 1);
    std::vector<int> next_other(other_start.begin(), other_start.end() - 1);
    const auto put = [&](int row, int col, double v) {
      if (row >= first && row < last) {
        if (owned_column(col))
          rows.diagonal_cols[next_diagonal[row - first]] = row_of_dof[col] - first_row,
          rows.diagonal_values[next_diagonal[row - first]++] = v;
        else
          rows.off_cols[next_off[row - first]] = row_of_dof[col], rows.off_values[next_off[row - first]++] = v;
      } else {
        other_cols[next_other[row]] = row_of_dof[col], other_values[next_other[row]++] = v;
      }
    };
    for (int j = 0; j < nd; ++j)
      for (int p = outer[j]; p < outer[j + 1]; ++p) {
        put(inner[p], j, value[p]);
        if (inner[p] != j) put(j, inner[p], value[p]);
      }
    K = Eigen::SparseMatrix<double>();
    next_diagonal = next_off = next_other = {};
    system->set_owned_rows(std::move(rows));
    std::vector<int> row_cols;
    std::vector<double> row_values;
    for (int d = 0; d < nd; ++d) {
      row_cols.clear(), row_values.clear();
      for (int p = other_start[d]; p < other_start[d + 1]; ++p)
        if (other_values[p] != 0) row_cols.push_back(other_cols[p]), row_values.push_back(other_values[p]);  // 0: no cell of this rank there
      if (!row_cols.empty())
        system->add_to_row(row_of_dof[d], static_cast<int>(row_cols.size()), row_cols.data(), row_values.data());
    }
    std::vector<int> load_rows;
    std::vector<double> load_values;
    for (int d = 0; d < layout.num_free(); ++d)
      if (load[d] != 0) load_rows.push_back(row_of_dof[d]), load_values.push_back(load[d]);
    system->add_load(static_cast<int>(load_rows.size()), load_rows.data(), load_values.data());
  });
  on_all_ranks([&] { system->finish_assembly(); });
  sol.timings.assembly += seconds_since(t);

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

}  // namespace knotwork
