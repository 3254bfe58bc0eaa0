// The adaptive study: estimate - mark (Doerfler) - refine (the family's local refinement) - solve,
// repeated, with its history and ParaView files.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <future>
#include <optional>

#include "studies/adaptive.hpp"
#include "studies/studies.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "studies/svg_plot.hpp"
#include "basis/core/input_error.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/residual_estimator.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

AdaptOutcome adapt_study(const CaseDescription& c, Ordering ordering, const std::string* output_directory,
                         const ProgressFunction& progress, int output_every) {
  if (output_every < 1) throw InputError("--output-every: must be at least 1, got " + std::to_string(output_every));
  check_adaptive_family(c);
  if (c.adapt.steps < 1 || c.adapt.steps > 200) throw InputError("--steps: must be in [1, 200], got " + std::to_string(c.adapt.steps));
  if (!(c.adapt.theta > 0 && c.adapt.theta <= 1)) throw InputError("--theta: must be in (0, 1]");
  if (!(c.adapt.min_fraction >= 0 && c.adapt.min_fraction <= 1)) throw InputError("--min-fraction: must be in [0, 1]");
  if (c.adapt.max_dofs < 1) throw InputError("--max-dofs: must be positive");
  std::optional<OutputStage> stage;
  if (output_directory) stage.emplace(*output_directory);
  const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
  const auto say = [&](const std::string& what) { if (progress) progress(what); };
  AdaptOutcome out;
  std::vector<PvdEntry> pvd;
  std::string& description = out.description;
  std::vector<double> output_seconds;  // per step: building its ParaView files, and waiting for the last step's
  // A step's files are built on this thread (they need its space) and compressed and written
  // on another while the loop goes on; at most one step's files wait to be written.
  std::future<void> writing;
  const auto finish_writing = [&] {
    if (writing.valid()) writing.get();  // rethrows what the writer threw
  };
  out.steps = adapt_case(c, ordering, say, [&](const AdaptiveStepView& v) {
    if (v.step == 0) description = v.space.presentation().description();
    output_seconds.push_back(0);
    if (!stage || !c.write_bezier || (!v.last && v.step % output_every != 0)) return;
    const auto t0 = std::chrono::steady_clock::now();
    say("writing ParaView output");
    Eigen::VectorXd eta = v.indicators.eta_squared.cwiseSqrt();
    Eigen::VectorXd flag = Eigen::VectorXd::Zero(eta.size());
    for (int m : v.marked) flag[m] = 1;
    const std::string name = "step_" + std::to_string(v.step);
    std::vector<PreparedWrite> files;
    files.push_back(prepare_bezier_vtu(stage->stage(name + ".vtu"), v.space.mesh(), v.space.geometry(),
                                       v.solution.coefficients, exact, {{"error_indicator", eta}, {"marked", flag}},
                                       v.solution.exact_mean));
    pvd.push_back({double(v.step), 0, name + ".vtu"});
    // The knots are drawn on the writer thread too (some families take long: knot segments).
    if (std::function<KnotLines()> knots = v.space.presentation().knot_lines_later()) {
      files.push_back([knots = std::move(knots), path = stage->stage(name + "_knots.vtp")] {
        const KnotLines k = knots();
        prepare_polylines_vtp(path, k.lines, {{"kind", k.kind}, {"multiplicity", k.multiplicity}})();
      });
      pvd.push_back({double(v.step), 1, name + "_knots.vtp"});
    }
    finish_writing();
    writing = std::async(std::launch::async, [files = std::move(files)] {
      for (const PreparedWrite& f : files) f();
    });
    output_seconds.back() = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  });
  {
    const auto t0 = std::chrono::steady_clock::now();
    finish_writing();
    if (!output_seconds.empty()) output_seconds.back() += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
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
        .set("seconds_output", output_seconds.at(s)).set("solver", v.solver).set("iterations", v.iterations)
        .set("notes", Json::strings(v.notes));
    const PoissonTimings& t = v.solve_phases;
    Json phases = Json::object();
    phases.set("setup", t.setup).set("assembly", t.assembly).set("analysis", t.analysis)
        .set("factorization", t.factorization).set("solve", t.solve).set("preconditioner", t.preconditioner)
        .set("iterations", t.iterations).set("errors", t.errors);
    j.set("solve_phases", phases);
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
  root.set("case", c.path).set("family", c.family).set("space", description).set("theta", c.adapt.theta).set("marking", c.adapt.mark_functions ? "functions" : "cells")
      .set("strategy", c.adapt.maximum_strategy ? "maximum" : "dorfler").set("min_fraction", c.adapt.min_fraction)
      .set("solver", steps.empty() ? std::string() : steps.front().solver)
      .set("solver_note", steps.empty() ? std::string() : steps.front().solver_note)
      .set("steps", js);
  if (steps.size() >= 4 && !std::isnan(steps.back().h1_semi))
    root.set("h1_rate_last_half", fitted_h1_rate(steps, steps.size() / 2));
  if (stage) {
    write_text_file(stage->stage("adapt.csv"), csv);
    write_text_file(stage->stage("adapt.json"), root.dump() + "\n");
    write_text_file(stage->stage("adapt.svg"),
                    loglog_svg(c.name + ": adaptive, " + description, "degrees of freedom", "error", plot));
    if (!pvd.empty()) {
      // The interfaces of a multipatch domain drawn over every step (part 2).
      const std::string interfaces = write_interface_lines(c, *stage);
      const size_t steps_written = pvd.size();
      for (size_t k = 0; k < steps_written; ++k)
        if (!interfaces.empty() && pvd[k].part == 0) pvd.push_back({pvd[k].time, 2, interfaces});
      std::stable_sort(pvd.begin(), pvd.end(), [](const PvdEntry& a, const PvdEntry& b) { return a.time < b.time; });
      write_pvd(stage->stage("adapt.pvd"), pvd);
    }
    out.outputs = stage->commit();
  }
  root.set("outputs", Json::strings(out.outputs));
  return out;
}

}  // namespace knotwork
