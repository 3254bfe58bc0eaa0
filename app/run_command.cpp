// knotwork run: one case, one solve, for every family through the family interface.
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <optional>

#include "app/commands.hpp"
#include "app/progress.hpp"
#include "app/report.hpp"
#include "app/studies.hpp"
#include "basis/core/input_error.hpp"
#include "solver/distributed_poisson.hpp"
#include "solver/petsc_module.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {
double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

void override_case(CaseDescription& c, int degree, int elements, const std::string& solver, double tolerance,
                   const std::string* petsc_options) {
  space_family(c).override_options(c, degree, elements);
  override_solver(c, solver, tolerance, petsc_options);
}

double RunOutcome::total_without_output() const {
  const PoissonTimings& tm = solution.timings;
  return tm.setup + tm.assembly + tm.analysis + tm.factorization + tm.solve + tm.preconditioner + tm.iterations + tm.errors;
}

std::string write_pieces(OutputStage* stage, ParallelWorld world, const std::string& base, CellRange mine,
                         const PieceWriter& write) {
  std::vector<std::string> pieces;
  for (int r = 0; r < world.size; ++r) pieces.push_back(base + "_" + std::to_string(r) + ".vtu");
  // Rank 0 stages every name (so that an interrupt or a failure removes them all) and tells
  // the others where its staging folder is.
  std::string folder;
  PieceSummary summary;
  if (stage) {
    for (const std::string& piece : pieces) folder = std::filesystem::path(stage->stage(piece)).parent_path().string();
    summary = PieceSummary{stage->stage(base + ".pvtu"), pieces};
  }
  broadcast_from_first(folder);
  const std::string path = (std::filesystem::path(folder) / pieces[world.rank]).string();
  on_all_ranks([&] { write(path, mine, stage ? &summary : nullptr); });
  return base + ".pvtu";
}

void write_run_output(const CaseDescription& c, const SplineSpace& space, const PoissonSolution& s, OutputStage& stage) {
  const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
  CellFields cell_fields;
  if (s.cell_h1_squared.size() > 0) cell_fields.emplace_back("h1_error_squared", s.cell_h1_squared);
  if (c.write_bezier)
    write_bezier_vtu(stage.stage("solution.vtu"), space.mesh(), space.geometry(), s.coefficients, exact, cell_fields,
                     s.exact_mean);
  if (c.write_sampled)
    write_sampled_vtu(stage.stage("solution_sampled.vtu"), space.mesh(), space.geometry(), s.coefficients, exact,
                      c.samples, s.exact_mean);
}

namespace {

// Under mpirun: write_run_output's files as pieces and .pvtu summaries.
void write_run_pieces(const CaseDescription& c, const SplineSpace& space, const PoissonSolution& s,
                      OutputStage* stage, ParallelWorld world) {
  const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
  CellFields cell_fields;
  if (s.cell_h1_squared.size() > 0) cell_fields.emplace_back("h1_error_squared", s.cell_h1_squared);
  const CellRange cells = cells_to_write(space, world);
  if (c.write_bezier)
    write_pieces(stage, world, "solution", cells, [&](const std::string& path, CellRange mine, const PieceSummary* sum) {
      write_bezier_vtu(path, space.mesh(), space.geometry(), s.coefficients, exact, cell_fields, s.exact_mean, mine, sum);
    });
  if (c.write_sampled)
    write_pieces(stage, world, "solution_sampled", cells,
                 [&](const std::string& path, CellRange mine, const PieceSummary* sum) {
                   write_sampled_vtu(path, space.mesh(), space.geometry(), s.coefficients, exact, c.samples,
                                     s.exact_mean, mine, sum);
                 });
}

}  // namespace

RunOutcome run_study(const CaseDescription& c, Ordering ordering, const std::string* output_directory,
                     const ProgressFunction& progress) {
  using clock = std::chrono::steady_clock;
  // Under mpirun, rank 0 makes the output folder (and says to all if it cannot).
  const ParallelWorld world = launched_world();
  const bool writes = output_directory != nullptr;
  std::optional<OutputStage> stage;
  if (world.size > 1 && writes)
    on_all_ranks([&] {
      if (world.rank == 0) stage.emplace(*output_directory);
    });
  else if (writes)
    stage.emplace(*output_directory);
  const auto say = [&](const std::string& what) { if (progress) progress(what); };
  RunOutcome r;
  say("building the space ([space] family = \"" + c.family + "\")");
  auto t = clock::now();
  r.space = build_space(c, 0, say);
  const double t_space = since(t);
  r.seconds_space = t_space;
  r.description = r.space->description();
  r.solution = solve_case(c, *r.space, ordering, say, &r.solver);
  r.solution.timings.setup += t_space;
  r.fields = r.space->report();
  if (c.solver.estimate_condition) {
    const std::vector<ReportField> kappa = condition_fields(r.solution);
    r.fields.insert(r.fields.end(), kappa.begin(), kappa.end());
  }
  t = clock::now();
  const std::vector<ReportField> checks = r.space->check_solution(r.solution.coefficients);
  r.seconds_checks = since(t);
  r.fields.insert(r.fields.end(), checks.begin(), checks.end());
  if (world.size > 1 && writes) {
    say("writing ParaView output (a piece per rank)");
    t = clock::now();
    write_run_pieces(c, *r.space, r.solution, stage ? &*stage : nullptr, world);
    if (stage) r.outputs = stage->commit();
    r.seconds_output = since(t);
  } else if (stage) {
    say("writing ParaView output");
    t = clock::now();
    write_run_output(c, *r.space, r.solution, *stage);
    r.outputs = stage->commit();
    r.seconds_output = since(t);
  }
  return r;
}

