#include "studies/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>

#include "solver/amg_preconditioner.hpp"
#include "solver/nested_multigrid.hpp"
#include "solver/petsc_backend.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

std::unique_ptr<SplineSpace> build_space(const CaseDescription& c, int level, const ProgressFunction& progress) {
  const SpaceFamily& family = space_family(c);
  const ParallelWorld launched = launched_world();
  std::unique_ptr<SplineSpace> space;
  if (launched.size > 1 && c.solver.method == "petsc" && family.build_part) {
    on_all_ranks([&] { space = family.build_part(c, level, launched.rank, launched.size, progress); });
    if (space->part()) return space;  // a part of the space: the family checked its share
  } else {
    space = family.build(c, level, progress);
  }
  // The whole space on every process, which assembles its range of the cells.
  if (launched.size > 1 && c.solver.method == "petsc" && space->mesh().num_cells() < launched.size)
    throw InputError(c.path + ": [space]: the space has " + std::to_string(space->mesh().num_cells()) +
                     " cells, fewer than the " + std::to_string(launched.size) + " processes that share them: use at most " +
                     std::to_string(space->mesh().num_cells()) + " processes");
  return space;
}

int global_num_cells(const SplineSpace& space) {
  return space.part() ? space.part()->global_cells : space.mesh().num_cells();
}

double global_mesh_size(const SplineSpace& space) {
  double h = space.mesh_size();
  if (space.part()) max_over_ranks(&h, 1);
  return h;
}

CellRange cells_to_write(const SplineSpace& space, ParallelWorld world) {
  return space.part() ? space.part()->owned : cells_of_rank(space.mesh().num_cells(), world);
}

