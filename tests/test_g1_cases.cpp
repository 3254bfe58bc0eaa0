// Poisson and Laplace-Beltrami on G1 spaces through the case files: convergence rates
// against exact solutions (theory: O(h^(k+1)) in L2 and O(h^k) in H1 for degree k), C1
// continuity of the discrete solution across every interface, the C0 baseline's jumps,
// separability, and bad input through the real binary.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <variant>

#include "families/g1/g1_case.hpp"
#include "families/g1/g1_discretization.hpp"
#include "studies/pipeline.hpp"
#include "cases/spline_space.hpp"
#include "solver/amg_preconditioner.hpp"
#include "solver/residual_estimator.hpp"
#include "solver/poisson_solver.hpp"
#include "tests/cli_sandbox.hpp"
#include "tests/g1_test_meshes.hpp"
#include "tests/rounding_bounds.hpp"

using namespace knotwork;
using namespace cli_test;

namespace {

const std::string kSource = KNOTWORK_SOURCE_DIR;

struct Measured {
  double h, l2, h1, jump;
  int dofs;
};

// One level solved here with the library (not through the command line): h is the largest cell
// diagonal (both diagonals of every cell, as converge measures it; one diagonal alone gave
// rates that depend on which cell is largest at each level).
Measured solve(const CaseDescription& c, int level) {
  const G1Discretization d = discretize_g1(c, level);
  Measured m{0, 0, 0, 0, d.mesh.num_functions()};
  m.h = largest_cell_diagonal(d.mesh, *d.geometry);
  // Planar Poisson and Laplace-Beltrami alike: one solver.
  const PoissonSolution s = solve_poisson(d.mesh, *d.geometry, c.problem, PoissonSolveOptions{});
  m.l2 = s.errors->l2, m.h1 = s.errors->h1_semi;
  m.jump = g1_gradient_jump(d, s.coefficients);
  return m;
}

double rate(double e0, double e1, double h0, double h1) { return std::log(e0 / e1) / std::log(h0 / h1); }

}  // namespace

// Theory: C1 spaces converge optimally (h^(k+1) in L2, h^k in H1) when the gluing data are
// analysis-suitable (Collin-Sangalli-Takacs 2016); the symmetric data are not at an
// extraordinary vertex, and their locked strip along the first half of each edge is expected to
// cost half an order (the two-patch model of issue #22 gives 4.50 and 3.57 with these data):
// for k = 4 the expected rates are 4.5 (L2) and 3.5 (H1). At least those less 0.2 between the
// last two levels (one-sided: a better rate is no failure), and at least k, k - 1 over the study.
// (Observed: 4.53 and 3.57 between levels 2 and 3.)
TEST_CASE("G1 Poisson, case (a) with the earlier symmetric_c1 data: half an order lost, C1", "[g1][cases]") {
  CaseDescription c = load_case(kSource + "/cases/g1_three_quads.toml");
  g1_section(c).gluing = "symmetric_c1";
  std::vector<Measured> m;
  for (int l = 0; l <= 3; ++l) m.push_back(solve(c, l));
  for (const auto& x : m) {
    INFO("h " << x.h << " dofs " << x.dofs << " L2 " << x.l2 << " H1 " << x.h1 << " jump " << x.jump);
    REQUIRE(x.jump < 1e-9);
  }
  const double l2_rate = rate(m[2].l2, m[3].l2, m[2].h, m[3].h), h1_rate = rate(m[2].h1, m[3].h1, m[2].h, m[3].h);
  INFO("rates between levels 2 and 3: L2 " << l2_rate << ", H1 " << h1_rate);
  REQUIRE(l2_rate > 4.5 - 0.2);  // one-sided: a better rate is no failure
  REQUIRE(h1_rate > 3.5 - 0.2);
  // Over the whole study: at least h^4 in L2 and h^3 in H1 on average.
  REQUIRE(rate(m[0].l2, m[3].l2, m[0].h, m[3].h) > 4);
  REQUIRE(rate(m[0].h1, m[3].h1, m[0].h, m[3].h) > 3);
}

// The paper's symmetric data blend the vertex values with Hermite functions that are only C0
// at the edge midpoint; with a C1 split (r = 1) every G1 map with such data has a singular
// Jacobian where a has the kink (here: at the midpoints of the three interior edges). The C1
// blend has the same values at the vertices and no kink: the fitted map stays regular.
TEST_CASE("G1 geometry with the paper's C0-blended symmetric data is singular at edge midpoints", "[g1][cases]") {
  CaseDescription c = load_case(kSource + "/cases/g1_three_quads.toml");
  g1_section(c).gluing = "symmetric";
  const G1Discretization paper = discretize_g1(c, 0);
  REQUIRE(paper.min_regularity > 0);                          // positive at the Gauss points
  REQUIRE(std::abs(paper.min_regularity_nodes) < 1e-12);      // zero at a side midpoint ...
  REQUIRE(paper.singular_point.x() == Approx(0).margin(1e-12));  // ... on the edge from the vertex to (0, 1)
  REQUIRE(paper.singular_point.y() > 0.3);
  REQUIRE(paper.singular_point.y() < 0.6);
  g1_section(c).gluing = "symmetric_c1";
  const G1Discretization smooth = discretize_g1(c, 0);
  REQUIRE(smooth.min_regularity_nodes > 0.9);
}

