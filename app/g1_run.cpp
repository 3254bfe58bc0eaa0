// `knotwork run` and `knotwork converge` for family = "g1" cases: the G1 space on the
// (subdivided) quad mesh, planar Poisson through the common solver or Laplace-Beltrami on a
// closed surface, errors, the C1 check across interfaces and Bezier output for ParaView.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "app/commands.hpp"
#include "app/g1_discretize.hpp"
#include "app/json_writer.hpp"
#include "app/output_stage.hpp"
#include "app/progress.hpp"
#include "app/svg_plot.hpp"
#include "cases/gluing_file.hpp"
#include "basis/bezier_ops.hpp"
#include "quadrature/bernstein.hpp"
#include "solver/input_error.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

struct G1Level {
  int level = 0, faces = 0, cells = 0, dofs = 0, free = 0;
  double h = 0, l2 = NAN, h1_semi = NAN, h1 = NAN, l2_rate = NAN, h1_rate = NAN;
  double jump = 0, regularity = 0, regularity_nodes = 0, shape_distance = 0, seconds = 0;
  double exact_mean = 0;  // removed from the exact solution (surface problems with reaction 0)
  std::array<long, 5> counts{};
  Eigen::VectorXd coefficients;
  Eigen::VectorXd cell_h1_squared;  // planar: |u - u_h|^2_H1 per cell, for the .vtu
};

std::string describe_g1(const CaseDescription& c) {
  const auto& g = c.g1;
  return std::string(g.c0 ? "C0 multipatch baseline" : "G1 macro-patch splines (Blidia-Mourrain-Villamizar)") +
         ", degree " + std::to_string(g.degree) + ", C^" +
         std::to_string(g.split_smoothness) + " 4-split, " +
         (is_named_gluing(g.gluing) ? g.gluing : std::string("file")) + " gluing, " +
         (g.surface ? "Laplace-Beltrami on a " + g.shape + " surface" : std::string("planar Poisson"));
}

double largest_diagonal(const G1Discretization& d) {
  double h = 0;
  const int k = d.basis.k, last = (k + 1) * (k + 1) - 1;
  for (const auto& cell : d.cells)
    h = std::max({h, (cell.points.row(0) - cell.points.row(last)).norm(),
                  (cell.points.row(k) - cell.points.row(last - k)).norm()});
  return h;
}

G1Level solve_level(const CaseDescription& c, const G1Discretization& d, Ordering ordering, Progress& progress) {
  G1Level lv;
  lv.level = d.levels;
  lv.faces = d.level.mesh.num_faces();
  lv.cells = d.mesh.num_cells();
  lv.dofs = d.mesh.num_functions();
  lv.counts = d.basis.counts;
  lv.h = largest_diagonal(d);
  lv.regularity = d.min_regularity;
  lv.regularity_nodes = d.min_regularity_nodes;
  lv.shape_distance = d.shape_distance;
  if (!c.g1.surface) {
    PoissonSolveOptions so;
    so.quadrature = c.quadrature;
    so.ordering = ordering;
    so.progress = [&](const std::string& s) { progress(s); };
    so.compute_errors = false;  // below, once, with the per-cell split
    PoissonSolution s;
    try {
      s = solve_poisson(d.mesh, *d.planar, c.problem, so);
    } catch (const std::runtime_error& e) {
      throw InputError(c.path + ": " + e.what());
    }
    lv.free = s.num_free;
    lv.coefficients = s.coefficients;
    if (c.problem.exact) {
      progress("error norms");
      const ErrorNorms e = error_norms(d.mesh, *d.planar, s.coefficients, *c.problem.exact, c.quadrature, &lv.cell_h1_squared);
      lv.l2 = e.l2, lv.h1_semi = e.h1_semi, lv.h1 = e.h1;
    }
  } else {
    progress("assembly and solve (Laplace-Beltrami)");
    SurfaceProblem p;
    p.exact = c.g1.surface_exact;
    p.source = c.g1.surface_source;
    p.reaction = c.g1.reaction;
    SurfaceSolution s;
    try {
      s = solve_surface_poisson(d.mesh, d.cells, p, c.quadrature);
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": " + e.what());
    }
    lv.free = s.num_functions - (c.g1.reaction == 0 ? 1 : 0);
    lv.coefficients = s.coefficients;
    lv.exact_mean = s.exact_mean;
    if (s.errors) lv.l2 = s.errors->l2, lv.h1_semi = s.errors->h1_semi, lv.h1 = s.errors->h1;
  }
  progress("C1 check across interfaces");
  lv.jump = g1_gradient_jump(d, lv.coefficients);
  return lv;
}

