// The adaptive loop and its parts: geometry Hessians, the residual estimator, Doerfler
// marking, and the observed rates on the L-shape and an interior layer.
#include <catch2/catch.hpp>
#include <Eigen/SVD>
#include <limits>
#include <cmath>
#include <map>

#include "families/knot_segments/knot_segments_case.hpp"
#include "families/tensor/tensor_case.hpp"
#include "quadrature/bernstein.hpp"
#include "studies/adaptive.hpp"
#include "studies/pipeline.hpp"
#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "solver/cell_basis.hpp"
#include "solver/error_norms.hpp"
#include "quadrature/gauss_legendre.hpp"
#include "tests/rounding_bounds.hpp"

using namespace knotwork;

namespace {

CaseDescription shipped(const std::string& name) { return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name); }

// Uniform refinement of the same case (tensor-product start, no segments): H1 error at the
// first level with at least `dofs` functions.
std::pair<int, double> uniform_error_beyond(CaseDescription c, int dofs) {
  for (int n = patch_space(c).elements_per_span[0];; n *= 2) {
    patch_space(c).elements_per_span = {n, n};
    const auto d_space = build_space(c);
    const SplineSpace& d = *d_space;
    if (d.mesh().num_functions() < dofs) continue;
    const PoissonSolution s = solve_case(c, d, Ordering::kAmd, {});
    return {s.num_functions, s.errors->h1_semi};
  }
}

}  // namespace

TEST_CASE("Second derivatives of a NURBS geometry agree with finite differences", "[adaptive]") {
  BezierMesh mesh;
  BezierCell cell;
  cell.u0 = 0.2, cell.u1 = 0.7, cell.v0 = 0.1, cell.v1 = 0.4;
  const int ids[1] = {0};
  mesh.add_cell(cell, ids, mesh.add_extraction(Eigen::MatrixXd::Ones(1, 4)));
  const PatchGeometryMap map(mesh, quarter_annulus_patch(1.0, 2.0));  // rational: the quotient rule matters
  const double h = 1e-4;
  for (double u : {0.13, 0.5, 0.91})
    for (double v : {0.07, 0.62}) {
      Eigen::VectorXd U(7), V(7);
      U << u, u + h, u - h, u, u, u + h, u - h;
      V << v, v, v, v + h, v - h, v + h, v - h;
      GeometryAtPoints g;
      map.evaluate(0, U, V, g);
      Eigen::MatrixXd second;
      REQUIRE(map.second_derivatives(0, U.head(1), V.head(1), second));
      for (int d = 0; d < 2; ++d) {
        const double uu = (g.x(1, d) - 2 * g.x(0, d) + g.x(2, d)) / (h * h);
        const double vv = (g.x(3, d) - 2 * g.x(0, d) + g.x(4, d)) / (h * h);
        // (f(+,+) + f(-,-) - 2 f) / (2h^2) = (f_uu + f_vv)/2 + f_uv
        const double uv = (g.x(5, d) + g.x(6, d) - 2 * g.x(0, d)) / (2 * h * h) - 0.5 * (uu + vv);
        CHECK(second(0, 3 * d) == Approx(uu).margin(1e-5));
        CHECK(second(0, 3 * d + 1) == Approx(uv).margin(1e-5));
        CHECK(second(0, 3 * d + 2) == Approx(vv).margin(1e-5));
      }
    }
}

