// knotwork run: one case, one solve, for every family through the family interface.
#include <chrono>
#include <cstdio>
#include <optional>

#include "app/commands.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "app/pipeline.hpp"
#include "app/progress.hpp"
#include "app/report.hpp"
#include "solver/input_error.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {
double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

int run_command(const RunOptions& o) {
  using clock = std::chrono::steady_clock;
  CaseDescription c = load_case(o.case_file);
  const SpaceFamily& family = space_family(c);
  family.override_options(c, o.degree, o.elements);
  override_solver(c, o.solver, o.tolerance);
  c.allow_unverified_space = o.allow_unverified_space;
  const Ordering ordering = parse_ordering(o.ordering);
  std::optional<OutputStage> stage;
  if (!o.no_output) stage.emplace(o.out.empty() ? c.output_directory : o.out);
  Progress progress(o.quiet);

  progress("building the space ([space] family = \"" + c.family + "\")");
  auto t = clock::now();
  const std::unique_ptr<SplineSpace> space = family.build(c, 0, [&](const std::string& what) { progress(what); });
  const double t_space = since(t);
  const std::string description = space->description();

  SolverReport solver;
  PoissonSolution s = solve_case(c, *space, ordering, [&](const std::string& what) { progress(what); }, &solver);
  s.timings.setup += t_space;
  std::vector<ReportField> fields = space->report();
  t = clock::now();
  const std::vector<ReportField> checks = space->check_solution(s.coefficients);
  const double t_checks = since(t);
  fields.insert(fields.end(), checks.begin(), checks.end());

  std::vector<std::string> outputs;
  double t_output = 0;
  if (stage) {
    progress("writing ParaView output");
    t = clock::now();
    const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
    CellFields cell_fields;
    if (s.cell_h1_squared.size() > 0) cell_fields.emplace_back("h1_error_squared", s.cell_h1_squared);
    if (c.write_bezier)
      write_bezier_vtu(stage->stage("solution.vtu"), space->mesh(), space->geometry(), s.coefficients, exact, cell_fields,
                       s.exact_mean);
    if (c.write_sampled)
      write_sampled_vtu(stage->stage("solution_sampled.vtu"), space->mesh(), space->geometry(), s.coefficients, exact,
                        c.samples, s.exact_mean);
    outputs = stage->commit();
    t_output = since(t);
  }
  const PoissonTimings& tm = s.timings;
  const double total =
      tm.setup + tm.assembly + tm.analysis + tm.factorization + tm.solve + tm.preconditioner + tm.iterations + tm.errors;

  if (o.json) {
    Json timings = Json::object();
    timings.set("setup", tm.setup).set("assembly", tm.assembly).set("analysis", tm.analysis)
        .set("factorization", tm.factorization).set("solve", tm.solve).set("preconditioner", tm.preconditioner)
        .set("iterations", tm.iterations).set("errors", tm.errors)
        .set("checks", t_checks).set("output", t_output).set("total_without_output", total);
    Json j = Json::object();
    j.set("case", c.path).set("family", c.family).set("space", description)
        .set("degree", Json::array().push(double(space->degree()[0])).push(double(space->degree()[1])))
        .set("cells", space->mesh().num_cells()).set("dofs", s.num_functions).set("free_dofs", s.num_free)
        .set("matrix_nonzeros", s.matrix_nonzeros).set("factor_nonzeros", s.cholesky.factor_nonzeros)
        .set("refinement_correction", s.cholesky.refinement_correction);
    if (s.errors) j.set("l2_error", s.errors->l2).set("h1_seminorm_error", s.errors->h1_semi).set("h1_error", s.errors->h1);
    else j.set_null("l2_error").set_null("h1_seminorm_error").set_null("h1_error");
    if (s.zero_mean) j.set("area", s.area).set("source_mean", s.source_mean).set("exact_mean", s.exact_mean);
    Json sj = Json::object();
    sj.set("method", solver.method);
    if (solver.method == "iterative")
      sj.set("preconditioner", solver.preconditioner).set("iterations", s.iterative.iterations)
          .set("relative_residual", s.iterative.relative_residual).set("backward_error", s.iterative.backward_error)
          .set("tolerance", c.solver.tolerance);
    j.set("solver", sj);
    add_fields(j, fields);
    std::vector<std::string> notes = space->notes();
    if (!solver.note.empty()) notes.push_back(solver.note);
    j.set("notes", Json::strings(notes));
    j.set("timings", timings).set("outputs", Json::strings(outputs));
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork run %s%s\n", c.path.c_str(), c.title.empty() ? "" : ("  (" + c.title + ")").c_str());
  std::printf("  space    %s, %d cells\n", description.c_str(), space->mesh().num_cells());
  for (const auto& n : space->notes()) std::printf("  note     %s\n", n.c_str());
  if (!solver.note.empty()) std::printf("  note     %s\n", solver.note.c_str());
  std::printf("  dofs     %d functions, %d unknowns after %s, %ld stored matrix entries\n", s.num_functions, s.num_free,
              s.zero_mean ? "pinning one (zero mean)" : "Dirichlet elimination", s.matrix_nonzeros);
  print_field_lines(fields);
  if (s.zero_mean)
    std::printf("  surface  area %.6f; mean %.3e removed from the source and %.3e from the exact solution\n", s.area,
                s.source_mean, s.exact_mean);
  if (solver.method == "iterative")
    std::printf("  solver   CG + %s: %d iterations, backward error %.2e (tolerance %.0e), relative residual %.2e\n",
                solver.preconditioner.c_str(), s.iterative.iterations, s.iterative.backward_error, c.solver.tolerance,
                s.iterative.relative_residual);
  if (s.errors)
    std::printf("  errors   L2 %.6e   H1-seminorm %.6e   H1 %.6e\n", s.errors->l2, s.errors->h1_semi, s.errors->h1);
  if (solver.method == "iterative")
    std::printf("  time     setup %.3f s, assembly %.3f s, preconditioner %.3f s, iterations %.3f s, errors %.3f s"
                " (total %.3f s); output %.3f s\n",
                tm.setup, tm.assembly, tm.preconditioner, tm.iterations, tm.errors, total, t_output);
  else
    std::printf("  time     setup %.3f s, assembly %.3f s, analysis %.3f s, factorization %.3f s, solve %.3f s, errors %.3f s"
                " (total %.3f s); output %.3f s\n",
                tm.setup, tm.assembly, tm.analysis, tm.factorization, tm.solve, tm.errors, total, t_output);
  for (const auto& p : outputs) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
