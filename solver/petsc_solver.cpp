// The distributed solve of method = "petsc" (solver/petsc_module.hpp), in the PETSc module:
// PETSc does the message passing, the distributed matrix and the solvers (CG + hypre's
// BoomerAMG by default, MUMPS or any KSP/PC by options); knotwork gives each rank's element
// entries and takes back the solution.
#include <petscksp.h>

#include <algorithm>
#include <sstream>
#include <chrono>
#include <stdexcept>
#include <vector>

#include "solver/petsc_common.hpp"
#include "solver/petsc_module_api.hpp"

namespace knotwork {

namespace {

ParallelWorld world() {
  initialize_petsc();
  ParallelWorld w;
  MPI_Comm_rank(PETSC_COMM_WORLD, &w.rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &w.size);
  return w;
}

void reduce(double* values, int n, bool maximum) {
  initialize_petsc();
  check(MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, maximum ? MPI_MAX : MPI_SUM, PETSC_COMM_WORLD) ==
                MPI_SUCCESS
            ? 0
            : PETSC_ERR_MPI,
        "MPI_Allreduce");
}

std::optional<RankFailure> agree(int kind, const std::string& message) {
  const ParallelWorld w = world();
  int mine = kind != 0 ? w.rank : w.size, lowest = w.size;
  MPI_Allreduce(&mine, &lowest, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD);
  if (lowest == w.size) return std::nullopt;
  RankFailure f;
  f.rank = lowest;
  int header[2] = {kind, static_cast<int>(message.size())};
  MPI_Bcast(header, 2, MPI_INT, lowest, PETSC_COMM_WORLD);
  f.kind = header[0];
  f.message = w.rank == lowest ? message : std::string(header[1], ' ');
  MPI_Bcast(f.message.data(), header[1], MPI_CHAR, lowest, PETSC_COMM_WORLD);
  return f;
}

void broadcast(std::string& text) {
  initialize_petsc();
  int length = static_cast<int>(text.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, PETSC_COMM_WORLD);
  text.resize(length);
  MPI_Bcast(text.data(), length, MPI_CHAR, 0, PETSC_COMM_WORLD);
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// knotwork's preconditioner as a PCShell: the residual gathered on every rank, the whole
// preconditioner applied there, each rank's own rows kept.
struct ShellContext {
  const Preconditioner* preconditioner = nullptr;
  VecScatter gather = nullptr;
  Vec all = nullptr;
  Eigen::VectorXd r, z;
  ~ShellContext() {
    VecScatterDestroy(&gather);
    VecDestroy(&all);
  }
};

PetscErrorCode apply_shell(PC pc, Vec x, Vec y) {
  ShellContext* context = nullptr;
  PetscCall(PCShellGetContext(pc, &context));
  PetscCall(VecScatterBegin(context->gather, x, context->all, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(context->gather, x, context->all, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar* values = nullptr;
  PetscCall(VecGetArrayRead(context->all, &values));
  PetscInt n = 0, first = 0, last = 0;
  PetscCall(VecGetSize(context->all, &n));
  context->r = Eigen::Map<const Eigen::VectorXd>(values, n);
  PetscCall(VecRestoreArrayRead(context->all, &values));
  context->preconditioner->apply(context->r, context->z);
  PetscCall(VecGetOwnershipRange(y, &first, &last));
  PetscScalar* out = nullptr;
  PetscCall(VecGetArray(y, &out));
  for (PetscInt i = first; i < last; ++i) out[i - first] = context->z[i];
  PetscCall(VecRestoreArray(y, &out));
  return 0;
}

// What one solve creates, destroyed on every path.
struct Objects {
  Mat A = nullptr;
  Vec b = nullptr, x = nullptr, r = nullptr, all = nullptr;
  KSP ksp = nullptr;
  VecScatter gather = nullptr;
  ~Objects() {
    VecScatterDestroy(&gather);
    VecDestroy(&all);
    VecDestroy(&r);
    VecDestroy(&x);
    VecDestroy(&b);
    KSPDestroy(&ksp);
    MatDestroy(&A);
  }
};

// -log_view is PETSc's own (no prefix): taken out of the options, it starts PETSc's event
// log for this solve and prints the summary on stderr at its end (stdout may carry JSON).
bool take_log_view(std::string& options) {
  std::istringstream words(options);
  std::string rest, w;
  bool found = false;
  while (words >> w) {
    if (w == "-log_view") found = true;
    else rest += (rest.empty() ? "" : " ") + w;
  }
  options = rest;
  return found;
}

DistributedSolveResult solve(int num_free, const ElementEntries& local, const DistributedSolveOptions& asked) {
  initialize_petsc();
  using clock = std::chrono::steady_clock;
  DistributedSolveOptions options = asked;
  const bool log_view = take_log_view(options.petsc_options);
  if (log_view) check(PetscLogDefaultBegin(), "-log_view");
  DistributedSolveResult result;
  Objects o;
  auto t = clock::now();
  // PETSc may reorder the index arrays it is given: copies.
  std::vector<PetscInt> rows(local.rows.begin(), local.rows.end()), cols(local.cols.begin(), local.cols.end());
  check(MatCreate(PETSC_COMM_WORLD, &o.A), "matrix");
  check(MatSetSizes(o.A, PETSC_DECIDE, PETSC_DECIDE, num_free, num_free), "matrix sizes");
  check(MatSetType(o.A, MATAIJ), "matrix type");
  check(MatSetPreallocationCOO(o.A, static_cast<PetscCount>(rows.size()), rows.data(), cols.data()),
        "matrix preallocation");
  check(MatSetValuesCOO(o.A, local.values.data(), ADD_VALUES), "matrix values");
  check(MatSetOption(o.A, MAT_SYMMETRIC, PETSC_TRUE), "matrix symmetry");
  check(MatSetOption(o.A, MAT_SPD, PETSC_TRUE), "matrix definiteness");
  check(MatCreateVecs(o.A, &o.x, &o.b), "vectors");
  std::vector<PetscInt> rhs_rows(local.rhs_rows.begin(), local.rhs_rows.end());
  check(VecSetValues(o.b, static_cast<PetscInt>(rhs_rows.size()), rhs_rows.data(), local.rhs_values.data(), ADD_VALUES),
        "load");
  check(VecAssemblyBegin(o.b), "load");
  check(VecAssemblyEnd(o.b), "load");
  MatInfo info;
  check(MatGetInfo(o.A, MAT_GLOBAL_SUM, &info), "matrix info");
  result.global_nonzeros = static_cast<long>(info.nz_used);
  result.matrix_seconds = seconds_since(t);

  t = clock::now();
  check(KSPCreate(PETSC_COMM_WORLD, &o.ksp), "KSP");
  check(KSPSetOperators(o.ksp, o.A, o.A), "KSP operators");
  check(KSPSetType(o.ksp, KSPCG), "KSP type");
  PC pc;
  check(KSPGetPC(o.ksp, &pc), "PC");
  ShellContext shell;
  if (options.preconditioner == "shell") {
    if (!options.shell) throw std::logic_error("solve_distributed: a shell preconditioner without one");
    shell.preconditioner = options.shell;
    check(VecScatterCreateToAll(o.b, &shell.gather, &shell.all), "shell gather");
    check(PCSetType(pc, PCSHELL), "PCSHELL");
    check(PCShellSetContext(pc, &shell), "PCSHELL");
    check(PCShellSetApply(pc, apply_shell), "PCSHELL");
    check(PCShellSetName(pc, "knotwork"), "PCSHELL");
  } else if (options.preconditioner == "jacobi") {
    check(PCSetType(pc, PCJACOBI), "PCJACOBI");
  } else {
    check(PCSetType(pc, PCHYPRE), "PCHYPRE");
    check(PCHYPRESetType(pc, "boomeramg"), "BoomerAMG");
  }
  check(KSPSetTolerances(o.ksp, options.tolerance, PETSC_DEFAULT, PETSC_DEFAULT, options.max_iterations),
        "KSP tolerances");
  check(KSPSetNormType(o.ksp, KSP_NORM_UNPRECONDITIONED), "KSP norm");
  // hypre's default smoother is not symmetric across processes: CG then met an indefinite
  // preconditioner on 3 ranks (g1_mixed_valences). The l1-scaled hybrid symmetric
  // Gauss-Seidel is, and converges for every SPD matrix. The user's options come after it.
  check(PetscOptionsSetValue(nullptr, "-knotwork_pc_hypre_boomeramg_relax_type_all", "l1scaled-SOR/Jacobi"),
        "default smoother");
  check(KSPSetOptionsPrefix(o.ksp, "knotwork_"), "options prefix");
  const ScopedOptions given("knotwork_", options.petsc_options);
  given.read([&] { return KSPSetFromOptions(o.ksp); });
  if (!given.sets("pc_hypre_boomeramg_relax_type_all"))
    PetscOptionsClearValue(nullptr, "-knotwork_pc_hypre_boomeramg_relax_type_all");
  check(KSPSetUp(o.ksp), "solver setup");  // factorizations read their options here
  if (const std::string unused = given.unused(); !unused.empty())
    throw std::invalid_argument(unused + ": not an option of PETSc's KSP, PC or factorization as set up (as in "
                                         "-ksp_type cg -pc_type hypre, -pc_type cholesky "
                                         "-pc_factor_mat_solver_type mumps)");
  result.setup_seconds = seconds_since(t);

  t = clock::now();
  check(KSPSolve(o.ksp, o.b, o.x), "solve");
  result.solve_seconds = seconds_since(t);
  KSPConvergedReason reason;
  check(KSPGetConvergedReason(o.ksp, &reason), "converged reason");
  result.converged = reason > 0;
  result.reason = KSPConvergedReasons[reason];
  check(KSPGetIterationNumber(o.ksp, &result.iterations), "iterations");
  // The true residual, whatever norm the chosen KSP watched.
  PetscReal norm_b = 0, norm_r = 0;
  check(VecDuplicate(o.b, &o.r), "residual");
  check(MatMult(o.A, o.x, o.r), "residual");
  check(VecAYPX(o.r, -1.0, o.b), "residual");
  check(VecNorm(o.r, NORM_2, &norm_r), "residual");
  check(VecNorm(o.b, NORM_2, &norm_b), "residual");
  result.relative_residual = norm_b > 0 ? norm_r / norm_b : norm_r;
  KSPType ksp_type;
  PCType pc_type;
  check(KSPGetType(o.ksp, &ksp_type), "KSP type");
  check(PCGetType(pc, &pc_type), "PC type");
  result.ksp_type = ksp_type;
  result.pc_type = pc_type;
  if (result.pc_type == PCCHOLESKY || result.pc_type == PCLU) {
    MatSolverType package = nullptr;
    check(PCFactorGetMatSolverType(pc, &package), "factor package");
    if (package) result.factor_package = package;
  }

  check(VecScatterCreateToAll(o.x, &o.gather, &o.all), "gather");
  check(VecScatterBegin(o.gather, o.x, o.all, INSERT_VALUES, SCATTER_FORWARD), "gather");
  check(VecScatterEnd(o.gather, o.x, o.all, INSERT_VALUES, SCATTER_FORWARD), "gather");
  const PetscScalar* values = nullptr;
  check(VecGetArrayRead(o.all, &values), "gather");
  result.solution = Eigen::Map<const Eigen::VectorXd>(values, num_free);
  check(VecRestoreArrayRead(o.all, &values), "gather");
  if (log_view) check(PetscLogView(PETSC_VIEWER_STDERR_WORLD), "-log_view");
  double times[3] = {result.matrix_seconds, result.setup_seconds, result.solve_seconds};
  reduce(times, 3, true);
  result.matrix_seconds = times[0], result.setup_seconds = times[1], result.solve_seconds = times[2];
  return result;
}

}  // namespace

Preconditioner* make_boomeramg(const Eigen::SparseMatrix<double>& lower, const std::string& petsc_options);

}  // namespace knotwork

// The module's one entry point, found by name (dlsym); C++ exceptions pass through its functions.
extern "C" __attribute__((visibility("default"))) const knotwork::PetscModuleApi* knotwork_petsc_api() {
  static const knotwork::PetscModuleApi api{knotwork::world, knotwork::reduce, knotwork::agree, knotwork::solve,
                                            knotwork::broadcast, knotwork::make_boomeramg};
  return &api;
}