// docs/G1_POISSON.md: the sub-optimal rates of case (a) with the earlier (not analysis-
// suitable) data come from the interfaces. The H1
// error squared per cell, split by the distance of the cell's centre to the interior edges
// of the coarse mesh: most of it lies within 1/8 of them (about a quarter of the area), and
// increasingly so (observed 82 % at level 1, 90 % at level 2).
TEST_CASE("Case (a) with the earlier symmetric_c1 data: the error concentrates along the G1 interfaces", "[g1][cases]") {
  CaseDescription c = load_case(kSource + "/cases/g1_three_quads.toml");
  g1_section(c).gluing = "symmetric_c1";
  std::vector<double> share;
  for (int level = 1; level <= 2; ++level) {
    const G1Discretization d = discretize_g1(c, level);
    const PoissonSolution s = solve_poisson(d.mesh, *d.geometry, c.problem, PoissonSolveOptions{});
    Eigen::VectorXd e;
    error_norms(d.mesh, *d.geometry, s.coefficients, *c.problem.exact, QuadratureOptions{}, &e);
    REQUIRE(e.size() == d.mesh.num_cells());
    REQUIRE(std::sqrt(e.sum()) == Approx(s.errors->h1_semi).epsilon(1e-12));  // the split adds up
    double near = 0;
    Eigen::VectorXd u(1), v(1);
    u << 0.5;
    v << 0.5;
    for (int cell = 0; cell < d.mesh.num_cells(); ++cell) {
      GeometryAtPoints g;
      d.geometry->evaluate(cell, u, v, g);
      const Eigen::Vector2d p = g.x.row(0).transpose();
      double distance = INFINITY;
      for (int edge = 0; edge < d.coarse.num_edges(); ++edge) {
        const auto& E = d.coarse.edge(edge);
        if (E.boundary()) continue;
        const Eigen::Vector2d a = d.coarse.vertex(E.v[0]).head<2>(), b = d.coarse.vertex(E.v[1]).head<2>();
        const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
        distance = std::min(distance, (p - a - t * (b - a)).norm());
      }
      if (distance < 0.125) near += e(cell);
    }
    share.push_back(near / e.sum());
  }
  INFO("share of the H1 error squared within 1/8 of the interior edges: " << share[0] << ", " << share[1]);
  REQUIRE(share[1] > 0.8);
  REQUIRE(share[1] > share[0]);
}

TEST_CASE("G1 cell interfaces: every shared side matched point for point, and the estimator sees a C1 solution", "[g1][cases][adaptive]") {
  const CaseDescription c = load_case(kSource + "/cases/g1_three_quads.toml");
  for (int level = 0; level <= 1; ++level) {
    const G1Discretization d = discretize_g1(c, level);
    const QuadMesh& m = d.level.mesh;
    int interior_edges = 0;
    for (int e = 0; e < m.num_edges(); ++e) interior_edges += !m.edge(e).boundary();
    // 4 inside each face (the 4-split) and 2 along each interior edge (its two halves).
    REQUIRE(d.mesh.has_interfaces());
    REQUIRE(static_cast<int>(d.mesh.interfaces().size()) == 4 * m.num_faces() + 2 * interior_edges);
    // Both sides of every interface are the same curve, point for point, through the geometry.
    double worst = 0;
    for (const CellInterface& f : d.mesh.interfaces()) {
      Eigen::VectorXd ua(3), va(3), ub(3), vb(3);
      for (int k = 0; k < 3; ++k) {
        const double w = 0.1 + 0.4 * k;
        auto put = [](CellSide side, double t, double& u, double& v) {
          u = side == kSideBottom || side == kSideTop ? t : side == kSideRight ? 1 : 0;
          v = side == kSideLeft || side == kSideRight ? t : side == kSideTop ? 1 : 0;
        };
        put(f.side_a, f.a_from + w * (f.a_to - f.a_from), ua[k], va[k]);
        put(f.side_b, f.b_from + w * (f.b_to - f.b_from), ub[k], vb[k]);
      }
      GeometryAtPoints ga, gb;
      d.geometry->evaluate(f.cell_a, ua, va, ga);
      d.geometry->evaluate(f.cell_b, ub, vb, gb);
      worst = std::max(worst, (ga.x - gb.x).cwiseAbs().maxCoeff());
    }
    REQUIRE(worst < 1e-12);
    // The residual estimator on the multi-patch mesh: the discrete solution is C1, so the
    // gradient jumps across all interfaces are rounding, and the residual part carries eta.
    const PoissonSolution s = solve_poisson(d.mesh, *d.geometry, c.problem, PoissonSolveOptions{});
    const ErrorIndicators ind = residual_indicators(d.mesh, *d.geometry, s.coefficients, c.problem);
    INFO("level " << level << ": largest gradient jump " << ind.max_gradient_jump << ", eta " << std::sqrt(ind.total()));
    REQUIRE(ind.max_gradient_jump < 1e-9);
    REQUIRE(ind.residual_part > 0);
  }
}

TEST_CASE("The C0 multipatch baseline on the same mesh is not C1 (the jump check sees it)", "[g1][cases]") {
  CaseDescription c = load_case(kSource + "/cases/g1_three_quads.toml");
  g1_section(c).c0 = true;
  const Measured m = solve(c, 1);
  INFO("C0 gradient jump " << m.jump);
  REQUIRE(m.jump > 1e-4);  // the G1 spaces stay below 1e-9 (test above); this is O(h^k), not rounding
  REQUIRE(m.l2 < 1e-3);  // and it converges: a fair baseline
}

