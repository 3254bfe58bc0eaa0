// knotwork adapt: estimate - mark (Doerfler) - refine (the family's local refinement) - solve, repeated.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>

#include "app/adaptive.hpp"
#include "app/studies.hpp"
#include "app/commands.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "app/progress.hpp"
#include "app/svg_plot.hpp"
#include "basis/core/input_error.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/residual_estimator.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

std::string rate_text(double r) {
  if (std::isnan(r)) return "-";
  char b[16];
  std::snprintf(b, sizeof b, "%.2f", r);
  return b;
}

}  // namespace

AdaptOutcome adapt_study(const CaseDescription& c, Ordering ordering, const std::string* output_directory,
                         const ProgressFunction& progress, int output_every) {
  if (output_every < 1) throw InputError("--output-every: must be at least 1, got " + std::to_string(output_every));
  check_adaptive_family(c);
  if (c.adapt.steps < 1 || c.adapt.steps > 200) throw InputError("--steps: must be in [1, 200], got " + std::to_string(c.adapt.steps));
  if (!(c.adapt.theta > 0 && c.adapt.theta <= 1)) throw InputError("--theta: must be in (0, 1]");
  if (c.adapt.max_dofs < 1) throw InputError("--max-dofs: must be positive");
  std::optional<OutputStage> stage;
  if (output_directory) stage.emplace(*output_directory);
  const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
  const auto say = [&](const std::string& what) { if (progress) progress(what); };
  AdaptOutcome out;
  std::vector<PvdEntry> pvd;
  std::string& description = out.description;
  out.steps = adapt_case(c, ordering, say, [&](const AdaptiveStepView& v) {
    if (v.step == 0) description = v.space.description();
    if (!stage || !c.write_bezier || (!v.last && v.step % output_every != 0)) return;
    say("writing ParaView output");
    Eigen::VectorXd eta = v.indicators.eta_squared.cwiseSqrt();
    Eigen::VectorXd flag = Eigen::VectorXd::Zero(eta.size());
    for (int m : v.marked) flag[m] = 1;
    const std::string name = "step_" + std::to_string(v.step);
    write_bezier_vtu(stage->stage(name + ".vtu"), v.space.mesh(), v.space.geometry(), v.solution.coefficients, exact,
                     {{"error_indicator", eta}, {"marked", flag}}, v.solution.exact_mean);
    pvd.push_back({double(v.step), 0, name + ".vtu"});
    const KnotLines knots = v.space.knot_lines();
    if (!knots.lines.empty()) {
      write_polylines_vtp(stage->stage(name + "_knots.vtp"), knots.lines,
                          {{"kind", knots.kind}, {"multiplicity", knots.multiplicity}});
      pvd.push_back({double(v.step), 1, name + "_knots.vtp"});
    }
  });
  const std::vector<AdaptiveStep>& steps = out.steps;
  std::string csv = "step,dofs,cells,marked,estimator,l2_error,h1_seminorm_error,h1_rate_vs_dofs\n";
  Json js = Json::array();
  PlotSeries se{"estimator", {}, {}, "#2ca02c"}, sl2{"L2 error", {}, {}, "#1f77b4"}, sh1{"H1 seminorm error", {}, {}, "#d62728"};
  for (size_t s = 0; s < steps.size(); ++s) {
    const AdaptiveStep& v = steps[s];
    auto num = [](double x) { return std::isnan(x) ? std::string() : json_number(x); };
    csv += std::to_string(s) + "," + std::to_string(v.dofs) + "," + std::to_string(v.cells) + "," + std::to_string(v.marked) +
           "," + json_number(v.estimator) + "," + num(v.l2) + "," + num(v.h1_semi) + "," + num(v.h1_rate) + "\n";
    Json j = Json::object();
    j.set("step", static_cast<int>(s)).set("dofs", v.dofs).set("cells", v.cells).set("marked", v.marked)
        .set("extended_segments", v.extended).set("estimator", v.estimator).set("l2_error", v.l2)
        .set("h1_seminorm_error", v.h1_semi).set("h1_rate_vs_dofs", v.h1_rate).set("seconds", v.seconds)
        .set("seconds_space", v.seconds_space).set("seconds_solve", v.seconds_solve)
        .set("seconds_estimate", v.seconds_estimate).set("seconds_refine", v.seconds_refine)
        .set("notes", Json::strings(v.notes));
    js.push(j);
    se.x.push_back(v.dofs);
    se.y.push_back(v.estimator);
    if (!std::isnan(v.l2)) {
      sl2.x.push_back(v.dofs);
      sl2.y.push_back(v.l2);
      sh1.x.push_back(v.dofs);
      sh1.y.push_back(v.h1_semi);
    }
  }
  std::vector<PlotSeries> plot{se};
  if (!sl2.x.empty()) plot.insert(plot.end(), {sl2, sh1});
  Json& root = out.json;
  root.set("case", c.path).set("family", c.family).set("space", description).set("theta", c.adapt.theta).set("marking", c.adapt.mark_functions ? "functions" : "cells").set("steps", js);
  if (steps.size() >= 4 && !std::isnan(steps.back().h1_semi))
    root.set("h1_rate_last_half", fitted_h1_rate(steps, steps.size() / 2));
  if (stage) {
    write_text_file(stage->stage("adapt.csv"), csv);
    write_text_file(stage->stage("adapt.json"), root.dump() + "\n");
    write_text_file(stage->stage("adapt.svg"),
                    loglog_svg(c.name + ": adaptive, " + description, "degrees of freedom", "error", plot));
    if (!pvd.empty()) write_pvd(stage->stage("adapt.pvd"), pvd);
    out.outputs = stage->commit();
  }
  root.set("outputs", Json::strings(out.outputs));
  return out;
}

int adapt_command(const AdaptOptions& o) {
  CaseDescription c = load_case(o.case_file);
  override_case(c, o.degree, o.elements, o.solver, o.tolerance, o.petsc_options_given ? &o.petsc_options : nullptr);
  if (o.steps) c.adapt.steps = o.steps;
  if (o.theta) c.adapt.theta = o.theta;
  if (o.max_dofs) c.adapt.max_dofs = o.max_dofs;
  c.allow_unverified_space = o.allow_unverified_space;
  if (!o.marking.empty()) c.adapt.mark_functions = o.marking == "functions";
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
  std::printf("knotwork adapt %s: %s, Doerfler theta = %g%s\n", c.path.c_str(), description.c_str(), c.adapt.theta,
              c.adapt.mark_functions ? " on functions" : "");
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
    std::printf("  H1 rate against dofs, least squares over the last %zu steps: %.2f (optimal: N^(-p/2))\n",
                steps.size() - steps.size() / 2, fitted_h1_rate(steps, steps.size() / 2));
  std::printf("  (rate: of the H1-seminorm error against dofs, -log(e1/e0)/log(N1/N0))\n");
  for (const auto& p : outputs)
    if (p.find("adapt.") != std::string::npos) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
