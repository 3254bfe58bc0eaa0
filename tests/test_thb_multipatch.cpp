// THB-splines on several patches (basis/thb/thb_multipatch glued by basis/core/glue_patches),
// checked by properties that do not depend on how the space was built: after local
// refinement the glued functions are a partition of unity, linearly independent, equal on both
// sides of every interface at points along it (C0), and reproduce a quadratic to rounding;
// a refinement on one side of an interface only is refused; and the adaptive loop on the
// three-patch L-shape reaches the optimal rate of the singular solution.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "basis/core/bezier_mesh_checks.hpp"
#include "basis/core/geometry_map.hpp"
#include "basis/core/glue_patches.hpp"
#include "basis/core/input_error.hpp"
#include "basis/thb/thb_multipatch.hpp"
#include "cases/case_file.hpp"
#include "cases/geometry_file.hpp"
#include "cli_sandbox.hpp"
#include "families/tensor/tensor_case.hpp"
#include "studies/adaptive.hpp"
#include "studies/pipeline.hpp"

using namespace knotwork;
using namespace cli_test;

namespace {

const std::string kLshape = std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/lshape_3patches.xml";

double bernstein(int p, int a, double t) {
  double binomial = 1;
  for (int k = 1; k <= a; ++k) binomial = binomial * (p - a + k) / k;
  return binomial * std::pow(t, a) * std::pow(1 - t, p - a);
}

// The global functions' values at reference point (s, t) of a cell, by function id.
std::map<int, double> cell_values(const BezierMesh& mesh, int c, double s, double t) {
  const BezierCell& cell = mesh.cell(c);
  Eigen::VectorXd B((cell.degree_u + 1) * (cell.degree_v + 1));
  for (int b = 0; b <= cell.degree_v; ++b)
    for (int a = 0; a <= cell.degree_u; ++a) B[a + (cell.degree_u + 1) * b] = bernstein(cell.degree_u, a, s) * bernstein(cell.degree_v, b, t);
  const Eigen::VectorXd v = mesh.extraction(c) * B;
  std::map<int, double> out;
  const auto ids = mesh.functions(c);
  for (size_t k = 0; k < ids.size(); ++k) out[ids[k]] += v[k];
  return out;
}

// The reference point at coordinate r along a side of a cell.
std::pair<double, double> on_side(CellSide side, double r) {
  switch (side) {
    case kSideBottom: return {r, 0};
    case kSideRight: return {1, r};
    case kSideTop: return {r, 1};
    default: return {0, r};
  }
}

CaseDescription lshape_case(const Sandbox& box, int degree, const std::string& exact) {
  const auto path = box.file("lshape.toml", "[geometry]\nfile = \"" + kLshape + "\"\n[space]\nfamily = \"thb\"\ndegree = " +
                                                std::to_string(degree) + "\nelements = 2\n[problem]\nexact = \"" + exact + "\"\n");
  return load_case(path.string());
}

// Marks about an eighth of the cells at random, and always the cells at the patches' common
// corner (the origin), so that the refinement reaches across both interfaces at every step.
std::vector<int> some_cells(const SplineSpace& space, std::mt19937& rng) {
  const BezierMesh& mesh = space.mesh();
  std::vector<int> marked;
  std::uniform_int_distribution<int> pick(0, 7);
  GeometryAtPoints g;
  const Eigen::VectorXd corners = (Eigen::VectorXd(4) << 0, 1, 0, 1).finished();
  for (int c = 0; c < mesh.num_cells(); ++c) {
    bool at_origin = false;
    for (int k = 0; k < 4; ++k) {
      space.geometry().evaluate(c, Eigen::VectorXd::Constant(1, corners[k % 2]), Eigen::VectorXd::Constant(1, corners[2 + k / 2]), g);
      at_origin = at_origin || g.x.row(0).norm() < 1e-12;
    }
    if (at_origin || pick(rng) == 0) marked.push_back(c);
  }
  return marked;
}

}  // namespace

TEST_CASE("THB on three patches stays a C0 partition of unity of independent functions under local refinement",
          "[thb][multipatch]") {
  Sandbox box;
  for (int p : {1, 2, 3}) {
    const CaseDescription c = lshape_case(box, p, "x");
    std::unique_ptr<SplineSpace> space = build_space(c);
    std::mt19937 rng(17 + p);
    for (int step = 0; step < 5; ++step) {
      const BezierMesh& mesh = space->mesh();
      INFO("degree " << p << ", step " << step << ": " << mesh.num_functions() << " functions on " << mesh.num_cells() << " cells");
      // Sums of at most (p + 1)^2 levels' worth of coefficients in [0, 1]: 1e-13 is far above
      // their rounding and far below any missing or doubled function.
      CHECK(partition_of_unity_error(mesh) < 1e-13);
      CHECK(bezier_rank(mesh) == mesh.num_functions());
      int across = 0;
      double worst_value = 0, worst_point = 0;
      GeometryAtPoints ga, gb;
      for (const CellInterface& ci : mesh.interfaces()) {
        if (mesh.cell(ci.cell_a).patch == mesh.cell(ci.cell_b).patch) continue;
        ++across;
        for (double r : {0.0, 0.3, 0.71, 1.0}) {
          const double ra = ci.a_from + r * (ci.a_to - ci.a_from), rb = ci.b_from + r * (ci.b_to - ci.b_from);
          const auto [sa, ta] = on_side(ci.side_a, ra);
          const auto [sb, tb] = on_side(ci.side_b, rb);
          // The same physical point from both cells ...
          space->geometry().evaluate(ci.cell_a, Eigen::VectorXd::Constant(1, sa), Eigen::VectorXd::Constant(1, ta), ga);
          space->geometry().evaluate(ci.cell_b, Eigen::VectorXd::Constant(1, sb), Eigen::VectorXd::Constant(1, tb), gb);
          worst_point = std::max(worst_point, (ga.x - gb.x).norm());
          // ... where every function has one value (a function alive on one cell only is 0 on the other side).
          std::map<int, double> va = cell_values(mesh, ci.cell_a, sa, ta), vb = cell_values(mesh, ci.cell_b, sb, tb);
          for (const auto& [f, v] : va) worst_value = std::max(worst_value, std::abs(v - (vb.count(f) ? vb[f] : 0.0)));
          for (const auto& [f, v] : vb) worst_value = std::max(worst_value, std::abs(v - (va.count(f) ? va[f] : 0.0)));
        }
      }
      CHECK(across > 0);
      // The L-shape's patches are affine maps of unit squares: both sides compute the point
      // from the same corners in a few operations, so they agree to a few ulps of |x| <= 1
      // (1e-14 is 45 ulps). Function values are sums of at most (p + 1)^2 products of
      // coefficients and Bernstein values in [0, 1]: rounding about 16 eps = 4e-15 at p = 3;
      // 1e-13 is far below any function missing or unglued on one side (values of order 0.1).
      CHECK(worst_point < 1e-14);
      CHECK(worst_value < 1e-13);
      space = std::move(*space).refine(some_cells(*space, rng), {}, nullptr, {});
    }
  }
}

