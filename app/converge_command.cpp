// knotwork converge: uniform refinement level after level, for every family through the
// family interface; the family adds its own columns (elements, faces, C1 jump).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include "app/commands.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "studies/studies.hpp"
#include "app/progress.hpp"
#include "studies/report.hpp"
#include "studies/svg_plot.hpp"
#include "basis/core/input_error.hpp"
#include "solver/petsc_backend.hpp"
#include "solver/petsc_module.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

int converge_command(const ConvergeOptions& o) {
  CaseDescription c = load_case(o.case_file);
  override_case(c, o.degree, o.elements, o.solver, o.tolerance, o.petsc_options_given ? &o.petsc_options : nullptr,
                o.preconditioner, o.matrix);
  c.solver.estimate_condition = o.condition;
  c.solver.ordering = o.ordering;
  const Ordering ordering = parse_ordering(o.ordering);
  const std::string directory = o.out.empty() ? c.output_directory : o.out;
  Progress progress(o.quiet);
  const ConvergeOutcome r = converge_study(c, o.levels, ordering, &directory, [&](const std::string& w) { progress(w); });
  if (o.json) {
    std::printf("%s\n", r.json.dump().c_str());
    return 0;
  }
  const std::vector<ConvergeLevel>& levels = r.levels;
  const std::string& description = r.description;
  const SolverReport& first_solver = r.first_solver;
  const int iterative_levels = r.iterative_levels;
  const std::vector<std::string>& outputs = r.outputs;
  std::vector<const ReportField*> columns;
  for (const auto& f : levels.front().fields)
    if (f.column) columns.push_back(&f);
  std::printf("knotwork converge %s: %s\n", c.path.c_str(), description.c_str());
  if (!first_solver.note.empty()) std::printf("  note     %s\n", first_solver.note.c_str());
  if (iterative_levels > 0)
    std::printf("  solver   %s to backward error %.0e%s\n", iterative_solvers_summary(levels).c_str(), c.solver.tolerance,
                iterative_levels < static_cast<int>(levels.size()) ? " (levels with a count under CG; CHOLMOD elsewhere)" : "");
  std::printf("%5s", "level");
  for (const ReportField* f : columns) std::printf(" %*s", f->width > 0 ? f->width : 12, f->key.c_str());
  std::printf(" %12s %10s %14s %8s %14s %8s\n", "h", "dofs", "L2 error", "rate", "H1-semi error", "rate");
  for (size_t l = 0; l < levels.size(); ++l) {
    const ConvergeLevel& v = levels[l];
    std::printf("%5zu", l);
    for (const ReportField* f : columns) {
      const ReportField* mine = find_field(v.fields, f->key);
      const int w = f->width > 0 ? f->width : 12;
      const double x = mine ? field_number(*mine) : NAN;
      if (mine && std::holds_alternative<long>(mine->value)) std::printf(" %*ld", w, std::get<long>(mine->value));
      else if (!mine || std::holds_alternative<std::monostate>(mine->value)) std::printf(" %*s", w, "-");
      else std::printf(" %*.2e", w, x);
    }
    std::printf(" %12.5e %10d %14.6e %8s %14.6e %8s\n", v.h, v.dofs, v.l2, rate_text(v.l2_rate).c_str(), v.h1_semi,
                rate_text(v.h1_rate).c_str());
  }
  for (const auto& p : outputs)
    if (p.find("convergence") != std::string::npos) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