namespace {

constexpr int kAutoIterativeFunctions = CaseDescription::Solver::kAutoIterativeFunctions;
// Above this many CG iterations with a space's first structured preconditioner, a note names
// its next one (measured: the fast diagonalization needs 2-5 where the operator separates,
// 32-34 on the L-shape patch, where multigrid needs 11: docs/SOLVERS.md).
constexpr int kManyStructuredIterations = 15;
// From here "auto" takes multigrid for CG without a matrix on affine elements: measured on the
// unit square at p = 2 (docs/SOLVERS.md), the fast diagonalization faster at 1024^2 (1.83 against
// 2.09 s), multigrid at 2048^2 (9.0 against 10.1 s) and 4096^2.
constexpr int kAutoMultigridFunctions = 2000000;
const std::string kMultigridName = "multigrid";

// `over_steps`: an adaptive loop solves with multigrid over its steps (AdaptiveSolve; it
// decided so, and checked the case's [solver] for it).
SolverReport resolve_solver(const CaseDescription& c, const SplineSpace& space, bool over_steps) {
  SolverReport r;
  if (over_steps) {
    r.method = "iterative";
    r.preconditioner = kMultigridName;
    if (c.solver.preconditioner == "auto")
      r.note = "[solver] preconditioner = \"auto\" in adapt: multigrid over the steps, measured faster than CHOLMOD and "
               "BoomerAMG on the adaptive loops measured (docs/ADAPTIVITY.md)";
    return r;
  }
  const std::vector<std::string> structured = space.structured_preconditioners();
  std::string automatic_why;
  const std::string automatic =
      !structured.empty() && space.structured_preconditioner_is_automatic() ? space.automatic_structured_preconditioner(automatic_why)
                                                                             : "";
  if (c.solver.method == "auto")
    r.method = !automatic.empty() && space.mesh().num_functions() >= kAutoIterativeFunctions ? "iterative" : "direct";
  else
    r.method = c.solver.method;
  const std::string& asked = c.solver.preconditioner;
  const bool algebraic = asked == "auto" || asked == "jacobi" || asked == kBoomerAmgName;
  // A structured preconditioner the space does not have is refused even where the direct path
  // is taken (so that `auto` on a small case does not hide a name that would never apply).
  if (r.method == "direct" && (algebraic || std::find(structured.begin(), structured.end(), asked) != structured.end()))
    return r;  // auto: the documented choice (docs/SOLVERS.md), not a fallback
  if (asked == "auto") {
    // Without a structure to use: algebraic multigrid, whose iteration count stays bounded as
    // h shrinks where Jacobi's grows like 1/h (docs/SOLVERS.md).
    r.preconditioner = automatic.empty() ? kBoomerAmgName : automatic;
    if (!automatic.empty() && !automatic_why.empty())
      r.note = "[solver] preconditioner = \"auto\": " + automatic + ", " + automatic_why;
    else if (structured.empty())
      r.note = "[solver] preconditioner = \"auto\": boomeramg (hypre BoomerAMG through PETSc), since this space (family \"" +
               c.family + "\"" + (c.multipatch() ? ", several patches" : "") + ") has no structured preconditioner";
    else if (automatic.empty())
      r.note = "[solver] preconditioner = \"auto\": boomeramg (hypre BoomerAMG through PETSc); this space's \"" + structured.front() +
               "\" is used only when asked for by name (docs/SOLVERS.md)";
  } else if (asked == "jacobi" || asked == kBoomerAmgName) {
    r.preconditioner = asked;  // algebraic: they apply to every family
  } else if (std::find(structured.begin(), structured.end(), asked) != structured.end()) {
    // (Under method = "petsc" every one is a PCShell, built from the whole matrix where it reads
    // more than the diagonal and has no operator to read: below.)
    r.preconditioner = asked;
  } else {
    std::string names;
    for (const std::string& s : structured) names += (names.empty() ? "\"" : ", \"") + s + "\"";
    throw InputError(c.path + ": [solver] preconditioner: \"" + asked + "\" does not apply to family \"" + c.family +
                     "\"" + (c.multipatch() ? " on several patches" : "") + " (" + (structured.empty() ? std::string("use \"auto\", \"boomeramg\" or \"jacobi\"")
                                                   : "it has " + names + "; or use \"boomeramg\" or \"jacobi\"") + ")");
  }
  if (r.method == "iterative" && r.preconditioner == kBoomerAmgName) {
    r.petsc_options = c.solver.petsc_options;
    if (space.geometry().parametric_dimension() == 3)
      r.petsc_options = std::string(kBoomerAmgVolumeOptions) + (r.petsc_options.empty() ? "" : " " + r.petsc_options);
  }
  return r;
}

// Gauss points per direction below degree + 1 leave the stiffness under-integrated: on a cell
// of degree p, L_n(u) L_n(v) (Legendre, n < p + 1 points) lies in the cell's polynomials and its
// gradient vanishes at every point of the rule, so the matrix can lose definiteness and the
// solve would then blame the boundary conditions. Refused before any work, naming the key.
void check_quadrature_points(const CaseDescription& c, const BezierMesh& mesh) {
  int pu = 0, pv = 0, pw = 0;  // pw: a volume's hexahedra
  for (int e = 0; e < mesh.num_cells(); ++e) {
    pu = std::max(pu, mesh.cell(e).degree_u);
    pv = std::max(pv, mesh.cell(e).degree_v);
    pw = std::max<int>(pw, mesh.cell(e).degree_w);
  }
  const int p = std::max({pu, pv, pw});
  auto check = [&](const char* key, int nu, int nv, int nw, const std::string& integrand) {
    for (const auto& [n, d] : {std::pair{nu, pu}, std::pair{nv, pv}, std::pair{nw, pw}})
      if (n > 0 && n < d + 1)
        throw InputError(c.path + ": [space] " + key + ": " + std::to_string(n) + " Gauss point" + (n == 1 ? "" : "s") +
                         " per direction, fewer than degree + 1 = " + std::to_string(d + 1) +
                         ", the fewest that integrate " + integrand + " (omit the key for the default)");
  };
  check("quadrature_points", c.quadrature.points_u, c.quadrature.points_v, c.quadrature.points_w,
        "the stiffness of a degree-" + std::to_string(p) + " space exactly on straight cells");
  check("error_quadrature_points", c.quadrature.error_points_u, c.quadrature.error_points_v, c.quadrature.error_points_w,
        "|grad u_h|^2 of a degree-" + std::to_string(p) + " solution exactly on straight cells");
}

// Why the space's operator (SplineSpace::matrix_free_operator, K of the constant-coefficient
// form on a patch or volume) cannot stand for this case's K ("" when it can, and then `op` is it).
std::string operator_obstacle(const CaseDescription& c, const SplineSpace& space, std::shared_ptr<const MatrixFreePoisson>& op) {
  if (space.geometry().parametric_dimension() != 3 && space.geometry().dimension() != 2) return "serves planar problems and volumes only (not surfaces)";
  if (!c.problem.coefficients.constant()) return "serves constant coefficients only (this case's [problem] coefficient or reaction varies)";
  if (c.problem.dirichlet_method == DirichletMethod::kNitsche) return "does not add Nitsche's boundary terms";
  try {
    op = space.matrix_free_operator(1.0, c.problem.reaction, c.quadrature);
  } catch (const std::invalid_argument& e) {  // the space has none here, and says why
    return std::string("is not available here (") + e.what() + ")";
  }
  if (!op) return "is not available for this space (family \"" + c.family + "\"" + (c.multipatch() ? ", several patches" : "") + ")";
  return "";
}

// Why K cannot be applied without a matrix for this case and solver ("" when it can, and then
// `op` is the operator).
std::string matrix_free_obstacle(const CaseDescription& c, const SplineSpace& space, const SolverReport& chosen,
                                 std::shared_ptr<const MatrixFreePoisson>& op) {
  if (chosen.method != "iterative") return "needs CG (method = \"iterative\", or \"auto\" from 10 000 functions)";
  if (chosen.preconditioner == kBoomerAmgName ||
      (chosen.preconditioner != "jacobi" && !space.structured_preconditioner_without_matrix(chosen.preconditioner)))
    return "needs a preconditioner that does without the matrix (not \"" + chosen.preconditioner + "\")";
  const bool surface = space.geometry().dimension() == 3 && space.geometry().parametric_dimension() == 2;
  if (!surface && c.problem.source.empty()) return "serves problems with a given source";
  if (c.solver.estimate_condition) return "has no matrix for --condition to estimate";
  return operator_obstacle(c, space, op);
}

}  // namespace