TEST_CASE("The NURBS map's exact Bezier cells agree with the patch evaluated directly", "[adaptive][geometry]") {
  // Two independent routes: the rational Bezier form of each cell (Bezier extraction of the
  // patch, subdivision to the cell, degree elevation) evaluated by Bernstein polynomials,
  // against de Boor's evaluation of the patch at the same points; on a tensor grid and on the
  // cells of a THB space (intervals that are not the patch's spans).
  TensorSpaceOptions o;
  o.degree = {3, 3};
  o.elements_per_span = {3, 2};
  const NurbsPatch patch = quarter_annulus_patch(1.0, 2.0);
  const TensorDiscretization d = build_tensor_discretization(patch, o);
  const PatchGeometryMap grid(d.mesh, patch, {d.space_u.breakpoints(), d.space_v.breakpoints(), 0});
  CaseDescription c = load_case_text("[geometry]\ntype = \"quarter_annulus\"\ninner_radius = 1.0\nouter_radius = 2.0\n"
                                     "[space]\nfamily = \"thb\"\ndegree = 2\nelements = 2\n[problem]\nexact = \"x*y\"\n",
                                     "thb.toml");
  std::unique_ptr<SplineSpace> thb = build_space(c);
  thb = std::move(*thb).refine({0, 3}, {CellSplit::kAcrossU, CellSplit::kAcrossV});
  REQUIRE(thb);
  const PatchGeometryMap cells(thb->mesh(), patch);
  Eigen::VectorXd u(3), v(3);
  u << 0.1, 0.5, 0.93;
  v << 0.77, 0.2, 0.5;
  for (const PatchGeometryMap* map : {&grid, &cells}) {
    const BezierMesh& mesh = map == &grid ? d.mesh : thb->mesh();
    for (int cell = 0; cell < mesh.num_cells(); ++cell) {
      const BezierGeometryCell b = map->bezier_cell(cell);
      REQUIRE(b.degree_u >= 2);
      Eigen::MatrixXd B, Bu, Bv;
      tensor_bernstein(b.degree_u, b.degree_v, u, v, B, Bu, Bv);
      const Eigen::VectorXd w = B * b.weights;
      const Eigen::MatrixXd x = (B * (b.points.array().colwise() * b.weights.array()).matrix()).array().colwise() / w.array();
      GeometryAtPoints direct;
      map->evaluate(cell, u, v, direct);
      REQUIRE((x - direct.x).cwiseAbs().maxCoeff() < 1e-13);
      // and the points stay on the annulus' circles: |x| = 1 + (the radial parameter)
      const BezierCell& bc = mesh.cell(cell);
      for (int k = 0; k < 3; ++k) REQUIRE(std::abs(x.row(k).norm() - (1.0 + bc.u0 + u[k] * (bc.u1 - bc.u0))) < 1e-13);
    }
  }
}

TEST_CASE("The estimator on a tensor space equals the one on the same space built from knot segments", "[adaptive]") {
  // The same B-spline space on the L-shape (degree 2, 4 elements per span), once by the tensor
  // family and once as the knot-segment family's tensor start: different cell numbering,
  // extraction and geometry code, so equal indicators check both.
  const std::string tail = "degree = 2\nelements = 4\n[problem]\nexact = \"(x^2+y^2)^(1/3)*sin(2/3*(atan2(-y,-x)+pi))\"\n";
  const CaseDescription t = load_case_text("[geometry]\ntype = \"lshape\"\n[space]\nrational = false\n" + tail, "tensor.toml");
  const CaseDescription k =
      load_case_text("[geometry]\ntype = \"lshape\"\n[space]\nfamily = \"knot_segments\"\n" + tail, "segments.toml");
  std::map<std::array<double, 2>, double> by_cell;
  for (const CaseDescription* c : {&t, &k}) {
    const auto space = build_space(*c);
    const PoissonSolution s = solve_case(*c, *space, Ordering::kAmd, {});
    const ErrorIndicators ind = residual_indicators(space->mesh(), space->geometry(), s.coefficients, c->problem);
    REQUIRE(ind.jump_part > 0);
    for (int e = 0; e < space->mesh().num_cells(); ++e) {
      const BezierCell& b = space->mesh().cell(e);
      const std::array<double, 2> key{b.u0, b.v0};
      if (c == &t) {
        by_cell[key] = ind.eta_squared[e];
      } else {
        REQUIRE(by_cell.count(key) == 1);
        CHECK(ind.eta_squared[e] == Approx(by_cell[key]).epsilon(1e-8));
      }
    }
    if (c == &k) REQUIRE(static_cast<int>(by_cell.size()) == space->mesh().num_cells());
  }
}

