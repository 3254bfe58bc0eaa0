// The run study: one case, one solve (and its files), as `knotwork run` and Python run it.
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <optional>

#include "studies/report.hpp"
#include "studies/studies.hpp"
#include "cases/case_reader.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"
#include "solver/petsc_backend.hpp"
#include "solver/petsc_module.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {
double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

void override_case(CaseDescription& c, int degree, int elements, const std::string& solver, double tolerance,
                   const std::string* petsc_options, const std::string& preconditioner, const std::string& matrix) {
  space_family(c).override_options(c, degree, elements);
  if (!matrix.empty()) c.solver.matrix = checked_name(matrix, {"auto", "assembled", "matrix_free"}, "--matrix", "");
  if (!preconditioner.empty()) {
    // Any known name; whether it applies to the case's space is the solve's to say, as for the key.
    c.solver.preconditioner = checked_name(preconditioner, preconditioner_names(), "--preconditioner", "");
  }
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
                      c.samples, s.exact_mean);  write_interface_lines(c, stage);
}

std::string write_interface_lines(const CaseDescription& c, OutputStage& stage) {
  if (!c.multipatch()) return "";
  // 65 points draw a side of any degree smoothly; ParaView joins them with straight segments.
  std::vector<Eigen::MatrixX2d> lines;
  std::vector<int> number;
  for (size_t k = 0; k < c.domain.interfaces.size(); ++k) {
    lines.push_back(side_curve(c.domain, c.domain.interfaces[k].a, 65));
    number.push_back(static_cast<int>(k) + 1);
  }
  write_polylines_vtp(stage.stage("interfaces.vtp"), lines, {{"interface", number}});
  return "interfaces.vtp";
}

namespace {

// Under mpirun: write_run_output's files as pieces and .pvtu summaries.
void write_run_pieces(const CaseDescription& c, const SplineSpace& space, const PoissonSolution& s,
                      OutputStage* stage, ParallelWorld world) {
  const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
  CellFields cell_fields;
  if (s.cell_h1_squared.size() > 0) cell_fields.emplace_back("h1_error_squared", s.cell_h1_squared);
  const CellRange cells = cells_to_write(space, world);
  if (stage) write_interface_lines(c, *stage);
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

void open_output_stage(const std::string* output_directory, std::optional<OutputStage>& stage) {
  if (!output_directory) return;
  const ParallelWorld world = launched_world();
  if (world.size > 1)
    on_all_ranks([&] {
      if (world.rank == 0) stage.emplace(*output_directory);
    });
  else
    stage.emplace(*output_directory);
}

RunOutcome run_study(const CaseDescription& c, Ordering ordering, const std::string* output_directory,
                     const ProgressFunction& progress) {
  using clock = std::chrono::steady_clock;
  const ParallelWorld world = launched_world();
  const bool writes = output_directory != nullptr;
  std::optional<OutputStage> stage;
  open_output_stage(output_directory, stage);
  const auto say = [&](const std::string& what) { if (progress) progress(what); };
  RunOutcome r;
  say("building the space ([space] family = \"" + c.family + "\")");
  auto t = clock::now();
  r.space = build_space(c, 0, say);
  const double t_space = since(t);
  r.seconds_space = t_space;
  r.description = r.space->presentation().description();
  r.solution = solve_case(c, *r.space, ordering, say, &r.solver);
  r.solution.timings.setup += t_space;
  r.fields = r.space->presentation().report();
  if (c.solver.estimate_condition) {
    const std::vector<ReportField> kappa = condition_fields(r.solution);
    r.fields.insert(r.fields.end(), kappa.begin(), kappa.end());
  }
  t = clock::now();
  const std::vector<ReportField> checks = r.space->presentation().check_solution(r.solution.coefficients);
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

static Json degree_json(const SplineSpace& space) {
  Json degrees = Json::array();
  for (int d : space.degree()) degrees.push(double(d));
  return degrees;
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
      .set("degree", degree_json(*r.space))
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
  sj.set("method", r.solver.method).set("assembly_method", s.assembly);
  if (r.solver.method == "iterative")
    sj.set("preconditioner", r.solver.preconditioner).set("matrix", r.solver.matrix_free ? "matrix_free" : "assembled")
        .set("petsc_options", r.solver.petsc_options).set("iterations", s.iterative.iterations)
        .set("relative_residual", s.iterative.relative_residual).set("backward_error", s.iterative.backward_error)
        .set("tolerance", c.solver.tolerance);
  if (r.solver.method == "petsc") {
    const PoissonSolution::Distributed& d = s.distributed;
    sj.set("ksp", d.ksp).set("pc", d.pc).set("preconditioner", r.solver.preconditioner)
        .set("iterations", s.iterative.iterations)
        .set("relative_residual", s.iterative.relative_residual).set("backward_error", s.iterative.backward_error)
        .set("tolerance", c.solver.tolerance).set("stop", d.stop).set("converged_reason", d.reason);
    if (!d.package.empty()) sj.set("factor_package", d.package);
    if (d.pc == "shell") sj.set("shell_built_from", r.solver.shell_built_from);
    j.set("ranks", d.ranks).set("space_parts", r.space->part() != nullptr).set("largest_part_cells", d.cells_held).set("peak_memory_mb_per_rank", d.peak_memory_mb);
  }
  j.set("solver", sj);
  add_fields(j, r.fields);
  std::vector<std::string> notes = r.space->presentation().notes();
  if (!r.solver.note.empty()) notes.push_back(r.solver.note);
  j.set("notes", Json::strings(notes));
  j.set("timings", timings).set("outputs", Json::strings(r.outputs));
  return j;
}

}  // namespace knotwork
