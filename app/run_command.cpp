// knotwork run: one case, one solve, for every family through the family interface.
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <optional>
#include "app/commands.hpp"
#include "app/progress.hpp"
#include "studies/report.hpp"
#include "studies/studies.hpp"
#include "basis/core/input_error.hpp"
#include "solver/petsc_backend.hpp"
#include "solver/petsc_module.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

// What a PCShell was built from, for the solver line.
std::string shell_origin(const std::string& built_from) {
  if (built_from == "operator") return " (PCShell, no matrix)";
  if (built_from == "whole_matrix") return " (PCShell, from the whole matrix on each process)";
  return " (PCShell)";
}

}  // namespace

int run_command(const RunOptions& o) {
  CaseDescription c = load_case(o.case_file);
  override_case(c, o.degree, o.elements, o.solver, o.tolerance, o.petsc_options_given ? &o.petsc_options : nullptr,
                o.preconditioner, o.matrix);
  c.allow_unverified_space = o.allow_unverified_space;
  c.solver.estimate_condition = o.condition;
  c.solver.ordering = o.ordering;
  const Ordering ordering = parse_ordering(o.ordering);
  const std::string out = o.out.empty() ? c.output_directory : o.out;
  Progress progress(o.quiet);
  const RunOutcome r = run_study(c, ordering, o.no_output ? nullptr : &out, [&](const std::string& w) { progress(w); });
  if (o.json) {
    std::printf("%s\n", run_json(c, r).dump().c_str());
    return 0;
  }
  const PoissonSolution& s = r.solution;
  const PoissonTimings& tm = s.timings;
  const SolverReport& solver = r.solver;
  const double total = r.total_without_output();
  std::printf("knotwork run %s%s\n", c.path.c_str(), c.title.empty() ? "" : ("  (" + c.title + ")").c_str());
  std::printf("  space    %s, %d cells\n", r.description.c_str(), global_num_cells(*r.space));
  for (const auto& n : r.space->presentation().notes()) std::printf("  note     %s\n", n.c_str());
  if (!solver.note.empty()) std::printf("  note     %s\n", solver.note.c_str());
  const bool nitsche = dirichlet_method_name(c.problem) && c.problem.dirichlet_method == DirichletMethod::kNitsche;
  std::printf("  dofs     %d functions, %d unknowns %s, %ld stored matrix entries\n", s.num_functions, s.num_free,
              s.zero_mean ? "after pinning one (zero mean)"
              : nitsche   ? "(Dirichlet data by Nitsche's method: none eliminated)"
                          : "after Dirichlet elimination",
              s.matrix_nonzeros);
  print_field_lines(r.fields);
  if (s.zero_mean)
    std::printf("  surface  area %.6f; mean %.3e removed from the source and %.3e from the exact solution\n", s.area,
                s.source_mean, s.exact_mean);
  if (solver.method == "iterative")
    std::printf("  solver   CG + %s%s: %d iterations, backward error %s%.2e (tolerance %.0e), relative residual %.2e\n",
                solver.preconditioner.c_str(), solver.matrix_free ? ", no matrix" : "", s.iterative.iterations,
                solver.matrix_free ? "at most " : "", s.iterative.backward_error, c.solver.tolerance,
                s.iterative.relative_residual);
  char stop[80];
  if (s.distributed.stop == "backward_error")
    std::snprintf(stop, sizeof stop, " (tolerance %.0e)", c.solver.tolerance);
  else
    std::snprintf(stop, sizeof stop, " (PETSc's own test, from petsc_options)");
  if (solver.method == "petsc")
    std::printf("  solver   PETSc %s + %s%s%s on %d process%s: %d iteration%s, backward error %.2e%s, relative residual %.2e\n",
                s.distributed.ksp.c_str(),
                (s.distributed.pc == "shell" ? solver.preconditioner + shell_origin(solver.shell_built_from) : s.distributed.pc).c_str(), s.distributed.package.empty() ? "" : " ",
                s.distributed.package.c_str(), s.distributed.ranks, s.distributed.ranks == 1 ? "" : "es",
                s.iterative.iterations, s.iterative.iterations == 1 ? "" : "s", s.iterative.backward_error, stop,
                s.iterative.relative_residual);
  if (solver.method == "petsc" && s.distributed.ranks > 1)
    std::printf("  parts    the largest rank held %d of the %d cells%s; peak memory %.0f MB per rank\n",
                s.distributed.cells_held, global_num_cells(*r.space),
                r.space->part() ? " (its share and the halo its rows need)" : " (the space is built whole on every rank)",
                s.distributed.peak_memory_mb);
  if (s.errors)
    std::printf("  errors   L2 %.6e   H1-seminorm %.6e   H1 %.6e\n", s.errors->l2, s.errors->h1_semi, s.errors->h1);
  if (solver.method == "petsc")
    std::printf("  time     setup %.3f s, assembly %.3f s, PETSc setup %.3f s, PETSc solve %.3f s, errors %.3f s"
                " (total %.3f s, slowest rank per phase); output %.3f s\n",
                tm.setup, tm.assembly, tm.preconditioner, tm.iterations, tm.errors, total, r.seconds_output);
  else if (solver.method == "iterative")
    std::printf("  time     setup %.3f s, assembly %.3f s, preconditioner %.3f s, iterations %.3f s, errors %.3f s"
                " (total %.3f s); output %.3f s\n",
                tm.setup, tm.assembly, tm.preconditioner, tm.iterations, tm.errors, total, r.seconds_output);
  else
    std::printf("  time     setup %.3f s, assembly %.3f s, analysis %.3f s, factorization %.3f s, solve %.3f s, errors %.3f s"
                " (total %.3f s); output %.3f s\n",
                tm.setup, tm.assembly, tm.analysis, tm.factorization, tm.solve, tm.errors, total, r.seconds_output);
  for (const auto& p : r.outputs) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