TEST_CASE("The estimator's gradient jumps equal their definition across hanging sides", "[adaptive]") {
  // The estimator evaluates u_h on the sides from Bernstein coefficients it keeps per cell; here
  // each side's term is recomputed from its definition by the generic route (u_h from the
  // functions and the extraction, the map evaluated anew): sum over sides of |E| times the
  // Gauss sum (max degree + 2 points) of ds |[grad u_h]|^2. On the L-shape the space is only
  // C0 across the fold u = 1/2, where the gradient jumps; the THB mesh is refined twice along
  // it, so that sides there meet two cells along part of a side (a_from, a_to not 0 and 1).
  // The two routes round differently; each gradient is
  // exact to a few thousand ulps of its size, so the sums agree to 1e-12 of the sum of
  // ds (|grad u_a| + |grad u_b|)^2 and the largest jumps to 1e-12 of the largest
  // |grad u_a| + |grad u_b|, not of the jumps, which cancel.
  CaseDescription c = shipped("lshape_adaptive_thb.toml");
  std::unique_ptr<SplineSpace> space = build_space(c);
  for (int step = 0; step < 2; ++step) {
    std::vector<int> marked;  // every other cell along the fold, on its left
    for (int cell = 0; cell < space->mesh().num_cells(); ++cell)
      if (space->mesh().cell(cell).u1 == 0.5 && cell % 2 == 0) marked.push_back(cell);
    space = std::move(*space).refine(marked, std::vector<CellSplit>(marked.size(), CellSplit::kAcrossU));
  }
  REQUIRE(space);
  const BezierMesh& mesh = space->mesh();
  const PoissonSolution s = solve_case(c, *space, Ordering::kAmd, {});
  const ErrorIndicators ind = residual_indicators(mesh, space->geometry(), s.coefficients, c.problem);
  double jump_part = 0, scale = 0, largest = 0, largest_gradients = 0;
  int hanging = 0;
  for (const CellInterface& e : mesh.interfaces()) {
    hanging += e.a_from != 0 || e.a_to != 1 || std::min(e.b_from, e.b_to) != 0 || std::max(e.b_from, e.b_to) != 1;
    const BezierCell& a = mesh.cell(e.cell_a);
    const QuadratureRule1D rule = gauss_legendre(std::max(a.degree_u, a.degree_v) + 2);
    const int n = static_cast<int>(rule.nodes.size());
    Eigen::VectorXd ua(n), va(n), ub(n), vb(n);
    auto point = [](CellSide side, double t, double& u, double& v) {
      u = side == kSideBottom || side == kSideTop ? t : side == kSideRight ? 1 : 0;
      v = side == kSideLeft || side == kSideRight ? t : side == kSideTop ? 1 : 0;
    };
    for (int k = 0; k < n; ++k) {
      point(e.side_a, e.a_from + rule.nodes[k] * (e.a_to - e.a_from), ua[k], va[k]);
      point(e.side_b, e.b_from + rule.nodes[k] * (e.b_to - e.b_from), ub[k], vb[k]);
    }
    CellField fa, fb;
    evaluate_cell_field_at(mesh, space->geometry(), e.cell_a, ua, va, s.coefficients, fa);
    evaluate_cell_field_at(mesh, space->geometry(), e.cell_b, ub, vb, s.coefficients, fb);
    // Both sides of the interface are the same points.
    REQUIRE((fa.geometry.x - fb.geometry.x).cwiseAbs().maxCoeff() < 1e-13);
    const int col = e.side_a == kSideBottom || e.side_a == kSideTop ? 0 : 1;
    double length = 0, integral = 0, bound = 0;
    for (int k = 0; k < n; ++k) {
      const double ds = std::hypot(fa.geometry.jacobian(k, col), fa.geometry.jacobian(k, 2 + col)) *
                        std::abs(e.a_to - e.a_from) * rule.weights[k];
      const double jump = (fa.gradient.row(k) - fb.gradient.row(k)).norm();
      length += ds;
      integral += ds * jump * jump;
      bound += ds * std::pow(fa.gradient.row(k).norm() + fb.gradient.row(k).norm(), 2);
      largest = std::max(largest, jump);
      largest_gradients = std::max(largest_gradients, fa.gradient.row(k).norm() + fb.gradient.row(k).norm());
    }
    jump_part += length * integral;
    scale += length * bound;
  }
  INFO(hanging << " hanging sides of " << mesh.interfaces().size() << "; jump part " << ind.jump_part << " against "
              << jump_part << ", largest jump " << ind.max_gradient_jump << " against " << largest);
  REQUIRE(hanging >= 4);
  CHECK(ind.jump_part > 0);
  CHECK(std::abs(ind.jump_part - jump_part) <= 1e-12 * scale);
  CHECK(std::abs(ind.max_gradient_jump - largest) <= 1e-12 * largest_gradients);
}