// The target: at equal dofs the G1 space is at least as accurate in H1 as the C0
// multipatch space of the same degree on the same mesh, the errors interpolated log-log in the
// dofs. Checked on the two meshes where G1 was behind on the coarse levels with the L2-projected
// Dirichlet data: at each finer G1 level (C0 interpolated) and at the C0 space's coarsest level
// (G1 interpolated: the G1 level 0 lies below every C0 point). Both use the planar default,
// Nitsche's method; with the projection G1's coarsest error is larger by a factor the C1 space's
// boundary vertices explain (docs/G1_POISSON.md), and that is asserted too.
TEST_CASE("G1 at least as accurate as C0 at equal dofs on the pentagon and the valence-8/6 mesh", "[g1][cases][c0]") {
  const auto at_dofs = [](const std::vector<Measured>& m, double n) {  // log-log, between two levels
    size_t i = 0;
    while (i + 2 < m.size() && m[i + 1].dofs < n) ++i;
    REQUIRE(m[i].dofs <= n);
    REQUIRE(n <= m[i + 1].dofs);
    const double t = std::log(n / m[i].dofs) / std::log(double(m[i + 1].dofs) / m[i].dofs);
    return std::exp((1 - t) * std::log(m[i].h1) + t * std::log(m[i + 1].h1));
  };
  for (const char* name : {"/cases/g1_pentagon.toml", "/cases/g1_valences_6_8.toml"}) {
    CaseDescription c = load_case(kSource + name);
    REQUIRE(c.problem.dirichlet_method == DirichletMethod::kNitsche);  // the planar default
    std::vector<Measured> g1, c0;
    for (int l = 0; l <= 2; ++l) g1.push_back(solve(c, l));
    g1_section(c).c0 = true;
    for (int l = 0; l <= 2; ++l) c0.push_back(solve(c, l));
    INFO(name);
    for (int l = 1; l <= 2; ++l) {
      INFO("G1 level " << l << ": " << g1[l].dofs << " dofs, H1 " << g1[l].h1 << "; C0 there " << at_dofs(c0, g1[l].dofs));
      REQUIRE(at_dofs(c0, g1[l].dofs) >= g1[l].h1);
    }
    INFO("C0 level 0: " << c0[0].dofs << " dofs, H1 " << c0[0].h1 << "; G1 there " << at_dofs(g1, c0[0].dofs));
    REQUIRE(at_dofs(g1, c0[0].dofs) <= c0[0].h1);
    g1_section(c).c0 = false;
    c.problem.dirichlet_method = DirichletMethod::kProjection;
    const Measured projected = solve(c, 0);
    INFO("G1 level 0 with the projection: H1 " << projected.h1 << ", with Nitsche's method " << g1[0].h1);
    REQUIRE(projected.h1 > 1.3 * g1[0].h1);
  }
}

TEST_CASE("Laplace-Beltrami on the G1 sphere with the earlier symmetric data: rates with the zero-mean constraint", "[g1][cases][surface]") {
  CaseDescription c = load_case(kSource + "/cases/g1_sphere_xy.toml");
  g1_section(c).gluing = "symmetric";
  std::vector<Measured> m;
  for (int l = 0; l <= 2; ++l) m.push_back(solve(c, l));
  for (const auto& x : m) {
    INFO("h " << x.h << " dofs " << x.dofs << " L2 " << x.l2 << " H1 " << x.h1 << " jump " << x.jump);
    REQUIRE(x.jump < 1e-9);
  }
  // Theory for k = 4: between the locked rates of the symmetric data at the valence-3
  // vertices (4.5 in L2, 3.5 in H1) and the optimal ones (5, 4), up to 0.2 either way while
  // the study is pre-asymptotic. (Observed 4.83 and 3.83 between levels 1 and 2.)
  const double l2_rate = rate(m[1].l2, m[2].l2, m[1].h, m[2].h), h1_rate = rate(m[1].h1, m[2].h1, m[1].h, m[2].h);
  INFO("rates between levels 1 and 2: L2 " << l2_rate << ", H1 " << h1_rate);
  REQUIRE(l2_rate > 4.5 - 0.2);
  REQUIRE(h1_rate > 3.5 - 0.2);
}

// Theory (Collin-Sangalli-Takacs 2016; Kapl-Sangalli-Takacs 2017, 2019): with analysis-
// suitable gluing data and a regular map, the C1 space approximates optimally: h^(k+1) in
// L2 and h^k in H1. The default data of every planar case are analysis-suitable (from the
// bilinear faces, which are then the geometry itself), and the linear symmetric data of the
// sphere are. Windows from the theory, between the last two of four levels: H1 >= k - 0.15,
// L2 >= k + 1 - 0.2; the solution C1 to 1e-9; the geometry the faces (fit deviation at
// rounding level).
void check_optimal(const char* name, bool planar) {
  const CaseDescription c = load_case(kSource + name);
  REQUIRE(g1_section(c).gluing == "analysis_suitable");
  const int k = g1_section(c).degree;
  std::vector<Measured> m;
  for (int l = 0; l <= 3; ++l) m.push_back(solve(c, l));
  for (const auto& x : m) {
    INFO(name << ": h " << x.h << " dofs " << x.dofs << " L2 " << x.l2 << " H1 " << x.h1 << " jump " << x.jump);
    REQUIRE(x.jump < 1e-9);
  }
  const double l2_rate = rate(m[2].l2, m[3].l2, m[2].h, m[3].h), h1_rate = rate(m[2].h1, m[3].h1, m[2].h, m[3].h);
  INFO(name << ": rates between levels 2 and 3: L2 " << l2_rate << ", H1 " << h1_rate);
  REQUIRE(l2_rate >= k + 1 - 0.2);
  REQUIRE(h1_rate >= k - 0.15);
  if (planar) {
    const G1Discretization d = discretize_g1(c, 0);
    REQUIRE(d.fit_deviation < 1e-10);
    REQUIRE(d.boundary_deviation < 1e-12);
    REQUIRE(d.min_regularity_nodes > 0);
  }
}

