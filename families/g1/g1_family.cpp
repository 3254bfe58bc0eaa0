// Family "g1": G1 macro-patch splines (Blidia-Mourrain-Villamizar) on a quad mesh of any
// topology, planar or a closed surface; the geometry is the G1 spline fitted once to the
// coarse mesh and restricted exactly to the subdivided cells. Refinement is uniform
// subdivision (one more per convergence level).
#include <cmath>
#include <cstdio>

#include "families/g1/g1_case.hpp"
#include "families/g1/g1_discretization.hpp"
#include "families/g1/gluing_file.hpp"
#include "cases/resource_limits.hpp"
#include "cases/basis_tool.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

std::unique_ptr<BasisTool> g1_basis_tool(CLI::App& basis);  // g1_basis_tool.cpp

namespace {

std::string describe_g1(const CaseDescription& c) {
  const auto& g = g1_section(c);
  return std::string(g.c0 ? "C0 multipatch baseline" : "G1 macro-patch splines (Blidia-Mourrain-Villamizar)") +
         ", degree " + std::to_string(g.degree) + ", C^" + std::to_string(g.split_smoothness) + " 4-split, " +
         (is_named_gluing(g.gluing) ? g.gluing : std::string("file")) + " gluing, " +
         (g.surface ? "Laplace-Beltrami on a " + g.shape + " surface" : std::string("planar Poisson"));
}

std::string format(const char* f, double a) {
  char b[64];
  std::snprintf(b, sizeof b, f, a);
  return b;
}

// Before anything is built: every subdivision quadruples the faces; each face has 4 cells
// and at most (2k - r + 1)^2 functions (the face space's dimension, an upper bound).
void check_g1_memory(const CaseDescription& c, int level) {
  const G1Section& g = g1_section(c);
  const int levels = g.refine + level;
  const double faces = double(g.faces) * std::pow(4.0, levels);
  const int k = g.degree, n = 2 * k - g.split_smoothness + 1;
  char what[160];
  std::snprintf(what, sizeof what, "%.3g faces (%d subdivisions) of degree %d", faces, levels, k);
  check_memory(c.path + ": [space] refine", galerkin_bytes(4 * faces, faces * n * n, k, k), what);
}

G1Discretization checked_discretization(const CaseDescription& c, int level, const ProgressFunction& progress) {
  check_g1_memory(c, level);
  return discretize_g1(c, level, progress);
}

class G1Space final : public SplineSpace, public SpaceReport {
 public:
  const SpaceReport& presentation() const override { return *this; }
  G1Space(const CaseDescription& c, int level, const ProgressFunction& progress)
      : case_(std::make_shared<const CaseDescription>(c)), d_(checked_discretization(c, level, progress)) {}
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *d_.geometry; }
  std::string description() const override { return describe_g1(*case_); }
  std::vector<int> degree() const override { return {g1_section(*case_).degree, g1_section(*case_).degree}; }
  std::vector<ReportField> report() const override {
    const auto& n = d_.basis.counts;
    const CaseDescription& c = *case_;
    const std::string regularity = g1_section(c).surface ? "min |x_u x x_v|/max" : "min det J/max";
    std::vector<ReportField> r{
        {.key = "faces",
         .value = long(d_.level.mesh.num_faces()),
         .text = std::to_string(d_.level.mesh.num_faces()) + " faces after " + std::to_string(d_.levels) +
                 " subdivisions, " + std::to_string(d_.mesh.num_cells()) + " Bezier cells",
         .label = "mesh",
         .column = true,
         .width = 6},
        {.key = "subdivisions", .value = long(d_.levels)},
        {.key = "counts.vertex",
         .value = n[0],
         .text = "vertex " + std::to_string(n[0]) + ", edge " + std::to_string(n[1]) + ", face " + std::to_string(n[2]) +
                 ", vertex-pair " + std::to_string(n[3]) + ", coupled " + std::to_string(n[4]) + " functions",
         .label = "basis"},
        {.key = "counts.edge", .value = n[1]},
        {.key = "counts.face", .value = n[2]},
        {.key = "counts.vertex_pair", .value = n[3]},
        {.key = "counts.coupled", .value = n[4]},
        {.key = "fit_deviation",
         .value = d_.fit_deviation,
         .text = "fitted to the " + g1_section(c).shape + " faces (largest coefficient deviation " +
                 format("%.3e", d_.fit_deviation) + "); " + regularity + " " + format("%.3e", d_.min_regularity) +
                 " (face " + std::to_string(d_.worst_face + 1) + ")" +
                 (g1_section(c).surface ? ", distance to the " + g1_section(c).shape + " " + format("%g", d_.shape_distance) : ""),
         .label = "geometry"},
        {.key = "boundary_deviation", .value = d_.boundary_deviation},
        {.key = "shape_distance", .value = d_.shape_distance},
        {.key = "worst_face", .value = long(d_.worst_face + 1)},
        {.key = "skewed_fans", .value = long(d_.coarse_gluing.skewed_fans.size())},
        {.key = "min_regularity", .value = d_.min_regularity},
        {.key = "min_regularity_cell_nodes", .value = d_.min_regularity_nodes},
    };
    return r;
  }
  std::vector<std::string> notes() const override {
    std::vector<std::string> out;
    if (const GluingData& g = d_.coarse_gluing; !g.skewed_fans.empty()) {
      out.push_back(std::to_string(g.skewed_fans.size()) + " crossing vertices (" + g.skewed_fans_list() +
                    ") get a skewed fan: Condition 3.2 fails there with the linear symmetric data (opposite "
                    "neighbours of different valences) or once a neighbour is skewed; the data stay "
                    "analysis-suitable (docs/G1_POISSON.md)");
    }
    if (d_.min_regularity_nodes > 1e-8) return out;
    char b[400];
    std::snprintf(b, sizeof b,
                  "%s = %.3g (relative) at (%.6g, %.6g, %.6g), a cell corner or side midpoint: the fitted geometry is "
                  "singular there (regular at every quadrature point); expect reduced rates",
                  g1_section(*case_).surface ? "|x_u x x_v|" : "det J", d_.min_regularity_nodes, d_.singular_point.x(),
                  d_.singular_point.y(), d_.singular_point.z());
    out.push_back(b);
    return out;
  }
  std::vector<ReportField> check_solution(const Eigen::VectorXd& coefficients) const override {
    const double jump = g1_gradient_jump(d_, coefficients);
    return {{.key = "c1_jump",
             .value = jump,
             .text = "largest gradient jump across interfaces " + format("%.3e", jump) + " (relative)",
             .label = "C1",
             .column = true,
             .width = 10}};
  }