TEST_CASE("The estimator vanishes when the discrete solution is exact", "[adaptive]") {
  // On the unit square u = x^2 y - y^2 + 3x is a biquadratic polynomial: u_h = u on any
  // knot-segment mesh, so f + Laplace(u_h) = 0 and no gradient jumps.
  CaseDescription c = shipped("interior_layer.toml");
  c.problem.exact = differentiate_exact_solution(Expression::parse("x^2*y - y^2 + 3*x", "test"));
  c.problem.source = c.problem.exact->minus_laplacian;
  knot_segments_section(c).segments = {{true, 0.3, 0.0, 0.75, 1}, {false, 0.6, 0.1, 0.9, 1}};
  const auto d_space = build_space(c);
  const SplineSpace& d = *d_space;
  // u_h - u is rounding alone (tests/rounding_bounds.hpp); the estimator applied to it is at most
  // an inverse-inequality constant times its H1 seminorm over the smallest cell: 1e3 / h_min is
  // the stated bound (degree 2: the constant is a few tens).
  double h_min = INFINITY;
  for (int e = 0; e < d.mesh().num_cells(); ++e)
    h_min = std::min({h_min, d.mesh().cell(e).u1 - d.mesh().cell(e).u0, d.mesh().cell(e).v1 - d.mesh().cell(e).v0});
  PoissonSolveOptions so;
  so.quadrature = c.quadrature;
  const auto solve = [&] {
    const rounding_test::Reproduction r = rounding_test::solve_reproducing(d.mesh(), d.geometry(), c.problem, so);
    REQUIRE_REPRODUCED(r);
    return std::pair{r.coefficients, 1e3 / h_min * r.h1_bound()};
  };
  const auto [s, bound] = solve();
  const ErrorIndicators ind = residual_indicators(d.mesh(), d.geometry(), s, c.problem);
  CHECK(std::sqrt(ind.total()) <= bound);
  CHECK(ind.max_gradient_jump <= bound);
  // With Nitsche's method the trace is the Galerkin solution's, and still u's (consistency): the
  // Dirichlet term h_E^-1 ||g - u_h||^2 vanishes too.
  c.problem.dirichlet_method = DirichletMethod::kNitsche;
  const auto [weak, weak_bound] = solve();
  const ErrorIndicators weak_ind = residual_indicators(d.mesh(), d.geometry(), weak, c.problem);
  CHECK(std::sqrt(weak_ind.total()) <= weak_bound);
}