Json run_json(const CaseDescription& c, const RunOutcome& r) {
  const PoissonSolution& s = r.solution;
  const PoissonTimings& tm = s.timings;
  Json timings = Json::object();
  timings.set("setup", tm.setup).set("space", r.seconds_space).set("assembly", tm.assembly).set("analysis", tm.analysis)
      .set("factorization", tm.factorization).set("solve", tm.solve).set("preconditioner", tm.preconditioner)
      .set("iterations", tm.iterations).set("errors", tm.errors)
      .set("checks", r.seconds_checks).set("output", r.seconds_output).set("total_without_output", r.total_without_output());
  Json j = Json::object();
  j.set("case", c.path).set("family", c.family).set("space", r.description)
      .set("degree", Json::array().push(double(r.space->degree()[0])).push(double(r.space->degree()[1])))
      .set("cells", global_num_cells(*r.space)).set("dofs", s.num_functions).set("free_dofs", s.num_free)
      .set("matrix_nonzeros", s.matrix_nonzeros).set("factor_nonzeros", s.cholesky.factor_nonzeros)
      .set("refinement_correction", s.cholesky.refinement_correction);
  if (s.errors) j.set("l2_error", s.errors->l2).set("h1_seminorm_error", s.errors->h1_semi).set("h1_error", s.errors->h1);
  else j.set_null("l2_error").set_null("h1_seminorm_error").set_null("h1_error");
  if (const char* m = dirichlet_method_name(c.problem)) {
    j.set("dirichlet_method", m);
    if (c.problem.dirichlet_method == DirichletMethod::kNitsche) j.set("nitsche_penalty", c.problem.nitsche_penalty);
  }
  if (s.zero_mean) j.set("area", s.area).set("source_mean", s.source_mean).set("exact_mean", s.exact_mean);
  Json sj = Json::object();
  sj.set("method", r.solver.method);
  if (r.solver.method == "iterative")
    sj.set("preconditioner", r.solver.preconditioner).set("iterations", s.iterative.iterations)
        .set("relative_residual", s.iterative.relative_residual).set("backward_error", s.iterative.backward_error)
        .set("tolerance", c.solver.tolerance);
  if (r.solver.method == "petsc") {
    const PoissonSolution::Distributed& d = s.distributed;
    sj.set("ksp", d.ksp).set("pc", d.pc).set("preconditioner", r.solver.preconditioner)
        .set("iterations", s.iterative.iterations)
        .set("relative_residual", s.iterative.relative_residual).set("tolerance", c.solver.petsc_tolerance())
        .set("converged_reason", d.reason);
    if (!d.package.empty()) sj.set("factor_package", d.package);
    j.set("ranks", d.ranks).set("space_parts", r.space->part() != nullptr).set("largest_part_cells", d.cells_held).set("peak_memory_mb_per_rank", d.peak_memory_mb);
  }
  j.set("solver", sj);
  add_fields(j, r.fields);
  std::vector<std::string> notes = r.space->notes();
  if (!r.solver.note.empty()) notes.push_back(r.solver.note);
  j.set("notes", Json::strings(notes));
  j.set("timings", timings).set("outputs", Json::strings(r.outputs));
  return j;
}

int run_command(const RunOptions& o) {
  CaseDescription c = load_case(o.case_file);
  override_case(c, o.degree, o.elements, o.solver, o.tolerance, o.petsc_options_given ? &o.petsc_options : nullptr);
  c.allow_unverified_space = o.allow_unverified_space;
  c.solver.estimate_condition = o.condition;
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
  for (const auto& n : r.space->notes()) std::printf("  note     %s\n", n.c_str());
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
    std::printf("  solver   CG + %s: %d iterations, backward error %.2e (tolerance %.0e), relative residual %.2e\n",
                solver.preconditioner.c_str(), s.iterative.iterations, s.iterative.backward_error, c.solver.tolerance,
                s.iterative.relative_residual);
  if (solver.method == "petsc")
    std::printf("  solver   PETSc %s + %s%s%s on %d process%s: %d iteration%s, relative residual %.2e (tolerance %.0e)\n",
                s.distributed.ksp.c_str(),
                (s.distributed.pc == "shell" ? solver.preconditioner + " (PCShell)" : s.distributed.pc).c_str(), s.distributed.package.empty() ? "" : " ",
                s.distributed.package.c_str(), s.distributed.ranks, s.distributed.ranks == 1 ? "" : "es",
                s.iterative.iterations, s.iterative.iterations == 1 ? "" : "s", s.iterative.relative_residual,
                c.solver.petsc_tolerance());
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
