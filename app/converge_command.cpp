#include <cmath>
#include <cstdio>
#include <fstream>

#include "app/commands.hpp"
#include "app/discretize.hpp"
#include "app/json_writer.hpp"
#include "app/output_stage.hpp"
#include "app/progress.hpp"
#include "app/svg_plot.hpp"
#include "solver/input_error.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

struct Level {
  int elements = 0;
  double h = 0;
  int dofs = 0, cells = 0;
  double l2 = 0, h1_semi = 0, h1 = 0;
  double l2_rate = NAN, h1_rate = NAN;
  double seconds = 0;
};


}  // namespace

int converge_command(const ConvergeOptions& o) {
  CaseDescription c = load_case(o.case_file);
  if (c.family == "g1") return converge_g1_case(o, c);
  if (!c.collection_file.empty())
    throw InputError(c.path + ": [space] collection: a convergence study refines uniformly, and a collection given "
                     "explicitly has fixed functions (use knotwork run, or knotwork adapt to refine it)");
  if (o.degree) override_degree(c, o.degree);
  if (o.elements) override_elements(c, o.elements);
  if (o.levels < 1 || o.levels > 12) throw InputError("--levels: must be in [1, 12], got " + std::to_string(o.levels));
  if (!c.problem.exact)
    throw InputError(c.path + ": [problem] exact: a convergence study needs the exact solution");
  const long finest = static_cast<long>(c.space.elements_per_span[0]) << (o.levels - 1);
  if (finest * (static_cast<long>(c.space.elements_per_span[1]) << (o.levels - 1)) > (1L << 26))
    throw InputError("--levels: the finest level would have more than 2^26 cells");
  const Ordering ordering = parse_ordering(o.ordering);
  OutputStage stage(o.out.empty() ? c.output_directory : o.out);
  Progress progress(o.quiet);
  const std::array<int, 2> base = c.space.elements_per_span;
  std::vector<Level> levels;
  std::vector<std::pair<double, std::string>> pvd, pvd_sampled;
  const ExactSolution* exact = &*c.problem.exact;

  for (int l = 0; l < o.levels; ++l) {
    c.space.elements_per_span = {base[0] << l, base[1] << l};
    progress.set_prefix("level " + std::to_string(l + 1) + "/" + std::to_string(o.levels) + ": ");
    progress("building the space (" + std::to_string(c.space.elements_per_span[0]) + " elements per span)");
    const auto t0 = std::chrono::steady_clock::now();
    const Discretization d = discretize(c);
    const PoissonSolution s = solve_case(c, d, ordering, [&](const std::string& what) { progress(what); });
    Level lv;
    lv.elements = c.space.elements_per_span[0];
    lv.h = mesh_size(d);
    lv.dofs = s.num_functions;
    lv.cells = d.mesh().num_cells();
    lv.l2 = s.errors->l2;
    lv.h1_semi = s.errors->h1_semi;
    lv.h1 = s.errors->h1;
    if (!levels.empty()) {
      const Level& prev = levels.back();
      lv.l2_rate = std::log(prev.l2 / lv.l2) / std::log(prev.h / lv.h);
      lv.h1_rate = std::log(prev.h1_semi / lv.h1_semi) / std::log(prev.h / lv.h);
    }
    progress("writing ParaView output");
    const std::string name = "level_" + std::to_string(l);
    if (c.write_bezier) {
      write_bezier_vtu(stage.stage(name + ".vtu"), d.mesh(), *d.geometry, s.coefficients, exact);
      pvd.emplace_back(l, name + ".vtu");
    }
    if (c.write_sampled) {
      write_sampled_vtu(stage.stage(name + "_sampled.vtu"), d.mesh(), *d.geometry, s.coefficients, exact, c.samples);
      pvd_sampled.emplace_back(l, name + "_sampled.vtu");
    }
    lv.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    levels.push_back(lv);
  }

  // Tables and plot.
  std::string csv = "level,elements,h,dofs,cells,l2_error,h1_seminorm_error,h1_error,l2_rate,h1_rate\n";
  Json jl = Json::array();
  PlotSeries sl2{"L2 error", {}, {}, "#1f77b4"}, sh1{"H1 seminorm", {}, {}, "#d62728"};
  for (size_t l = 0; l < levels.size(); ++l) {
    const Level& v = levels[l];
    csv += std::to_string(l) + "," + std::to_string(v.elements) + "," + json_number(v.h) + "," +
           std::to_string(v.dofs) + "," + std::to_string(v.cells) + "," + json_number(v.l2) + "," +
           json_number(v.h1_semi) + "," + json_number(v.h1) + "," +
           (std::isnan(v.l2_rate) ? "" : json_number(v.l2_rate)) + "," +
           (std::isnan(v.h1_rate) ? "" : json_number(v.h1_rate)) + "\n";
    Json j = Json::object();
    j.set("level", static_cast<int>(l)).set("elements", v.elements).set("h", v.h).set("dofs", v.dofs)
        .set("cells", v.cells).set("l2_error", v.l2).set("h1_seminorm_error", v.h1_semi).set("h1_error", v.h1)
        .set("l2_rate", v.l2_rate).set("h1_rate", v.h1_rate).set("seconds", v.seconds);
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
  Json root = Json::object();
  root.set("case", c.path).set("space", describe_space(c)).set("levels", jl);
  write_text_file(stage.stage("convergence.csv"), csv);
  write_text_file(stage.stage("convergence.json"), root.dump() + "\n");
  write_text_file(stage.stage("convergence.svg"),
             loglog_svg(c.name + ": " + describe_space(c), "h (largest cell diameter)", "error", {sl2, sh1}));
  if (!pvd.empty()) write_pvd(stage.stage("convergence.pvd"), pvd);
  if (!pvd_sampled.empty()) write_pvd(stage.stage("convergence_sampled.pvd"), pvd_sampled);
  const auto outputs = stage.commit();

  if (o.json) {
    root.set("outputs", Json::strings(outputs));
    std::printf("%s\n", root.dump().c_str());
    return 0;
  }
  std::printf("knotwork converge %s: %s\n", c.path.c_str(), describe_space(c).c_str());
  std::printf("%5s %9s %12s %10s %14s %8s %14s %8s\n", "level", "elements", "h", "dofs", "L2 error", "rate",
              "H1-semi error", "rate");
  for (size_t l = 0; l < levels.size(); ++l) {
    const Level& v = levels[l];
    auto rate = [](double r) { char b[16]; if (std::isnan(r)) return std::string("-"); std::snprintf(b, sizeof b, "%.2f", r); return std::string(b); };
    std::printf("%5zu %9d %12.5e %10d %14.6e %8s %14.6e %8s\n", l, v.elements, v.h, v.dofs, v.l2,
                rate(v.l2_rate).c_str(), v.h1_semi, rate(v.h1_rate).c_str());
  }
  for (const auto& p : outputs)
    if (p.find("convergence") != std::string::npos) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