void write_level_vtu(const std::string& path, const CaseDescription& c, const G1Discretization& d,
                     const G1Level& lv) {
  if (!c.g1.surface) {
    CellFields fields;
    if (lv.cell_h1_squared.size() > 0) fields.emplace_back("h1_error_squared", lv.cell_h1_squared);
    write_bezier_vtu(path, d.mesh, *d.planar, lv.coefficients, c.problem.exact ? &*c.problem.exact : nullptr, fields);
    return;
  }
  // Solution: its Bernstein coefficients (exact). Exact solution and error: interpolants at
  // the cells' equispaced nodes (what ParaView can show of a non-polynomial function).
  const int k = d.basis.k;
  const Eigen::MatrixXd interpolation = bernstein_interpolation_inverse(k, k);
  BezierSurface surface;
  std::vector<Eigen::VectorXd> solution, exact, error;
  std::optional<ExpressionEvaluator> u;
  if (c.g1.surface_exact) u.emplace(c.g1.surface_exact->u);
  Eigen::VectorXd nu((k + 1) * (k + 1)), nv((k + 1) * (k + 1));
  for (int b = 0; b <= k; ++b)
    for (int a = 0; a <= k; ++a) nu(a + (k + 1) * b) = double(a) / k, nv(a + (k + 1) * b) = double(b) / k;
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(k, k, nu, nv, B, Bu, Bv);
  for (int cell = 0; cell < d.mesh.num_cells(); ++cell) {
    surface.degree.push_back(k);
    surface.points.push_back(d.cells[cell].points);
    const auto ids = d.mesh.functions(cell);
    Eigen::VectorXd local(ids.size());
    for (size_t a = 0; a < ids.size(); ++a) local(a) = lv.coefficients(ids[a]);
    const Eigen::VectorXd bernstein = d.mesh.extraction(cell).transpose() * local;  // u_h on the cell, exactly
    if (u) {
      const Eigen::MatrixX3d x = B * d.cells[cell].points;
      Eigen::VectorXd ex(nu.size());
      for (Eigen::Index q = 0; q < nu.size(); ++q) ex(q) = (*u)(x(q, 0), x(q, 1), x(q, 2)) - lv.exact_mean;
      exact.push_back(interpolation * ex);
      error.push_back(bernstein - exact.back());
    }
    solution.push_back(bernstein);
  }
  surface.point_fields.emplace_back("solution", std::move(solution));
  if (u) {
    surface.point_fields.emplace_back("exact", std::move(exact));
    surface.point_fields.emplace_back("error", std::move(error));
  }
  write_bezier_surface_vtu(path, surface);
}


Json level_json(const G1Level& v) {
  Json j = Json::object();
  j.set("level", v.level).set("faces", v.faces).set("cells", v.cells).set("h", v.h).set("dofs", v.dofs)
      .set("free_dofs", v.free).set("l2_error", v.l2).set("h1_seminorm_error", v.h1_semi).set("h1_error", v.h1)
      .set("l2_rate", v.l2_rate).set("h1_rate", v.h1_rate).set("c1_jump", v.jump)
      .set("min_regularity", v.regularity).set("min_regularity_cell_nodes", v.regularity_nodes).set("seconds", v.seconds);
  Json counts = Json::object();
  counts.set("vertex", double(v.counts[0])).set("edge", double(v.counts[1])).set("face", double(v.counts[2]))
      .set("vertex_pair", double(v.counts[3])).set("coupled", double(v.counts[4]));
  j.set("counts", counts);
  return j;
}

