#include <chrono>
#include <cstdio>
#include <optional>

#include "app/commands.hpp"
#include "app/discretize.hpp"
#include "app/json_writer.hpp"
#include "app/output_stage.hpp"
#include "app/progress.hpp"
#include "solver/input_error.hpp"
#include "solver/poisson_solver.hpp"
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
  if (c.family == "g1") return run_g1_case(o, c);
  if (o.degree) override_degree(c, o.degree);
  if (o.elements) override_elements(c, o.elements);
  c.allow_non_semi_regular = o.allow_non_semi_regular;
  const Ordering ordering = parse_ordering(o.ordering);
  std::optional<OutputStage> stage;
  if (!o.no_output) stage.emplace(o.out.empty() ? c.output_directory : o.out);
  Progress progress(o.quiet);

  progress("building the space: " + describe_space(c));
  auto t = clock::now();
  const Discretization d = discretize(c);
  const double t_space = since(t);

  PoissonSolution s = solve_case(c, d, ordering, [&](const std::string& what) { progress(what); });
  s.timings.setup += t_space;

  std::vector<std::string> outputs;
  double t_output = 0;
  if (stage) {
    progress("writing ParaView output");
    t = clock::now();
    const ExactSolution* exact = c.problem.exact ? &*c.problem.exact : nullptr;
    if (c.write_bezier) write_bezier_vtu(stage->stage("solution.vtu"), d.mesh(), *d.geometry, s.coefficients, exact);
    if (c.write_sampled)
      write_sampled_vtu(stage->stage("solution_sampled.vtu"), d.mesh(), *d.geometry, s.coefficients, exact, c.samples);
    outputs = stage->commit();
    t_output = since(t);
  }
  const PoissonTimings& tm = s.timings;
  const double total = tm.setup + tm.assembly + tm.analysis + tm.factorization + tm.solve + tm.errors;

  if (o.json) {
    Json timings = Json::object();
    timings.set("setup", tm.setup).set("assembly", tm.assembly).set("analysis", tm.analysis)
        .set("factorization", tm.factorization).set("solve", tm.solve).set("errors", tm.errors)
        .set("output", t_output).set("total_without_output", total);
    Json j = Json::object();
    j.set("case", c.path).set("space", describe_space(c))
        .set("degree", Json::array().push(double(c.space.degree[0])).push(double(c.space.degree[1])))
        .set("cells", d.mesh().num_cells()).set("dofs", s.num_functions).set("free_dofs", s.num_free)
        .set("matrix_nonzeros", s.matrix_nonzeros).set("factor_nonzeros", s.cholesky.factor_nonzeros)
        .set("refinement_correction", s.cholesky.refinement_correction);
    if (s.errors) j.set("l2_error", s.errors->l2).set("h1_seminorm_error", s.errors->h1_semi).set("h1_error", s.errors->h1);
    else j.set_null("l2_error").set_null("h1_seminorm_error").set_null("h1_error");
    j.set("timings", timings).set("outputs", Json::strings(outputs));
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork run %s%s\n", c.path.c_str(), c.title.empty() ? "" : ("  (" + c.title + ")").c_str());
  std::printf("  space    %s, %d cells\n", describe_space(c).c_str(), d.mesh().num_cells());
  for (const auto& r : d.insertions)
    if (r.extended)
      std::printf("  note     segment %s = %g, [%g, %g] was extended to [%g, %g] to keep the basis semi-regular\n",
                  r.requested.vertical ? "x" : "y", r.requested.position, r.requested.from, r.requested.to,
                  r.inserted.from, r.inserted.to);
  std::printf("  dofs     %d functions, %d unknowns after Dirichlet elimination, %ld stored matrix entries\n",
              s.num_functions, s.num_free, s.matrix_nonzeros);
  if (s.errors)
    std::printf("  errors   L2 %.6e   H1-seminorm %.6e   H1 %.6e\n", s.errors->l2, s.errors->h1_semi, s.errors->h1);
  std::printf("  time     setup %.3f s, assembly %.3f s, analysis %.3f s, factorization %.3f s, solve %.3f s, errors %.3f s"
              " (total %.3f s); output %.3f s\n",
              tm.setup, tm.assembly, tm.analysis, tm.factorization, tm.solve, tm.errors, total, t_output);
  for (const auto& p : outputs) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
