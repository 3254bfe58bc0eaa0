// The distributed solve of method = "petsc" (solver/petsc_module.hpp), in the PETSc module:
// PETSc does the message passing, the distributed matrix and the solvers (CG + hypre's
// BoomerAMG by default, MUMPS or any KSP/PC by options); knotwork gives each rank's element
// entries and takes back the solution.
#include <petscksp.h>

#include <algorithm>
#include <numeric>
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

std::vector<double> gather_all(const std::vector<double>& mine) {
  const ParallelWorld w = world();
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(w.size), offsets(w.size + 1, 0);
  check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, PETSC_COMM_WORLD) == MPI_SUCCESS ? 0 : PETSC_ERR_MPI,
        "MPI_Allgather");
  for (int r = 0; r < w.size; ++r) offsets[r + 1] = offsets[r] + counts[r];
  std::vector<double> all(offsets[w.size]);
  check(MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE,
                       PETSC_COMM_WORLD) == MPI_SUCCESS
            ? 0
            : PETSC_ERR_MPI,
        "MPI_Allgatherv");
  return all;
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

// The serial CG's stop (solver/iterative_solver.cpp) as PETSc's convergence test: the normwise
// backward error of the iterate, omega = ||b - A x||_inf / (||A||_inf ||x||_inf + ||b||_inf),
// at most `tolerance`. A relative residual cannot serve: its rounding floor grows like the
// condition number, and at PETSc's usual 1e-10 CG stopped with H1 errors 10^4 times the
// discretization's at p = 6 (docs/SOLVERS.md). The true residual costs a product with A, so
// it is computed only where the recurrence's 2-norm (at least its infinity norm) allows
// convergence, with a margin for the drift between the two. Stagnation as serially: no 10%
// gain over max(30, iterations / 2) checks while within 10^3 of the attainable accuracy.
struct BackwardErrorTest {
  PetscReal tolerance = 1e-15, a_norm = 0, b_norm = 0, attainable = 0, sqrt_n = 1;
  bool recurrence_norm = false;  // rnorm is the unpreconditioned residual's 2-norm
  Vec work = nullptr, residual = nullptr;
  PetscReal omega = -1, best = PETSC_INFINITY;  // the last and best computed (-1: none yet)
  PetscInt checks = 0, best_at = 0;
  bool converged = false, stagnated = false;
  ~BackwardErrorTest() {
    VecDestroy(&work);
    VecDestroy(&residual);
  }
};

PetscErrorCode backward_error_test(KSP ksp, PetscInt iteration, PetscReal rnorm, KSPConvergedReason* reason, void* context) {
  auto* t = static_cast<BackwardErrorTest*>(context);
  *reason = KSP_CONVERGED_ITERATING;
  if (t->b_norm == 0) {  // x = 0 solves it
    *reason = KSP_CONVERGED_ATOL;
    t->converged = true;
    t->omega = 0;
    return 0;
  }
  Vec x = nullptr;
  PetscCall(KSPBuildSolution(ksp, nullptr, &x));
  PetscReal x_norm = 0;
  PetscCall(VecNorm(x, NORM_INFINITY, &x_norm));
  const PetscReal scale = t->a_norm * x_norm + t->b_norm;
  constexpr PetscReal kDrift = 10;
  if (t->recurrence_norm && iteration > 0 && rnorm > kDrift * t->sqrt_n * t->tolerance * scale) return 0;
  Vec r = nullptr;
  PetscCall(KSPBuildResidual(ksp, t->work, t->residual, &r));
  PetscReal r_norm = 0;
  PetscCall(VecNorm(r, NORM_INFINITY, &r_norm));
  t->omega = r_norm / scale;
  ++t->checks;
  if (t->omega <= t->tolerance) {
    *reason = KSP_CONVERGED_ATOL;
    t->converged = true;
    return 0;
  }
  if (t->omega < 0.9 * t->best) t->best = t->omega, t->best_at = t->checks;
  if (t->checks - t->best_at >= std::max<PetscInt>(30, iteration / 2) && t->best <= 1e3 * t->attainable) {
    *reason = KSP_DIVERGED_BREAKDOWN;
    t->stagnated = true;
  }
  return 0;
}

// The most entries in one row of A, over all ranks (the attainable accuracy's m).
PetscInt max_row_entries(Mat A) {
  PetscInt first = 0, last = 0, most = 0;
  check(MatGetOwnershipRange(A, &first, &last), "rows");
  for (PetscInt row = first; row < last; ++row) {
    PetscInt n = 0;
    check(MatGetRow(A, row, &n, nullptr, nullptr), "row");
    most = std::max(most, n);
    check(MatRestoreRow(A, row, &n, nullptr, nullptr), "row");
  }
  PetscInt all = most;
  check(MPI_Allreduce(&most, &all, 1, MPIU_INT, MPI_MAX, PETSC_COMM_WORLD) == MPI_SUCCESS ? 0 : PETSC_ERR_MPI, "MPI_Allreduce");
  return all;
}

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

