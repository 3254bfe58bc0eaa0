// knotwork adapt: estimate - mark (Doerfler) - refine (the family's local refinement) - solve, repeated.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>
#include "studies/adaptive.hpp"
#include "studies/report.hpp"
#include "studies/studies.hpp"
#include "app/commands.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "app/progress.hpp"
#include "studies/svg_plot.hpp"
#include "basis/core/input_error.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/residual_estimator.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

int adapt_command(const AdaptOptions& o) {
  CaseDescription c = load_case(o.case_file);
  override_case(c, o.degree, o.elements, o.solver, o.tolerance, o.petsc_options_given ? &o.petsc_options : nullptr,
                o.preconditioner, o.matrix);
  if (o.steps) c.adapt.steps = o.steps;
  if (o.theta) c.adapt.theta = o.theta;
  if (o.max_dofs) c.adapt.max_dofs = o.max_dofs;
  c.allow_unverified_space = o.allow_unverified_space;
  if (!o.marking.empty()) c.adapt.mark_functions = o.marking == "functions";
  if (!o.strategy.empty()) c.adapt.maximum_strategy = o.strategy == "maximum";
  if (o.min_fraction >= 0) c.adapt.min_fraction = o.min_fraction;
  const Ordering ordering = parse_ordering(o.ordering);
  const std::string directory = o.out.empty() ? c.output_directory : o.out;
  Progress progress(o.quiet);
  const AdaptOutcome r = adapt_study(c, ordering, o.no_output ? nullptr : &directory,
                                     [&](const std::string& w) { progress(w); }, o.output_every);
  if (o.json) {
    std::printf("%s\n", r.json.dump().c_str());
    return 0;
  }
  const std::vector<AdaptiveStep>& steps = r.steps;
  const std::string& description = r.description;
  const std::vector<std::string>& outputs = r.outputs;
  std::printf("knotwork adapt %s: %s, %s theta = %g%s", c.path.c_str(), description.c_str(),
              c.adapt.maximum_strategy ? "maximum strategy" : "Doerfler", c.adapt.theta, c.adapt.mark_functions ? " on functions" : "");
  if (c.adapt.min_fraction > 0) std::printf(", at least %g of them", c.adapt.min_fraction);
  std::printf("\n");
  if (!steps.empty()) {
    std::printf("  solver   %s\n", steps.front().solver.c_str());
    if (!steps.front().solver_note.empty()) std::printf("  note     %s\n", steps.front().solver_note.c_str());
  }
  for (size_t s = 0; s < steps.size(); ++s)
    for (const auto& n : steps[s].notes) std::printf("  note     step %zu: %s\n", s, n.c_str());
  std::printf("%4s %8s %8s %7s %13s %13s %13s %7s\n", "step", "dofs", "cells", "marked", "estimator", "L2 error",
              "H1-semi error", "rate");
  for (size_t s = 0; s < steps.size(); ++s) {
    const AdaptiveStep& v = steps[s];
    std::printf("%4zu %8d %8d %7d %13.5e %13.5e %13.5e %7s\n", s, v.dofs, v.cells, v.marked, v.estimator, v.l2, v.h1_semi,
                rate_text(v.h1_rate).c_str());
  }
  if (steps.size() >= 4 && !std::isnan(steps.back().h1_semi))
    std::printf("  H1 rate against dofs, least squares over the last %zu steps: %.2f (optimal: N^(-p/%d))\n",
                steps.size() - steps.size() / 2, fitted_h1_rate(steps, steps.size() / 2), c.is_volume() ? 3 : 2);
  std::printf("  (rate: of the H1-seminorm error against dofs, -log(e1/e0)/log(N1/N0))\n");
  for (const auto& p : outputs)
    if (p.find("adapt.") != std::string::npos) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