PoissonSolution solve_case(const CaseDescription& c, const SplineSpace& space, Ordering ordering,
                           const ProgressFunction& progress, SolverReport* report, AdaptiveSolve* adaptive) {
  space.check_solvable();
  check_quadrature_points(c, space.mesh());
  PoissonSolveOptions so;
  so.quadrature = c.quadrature;
  so.ordering = ordering;
  so.progress = progress;
  so.cell_errors = true;
  so.estimate_condition = c.solver.estimate_condition;
  SolverReport chosen = resolve_solver(c, space, adaptive != nullptr);
  const bool steps_multigrid = adaptive != nullptr;
  if (report) *report = chosen;
  const ParallelWorld launched = launched_world();
  if (launched.size > 1 && chosen.method != "petsc")
    throw InputError(c.path + ": [solver] method: \"" + chosen.method + "\" under mpirun with " +
                     std::to_string(launched.size) + " processes: each would solve the whole problem alone; use "
                     "--solver petsc (or method = \"petsc\") to share it");
  if (c.solver.estimate_condition && chosen.method == "petsc")
    throw InputError(c.path + ": --condition: estimated on the serial paths only (direct or iterative), not with "
                     "method = \"petsc\"");
  // The operator CG applies when it runs without a matrix (set below), for a preconditioner
  // that needs more of it than its diagonal.
  const auto without_matrix = std::make_shared<std::shared_ptr<const MatrixFreePoisson>>();
  if (chosen.method == "iterative" || chosen.method == "petsc") {
    so.iterative = chosen.method == "iterative";
    so.tolerance = c.solver.tolerance;
    so.max_iterations = c.solver.max_iterations;
    // (Under petsc, BoomerAMG and Jacobi are PETSc's own PCs; a structured one is a PCShell.)
    if (steps_multigrid) {
      // This step's matrix becomes the finest level; the family's prolongation links it to the last.
      const std::shared_ptr<NestedMultigrid> levels = adaptive->multigrid;
      const Eigen::SparseMatrix<double>* prolongation = space.prolongation_from_predecessor();
      so.preconditioner = [levels, prolongation](const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
        levels->add_level(layout, lower, levels->levels() > 0 ? prolongation : nullptr);
        return levels->preconditioner();
      };
      so.initial = adaptive->initial;
      so.energy_tolerance = adaptive->energy_tolerance;
    } else if (chosen.preconditioner == kBoomerAmgName && chosen.method == "iterative") {
      const std::string options = chosen.petsc_options, path = c.path;
      so.preconditioner = [options, path](const DofLayout&, const Eigen::SparseMatrix<double>& lower) {
        try {
          return boomeramg_preconditioner(lower, options);
        } catch (const std::invalid_argument& e) {
          throw InputError(path + ": [solver] petsc_options: " + e.what());
        }
      };
    } else if (chosen.preconditioner != kBoomerAmgName && chosen.preconditioner != "jacobi") {
      const std::string path = c.path;
      const PoissonProblem* problem = &c.problem;
      // (The name is read when the preconditioner is built: "auto" may still change it below.)
      const bool distributed = chosen.method == "petsc";
      so.preconditioner = [&space, &chosen, path, problem, without_matrix, distributed](
                              const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
        const std::string& name = chosen.preconditioner;
        std::unique_ptr<Preconditioner> p;
        if (*without_matrix && !space.structured_preconditioner_needs_only_diagonal(name)) {
          // Without a matrix (serially, or a PCShell made so), `lower` holds K's diagonal alone.
          try {
            p = space.make_structured_preconditioner_without_matrix(name, layout, *without_matrix, lower.diagonal());
          } catch (const std::invalid_argument& e) {  // it applies to these unknowns, not to this hierarchy
            throw InputError(path + ": [solver] preconditioner: " + e.what());
          }
          if (!p)
            throw InputError(path + ": [solver] preconditioner: \"" + name + "\" without a matrix needs the unknowns to be a "
                             "tensor product and the geometry to live on the elements of the first coarser level (every "
                             "other breakpoint dropped); " +
                             (distributed ? "with method = \"petsc\" use \"boomeramg\", or method = \"iterative\" with matrix = \"assembled\""
                                          : "use [solver] matrix = \"assembled\" (--matrix assembled)"));
          return p;
        }
        try {
          p = space.make_structured_preconditioner(name, layout, lower, *problem);
        } catch (const std::invalid_argument& e) {  // it applies to these unknowns, not to this hierarchy
          throw InputError(path + ": [solver] preconditioner: " + e.what());
        }
        if (!p)
          throw InputError(path + ": [solver] preconditioner: \"" + name +
                           "\" does not apply to this problem's unknowns (they are not a tensor product: use \"boomeramg\", \"jacobi\" "
                           "or method = \"direct\")");
        return p;
      };
    }
  }
  // Building the operator (its tables, the affine search) is part of the set-up: it is timed
  // here and added to the solve's.
  double seconds_operator = 0;
  if (chosen.method == "iterative" && c.solver.matrix != "assembled") {
    std::shared_ptr<const MatrixFreePoisson> op;
    const auto started = std::chrono::steady_clock::now();
    const std::string obstacle = matrix_free_obstacle(c, space, chosen, op);
    seconds_operator = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (c.solver.matrix == "matrix_free" && !obstacle.empty())
      throw InputError(c.path + ": [solver] matrix: \"matrix_free\" " + obstacle + "; use \"assembled\" or \"auto\"");
    // "auto": without a matrix where every element is affine, measured faster there and slower
    // on curved elements (docs/SOLVERS.md); not a fallback, the documented choice.
    if (obstacle.empty() && (c.solver.matrix == "matrix_free" || op->all_elements_affine())) {
      so.matrix_free = [op] { return op; };
      *without_matrix = op;
      if (report) report->matrix_free = true;
      // "auto" on affine elements from kAutoMultigridFunctions unknowns: multigrid, whose cost
      // grows like N where the fast diagonalization's grows like N^1.5 (measured: docs/SOLVERS.md).
      // Not on volumes: there the fast diagonalization's application is O(N^(4/3)) and it was
      // faster at every size measured, up to 17.2M unknowns ("multigrid on volumes").
      const std::vector<std::string> structured = space.structured_preconditioners();
      if (c.solver.preconditioner == "auto" && !structured.empty() && chosen.preconditioner == structured.front() &&
          std::find(structured.begin(), structured.end(), kMultigridName) != structured.end() &&
          space.structured_preconditioner_without_matrix(kMultigridName) && op->all_elements_affine() &&
          op->num_functions() >= kAutoMultigridFunctions && space.geometry().parametric_dimension() == 2) {
        chosen.preconditioner = kMultigridName;
        if (report) {
          report->preconditioner = kMultigridName;
          report->note = "[solver] preconditioner = \"auto\": multigrid, since CG runs without a matrix on affine elements "
                         "and from " + std::to_string(kAutoMultigridFunctions) + " functions (measured faster there than \"" +
                         structured.front() + "\", whose cost grows like N^1.5: docs/SOLVERS.md)";
        }
      }
    }
  } else if (c.solver.matrix == "matrix_free") {
    throw InputError(c.path + ": [solver] matrix: \"matrix_free\" needs CG (method = \"iterative\", or \"auto\" from "
                     "10 000 functions); this solve is " + chosen.method);
  }
  // Under PETSc a structured preconditioner that reads more than K's diagonal is a PCShell
  // that every process applies to the whole residual. As serial CG's "auto" decides: where
  // every element is affine, it is made without a matrix from the space's operator (the part's,
  // from which the space makes the whole one); elsewhere from the whole matrix, gathered on
  // every process (docs/SOLVERS.md, "Multigrid under PETSc"). Decided together: a process whose rows are
  // affine may share the patch with one whose rows are not.
  bool shell_reads_matrix = false;
  if (chosen.method == "petsc" && chosen.preconditioner != kBoomerAmgName && chosen.preconditioner != "jacobi" &&
      !space.structured_preconditioner_needs_only_diagonal(chosen.preconditioner)) {
    std::shared_ptr<const MatrixFreePoisson> op;
    std::string obstacle;
    try {
      obstacle = operator_obstacle(c, space, op);
    } catch (const std::invalid_argument& e) {
      obstacle = e.what();
    }
    double needs_matrix = !(obstacle.empty() && op->all_elements_affine() &&
                            space.structured_preconditioner_without_matrix(chosen.preconditioner));
    max_over_ranks(&needs_matrix, 1);
    if (needs_matrix != 0) shell_reads_matrix = true;
    else *without_matrix = op;
  }
  if (report && chosen.method == "petsc" && chosen.preconditioner != kBoomerAmgName && chosen.preconditioner != "jacobi")
    report->shell_built_from = shell_reads_matrix ? "whole_matrix" : *without_matrix ? "operator" : "diagonal";
  // Where a matrix is assembled, the space's operator writes it itself when it can (a tensor
  // patch with one affine map: its Kronecker form; under PETSc each process its own rows), the
  // same matrix as the element loop's, up to rounding, in a fraction of the time
  // (docs/SOLVERS.md).
  if ((chosen.method == "direct" || chosen.method == "iterative" || chosen.method == "petsc") && !so.matrix_free)
    assemble_by_operator_where_possible(c, space, so);
  try {
    if (chosen.method == "petsc") {
      DistributedSolveOptions petsc;
      petsc.petsc_options = c.solver.petsc_options;
      petsc.preconditioner = chosen.preconditioner == kBoomerAmgName || chosen.preconditioner == "jacobi"
                                 ? chosen.preconditioner
                                 : "shell";
      petsc.shell_reads_matrix = shell_reads_matrix;
      petsc.tolerance = c.solver.tolerance;
      petsc.max_iterations = c.solver.max_iterations;
      const Distribution distribution{space.part(), &petsc};
      return solve_poisson(space.mesh(), space.geometry(), c.problem, so, &distribution);
    }
    PoissonSolution solution = solve_poisson(space.mesh(), space.geometry(), c.problem, so);
    solution.timings.setup += seconds_operator;
    // The automatic structured preconditioner is exact only where the operator separates; when
    // CG needed many iterations with it, say which of the space's others keeps them bounded.
    const std::vector<std::string> structured = space.structured_preconditioners();
    if (report && chosen.method == "iterative" && structured.size() > 1 && chosen.preconditioner == structured[0] &&
        structured[1] == kMultigridName && solution.iterative.iterations > kManyStructuredIterations && report->note.empty())
      report->note = "CG took " + std::to_string(solution.iterative.iterations) + " iterations with \"" + structured[0] +
                     "\" (the geometry or the coefficients do not separate); [solver] preconditioner = \"" +
                     structured[1] + "\" keeps them bounded in h and p (measured faster from about 200 000 functions, where \"auto\" takes it when the map does not separate: docs/SOLVERS.md)";
    return solution;
  } catch (...) {
    rethrow_as_case_error(c);
  }
}

