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
  DirichletPieces mine = dirichlet_pieces(mesh, geometry, problem, quadrature, part.owned, part);
  // One process has nothing to exchange (the copies below cost 64 bytes per boundary mass entry:
  // 2 GB at 256^3 hexahedra, p = 2).
  if (launched_world().size == 1) return solve_dirichlet_projection(std::move(mine));
  // Sent as doubles (function numbers < 2^31 are exact): counts, then functions and load, then
  // the mass entries as (row, column, value).
  std::vector<double> flat{double(mine.functions.size()), double(mine.mass.size())};
  flat.reserve(2 + 2 * mine.functions.size() + 3 * mine.mass.size());
  for (size_t k = 0; k < mine.functions.size(); ++k) flat.push_back(mine.functions[k]), flat.push_back(mine.load[k]);
  for (const auto& t : mine.mass) flat.push_back(t.row()), flat.push_back(t.col()), flat.push_back(t.value());
  std::vector<Eigen::Triplet<double>>().swap(mine.mass);
  std::vector<double> all = gather_from_all_ranks(flat);
  std::vector<double>().swap(flat);
  DirichletPieces pieces;
  for (size_t at = 0; at < all.size();) {
    const size_t functions = static_cast<size_t>(all[at]), entries = static_cast<size_t>(all[at + 1]);
    at += 2;
    for (size_t k = 0; k < functions; ++k, at += 2)
      pieces.functions.push_back(static_cast<int>(all[at])), pieces.load.push_back(all[at + 1]);
    for (size_t k = 0; k < entries; ++k, at += 3)
      pieces.mass.emplace_back(static_cast<int>(all[at]), static_cast<int>(all[at + 1]), all[at + 2]);
  }
  std::vector<double>().swap(all);
  return solve_dirichlet_projection(std::move(pieces));
}

void solve_with_petsc(RankRows&& rows, const Eigen::VectorXd& load, const DofLayout& layout, int first_row,
                    int last_row, int n,
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
    // The owned rows go to PETSc as they are; the halo rows, what this rank's cells put in
    // rows other ranks own, are added to their owners' rows.
    const int nd = layout.num_free();
    const std::vector<double> halo_values(rows.owned.values.begin() + rows.halo_offset(), rows.owned.values.end());
    rows.owned.values.resize(rows.halo_offset());
    system->set_owned_rows(std::move(rows.owned));
    std::vector<int> row_cols;
    for (int d = 0; d < nd; ++d) {
      const int begin = rows.halo_start[d], end = rows.halo_start[d + 1];
      if (begin == end) continue;
      row_cols.clear();
      for (int p = begin; p < end; ++p) row_cols.push_back(rows.global_row[rows.halo_cols[p]]);
      system->add_to_row(rows.global_row[d], end - begin, row_cols.data(), halo_values.data() + begin);
    }
    std::vector<int> load_rows;
    std::vector<double> load_values;
    for (int d = 0; d < layout.num_free(); ++d)
      if (load[d] != 0) load_rows.push_back(rows.global_row[d]), load_values.push_back(load[d]);
    system->add_load(static_cast<int>(load_rows.size()), load_rows.data(), load_values.data());
  });
  on_all_ranks([&] { system->finish_assembly(); });
  sol.timings.assembly += seconds_since(t);

  // knotwork's own preconditioner as a PCShell: built on every rank from what it needs of
  // the matrix, the diagonal or the whole matrix.
  std::unique_ptr<Preconditioner> shell;
  DistributedSolveOptions solve_options = petsc;
  if (petsc.preconditioner == "shell") {
    say("preconditioner");
    t = clock::now();
    Eigen::SparseMatrix<double> matrix(n, n);
    if (petsc.shell_reads_matrix) {
      on_all_ranks([&] { matrix = system->whole_lower(); });
    } else {
      Eigen::VectorXd diagonal;
      on_all_ranks([&] { diagonal = system->diagonal(); });
      std::vector<Eigen::Triplet<double>> d;
      for (int i = 0; i < n; ++i) d.emplace_back(i, i, diagonal[i]);
      matrix.setFromTriplets(d.begin(), d.end());
    }
    // It acts on every free dof of the global space (its numbering is the rows').
    std::vector<bool> fixed_globally(part.global_functions, false);
    for (int g : fixed_functions) fixed_globally[g] = true;
    const DofLayout global_layout = make_dof_layout(part.global_functions, fixed_globally);
    on_all_ranks([&] {
      if (options.preconditioner) shell = options.preconditioner(global_layout, matrix);
      if (!shell) throw std::invalid_argument("[solver] preconditioner: the space's own preconditioner does not "
                                              "apply to this problem's unknowns");
    });
    solve_options.shell = shell.get();
    sol.timings.preconditioner = seconds_since(t);
  }
  say("PETSc solve");
  DistributedSolveResult r;
  solve_options.wanted_rows = &rows.global_row;
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
  sol.iterative.backward_error = r.backward_error;
  sol.distributed.stop = r.tolerance_kind;
  sol.iterative.converged = r.converged;
  sol.distributed.ksp = r.ksp_type;
  sol.distributed.pc = r.pc_type;
  sol.distributed.package = r.factor_package;
  sol.distributed.reason = r.reason;
  if (!r.converged) {
    char b[300];
    if (r.tolerance_kind == "backward_error")
      std::snprintf(b, sizeof b, "PETSc's %s + %s stopped after %d iterations (%s) at backward error %.3e (relative residual "
                    "%.3e), above the tolerance %.1e",
                    r.ksp_type.c_str(), r.pc_type.c_str(), r.iterations, r.reason.c_str(), r.backward_error,
                    r.relative_residual, petsc.tolerance);
    else
      std::snprintf(b, sizeof b, "PETSc's %s + %s stopped after %d iterations (%s) at relative residual %.3e (PETSc's test, "
                    "from petsc_options)",
                    r.ksp_type.c_str(), r.pc_type.c_str(), r.iterations, r.reason.c_str(), r.relative_residual);
    throw NotConverged(b);
  }
  for (int d = 0; d < layout.num_free(); ++d) sol.coefficients[layout.function_of_dof[d]] = r.solution[d];
}

}  // namespace knotwork
