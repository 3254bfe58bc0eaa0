// The convergence study: uniform refinement level after level, for every family through the
// family interface; the family adds its own columns (elements, faces, C1 jump).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "studies/studies.hpp"
#include "studies/report.hpp"
#include "studies/svg_plot.hpp"
#include "basis/core/input_error.hpp"
#include "solver/petsc_backend.hpp"
#include "solver/petsc_module.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

std::string iterative_solvers_summary(const std::vector<ConvergeLevel>& levels) {
  struct Run {
    std::string what;
    size_t first, last;
  };
  std::vector<Run> runs;
  for (size_t l = 0; l < levels.size(); ++l) {
    const SolverReport& s = levels[l].solver;
    if (s.method != "iterative") continue;
    const std::string what = s.preconditioner + (s.matrix_free ? " (no matrix)" : "");
    if (!runs.empty() && runs.back().what == what && runs.back().last + 1 == l) runs.back().last = l;
    else runs.push_back({what, l, l});
  }
  if (runs.empty()) return "";
  bool one = true;
  for (const Run& r : runs) one = one && r.what == runs.front().what;
  if (one) return "CG + " + runs.front().what;
  std::string out = "CG: ";
  for (size_t k = 0; k < runs.size(); ++k) {
    const Run& r = runs[k];
    out += (k ? "; " : "") + r.what + (r.first == r.last ? " on level " + std::to_string(r.first)
                                                         : " on levels " + std::to_string(r.first) + "-" + std::to_string(r.last));
  }
  return out;
}