// --degree and --elements on a G1 case.
void apply_overrides(const CommonOptions& o, CaseDescription& c) {
  if (o.elements)
    throw InputError("--elements: not used with family = \"g1\" (refine with [space] refine; converge subdivides)");
  if (!o.degree) return;
  if (o.degree < 2 || o.degree > 12) throw InputError("--degree: must be in [2, 12] for G1 spaces");
  if (c.g1.split_smoothness > o.degree - 1)
    throw InputError("--degree: " + std::to_string(o.degree) + " is too low for the case's split_smoothness " +
                     std::to_string(c.g1.split_smoothness) + " (needs degree >= split_smoothness + 1)");
  c.g1.degree = o.degree;
}

}  // namespace

int run_g1_case(const RunOptions& o, CaseDescription& c) {
  apply_overrides(o, c);
  const Ordering ordering = parse_ordering(o.ordering);
  std::optional<OutputStage> stage;
  if (!o.no_output) stage.emplace(o.out.empty() ? c.output_directory : o.out);
  Progress progress(o.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  const G1Discretization d = discretize_g1(c, 0, [&](const std::string& s) { progress(s); });
  G1Level lv = solve_level(c, d, ordering, progress);
  std::vector<std::string> outputs;
  if (stage) {
    progress("writing ParaView output");
    write_level_vtu(stage->stage("solution.vtu"), c, d, lv);
    outputs = stage->commit();
  }
  lv.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.json) {
    Json j = level_json(lv);
    j.set("case", c.path).set("space", describe_g1(c)).set("fit_deviation", d.fit_deviation)
        .set("boundary_deviation", d.boundary_deviation).set("shape_distance", d.shape_distance)
        .set("worst_face", d.worst_face + 1)
        .set("min_regularity_cell_nodes", d.min_regularity_nodes).set("outputs", Json::strings(outputs));
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork run %s%s\n", c.path.c_str(), c.title.empty() ? "" : ("  (" + c.title + ")").c_str());
  std::printf("  space    %s\n", describe_g1(c).c_str());
  std::printf("  mesh     %d faces after %d subdivisions, %d Bezier cells\n", lv.faces, d.levels, lv.cells);
  std::printf("  dofs     %d functions (vertex %ld, edge %ld, face %ld, vertex-pair %ld, coupled %ld), %d unknowns\n",
              lv.dofs, lv.counts[0], lv.counts[1], lv.counts[2], lv.counts[3], lv.counts[4], lv.free);
  std::printf("  geometry fitted to the %s faces (largest coefficient deviation %.3e); %s %.3e (face %d)%s\n",
              c.g1.shape.c_str(), d.fit_deviation, c.g1.surface ? "min |x_u x x_v|/max" : "min det J/max",
              d.min_regularity, d.worst_face + 1,
              c.g1.surface ? (", distance to the " + c.g1.shape + " " + std::to_string(d.shape_distance)).c_str() : "");
  if (d.min_regularity_nodes <= 1e-8)
    std::printf("  warning  %s = %.3g (relative) at (%.6g, %.6g, %.6g), a cell corner or side midpoint: the fitted\n"
                "           geometry is singular there (regular at every quadrature point); expect reduced rates\n",
                c.g1.surface ? "|x_u x x_v|" : "det J", d.min_regularity_nodes, d.singular_point.x(),
                d.singular_point.y(), d.singular_point.z());
  if (!std::isnan(lv.l2))
    std::printf("  errors   L2 %.6e   H1-seminorm %.6e   H1 %.6e\n", lv.l2, lv.h1_semi, lv.h1);
  std::printf("  C1       largest gradient jump across interfaces %.3e (relative)\n", lv.jump);
  std::printf("  time     %.3f s\n", lv.seconds);
  for (const auto& p : outputs) std::printf("  output   %s\n", p.c_str());
  return 0;
}

int converge_g1_case(const ConvergeOptions& o, CaseDescription& c) {
  apply_overrides(o, c);
  if (o.levels < 1 || o.levels > 7) throw InputError("--levels: must be in [1, 7] for G1 spaces, got " + std::to_string(o.levels));
  if (!c.problem.exact && !c.g1.surface_exact)
    throw InputError(c.path + ": [problem] exact: a convergence study needs the exact solution");
  const Ordering ordering = parse_ordering(o.ordering);
  OutputStage stage(o.out.empty() ? c.output_directory : o.out);
  Progress progress(o.quiet);
  std::vector<G1Level> levels;
  std::vector<std::pair<double, std::string>> pvd;
  for (int l = 0; l < o.levels; ++l) {
    progress.set_prefix("level " + std::to_string(l + 1) + "/" + std::to_string(o.levels) + ": ");
    const auto t0 = std::chrono::steady_clock::now();
    const G1Discretization d = discretize_g1(c, l, [&](const std::string& s) { progress(s); });
    G1Level lv = solve_level(c, d, ordering, progress);
    if (!levels.empty()) {
      const G1Level& prev = levels.back();
      lv.l2_rate = std::log(prev.l2 / lv.l2) / std::log(prev.h / lv.h);
      lv.h1_rate = std::log(prev.h1_semi / lv.h1_semi) / std::log(prev.h / lv.h);
    }
    if (c.write_bezier) {
      progress("writing ParaView output");
      const std::string name = "level_" + std::to_string(l) + ".vtu";
      write_level_vtu(stage.stage(name), c, d, lv);
      pvd.emplace_back(l, name);
    }
    lv.coefficients.resize(0);
    lv.cell_h1_squared.resize(0);
    lv.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    levels.push_back(lv);
  }
  std::string csv =
      "level,faces,h,dofs,l2_error,h1_seminorm_error,l2_rate,h1_rate,c1_jump,min_regularity,min_regularity_cell_nodes\n";
  Json jl = Json::array();
  PlotSeries sl2{"L2 error", {}, {}, "#1f77b4"}, sh1{"H1 seminorm", {}, {}, "#d62728"};
  auto num = [](double x) { return std::isnan(x) ? std::string() : json_number(x); };
  for (const auto& v : levels) {
    csv += std::to_string(v.level) + "," + std::to_string(v.faces) + "," + json_number(v.h) + "," +
           std::to_string(v.dofs) + "," + num(v.l2) + "," + num(v.h1_semi) + "," + num(v.l2_rate) + "," +
           num(v.h1_rate) + "," + json_number(v.jump) + "," + json_number(v.regularity) + "," +
           json_number(v.regularity_nodes) + "\n";
    jl.push(level_json(v));
    sl2.x.push_back(v.h), sl2.y.push_back(v.l2);
    sh1.x.push_back(v.h), sh1.y.push_back(v.h1_semi);
  }
  Json root = Json::object();
  root.set("case", c.path).set("space", describe_g1(c)).set("levels", jl);
  write_text_file(stage.stage("convergence.csv"), csv);
  write_text_file(stage.stage("convergence.json"), root.dump() + "\n");
  write_text_file(stage.stage("convergence.svg"),
             loglog_svg(c.name + ": " + describe_g1(c), "h (largest cell diagonal)", "error", {sl2, sh1}));
  if (!pvd.empty()) write_pvd(stage.stage("convergence.pvd"), pvd);
  const auto outputs = stage.commit();
  if (o.json) {
    root.set("outputs", Json::strings(outputs));
    std::printf("%s\n", root.dump().c_str());
    return 0;
  }
  std::printf("knotwork converge %s: %s\n", c.path.c_str(), describe_g1(c).c_str());
  std::printf("%5s %6s %11s %8s %13s %6s %13s %6s %10s\n", "level", "faces", "h", "dofs", "L2 error", "rate",
              "H1-semi error", "rate", "C1 jump");
  auto rate = [](double r) {
    char b[16];
    if (std::isnan(r)) return std::string("-");
    std::snprintf(b, sizeof b, "%.2f", r);
    return std::string(b);
  };
  for (const auto& v : levels)
    std::printf("%5d %6d %11.4e %8d %13.5e %6s %13.5e %6s %10.2e\n", v.level, v.faces, v.h, v.dofs, v.l2,
                rate(v.l2_rate).c_str(), v.h1_semi, rate(v.h1_rate).c_str(), v.jump);
  for (const auto& p : outputs)
    if (p.find("convergence") != std::string::npos) std::printf("  output   %s\n", p.c_str());
  return 0;
}

}  // namespace knotwork