TEST_CASE("The estimator bounds the error on the L-shape, and jumps appear only at the C0 fold", "[adaptive]") {
  CaseDescription c = shipped("lshape_adaptive.toml");
  patch_space(c).elements_per_span = {4, 4};
  const auto d_space = build_space(c);
  const SplineSpace& d = *d_space;
  const PoissonSolution s = solve_case(c, d, Ordering::kAmd, {});
  const ErrorIndicators ind = residual_indicators(d.mesh(), d.geometry(), s.coefficients, c.problem);
  // Reliability |u - u_h|_1 <= C eta with a moderate constant, and not wildly pessimistic.
  const double ratio = std::sqrt(ind.total()) / s.errors->h1_semi;
  INFO("efficiency index " << ratio);
  CHECK(ratio > 1.0);
  CHECK(ratio < 50.0);
  CHECK(ind.jump_part > 0);  // the fold u = 1/2 is only C0
  // Elsewhere the space is C1: across every vertical side away from the fold u = 1/2 the
  // gradient jumps by roundoff only. The start is the tensor grid of 2 spans x 4 elements in
  // u and 4 in v: 7 interior vertical lines of 4 sides each, one of them the fold, so 24 sides.
  const BezierMesh& mesh = d.mesh();
  int compared = 0;
  double largest_jump = 0, largest_at_fold = 0;
  Eigen::VectorXd u(1), v(1), u2(1), v2(1);
  u << 1.0, v << 0.5;
  u2 << 0.0, v2 << 0.5;
  for (int cell = 0; cell < mesh.num_cells(); ++cell) {
    const BezierCell& b = mesh.cell(cell);
    for (int other = 0; other < mesh.num_cells(); ++other) {
      const BezierCell& o = mesh.cell(other);
      if (o.u0 != b.u1 || o.v0 != b.v0 || o.v1 != b.v1) continue;
      const Eigen::MatrixX3d left = evaluate_solution(mesh, d.geometry(), s.coefficients, cell, u, v);
      const Eigen::MatrixX3d right = evaluate_solution(mesh, d.geometry(), s.coefficients, other, u2, v2);
      const double jump = (left.row(0).tail<2>() - right.row(0).tail<2>()).norm();
      if (b.u1 == 0.5) {
        largest_at_fold = std::max(largest_at_fold, jump);
        continue;
      }
      largest_jump = std::max(largest_jump, jump);
      ++compared;
    }
  }
  INFO("largest gradient jump across C1 sides " << largest_jump << ", across the fold " << largest_at_fold);
  CHECK(compared == 24);
  CHECK(largest_jump < 1e-10);
  CHECK(largest_at_fold > 1e-3);  // the fold is only C0, and the check sees it
}

TEST_CASE("Doerfler marking takes the fewest largest indicators reaching theta", "[adaptive]") {
  Eigen::VectorXd eta2(6);
  eta2 << 1, 8, 2, 5, 3, 1;  // total 20
  CHECK(mark(eta2, {Marking::Strategy::kDorfler, 0.5, 0}) == std::vector<int>{1, 3});        // 8 + 5 = 13 >= 10
  CHECK(mark(eta2, {Marking::Strategy::kDorfler, 0.7, 0}) == std::vector<int>{1, 3, 4});     // 16 >= 14
  CHECK(mark(eta2, {Marking::Strategy::kDorfler, 1.0, 0}).size() == 6);
  CHECK_THROWS(mark(eta2, {Marking::Strategy::kDorfler, 0.0, 0}));
  CHECK_THROWS(mark(eta2, {Marking::Strategy::kDorfler, 1.5, 0}));
}

TEST_CASE("Maximum marking takes every indicator within theta of the largest, and at least a minimum share", "[adaptive]") {
  Eigen::VectorXd eta2(6);
  eta2 << 1, 16, 4, 9, 4, 0;  // eta: 1, 4, 2, 3, 2, 0
  using S = Marking::Strategy;
  CHECK(mark(eta2, {S::kMaximum, 0.5, 0}) == std::vector<int>{1, 3, 2, 4});  // eta >= 2 (ties: lower index first)
  CHECK(mark(eta2, {S::kMaximum, 0.75, 0}) == std::vector<int>{1, 3});       // eta >= 3
  CHECK(mark(eta2, {S::kMaximum, 1.0, 0}) == std::vector<int>{1});
  // The minimum share: ceil(0.5 * 6) = 3 items even where the strategy picks fewer.
  CHECK(mark(eta2, {S::kMaximum, 1.0, 0.5}) == std::vector<int>{1, 3, 2});
  CHECK(mark(eta2, {S::kDorfler, 0.3, 0.5}) == std::vector<int>{1, 3, 2});  // Doerfler alone: {1} (16 >= 10.2)
  CHECK(mark(eta2, {S::kDorfler, 0.3, 0}) == std::vector<int>{1});
  CHECK(mark(eta2, {S::kMaximum, 0.5, 1.0}).size() == 6);
  CHECK(mark(Eigen::VectorXd(), {S::kMaximum, 0.5, 0.5}).empty());
  CHECK_THROWS(mark(eta2, {S::kMaximum, 0.0, 0}));
  CHECK_THROWS(mark(eta2, {S::kMaximum, 0.5, -0.1}));
  CHECK_THROWS(mark(eta2, {S::kMaximum, 0.5, 1.1}));
  eta2[2] = NAN;
  CHECK_THROWS(mark(eta2, {S::kDorfler, 0.5, 0}));
}