TEST_CASE("Analysis-suitable data, three quads (valence 3): optimal rates", "[g1][cases][optimal]") {
  check_optimal("/cases/g1_three_quads.toml", true);
}
TEST_CASE("Analysis-suitable data, pentagon (valence 5): optimal rates", "[g1][cases][optimal]") {
  check_optimal("/cases/g1_pentagon.toml", true);
}
TEST_CASE("Analysis-suitable data, unit square with valences 3, 4, 5, 6: optimal rates", "[g1][cases][optimal]") {
  check_optimal("/cases/g1_mixed_valences.toml", true);
}
TEST_CASE("Analysis-suitable data, valences 8 and 6: optimal rates", "[g1][cases][optimal]") {
  check_optimal("/cases/g1_valences_6_8.toml", true);
}
TEST_CASE("Analysis-suitable data, L-shape with extraordinary vertices: optimal rates", "[g1][cases][optimal]") {
  check_optimal("/cases/g1_lshape.toml", true);
}
TEST_CASE("Analysis-suitable data, sphere from a cube (valence 3): optimal rates", "[g1][cases][optimal]") {
  check_optimal("/cases/g1_sphere_xy.toml", false);
}
// Valence 5 on a closed surface: the linear symmetric data are irrational there (sums of
// cosines), the dimension a rank modulo primes with a 10th root of unity, the local functions
// floating point.
TEST_CASE("Analysis-suitable data, sphere from a dodecahedron (valences 3, 4, 5): optimal rates", "[g1][cases][optimal]") {
  const CaseDescription c = load_case(kSource + "/cases/g1_sphere_dodecahedron.toml");
  const G1Discretization d = discretize_g1(c, 0);
  REQUIRE(!d.basis.exact);
  REQUIRE(d.basis.space.cyclotomic == 10);
  REQUIRE(static_cast<long>(d.basis.functions.size()) == d.basis.space.dimension);
  check_optimal("/cases/g1_sphere_dodecahedron.toml", false);
}

// A closed mesh where the linear symmetric data fail Condition 3.2: the split pentagonal
// prism, whose pentagon-edge midpoints (valence 4) have a pentagon centre (5) across from a
// rectangle centre (4). Which crossings fail is counted from the valences alone
// (test::crossings_with_unequal_neighbours);
// the symmetric data are refused at exactly those, the default skews exactly those, and the
// rates are optimal.
TEST_CASE("Analysis-suitable data, sphere from a split pentagonal prism (skewed crossings): optimal rates",
          "[g1][cases][optimal]") {
  const CaseDescription c = load_case(kSource + "/cases/g1_sphere_prism.toml");
  const G1Discretization d = discretize_g1(c, 0);
  const QuadMesh& mesh = d.coarse;
  const std::vector<int> expected = test::crossings_with_unequal_neighbours(mesh);
  REQUIRE(expected.size() == 10);
  REQUIRE(d.coarse_gluing.skewed_fans == expected);
  const auto refused = gluing_violations(mesh, symmetric_gluing(mesh, SymmetricBlend::kLinear));
  REQUIRE(refused.size() == expected.size());
  for (size_t i = 0; i < refused.size(); ++i)
    REQUIRE(refused[i].find("vertex " + std::to_string(expected[i] + 1) + " (crossing, valence 4): Condition 3.2") == 0);
  REQUIRE(gluing_violations(mesh, d.coarse_gluing).empty());
  for (const auto& e : d.coarse_gluing.edges) {  // analysis-suitable by degree
    REQUIRE(e);
    REQUIRE(e->a.degree() <= 1);
    REQUIRE(e->b.degree() <= 1);
    REQUIRE(e->c.degree() == 0);
  }
  check_optimal("/cases/g1_sphere_prism.toml", false);
}

// The split pentagonal antiprism: its first failing crossings (the midpoints of the edges
// between a triangle and a pentagon: a valence-3 centre across from a valence-5 one) are skewed,
// which makes the antiprism's corners (valence-4 crossings next to them) fail in turn: the
// construction's second round skews those too. Everything passes afterwards and the rates are
// optimal.
TEST_CASE("Analysis-suitable data, sphere from a split pentagonal antiprism (skewed in two rounds): optimal rates",
          "[g1][cases][optimal]") {
  const CaseDescription c = load_case(kSource + "/cases/g1_sphere_antiprism.toml");
  const G1Discretization d = discretize_g1(c, 0);
  const QuadMesh& mesh = d.coarse;
  const std::vector<int> first_round = test::crossings_with_unequal_neighbours(mesh);
  REQUIRE(first_round.size() == 10);
  const auto& skewed = d.coarse_gluing.skewed_fans;
  REQUIRE(skewed.size() == 20);
  REQUIRE(std::includes(skewed.begin(), skewed.end(), first_round.begin(), first_round.end()));
  for (int v : skewed)  // the second round: the antiprism's corners, the first 10 vertices of the file
    if (!std::binary_search(first_round.begin(), first_round.end(), v)) REQUIRE(v < 10);
  REQUIRE(gluing_violations(mesh, d.coarse_gluing).empty());
  check_optimal("/cases/g1_sphere_antiprism.toml", false);
}

// The one case seen where the floating-point local functions go wrong: the earlier
// symmetric_c1 data on that prism (valence 5 irrational), 3 subdivisions. One vertex function
// at each of 85 vertices lies within 3e-10 of its edges' functions; tidying it left rounding
// noise (residual 3.6e-6) and the solve gave errors of order 1. The build refuses it, naming
// a vertex; the default data on the same mesh stay far from that (distance 1 at every level).
// The earlier symmetric_c1 data (sums of cosines: floating-point local functions) on the prism
// sphere at 3 subdivisions. With null vectors accurate only to eps over the smallest singular
// value kept, one vertex function came within 3e-10 of its edges' functions there: before
// 2026-12-02 the solution was wrong without a word (L2 0.36, C1 jump 1.9e-4), then refused as
// numerically dependent. With the refined null vectors the level is C1 and converges; the
// window is the one for data that are not analysis-suitable (at least k + 1 - 1 in L2 and
// k - 1 in H1; observed 5.10 and 3.97).
TEST_CASE("Earlier symmetric_c1 data on the prism sphere: the third subdivision is C1 and converges", "[g1][cases][floating]") {
  CaseDescription c = load_case(kSource + "/cases/g1_sphere_prism.toml");
  g1_section(c).gluing = "symmetric_c1";
  const int k = g1_section(c).degree;
  const Measured m2 = solve(c, 2), m3 = solve(c, 3);
  INFO("L2 " << m2.l2 << " -> " << m3.l2 << ", H1 " << m2.h1 << " -> " << m3.h1 << ", jump " << m3.jump);
  REQUIRE(m3.jump < 1e-9);
  REQUIRE(rate(m2.l2, m3.l2, m2.h, m3.h) >= k);
  REQUIRE(rate(m2.h1, m3.h1, m2.h, m3.h) >= k - 1);
}

