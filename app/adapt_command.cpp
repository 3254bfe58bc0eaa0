// knotwork adapt: estimate - mark (Doerfler) - refine (knot segments or T-mesh cells) - solve, repeated.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>

#include "app/commands.hpp"
#include "app/adaptive.hpp"
#include "app/json_writer.hpp"
#include "app/output_stage.hpp"
#include "app/progress.hpp"
#include "app/svg_plot.hpp"
#include "basis/partition_topology.hpp"
#include "solver/input_error.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/residual_estimator.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

// The knots of the partition (lines, rays, segments) as polylines in physical space, with
// their kind (0 line, 1 ray, 2 segment) and multiplicity.
void write_knot_lines(const std::string& path, const RectangularPartition& partition, const NurbsPatch& geometry,
                      const std::function<int(bool vertical, double at, double from, double to)>& multiplicity_of) {
  const PartitionTopology topo = partition_topology(partition);
  std::vector<Eigen::MatrixX2d> lines;
  std::vector<int> kind, multiplicity;
  const int samples = 8;  // per edge: curved geometries stay curved
  for (const auto& k : topo.knots) {
    const double at = k.position.get_d();
    std::vector<double> stops;
    for (int v : k.vertices) stops.push_back((k.vertical ? topo.vertices[v].y : topo.vertices[v].x).get_d());
    Eigen::MatrixX2d poly((stops.size() - 1) * samples + 1, 2);
    int row = 0;
    for (size_t e = 0; e + 1 < stops.size(); ++e)
      for (int s = 0; s < samples + (e + 2 == stops.size() ? 1 : 0); ++s) {
        const double t = stops[e] + (stops[e + 1] - stops[e]) * s / samples;
        poly.row(row++) = patch_point(geometry, k.vertical ? at : t, k.vertical ? t : at).transpose();
      }
    lines.push_back(poly);
    kind.push_back(k.kind == PartitionTopology::KnotKind::kLine ? 0 : k.kind == PartitionTopology::KnotKind::kRay ? 1 : 2);
    multiplicity.push_back(multiplicity_of(k.vertical, at, stops.front(), stops.back()));
  }
  write_polylines_vtp(path, lines, {{"kind", kind}, {"multiplicity", multiplicity}});
}

std::string rate_text(double r) {
  if (std::isnan(r)) return "-";
  char b[16];
  std::snprintf(b, sizeof b, "%.2f", r);
  return b;
}

}  // namespace

int adapt_command(const AdaptOptions& o) {
  CaseDescription c = load_case(o.case_file);
  if (o.degree) override_degree(c, o.degree);
  if (o.elements) override_elements(c, o.elements);
  if (o.steps) c.adapt.steps = o.steps;
  if (o.theta) c.adapt.theta = o.theta;
  if (o.max_dofs) c.adapt.max_dofs = o.max_dofs;
  if (c.adapt.steps < 1 || c.adapt.steps > 200) throw InputError("--steps: must be in [1, 200], got " + std::to_string(c.adapt.steps));
  if (!(c.adapt.theta > 0 && c.adapt.theta <= 1)) throw InputError("--theta: must be in (0, 1]");
  if (c.adapt.max_dofs < 1) throw InputError("--max-dofs: must be positive");
  const Ordering ordering = parse_ordering(o.ordering);
  OutputStage stage(o.out.empty() ? c.output_directory : o.out);
  Progress progress(o.quiet);
  const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;

  std::vector<PvdEntry> pvd;
  const auto steps = adapt_case(c, ordering, [&](const std::string& what) { progress(what); },
                                [&](const AdaptiveStepView& v) {
    if (!c.write_bezier) return;
    progress("writing ParaView output");
    Eigen::VectorXd eta = v.indicators.eta_squared.cwiseSqrt();
    Eigen::VectorXd flag = Eigen::VectorXd::Zero(eta.size());
    for (int m : v.marked) flag[m] = 1;
    const std::string name = "step_" + std::to_string(v.step);
    const Discretization& d = v.discretization;
    write_bezier_vtu(stage.stage(name + ".vtu"), d.mesh(), *d.geometry, v.solution.coefficients, exact,
                     {{"error_indicator", eta}, {"marked", flag}});
    if (v.collection) {
      write_knot_lines(stage.stage(name + "_knots.vtp"), v.collection->partition(), c.geometry,
                       [&](bool vertical, double at, double from, double to) {
                         return v.collection->knot_multiplicity(vertical, at, from, to);
                       });
    } else {
      // PT-spline knots are simple, except along the C0 lines.
      const auto& c0 = d.pt->c0;
      write_knot_lines(stage.stage(name + "_knots.vtp"), *v.tmesh, c.geometry, [&](bool vertical, double at, double, double) {
        for (const auto& t : vertical ? c0.x : c0.y)
          if (t.get_d() == at) return vertical ? d.pt->m : d.pt->n;
        return 1;
      });
    }
    pvd.push_back({double(v.step), 0, name + ".vtu"});
    pvd.push_back({double(v.step), 1, name + "_knots.vtp"});
  });
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
        .set("seconds_estimate", v.seconds_estimate).set("seconds_refine", v.seconds_refine);
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
  Json root = Json::object();
  root.set("case", c.path).set("space", describe_space(c)).set("theta", c.adapt.theta).set("steps", js);
  if (steps.size() >= 4 && !std::isnan(steps.back().h1_semi))
    root.set("h1_rate_last_half", fitted_h1_rate(steps, steps.size() / 2));
  write_text_file(stage.stage("adapt.csv"), csv);
  write_text_file(stage.stage("adapt.json"), root.dump() + "\n");
  write_text_file(stage.stage("adapt.svg"), loglog_svg(c.name + (c.family == "pt" ? ": adaptive PT-splines" : ": adaptive knot segments"), "degrees of freedom", "error", plot));
  if (!pvd.empty()) write_pvd(stage.stage("adapt.pvd"), pvd);
  const auto outputs = stage.commit();

  if (o.json) {
    root.set("outputs", Json::strings(outputs));
    std::printf("%s\n", root.dump().c_str());
    return 0;
  }
  std::printf("knotwork adapt %s: %s, Doerfler theta = %g\n", c.path.c_str(), describe_space(c).c_str(), c.adapt.theta);
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