TEST_CASE("THB on three patches reproduces a quadratic to rounding after local refinement", "[thb][multipatch]") {
  // The patches are affine maps of squares: x^2 - x y + 2 y^2 is a quadratic in each patch's
  // parameters, in the space for p >= 2, and the discrete solution is exact up to rounding:
  // by backward stability about kappa eps |u| (|u| <= 4 here); 1e3 leaves room for growth.
  Sandbox box;
  for (int p : {2, 3}) {
    CaseDescription c = lshape_case(box, p, "x^2 - x*y + 2*y^2");
    c.solver.estimate_condition = true;
    std::unique_ptr<SplineSpace> space = build_space(c);
    std::mt19937 rng(5 + p);
    for (int step = 0; step < 4; ++step) space = std::move(*space).refine(some_cells(*space, rng), {}, nullptr, {});
    const PoissonSolution s = solve_case(c, *space, Ordering::kAmd);
    REQUIRE(s.stiffness_spectrum.computed);
    const double tolerance = 4e3 * s.stiffness_spectrum.condition() * std::numeric_limits<double>::epsilon();
    INFO("degree " << p << ", " << s.num_functions << " functions, condition " << s.stiffness_spectrum.condition());
    CHECK(s.errors->l2 < tolerance);
    CHECK(s.errors->h1_semi < tolerance);
  }
}

TEST_CASE("Two patches refined near their interface on one side only do not glue, and the message names it",
          "[thb][multipatch]") {
  MultiPatch domain = read_geometry_file(kLshape);
  TensorSpaceOptions space;
  space.degree = {2, 2};
  space.elements_per_span = {2, 2};
  std::vector<ThbHierarchy> h;
  for (const NurbsPatch& p : domain.patches)
    h.emplace_back(patch_dyadic_knots(p, space, 0, 0), patch_dyadic_knots(p, space, 1, 0), 0);
  // Every level-0 cell of the first patch that touches its side of the first interface.
  const PatchSideRef side = domain.interfaces.front().a;
  std::vector<ThbCell> touching;
  for (int64_t i = 0; i < 2; ++i)
    for (int64_t j = 0; j < 2; ++j)
      if ((side.side == 1 && i == 0) || (side.side == 2 && i == 1) || (side.side == 3 && j == 0) || (side.side == 4 && j == 1))
        touching.push_back({0, i, j});
  REQUIRE(touching.size() == 2);
  {
    // Refined through ThbMultiPatch, the other side follows and the spaces glue.
    ThbMultiPatch both(domain, h);
    std::vector<ThbPatchCell> cells;
    for (const ThbCell& t : touching) cells.push_back({side.patch, t});
    CHECK(both.refine(cells) > 0);
    CHECK_NOTHROW(both.build());
  }
  h[side.patch].refine(touching);
  std::vector<BezierMesh> meshes;
  for (const ThbHierarchy& x : h) meshes.push_back(x.build().mesh);
  const std::vector<const BezierMesh*> pointers{&meshes[0], &meshes[1], &meshes[2]};
  CHECK_THROWS_AS(glue_patches(domain, pointers), GeometryError);
  CHECK_THROWS_WITH(glue_patches(domain, pointers),
                       Catch::Contains(domain.interfaces.front().where) && Catch::Contains("do not match"));
}

TEST_CASE("Adaptive THB on the three-patch L-shape: H1 error ~ N^(-p/2)", "[thb][multipatch][adaptive]") {
  for (int p : {2, 3}) {
    CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_lshape_adaptive_thb.toml");
    space_family(c).override_options(c, p, 0);
    c.adapt.steps = 60;
    c.adapt.max_dofs = 8000;
    const std::vector<AdaptiveStep> steps = adapt_case(c, Ordering::kAmd, {});
    INFO("degree " << p);
    REQUIRE(steps.back().dofs >= 8000);
    // Theory (Buffa, Giannelli 2016; Gantner et al. 2017): optimal rate p/2 in dofs.
    CHECK(fitted_h1_rate(steps, steps.size() / 2) >= 0.85 * p / 2);
  }
}