// Floating-point data (geometric data of the pentagon with decimal coordinates, k = 5) beyond the
// 10 000 unknowns the dense SVD allowed: the dimension from local SVDs, and convergence that goes
// on at 3 and 4 subdivisions (32 000 and 128 000 unknowns). Without the long-double refinement
// of the local null vectors the errors grew there (H1 1.4e-7, then 6.4e-7): the null vectors were
// accurate only to eps over the smallest singular value kept, which falls with each subdivision.
// These data are not analysis-suitable; the window is the one for such data above: at least
// k + 1 - 1 in L2 and k - 1 in H1. (Observed 5.43 and 4.41.)
TEST_CASE("Floating-point gluing data: local SVDs beyond the dense limit, and convergence that goes on", "[g1][cases][floating]") {
  CaseDescription c = load_case(kSource + "/cases/g1_pentagon.toml");
  g1_section(c).mesh_file = kSource + "/tests/bad_inputs/uses_pentagon_decimals.obj";
  g1_section(c).gluing = "geometric";
  g1_section(c).degree = 5;
  const int k = 5;
  {
    const G1Discretization d = discretize_g1(c, 3);
    REQUIRE(!d.coarse_gluing.algebraic());
    REQUIRE(d.basis.space.local);
    REQUIRE(d.basis.space.unknowns > 10000);
    REQUIRE(d.basis.space.smallest_kept > 10 * d.basis.space.largest_dropped);
  }
  const Measured m3 = solve(c, 3), m4 = solve(c, 4);
  INFO("L2 " << m3.l2 << " -> " << m4.l2 << ", H1 " << m3.h1 << " -> " << m4.h1);
  REQUIRE(m4.jump < 1e-9);
  REQUIRE(rate(m3.l2, m4.l2, m3.h, m4.h) >= k);
  REQUIRE(rate(m3.h1, m4.h1, m3.h, m4.h) >= k - 1);
}

// The torus (all valence 4: a = 0, b = -1, c = 1) from the first refinement: at least the
// optimal 5 and 4 less 0.3 (pre-asymptotic). (Observed 5.07/4.07.)
TEST_CASE("Torus: optimal rates from the first refinement", "[g1][cases]") {
  const CaseDescription c = load_case(kSource + "/cases/g1_torus.toml");
  const Measured m0 = solve(c, 0), m1 = solve(c, 1);
  INFO("L2 " << m0.l2 << " -> " << m1.l2 << ", H1 " << m0.h1 << " -> " << m1.h1);
  REQUIRE(rate(m0.l2, m1.l2, m0.h, m1.h) > 5 - 0.3);
  REQUIRE(rate(m0.h1, m1.h1, m0.h, m1.h) > 4 - 0.3);
  REQUIRE(m1.jump < 1e-9);
}

// The fit weighs the boundary rows heavily and regular_fans keeps the mesh's directions at
// boundary vertices: the unit square of case (c) stays the unit square. Checked on the
// boundary control points of the fitted cells (each must lie on a side of [0, 1]^2).
TEST_CASE("The fitted G1 geometry keeps straight sides straight and corners", "[g1][cases]") {
  const CaseDescription c = load_case(kSource + "/cases/g1_mixed_valences.toml");
  const G1Discretization d = discretize_g1(c, 0);
  const int k = d.basis.k;
  double worst = 0;
  int sides = 0;
  for (int cell = 0; cell < d.mesh.num_cells(); ++cell)
    for (int side = 0; side < 4; ++side) {
      if (d.mesh.cell(cell).boundary[side] < 0) continue;
      ++sides;
      for (int i = 0; i <= k; ++i) {
        const int a = side == kSideBottom ? i : side == kSideRight ? k : side == kSideTop ? k - i : 0;
        const int b = side == kSideBottom ? 0 : side == kSideRight ? i : side == kSideTop ? k : k - i;
        const Eigen::RowVector2d p = d.geometry->bezier_cell(cell).points.row(a + (k + 1) * b);
        worst = std::max(worst, std::min({std::abs(p.x()), std::abs(p.x() - 1), std::abs(p.y()), std::abs(p.y() - 1)}));
      }
    }
  int boundary_edges = 0;
  for (int e = 0; e < d.coarse.num_edges(); ++e) boundary_edges += d.coarse.edge(e).boundary();
  REQUIRE(sides == 2 * boundary_edges);  // two cells along each boundary edge
  INFO("largest distance of a boundary control point from the square's sides " << worst);
  REQUIRE(worst < 1e-5);
  REQUIRE(d.min_regularity > 0.05);
}