// The entries `rows` (global) of a distributed vector, on this rank.
Eigen::VectorXd gather_rows(Vec v, const std::vector<int>& rows) {
  IS from = nullptr;
  Vec local = nullptr;
  VecScatter scatter = nullptr;
  const PetscInt n = static_cast<PetscInt>(rows.size());
  Eigen::VectorXd result;
  PetscErrorCode code = ISCreateGeneral(PETSC_COMM_SELF, n, rows.data(), PETSC_USE_POINTER, &from);
  if (!code) code = VecCreateSeq(PETSC_COMM_SELF, n, &local);
  if (!code) code = VecScatterCreate(v, from, local, nullptr, &scatter);
  if (!code) code = VecScatterBegin(scatter, v, local, INSERT_VALUES, SCATTER_FORWARD);
  if (!code) code = VecScatterEnd(scatter, v, local, INSERT_VALUES, SCATTER_FORWARD);
  const PetscScalar* values = nullptr;
  if (!code) code = VecGetArrayRead(local, &values);
  if (!code) {
    result = Eigen::Map<const Eigen::VectorXd>(values, n);
    code = VecRestoreArrayRead(local, &values);
  }
  VecScatterDestroy(&scatter);
  VecDestroy(&local);
  ISDestroy(&from);
  check(code, "gather");
  return result;
}

// Every entry of a distributed vector, on every rank.
Eigen::VectorXd gather_on_all(Vec v) {
  PetscInt n = 0;
  check(VecGetSize(v, &n), "gather");
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  return gather_rows(v, all);
}

class PetscSystem final : public DistributedSystem {
 public:
  PetscSystem(int num_free, int first_row, int last_row) : num_free_(num_free), local_(last_row - first_row) {
    static_assert(sizeof(PetscInt) == sizeof(int), "PETSc with 32-bit indices (Debian's petsc-dev)");
    initialize_petsc();
    try {
      check(VecCreateMPI(PETSC_COMM_WORLD, local_, num_free, &b_), "load");
    } catch (...) {
      release();
      throw;
    }
  }
  ~PetscSystem() override { release(); }