TEST_CASE("Marking by functions refines the supports of the functions Doerfler picks", "[adaptive]") {
  // Four cells in a row, linear hats 0..4: hat k lives on cells k-1 and k.
  BezierMesh mesh;
  mesh.set_num_functions(5);
  for (int c = 0; c < 4; ++c) {
    BezierCell cell;
    cell.u0 = c, cell.u1 = c + 1;
    const int ids[2] = {c, c + 1};
    mesh.add_cell(cell, ids, mesh.add_extraction(Eigen::MatrixXd::Identity(2, 4)));
  }
  Eigen::VectorXd eta2(4);
  eta2 << 9, 1, 0, 4;  // per function: 9, 10, 1, 4, 4 (total 28)
  // Half of 28: function 1 (10) then 0 (9) = 19 >= 14: cells 0 and 1.
  CHECK(cells_of_marked_functions(mesh, eta2, {Marking::Strategy::kDorfler, 0.5, 0}) == std::vector<int>{0, 1});
  // 0.75 of 28 = 21: functions 1, 0, then 3 (4): cells 0, 1, 2, 3 (function 3 lives on 2 and 3).
  CHECK(cells_of_marked_functions(mesh, eta2, {Marking::Strategy::kDorfler, 0.75, 0}) == std::vector<int>{0, 1, 2, 3});
  // Maximum strategy, theta = 0.6: eta of the functions 3, 3.16, 1, 2, 2; at least 0.6 * 3.16 = 1.90:
  // functions 0, 1, 3, 4, whose supports are every cell.
  CHECK(cells_of_marked_functions(mesh, eta2, {Marking::Strategy::kMaximum, 0.6, 0}) == std::vector<int>{0, 1, 2, 3});
  // theta = 0.9 (2.85): functions 1 and 0, cells 0 and 1.
  CHECK(cells_of_marked_functions(mesh, eta2, {Marking::Strategy::kMaximum, 0.9, 0}) == std::vector<int>{0, 1});
}

TEST_CASE("Adaptive knot segments on the L-shape: H1 error ~ N^(-p/2), uniform ~ N^(-1/3)", "[adaptive][slow]") {
  for (int p : {2, 3}) {
    CaseDescription c = shipped("lshape_adaptive.toml");
    patch_space(c).degree = {p, p};
    c.adapt.steps = 60;
    c.adapt.max_dofs = p == 2 ? 3000 : 3500;
    const auto steps = adapt_case(c, Ordering::kAmd, {});
    const double rate = fitted_h1_rate(steps, steps.size() / 2);
    const auto [uniform_dofs, uniform_error] = uniform_error_beyond(c, steps.back().dofs);
    WARN("L-shape p = " << p << ": " << steps.size() << " steps to " << steps.back().dofs << " dofs, H1 error "
                        << steps.back().h1_semi << ", rate over the last half " << rate << "; uniform: "
                        << uniform_dofs << " dofs, H1 error " << uniform_error);
    CHECK(rate > p / 2.0 - 0.15);  // one-sided: the optimal rate less 0.15
    CHECK(steps.back().h1_semi < uniform_error / 5);
    // Reliability and efficiency (Verfurth): c |u - u_h|_1 <= eta <= C |u - u_h|_1 with
    // constants independent of the mesh, so the ratio eta / error must not drift as the mesh
    // is refined: at the last step it is within a factor 2 of its value halfway.
    const auto ratio = [&](size_t k) { return steps[k].estimator / steps[k].h1_semi; };
    INFO("eta / error: halfway " << ratio(steps.size() / 2) << ", last " << ratio(steps.size() - 1));
    CHECK(ratio(steps.size() - 1) / ratio(steps.size() / 2) < 2.0);
    CHECK(ratio(steps.size() - 1) / ratio(steps.size() / 2) > 0.5);
  }
}