TEST_CASE("Separability of edges (Definition 4.11) computed on the edge's two faces", "[g1][separability]") {
  const QuadMesh cube = knotwork::test::cube(), three = knotwork::test::three_quads();
  // The cube with symmetric data needs k >= 4 at r = 1 (at k = 3 its basis has no vertex
  // functions at all: knotwork basis reports vertex-pair and coupled ones).
  REQUIRE(g1_inseparable_edges(cube, symmetric_gluing(cube), 3, 1).size() == 12);
  REQUIRE(g1_inseparable_edges(cube, symmetric_gluing(cube), 4, 1).empty());
  for (int k = 3; k <= 5; ++k) REQUIRE(g1_inseparable_edges(three, symmetric_gluing(three), k, 1).empty());
}

TEST_CASE("G1 cases through the binary: run, converge with a .pvd over levels, and bad input", "[g1][cases][cli]") {
  Sandbox box;
  const std::string meshes = kSource + "/cases/meshes/";
  const Result run = box.run("converge " + kSource + "/cases/g1_sphere_xy.toml --levels 2 --quiet --out conv");
  INFO(run.err);
  REQUIRE(run.code == 0);
  REQUIRE(fs::exists(box.dir() / "conv" / "level_1.vtu"));
  REQUIRE(slurp(box.dir() / "conv" / "convergence.pvd").find("level_1.vtu") != std::string::npos);
  // Which data a surface gets is said: the prism sphere's skewed crossings in the notes and JSON.
  const Result prism = box.run("run " + kSource + "/cases/g1_sphere_prism.toml --quiet --no-output");
  INFO(prism.err);
  REQUIRE(prism.code == 0);
  REQUIRE(prism.out.find("note     10 crossing vertices (12, 13, 14, 15, 16, 18, 19, 20, 21, 22)") != std::string::npos);
  REQUIRE(box.run("run " + kSource + "/cases/g1_sphere_prism.toml --quiet --no-output --json").out.find(
              "\"skewed_fans\": 10") != std::string::npos);

  auto rejected = [&](const std::string& name, const std::string& text, const std::vector<std::string>& mentions) {
    box.file(name, text);
    INFO(text);
    expect_one_line_error(box.run("run " + name + " --quiet --out never"), mentions);
    REQUIRE(!fs::exists(box.dir() / "never" / "solution.vtu"));
  };
  const std::string space = "[space]\nfamily = \"g1\"\n";
  // A surface case with Dirichlet data but no boundary.
  rejected("closed.toml",
           space + "mesh = \"" + meshes + "cube_centered.obj\"\n[geometry]\nshape = \"sphere\"\n[problem]\n"
                   "operator = \"laplace_beltrami\"\nexact = \"x*y\"\ndirichlet = \"exact\"\n",
           {"closed.toml", "[problem] dirichlet", "closed", "no boundary"});
  // A planar case with z != 0.
  rejected("planar.toml", space + "mesh = \"" + meshes + "cube_centered.obj\"\n[problem]\nexact = \"x\"\n",
           {"planar.toml", "[space] mesh", "vertex 1 has z = -1", "laplace_beltrami"});
  // A convergence study whose finest level cannot fit in memory: refused before any level is
  // solved, with the estimate (the torus, 32 faces, refine 6 and 7 levels: 32 * 4^12 faces).
  {
    std::string text = slurp(fs::path(kSource) / "cases/g1_torus.toml");
    const size_t at = text.find("[space]");
    REQUIRE(at != std::string::npos);
    text.insert(at + 8, "refine = 6\n");
    text = std::regex_replace(text, std::regex("mesh = \"meshes/"), "mesh = \"" + meshes);
    box.file("huge.toml", text);
    const Result huge = box.run("converge huge.toml --levels 7 --quiet --out never");
    expect_one_line_error(huge, {"huge.toml", "[space] refine", "GB needed", "more than this machine's"});
    REQUIRE(!fs::exists(box.dir() / "never"));  // refused before the output folder, so before any level
  }
  // The degree below the separability of the gluing data: the edge is named.
  rejected("low.toml", space + "mesh = \"" + meshes + "pentagon.obj\"\ngluing = \"geometric\"\ndegree = 4\n[problem]\nexact = \"x\"\n",
           {"low.toml", "[space] degree", "separability of edge 1-2"});
  // Analysis-suitable data (the default) below their degree: the edge and the range are named.
  rejected("low_as.toml", space + "mesh = \"" + meshes + "pentagon.obj\"\ndegree = 3\n[problem]\nexact = \"x\"\n",
           {"low_as.toml", "[space] degree", "separability of edge", "analysis_suitable data need k >= 4"});
  // A quad that is not convex (a dart, reflex corner at vertex 5): analysis-suitable data
  // refuse it by name before anything is built; with other data the fitted geometry is not
  // regular there, and the face is named.
  box.file("dart.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1.75 1.75 0\nv 2 1 0\nv 0 2 0\nv 1 2 0\nv 2 2 0\n"
                       "f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\nf 5 6 9 8\n");
  rejected("dart_as.toml", space + "mesh = \"dart.obj\"\n[problem]\nexact = \"x\"\n",
           {"dart_as.toml", "[space] gluing", "face 4 is not a convex quad", "vertex 5"});
  rejected("dart.toml", space + "mesh = \"dart.obj\"\ngluing = \"geometric\"\n[problem]\nexact = \"x\"\n",
           {"dart.toml", "[geometry]", "not regular at face 4"});
  // Keys of other families, and surfaces that need an exact solution or a source.
  rejected("keys.toml", space + "mesh = \"" + meshes + "three_quads.obj\"\nelements = 4\n[problem]\nexact = \"x\"\n",
           {"keys.toml", "[space] elements", "unknown key"});
  rejected("nosource.toml",
           space + "mesh = \"" + meshes + "cube_centered.obj\"\n[geometry]\nshape = \"sphere\"\n[problem]\n"
                   "operator = \"laplace_beltrami\"\n",
           {"nosource.toml", "[problem] source", "missing"});
}