  // The owned rows become the matrix's two blocks as they are (PETSc does not copy them: they
  // live in rows_ until the matrix is destroyed).
  void set_owned_rows(OwnedRows&& rows) override {
    const auto t = std::chrono::steady_clock::now();
    rows_ = std::move(rows);
    check(MatCreateMPIAIJWithSplitArrays(PETSC_COMM_WORLD, local_, local_, num_free_, num_free_,
                                         rows_.diagonal_start.data(), rows_.diagonal_cols.data(),
                                         rows_.values.data(), rows_.off_start.data(), rows_.off_cols.data(),
                                         rows_.values.data() + rows_.diagonal_nonzeros(), &A_),
          "matrix rows");
    // An entry outside the pattern is knotwork's error, not a slow path.
    check(MatSetOption(A_, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "matrix option");
    assembly_seconds_ += seconds_since(t);
  }
  void add_to_row(int row, int n, const int* cols, const double* values) override {
    const auto t = std::chrono::steady_clock::now();
    check(MatSetValues(A_, 1, &row, n, cols, values, ADD_VALUES), "matrix values");
    assembly_seconds_ += seconds_since(t);
  }
  void add_load(int n, const int* dofs, const double* values) override {
    check(VecSetValues(b_, n, dofs, values, ADD_VALUES), "load values");
  }
  void finish_assembly() override {
    const auto t = std::chrono::steady_clock::now();
    check(MatAssemblyBegin(A_, MAT_FINAL_ASSEMBLY), "matrix assembly");
    check(MatAssemblyEnd(A_, MAT_FINAL_ASSEMBLY), "matrix assembly");
    check(VecAssemblyBegin(b_), "load assembly");
    check(VecAssemblyEnd(b_), "load assembly");
    check(MatSetOption(A_, MAT_SYMMETRIC, PETSC_TRUE), "matrix symmetry");
    check(MatSetOption(A_, MAT_SPD, PETSC_TRUE), "matrix definiteness");
    assembly_seconds_ += seconds_since(t);
  }
  Eigen::VectorXd diagonal() override {
    Vec d = nullptr;
    check(VecDuplicate(b_, &d), "diagonal");
    PetscErrorCode code = MatGetDiagonal(A_, d);
    Eigen::VectorXd result;
    if (!code) {
      try {
        result = gather_on_all(d);
      } catch (...) {
        VecDestroy(&d);
        throw;
      }
    }
    VecDestroy(&d);
    check(code, "diagonal");
    return result;
  }
  Eigen::SparseMatrix<double> whole_lower() override {
    IS all = nullptr;
    Mat* copies = nullptr;
    check(ISCreateStride(PETSC_COMM_SELF, num_free_, 0, 1, &all), "whole matrix");
    PetscErrorCode code = MatCreateSubMatrices(A_, 1, &all, &all, MAT_INITIAL_MATRIX, &copies);
    ISDestroy(&all);
    check(code, "whole matrix");
    // Row i's entries from its diagonal on are column i of the lower triangle (symmetric).
    Eigen::SparseMatrix<double> lower(num_free_, num_free_);
    std::vector<int> starts(num_free_ + 1, 0), rows;
    std::vector<double> values;
    MatInfo info;
    if (!code && !(code = MatGetInfo(copies[0], MAT_LOCAL, &info))) {
      rows.reserve(static_cast<size_t>((info.nz_used + num_free_) / 2));
      values.reserve(rows.capacity());
    }
    for (PetscInt i = 0; i < num_free_ && !code; ++i) {
      PetscInt n = 0;
      const PetscInt* cols = nullptr;
      const PetscScalar* v = nullptr;
      if ((code = MatGetRow(copies[0], i, &n, &cols, &v))) break;
      for (PetscInt k = 0; k < n; ++k)
        if (cols[k] >= i) rows.push_back(cols[k]), values.push_back(v[k]);
      starts[i + 1] = static_cast<int>(rows.size());
      code = MatRestoreRow(copies[0], i, &n, &cols, &v);
    }
    MatDestroySubMatrices(1, &copies);
    check(code, "whole matrix rows");
    lower.resizeNonZeros(static_cast<Eigen::Index>(rows.size()));
    std::copy(starts.begin(), starts.end(), lower.outerIndexPtr());
    std::copy(rows.begin(), rows.end(), lower.innerIndexPtr());
    std::copy(values.begin(), values.end(), lower.valuePtr());
    return lower;
  }
  double assembly_seconds() const override { return assembly_seconds_; }
  DistributedSolveResult solve(const DistributedSolveOptions& asked) override;

 private:
  void release() {
    VecDestroy(&b_);
    MatDestroy(&A_);
  }
  int num_free_ = 0, local_ = 0;
  OwnedRows rows_;
  Mat A_ = nullptr;
  Vec b_ = nullptr;
  double assembly_seconds_ = 0;
};

// What one solve creates, destroyed on every path.
struct SolveObjects {
  Vec x = nullptr, r = nullptr;
  KSP ksp = nullptr;
  ~SolveObjects() {
    VecDestroy(&r);
    VecDestroy(&x);
    KSPDestroy(&ksp);
  }
};

DistributedSolveResult PetscSystem::solve(const DistributedSolveOptions& asked) {
  using clock = std::chrono::steady_clock;
  DistributedSolveOptions options = asked;
  const bool log_view = take_log_view(options.petsc_options);
  if (log_view) check(PetscLogDefaultBegin(), "-log_view");
  DistributedSolveResult result;
  SolveObjects o;
  MatInfo info;
  check(MatGetInfo(A_, MAT_GLOBAL_SUM, &info), "matrix info");
  result.global_nonzeros = static_cast<long>(info.nz_used);
  result.matrix_seconds = assembly_seconds_;
  check(VecDuplicate(b_, &o.x), "solution");

  auto t = clock::now();
  check(KSPCreate(PETSC_COMM_WORLD, &o.ksp), "KSP");
  check(KSPSetOperators(o.ksp, A_, A_), "KSP operators");
  check(KSPSetType(o.ksp, KSPCG), "KSP type");
  PC pc;
  check(KSPGetPC(o.ksp, &pc), "PC");
  ShellContext shell;
  if (options.preconditioner == "shell") {
    if (!options.shell) throw std::logic_error("DistributedSystem::solve: a shell preconditioner without one");
    shell.preconditioner = options.shell;
    check(VecScatterCreateToAll(b_, &shell.gather, &shell.all), "shell gather");
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
  check(KSPSetTolerances(o.ksp, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, options.max_iterations), "KSP tolerances");
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
  // knotwork's stop, unless the user's options ask for PETSc's own (-ksp_rtol, -ksp_atol).
  BackwardErrorTest stop;
  const bool petsc_stop = given.sets("ksp_rtol") || given.sets("ksp_atol");
  if (!petsc_stop) {
    stop.tolerance = options.tolerance;
    check(MatNorm(A_, NORM_INFINITY, &stop.a_norm), "matrix norm");
    check(VecNorm(b_, NORM_INFINITY, &stop.b_norm), "load norm");
    const PetscReal m_eps = PetscReal(max_row_entries(A_) + 1) * PETSC_MACHINE_EPSILON;
    stop.attainable = m_eps / (1 - std::min<PetscReal>(m_eps, 0.5));
    PetscInt n = 0;
    check(VecGetSize(b_, &n), "size");
    stop.sqrt_n = std::sqrt(PetscReal(n));
    KSPNormType norm_type;
    check(KSPGetNormType(o.ksp, &norm_type), "KSP norm");
    stop.recurrence_norm = norm_type == KSP_NORM_UNPRECONDITIONED;
    check(VecDuplicate(b_, &stop.work), "work");
    check(VecDuplicate(b_, &stop.residual), "work");
    check(KSPSetConvergenceTest(o.ksp, backward_error_test, &stop, nullptr), "convergence test");
  }
  check(KSPSetUp(o.ksp), "solver setup");  // factorizations read their options here
  if (const std::string unused = given.unused(); !unused.empty())
    throw std::invalid_argument(unused + ": not an option of PETSc's KSP, PC or factorization as set up (as in "
                                         "-ksp_type cg -pc_type hypre, -pc_type cholesky "
                                         "-pc_factor_mat_solver_type mumps)");
  result.setup_seconds = seconds_since(t);

  t = clock::now();
  check(KSPSolve(o.ksp, b_, o.x), "solve");
  result.solve_seconds = seconds_since(t);
  KSPConvergedReason reason;
  check(KSPGetConvergedReason(o.ksp, &reason), "converged reason");
  result.converged = reason > 0;
  result.reason = KSPConvergedReasons[reason];
  if (!petsc_stop) {
    if (stop.converged) result.reason = "CONVERGED_BACKWARD_ERROR";
    if (stop.stagnated) result.reason = "STAGNATED_BACKWARD_ERROR";
  }
  check(KSPGetIterationNumber(o.ksp, &result.iterations), "iterations");
  // The true residual, whatever norm the chosen KSP watched.
  PetscReal norm_b = 0, norm_r = 0;
  check(VecDuplicate(b_, &o.r), "residual");
  check(MatMult(A_, o.x, o.r), "residual");
  check(VecAYPX(o.r, -1.0, b_), "residual");
  check(VecNorm(o.r, NORM_2, &norm_r), "residual");
  check(VecNorm(b_, NORM_2, &norm_b), "residual");
  result.relative_residual = norm_b > 0 ? norm_r / norm_b : norm_r;
  {
    PetscReal a_inf = stop.a_norm, x_inf = 0, b_inf = 0, r_inf = 0;
    if (petsc_stop) check(MatNorm(A_, NORM_INFINITY, &a_inf), "matrix norm");  // (else the test's)
    check(VecNorm(o.x, NORM_INFINITY, &x_inf), "residual");
    check(VecNorm(b_, NORM_INFINITY, &b_inf), "residual");
    check(VecNorm(o.r, NORM_INFINITY, &r_inf), "residual");
    result.backward_error = a_inf * x_inf + b_inf > 0 ? r_inf / (a_inf * x_inf + b_inf) : 0;
  }
  result.tolerance_kind = petsc_stop ? "relative_residual" : "backward_error";
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
  result.solution = options.wanted_rows ? gather_rows(o.x, *options.wanted_rows) : gather_on_all(o.x);
  if (log_view) check(PetscLogView(PETSC_VIEWER_STDERR_WORLD), "-log_view");
  double times[3] = {result.matrix_seconds, result.setup_seconds, result.solve_seconds};
  reduce(times, 3, true);
  result.matrix_seconds = times[0], result.setup_seconds = times[1], result.solve_seconds = times[2];
  return result;
}

DistributedSystem* make_system(int num_free, int first_row, int last_row) {
  return new PetscSystem(num_free, first_row, last_row);
}

}  // namespace

Preconditioner* make_boomeramg(const Eigen::SparseMatrix<double>& lower, const std::string& petsc_options);

}  // namespace knotwork

// The module's one entry point, found by name (dlsym); C++ exceptions pass through its functions.
extern "C" __attribute__((visibility("default"))) const knotwork::PetscModuleApi* knotwork_petsc_api() {
  static const knotwork::PetscModuleApi api{knotwork::world,     knotwork::reduce,         knotwork::agree,
                                            knotwork::make_system, knotwork::broadcast,     knotwork::make_boomeramg,
                                            knotwork::gather_all};
  return &api;
}