ConvergeOutcome converge_study(const CaseDescription& c, int num_levels, Ordering ordering,
                               const std::string* output_directory, const ProgressFunction& progress) {
  const SpaceFamily& family = space_family(c);
  if (num_levels < 1 || num_levels > 12) throw InputError("--levels: must be in [1, 12], got " + std::to_string(num_levels));
  if (family.check_converge) family.check_converge(c, num_levels);
  if (!c.problem.exact) throw InputError(c.path + ": [problem] exact: a convergence study needs the exact solution");
  // Rank 0 writes the tables; every rank writes its piece of each level.
  const ParallelWorld world = launched_world();
  const bool writes = output_directory != nullptr;
  std::optional<OutputStage> stage;
  open_output_stage(output_directory, stage);
  ConvergeOutcome out;
  std::vector<ConvergeLevel>& levels = out.levels;
  std::vector<std::pair<double, std::string>> pvd, pvd_sampled;
  const ExactSolution* exact = &*c.problem.exact;
  std::string& description = out.description;
  SolverReport &first_solver = out.first_solver, &iterative_solver = out.iterative_solver;
  int& iterative_levels = out.iterative_levels;
  for (int l = 0; l < num_levels; ++l) {
    const std::string prefix = "level " + std::to_string(l + 1) + "/" + std::to_string(num_levels) + ": ";
    const auto say = [&](const std::string& what) { if (progress) progress(prefix + what); };
    say("building the space");
    const auto t0 = std::chrono::steady_clock::now();
    const std::unique_ptr<SplineSpace> space = build_space(c, l, say);
    if (l == 0) description = space->presentation().description();
    SolverReport solver;
    const PoissonSolution s = solve_case(c, *space, ordering, say, &solver);
    if (l == 0) first_solver = solver;
    if (solver.method == "iterative") iterative_solver = solver, ++iterative_levels;
    ConvergeLevel lv;
    lv.solver = solver;
    lv.h = global_mesh_size(*space);
    lv.dofs = s.num_functions;
    lv.free = s.num_free;
    lv.cells = global_num_cells(*space);
    lv.l2 = s.errors->l2;
    lv.h1_semi = s.errors->h1_semi;
    lv.h1 = s.errors->h1;
    lv.fields = space->presentation().report();
    for (auto& f : space->presentation().check_solution(s.coefficients)) lv.fields.push_back(std::move(f));
    if (c.solver.estimate_condition)
      for (auto& f : condition_fields(s)) lv.fields.push_back(std::move(f));
    // The CG count of the level (null where the level was solved directly: `auto` decides by size).
    if (c.solver.method == "iterative" || (c.solver.method == "auto" && !space->structured_preconditioners().empty() &&
                                             space->structured_preconditioner_is_automatic()))
      lv.fields.push_back({.key = "cg_iterations",
                           .value = solver.method == "iterative" ? ReportValue(long(s.iterative.iterations)) : ReportValue{},
                           .label = "CG", .column = true, .width = 13});
    if (solver.method == "petsc")
      lv.fields.push_back({.key = "ksp_iterations", .value = ReportValue(long(s.iterative.iterations)), .label = "KSP",
                           .column = true, .width = 14});
    if (!levels.empty()) {
      const ConvergeLevel& prev = levels.back();
      lv.l2_rate = std::log(prev.l2 / lv.l2) / std::log(prev.h / lv.h);
      lv.h1_rate = std::log(prev.h1_semi / lv.h1_semi) / std::log(prev.h / lv.h);
    }
    const std::string name = "level_" + std::to_string(l);
    if (writes) say("writing ParaView output");
    if (writes && world.size > 1) {
      const CellRange cells = cells_to_write(*space, world);
      const CellFields errors{{"h1_error_squared", s.cell_h1_squared}};
      if (c.write_bezier)
        pvd.emplace_back(l, write_pieces(stage ? &*stage : nullptr, world, name, cells,
                                         [&](const std::string& path, CellRange mine, const PieceSummary* sum) {
                                           write_bezier_vtu(path, space->mesh(), space->geometry(), s.coefficients,
                                                            exact, errors, s.exact_mean, mine, sum);
                                         }));
      if (c.write_sampled)
        pvd_sampled.emplace_back(l, write_pieces(stage ? &*stage : nullptr, world, name + "_sampled", cells,
                                                 [&](const std::string& path, CellRange mine, const PieceSummary* sum) {
                                                   write_sampled_vtu(path, space->mesh(), space->geometry(),
                                                                     s.coefficients, exact, c.samples, s.exact_mean,
                                                                     mine, sum);
                                                 }));
    } else if (stage && c.write_bezier) {
      write_bezier_vtu(stage->stage(name + ".vtu"), space->mesh(), space->geometry(), s.coefficients, exact,
                       {{"h1_error_squared", s.cell_h1_squared}}, s.exact_mean);
      pvd.emplace_back(l, name + ".vtu");
    }
    if (world.size == 1 && stage && c.write_sampled) {
      write_sampled_vtu(stage->stage(name + "_sampled.vtu"), space->mesh(), space->geometry(), s.coefficients, exact,
                        c.samples, s.exact_mean);
      pvd_sampled.emplace_back(l, name + "_sampled.vtu");
    }
    lv.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    levels.push_back(std::move(lv));
  }

  // Tables and plot. The family's table columns come right after the level number.
  std::vector<const ReportField*> columns;
  for (const auto& f : levels.front().fields)
    if (f.column) columns.push_back(&f);
  std::string csv = "level";
  for (const ReportField* f : columns) csv += "," + f->key;
  csv += ",h,dofs,cells,l2_error,h1_seminorm_error,h1_error,l2_rate,h1_rate\n";
  Json jl = Json::array();
  PlotSeries sl2{"L2 error", {}, {}, "#1f77b4"}, sh1{"H1 seminorm", {}, {}, "#d62728"};
  for (size_t l = 0; l < levels.size(); ++l) {
    const ConvergeLevel& v = levels[l];
    csv += std::to_string(l);
    for (const ReportField* f : columns) {
      const ReportField* mine = find_field(v.fields, f->key);
      csv += ',';
      if (mine) csv += field_csv(*mine);  // (GCC 12 warns, wrongly, about "," + an empty string)
    }
    csv += "," + json_number(v.h) + "," + std::to_string(v.dofs) + "," + std::to_string(v.cells) + "," +
           json_number(v.l2) + "," + json_number(v.h1_semi) + "," + json_number(v.h1) + "," +
           (std::isnan(v.l2_rate) ? "" : json_number(v.l2_rate)) + "," +
           (std::isnan(v.h1_rate) ? "" : json_number(v.h1_rate)) + "\n";
    Json j = Json::object();
    j.set("level", static_cast<int>(l)).set("h", v.h).set("dofs", v.dofs).set("free_dofs", v.free).set("cells", v.cells)
        .set("l2_error", v.l2).set("h1_seminorm_error", v.h1_semi).set("h1_error", v.h1)
        .set("l2_rate", v.l2_rate).set("h1_rate", v.h1_rate).set("seconds", v.seconds);
    if (v.solver.method == "iterative")
      j.set("preconditioner", v.solver.preconditioner).set("matrix", v.solver.matrix_free ? "matrix_free" : "assembled");
    add_fields(j, v.fields);
    jl.push(j);
    sl2.x.push_back(v.h); sl2.y.push_back(v.l2);
    sh1.x.push_back(v.h); sh1.y.push_back(v.h1_semi);
  }
  if (levels.size() > 1) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "L2 (rate %.2f)", levels.back().l2_rate);
    sl2.label = buf;
    std::snprintf(buf, sizeof buf, "H1 semi (rate %.2f)", levels.back().h1_rate);
    sh1.label = buf;
  }
  Json& root = out.json;
  Json sj = Json::object();
  sj.set("method", c.solver.method).set("iterative_levels", iterative_levels);
  if (c.solver.method == "petsc") sj.set("ranks", launched_world().size).set("tolerance", c.solver.tolerance);
  if (iterative_levels > 0)
    sj.set("preconditioner", iterative_solver.preconditioner).set("summary", iterative_solvers_summary(levels))
        .set("tolerance", c.solver.tolerance);
  root.set("case", c.path).set("family", c.family).set("space", description).set("solver", sj);
  if (const char* m = dirichlet_method_name(c.problem)) root.set("dirichlet_method", m);
  root.set("levels", jl);
  if (!first_solver.note.empty()) root.set("notes", Json::strings({first_solver.note}));
  if (stage) {
    write_text_file(stage->stage("convergence.csv"), csv);
    write_text_file(stage->stage("convergence.json"), root.dump() + "\n");
    write_text_file(stage->stage("convergence.svg"),
                    loglog_svg(c.name + ": " + description, "h (largest cell diameter)", "error", {sl2, sh1}));
    if (!pvd.empty()) {
      // Every level with the interfaces of a multipatch domain drawn over it (part 1).
      const std::string interfaces = write_interface_lines(c, *stage);
      std::vector<PvdEntry> entries;
      for (const auto& [level, file] : pvd) {
        entries.push_back({level, 0, file});
        if (!interfaces.empty()) entries.push_back({level, 1, interfaces});
      }
      write_pvd(stage->stage("convergence.pvd"), entries);
    }
    if (!pvd_sampled.empty()) write_pvd(stage->stage("convergence_sampled.pvd"), pvd_sampled);
    out.outputs = stage->commit();
  }
  root.set("outputs", Json::strings(out.outputs));
  return out;
}

}  // namespace knotwork