std::shared_ptr<const MatrixFreePoisson> space_operator(const SplineSpace& space, double stiffness, double reaction,
                                                        const QuadratureOptions& quadrature) {
  try {
    return space.matrix_free_operator(stiffness, reaction, quadrature);
  } catch (const std::invalid_argument&) {
    // Then there is no operator, and the element loop assembles, as for every other space.
    return nullptr;
  }
}

void assemble_by_operator_where_possible(const CaseDescription& c, const SplineSpace& space, PoissonSolveOptions& so) {
  const double reaction = c.problem.reaction;
  const QuadratureOptions quadrature = c.quadrature;
  so.matrix_from_operator = [&space, reaction, quadrature] { return space_operator(space, 1.0, reaction, quadrature); };
}

void rethrow_as_case_error(const CaseDescription& c) {
  try {
    throw;
  } catch (const NotConverged& e) {
    throw InputError(c.path + ": [solver]: " + e.what() + "; raise max_iterations, loosen tolerance or use method = \"direct\"");
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry]: " + e.what());
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": " + e.what());
  }
}

// Written as a case file, so that it is read and validated like one.
CaseDescription unit_square_benchmark_case(int p, int n) {
  const std::string text = "[geometry]\ntype = \"rectangle\"\n[space]\ndegree = " + std::to_string(p) +
                           "\nelements = " + std::to_string(n) + "\n[problem]\nexact = \"sin(pi*x)*sin(pi*y)\"\n";
  return load_case_text(text, "bench");
}

CaseDescription unit_cube_benchmark_case(int p, int n) {
  const std::string text = "[geometry]\ntype = \"box\"\n[space]\ndegree = " + std::to_string(p) + "\nelements = " +
                           std::to_string(n) + "\n[problem]\nexact = \"sin(pi*x)*sin(pi*y)*sin(pi*z)\"\n";
  return load_case_text(text, "bench");
}

}  // namespace knotwork