TEST_CASE("Nothing typed into a G1 case file crashes knotwork", "[g1][cases][fuzz]") {
  // Random edits of small planar and surface G1 cases: every run ends with exit 0 or one
  // error line, never a signal.
  Sandbox box;
  std::mt19937 rng(1122);
  const std::string alphabet = "[]{}=\"',.-+0123456789eEnaxyzpi*/^() \n#_";
  // The meshes are copied next to the case so that the fuzzed text, and hence the edits,
  // do not depend on where the source tree lives.
  for (const std::string mesh : {"three_quads.obj", "cube_centered.obj"})
    box.file(mesh, slurp(kSource + "/cases/meshes/" + mesh));
  const std::vector<std::string> good = {
      "[space]\nfamily = \"g1\"\nmesh = \"three_quads.obj\"\ndegree = 4\nsplit_smoothness = 1\n"
      "gluing = \"symmetric_c1\"\n[problem]\nexact = \"x*y + 1\"\n",
      "[space]\nfamily = \"g1\"\nmesh = \"cube_centered.obj\"\ndegree = 4\n[geometry]\nshape = \"sphere\"\n"
      "radius = 1\n[problem]\noperator = \"laplace_beltrami\"\nreaction = 1\nexact = \"x*z\"\n"};
  fuzz(box, 80, [&](int trial) {
    std::string text = good[trial % 2];
    if (trial % 4 < 2) {
      const int edits = 1 + static_cast<int>(rng() % 2);
      for (int e = 0; e < edits; ++e) random_edit(text, rng, alphabet);
    } else {
      // Half the trials edit one value only (after an '='), which mostly still parses and
      // so reaches the geometry, the space and the solver with odd numbers and formulas.
      std::vector<size_t> values;
      for (size_t at = text.find(" = "); at != std::string::npos; at = text.find(" = ", at + 1)) values.push_back(at + 3);
      const size_t begin = values[rng() % values.size()], end = text.find('\n', begin);
      std::string value = text.substr(begin, end - begin);
      random_edit(value, rng, alphabet);
      text.replace(begin, end - begin, value);
    }
    box.file("fuzz.toml", text);
    return std::pair{std::string("run -q --no-output fuzz.toml"), text};
  });
}

// Robustness of the defaults: planar meshes of convex quads a user might bring, with interior
// vertices of valence 3 to 8 (jittered grids cut into triangles along random diagonals, each
// triangle split into three quads), run with nothing but the mesh, k = 4 and r = 1: no
// refusal, no fold-over (the geometry is the faces), C1, and a linear u reproduced (it is in
// the space when the map is bilinear).
TEST_CASE("Defaults on random meshes of convex quads with valences 3 to 8: no refusal, exact for linear u",
          "[g1][cases][robust]") {
  std::mt19937 rng(2212);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("knotwork_g1_random_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  int highest_valence = 0;
  for (int trial = 0; trial < 4; ++trial) {
    const int n = 3;
    // Integer arithmetic on mt19937's output (which the standard fixes bit for bit): every
    // standard library draws the same meshes (uniform_real_distribution's output is not fixed).
    const unsigned steps = static_cast<unsigned>(0.3 / n * 1024);  // jitter in [-0.3/n, 0.3/n]
    const auto jitter = [&](std::mt19937& g) { return (static_cast<double>(g() % (2 * steps + 1)) - steps) / 1024; };
    std::vector<Eigen::Vector3d> grid;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const bool inside = i > 0 && i < n && j > 0 && j < n;
        // Multiples of 1/1024, so that edge midpoints are exact and exactly collinear.
        const auto snap = [](double x) { return std::round(x * 1024) / 1024; };
        // y's jitter drawn first, in its own statement (gcc's order of the former argument list;
        // argument order is unspecified, and every compiler must see the same mesh).
        const double dy = inside ? jitter(rng) : 0, dx = inside ? jitter(rng) : 0;
        grid.emplace_back(snap(double(i) / n + dx), snap(double(j) / n + dy), 0);
      }
    std::vector<std::array<int, 3>> triangles;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = i + (n + 1) * j, b = a + 1, c = a + n + 2, d = a + n + 1;
        if (rng() % 2) triangles.push_back({a, b, c}), triangles.push_back({a, c, d});
        else triangles.push_back({a, b, d}), triangles.push_back({b, c, d});
      }
    std::vector<Eigen::Vector3d> v = grid;
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int x, int y) {
      const auto key = std::minmax(x, y);
      if (auto it = midpoint.find(key); it != midpoint.end()) return it->second;
      v.push_back(0.5 * (grid[x] + grid[y]));
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::string obj;
    std::vector<std::array<int, 4>> faces;
    for (const auto& t : triangles) {
      v.push_back((grid[t[0]] + grid[t[1]] + grid[t[2]]) / 3);
      const int g = static_cast<int>(v.size()) - 1;
      for (int i = 0; i < 3; ++i) faces.push_back({t[i], mid(t[i], t[(i + 1) % 3]), g, mid(t[(i + 2) % 3], t[i])});
    }
    char line[96];
    for (const auto& p : v) {
      std::snprintf(line, sizeof line, "v %.17g %.17g 0\n", p.x(), p.y());
      obj += line;
    }
    for (const auto& f : faces)
      obj += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " + std::to_string(f[2] + 1) + " " +
             std::to_string(f[3] + 1) + "\n";
    const std::string mesh = (dir / ("random_" + std::to_string(trial) + ".obj")).string();
    std::ofstream(mesh) << obj;
    const QuadMesh q = QuadMesh::read_obj(mesh);
    for (int x = 0; x < q.num_vertices(); ++x)
      if (!q.boundary_vertex(x)) highest_valence = std::max(highest_valence, q.valence(x));
    const std::string case_file = (dir / ("random_" + std::to_string(trial) + ".toml")).string();
    std::ofstream(case_file) << "[space]\nfamily = \"g1\"\nmesh = \"" << mesh << "\"\n[problem]\nexact = \"x + 2*y\"\n";
    const CaseDescription c = load_case(case_file);
    INFO("trial " << trial << ": " << mesh);
    const G1Discretization d = discretize_g1(c, 0);
    REQUIRE(d.min_regularity > 0);
    REQUIRE(d.min_regularity_nodes > 0);
    // u is in the space: what is left is rounding, bounded from the solve's condition estimates.
    const rounding_test::Reproduction r = rounding_test::solve_reproducing(d.mesh, *d.geometry, c.problem);
    REQUIRE_REPRODUCED(r);
    REQUIRE(g1_gradient_jump(d, r.coefficients) < 1e-9);
  }
  // Written with 6 decimals, the last mesh's edge midpoints leave their lines by rounding:
  // refused, naming a vertex (exactly collinear edges make a crossing vertex; nearly collinear
  // ones bring functions that are dependent to rounding).
  {
    std::ifstream in(dir / "random_3.obj");
    std::string rounded, text;
    while (std::getline(in, text)) {
      if (text.rfind("v ", 0) == 0) {
        double x, y;
        std::sscanf(text.c_str(), "v %lf %lf", &x, &y);
        rounded += "v " + std::to_string(x) + " " + std::to_string(y) + " 0\n";
      } else {
        rounded += text + "\n";
      }
    }
    const std::string mesh = (dir / "rounded.obj").string(), case_file = (dir / "rounded.toml").string();
    std::ofstream(mesh) << rounded;
    std::ofstream(case_file) << "[space]\nfamily = \"g1\"\nmesh = \"" << mesh << "\"\n[problem]\nexact = \"x\"\n";
    REQUIRE_THROWS_WITH(discretize_g1(load_case(case_file), 0),
                        Catch::Contains("rounded.obj") && Catch::Contains("collinear only up to rounding") &&
                            Catch::Contains("vertex"));
  }
  std::filesystem::remove_all(dir);
  INFO("highest interior valence " << highest_valence);
  REQUIRE(highest_valence >= 7);
}