// Nitsche's method in the adaptive loop: the estimator adds h_E^-1 ||g - u_h||^2 on the Dirichlet
// sides (Becker, Hansbo, Stenberg 2003), and the loop keeps the optimal rate N^(-p/2) of the
// projection's loop on the L-shape, with a stable eta / error ratio.
TEST_CASE("Adaptive knot segments with Nitsche's method on the L-shape: H1 error ~ N^(-p/2)", "[adaptive][slow]") {
  CaseDescription c = shipped("lshape_adaptive.toml");
  c.problem.dirichlet_method = DirichletMethod::kNitsche;
  c.adapt.steps = 60;
  c.adapt.max_dofs = 3000;
  const auto steps = adapt_case(c, Ordering::kAmd, {});
  const double rate = fitted_h1_rate(steps, steps.size() / 2);
  const auto ratio = [&](size_t k) { return steps[k].estimator / steps[k].h1_semi; };
  INFO(steps.size() << " steps to " << steps.back().dofs << " dofs, H1 error " << steps.back().h1_semi
                    << ", rate over the last half " << rate << "; eta / error halfway " << ratio(steps.size() / 2)
                    << ", last " << ratio(steps.size() - 1));
  CHECK(rate > 1.0 - 0.15);  // p = 2: the optimal rate less 0.15
  CHECK(ratio(steps.size() - 1) / ratio(steps.size() / 2) < 2.0);
  CHECK(ratio(steps.size() - 1) / ratio(steps.size() / 2) > 0.5);
  // The Dirichlet term is there: on a mesh that does not resolve u, u_h misses g.
  const auto d_space = build_space(c);
  const PoissonSolution s = solve_case(c, *d_space, Ordering::kAmd, {});
  CHECK(residual_indicators(d_space->mesh(), d_space->geometry(), s.coefficients, c.problem).dirichlet_part > 0);
}

TEST_CASE("Adaptive knot segments resolve an interior layer with fewer dofs than uniform refinement", "[adaptive][slow]") {
  CaseDescription c = shipped("interior_layer.toml");
  c.adapt.max_dofs = 3000;
  const auto steps = adapt_case(c, Ordering::kAmd, {});
  // Uniform refinement with at least twice the functions is still less accurate.
  const auto [uniform_dofs, uniform_error] = uniform_error_beyond(c, 2 * steps.back().dofs);
  WARN("interior layer: " << steps.back().dofs << " dofs, H1 error " << steps.back().h1_semi << "; uniform "
                          << uniform_dofs << " dofs, H1 error " << uniform_error);
  CHECK(steps.back().h1_semi < uniform_error);
  CHECK(fitted_h1_rate(steps, steps.size() / 2) > 0.9);
}

TEST_CASE("Adaptivity refuses spaces it cannot refine", "[adaptive]") {
  CaseDescription c = shipped("square_sinsin.toml");
  REQUIRE_THROWS_WITH(adapt_case(c, Ordering::kAmd, {}), Catch::Contains("family") && Catch::Contains("knot_segments"));
}