 private:
  std::shared_ptr<const CaseDescription> case_;  // a copy: the space does not need the caller's case to live on
  G1Discretization d_;
};

}  // namespace

SpaceFamily g1_family() {
  SpaceFamily f;
  f.name = "g1";
  f.read_case = read_g1_case;
  f.space_keys = g1_space_keys();
  f.add_basis_tool = g1_basis_tool;
  f.build = [](const CaseDescription& c, int level, const ProgressFunction& progress) -> std::unique_ptr<SplineSpace> {
    return std::make_unique<G1Space>(c, level, progress);
  };
  f.override_options = [](CaseDescription& c, int degree, int elements) {
    if (elements)
      throw InputError("--elements: not used with family = \"g1\" (refine with [space] refine; converge subdivides)");
    if (!degree) return;
    if (degree < 2 || degree > 12) throw InputError("--degree: must be in [2, 12] for G1 spaces");
    if (!g1_section(c).split_smoothness_given) g1_section(c).split_smoothness = default_split_smoothness(degree);
    if (g1_section(c).split_smoothness > degree - 1)
      throw InputError("--degree: " + std::to_string(degree) + " is too low for the case's split_smoothness " +
                       std::to_string(g1_section(c).split_smoothness) + " (needs degree >= split_smoothness + 1)");
    g1_section(c).degree = degree;
  };
  f.check_converge = [](const CaseDescription& c, int levels) {
    if (levels > 7) throw InputError("--levels: must be in [1, 7] for G1 spaces, got " + std::to_string(levels));
    check_g1_memory(c, levels - 1);  // the finest level, before the first is solved
  };
  return f;
}

}  // namespace knotwork