// BoomerAMG (classical AMG) assumes the all-ones vector is near the matrix's kernel. The G1
// basis is built so that the constant function's coefficients are 1 on its interior functions
// (g1_basis.cpp, constant_carrying_functions); with orthonormal edge functions instead, the
// counts on g1_mixed_valences were 35, 41, 48 and 70 over four levels while the C0 space on the
// same faces stayed at 47-50 (docs/SOLVERS.md); the growth shows at level 3 only. The issue's
// requirement: within 2x of the C0 space's count at every level, and bounded in h; checked as
// at most 2x the C0 count at each level and at most 1.2x the G1 count of the level before
// (measured now: 33, 38, 41, 41; the former basis fails the second at level 3, 70 after 48).
TEST_CASE("BoomerAMG-CG on G1 spaces: iterations within 2x of the C0 space's and not growing with h", "[g1][cases][amg]") {
  CaseDescription c = load_case(kSource + "/cases/g1_mixed_valences.toml");
  PoissonSolveOptions options;
  options.iterative = true;
  options.compute_errors = false;
  options.preconditioner = [](const DofLayout&, const Eigen::SparseMatrix<double>& lower) {
    return boomeramg_preconditioner(lower, "");
  };
  auto iterations = [&](int level) {
    const G1Discretization d = discretize_g1(c, level);
    const PoissonSolution s = solve_poisson(d.mesh, *d.geometry, c.problem, options);
    REQUIRE(s.iterative.stop == IterativeStats::Stop::kConverged);
    return s.iterative.iterations;
  };
  std::vector<double> g1, c0;
  for (int l = 0; l <= 3; ++l) g1.push_back(iterations(l));
  g1_section(c).c0 = true;
  for (int l = 0; l <= 3; ++l) c0.push_back(iterations(l));
  for (int l = 0; l <= 3; ++l) {
    INFO("level " << l << ": G1 " << g1[l] << " iterations, C0 " << c0[l]);
    CHECK(g1[l] <= 2 * c0[l]);
    if (l > 0) CHECK(g1[l] <= 1.2 * g1[l - 1]);
  }
}

// The defaults of a G1 case (g1_case.hpp, measured in docs/G1_POISSON.md): k = 5 and r = k - 2,
// which has the same unknowns per face as the paper's k = 4, r = 1. An r the case leaves out
// follows --degree; one it gives stays.
TEST_CASE("G1 case defaults: degree 5, split smoothness k - 2, following --degree unless given", "[g1][cases]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("knotwork_g1_defaults_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string mesh = kSource + "/cases/meshes/three_quads.obj";
  auto load = [&](const std::string& space_lines) {
    const std::string file = (dir / "case.toml").string();
    std::ofstream(file) << "[space]\nfamily = \"g1\"\nmesh = \"" << mesh << "\"\n" << space_lines << "[problem]\nexact = \"x\"\n";
    return load_case(file);
  };
  CaseDescription c = load("");
  CHECK(g1_section(c).degree == 5);
  CHECK(g1_section(c).split_smoothness == 3);
  space_family(c).override_options(c, 4, 0);
  CHECK(g1_section(c).degree == 4);
  CHECK(g1_section(c).split_smoothness == 2);
  space_family(c).override_options(c, 3, 0);
  CHECK(g1_section(c).split_smoothness == 1);
  c = load("degree = 6\n");
  CHECK(g1_section(c).split_smoothness == 4);
  c = load("split_smoothness = 1\n");
  CHECK(g1_section(c).degree == 5);
  space_family(c).override_options(c, 7, 0);
  CHECK(g1_section(c).split_smoothness == 1);
  std::filesystem::remove_all(dir);
}