namespace {

// Every basis function of `mesh` at the parameter points (u_k, v_k) of one patch, each found in
// the cell whose parameter box holds it: points x functions. Polynomial spaces.
Eigen::MatrixXd basis_at_parameter_points(const BezierMesh& mesh, const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  REQUIRE_FALSE(mesh.is_rational());
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(u.size(), mesh.num_functions());
  std::vector<int> found(u.size(), 0);
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& b = mesh.cell(c);
    REQUIRE(b.patch == 0);
    for (Eigen::Index k = 0; k < u.size(); ++k) {
      if (u[k] < b.u0 || u[k] >= b.u1 || v[k] < b.v0 || v[k] >= b.v1) continue;
      ++found[k];
      Eigen::VectorXd ru(1), rv(1);
      ru << (u[k] - b.u0) / (b.u1 - b.u0);
      rv << (v[k] - b.v0) / (b.v1 - b.v0);
      Eigen::MatrixXd B, Bu, Bv;
      tensor_bernstein(b.degree_u, b.degree_v, ru, rv, B, Bu, Bv);
      const Eigen::VectorXd n = mesh.extraction(c) * B.row(0).transpose();
      const auto ids = mesh.functions(c);
      for (size_t a = 0; a < ids.size(); ++a) values(k, ids[a]) = n[a];
    }
  }
  for (int f : found) REQUIRE(f == 1);
  return values;
}

}  // namespace

TEST_CASE("The adaptive spaces on the L-shape are nested, and the error rises only where a step adds no free function", "[adaptive]") {
  // The span of step s's basis lies in step s+1's iff the least-squares fit of the old functions
  // by the new ones, sampled on a grid off every dyadic line, leaves a residual at rounding level:
  // below 100 kappa eps, kappa the sampled new basis's condition number. Transitions whose
  // newest cells are too small for the grid to sample every function (kappa > 1e6) are not
  // judged. The reverse fit (new by old) must fail where the space grew: the check can fail.
  const int n = 90;
  Eigen::VectorXd u(n * n), v(n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) u[i + n * j] = (i + 0.3711) / n, v[i + n * j] = (j + 0.6173) / n;
  for (const char* name : {"lshape_adaptive_thb.toml", "lshape_adaptive_lr.toml", "lshape_adaptive_pt.toml", "lshape_adaptive.toml"}) {
    CaseDescription c = shipped(name);
    patch_space(c).degree = {3, 3};
    c.adapt.steps = 7;
    std::vector<Eigen::MatrixXd> sampled;
    std::vector<int> free;
    std::vector<double> error;
    adapt_case(c, Ordering::kAmd, {}, [&](const AdaptiveStepView& s) {
      sampled.push_back(basis_at_parameter_points(s.space.mesh(), u, v));
      free.push_back(s.solution.num_free);
      error.push_back(s.solution.errors->h1_semi);
    });
    int judged = 0;
    for (size_t s = 0; s + 1 < sampled.size(); ++s) {
      const Eigen::MatrixXd &old_basis = sampled[s], &new_basis = sampled[s + 1];
      const Eigen::BDCSVD<Eigen::MatrixXd> svd(new_basis, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const double kappa = svd.singularValues()(0) / svd.singularValues().tail(1)(0);
      INFO(name << ", step " << s << " -> " << s + 1 << ": " << old_basis.cols() << " -> " << new_basis.cols()
                << " functions, kappa " << kappa);
      if (!(kappa < 1e6)) continue;
      ++judged;
      const double residual = (new_basis * svd.solve(old_basis) - old_basis).norm() / old_basis.norm();
      CHECK(residual < 100 * kappa * std::numeric_limits<double>::epsilon());
      if (new_basis.cols() > old_basis.cols()) {
        const Eigen::BDCSVD<Eigen::MatrixXd> back(old_basis, Eigen::ComputeThinU | Eigen::ComputeThinV);
        CHECK((old_basis * back.solve(new_basis) - new_basis).norm() / new_basis.norm() > 1e-3);
      }
      // Nested spaces: Galerkin's solution is the best in the energy norm among functions with
      // the same boundary values. A step that adds only Dirichlet functions keeps the free space
      // and changes the boundary projection of g, and only there may the H1 error rise.
      if (error[s + 1] > error[s]) CHECK(free[s + 1] == free[s]);
    }
    CHECK(judged >= 4);
  }
}
