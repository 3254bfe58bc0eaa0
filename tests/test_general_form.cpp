// The general form -div(A grad u) + c u = f: the derived source against hand-written
// derivatives, the patch test (linear u reproduced to rounding with variable A and c, Neumann
// fluxes (A grad u).n and Nitsche's conormal terms), optimal rates for the tensor, THB and G1
// families, optimal adaptive rates, and the refusal of A that is not symmetric positive
// definite or c that is negative.
#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>

#include "basis/core/input_error.hpp"
#include "cases/case_file.hpp"
#include "families/tensor/tensor_case.hpp"
#include "solver/expression.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/surface_source.hpp"
#include "studies/adaptive.hpp"
#include "studies/pipeline.hpp"
#include "studies/studies.hpp"
#include "tests/rounding_bounds.hpp"

using namespace knotwork;

namespace {

CaseDescription shipped(const std::string& name) {
  return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
}

// The square [0, 1]^2 with a [problem] section given as TOML lines.
CaseDescription square_case(int degree, int elements, const std::string& problem) {
  return load_case_text("[geometry]\ntype = \"rectangle\"\ncorners = [[0.0, 0.0], [1.0, 1.0]]\n[space]\ndegree = " +
                            std::to_string(degree) + "\nelements = " + std::to_string(elements) +
                            "\nrational = false\n[problem]\n" + problem,
                        "general.toml");
}

// The message of the InputError that loading and solving the case throws ("" if none).
std::string refusal(const std::string& problem) {
  try {
    const CaseDescription c = square_case(2, 4, problem);
    const auto space = build_space(c);
    solve_case(c, *space, Ordering::kAmd);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// Both sources are sums of a dozen terms of size below 100 at these points: they agree to a few
// hundred ulps of 100, far below 1e-11.
TEST_CASE("The derived source is -div(A grad u) + c u, as differentiated by hand", "[general]") {
  const double pi = std::acos(-1.0);
  const Expression u = Expression::parse("sin(pi*x)*sin(pi*y)", "test: exact");
  SECTION("a scalar a = 1 + x and c = 2 + y") {
    const Expression f = derive_general_source(u, {Expression::parse("1 + x", "a")}, Expression::parse("2 + y", "c"), 0);
    ExpressionEvaluator derived(f);
    for (const auto& [x, y] : {std::pair{0.3, 0.7}, {0.81, 0.12}, {-0.4, 1.3}}) {
      const double s = std::sin(pi * x) * std::sin(pi * y);
      // -(a u_x)_x - (a u_y)_y = -u_x - a (u_xx + u_yy), u_xx + u_yy = -2 pi^2 u
      const double hand = -pi * std::cos(pi * x) * std::sin(pi * y) + 2 * pi * pi * (1 + x) * s + (2 + y) * s;
      CHECK(std::abs(derived(x, y) - hand) < 1e-11);
    }
  }
  SECTION("a constant matrix [[2, 1], [1, 3]] on u = x^2 y + y^3, with the constant c = 4") {
    const Expression cubic = Expression::parse("x^2*y + y^3", "test: exact");
    const Expression f = derive_general_source(
        cubic, {Expression::parse("2", "a11"), Expression::parse("1", "a12"), Expression::parse("3", "a22")}, {}, 4);
    ExpressionEvaluator derived(f);
    for (const auto& [x, y] : {std::pair{0.3, 0.7}, {0.81, 0.12}, {-0.4, 1.3}}) {
      // u_xx = 2y, u_xy = 2x, u_yy = 6y: -(2 u_xx + 2 u_xy + 3 u_yy) = -(4y + 4x + 18y)
      const double hand = -(4 * x + 22 * y) + 4 * (x * x * y + y * y * y);
      CHECK(std::abs(derived(x, y) - hand) < 1e-11);
    }
  }
  SECTION("a variable matrix: the mixed terms (a12 u_y)_x + (a12 u_x)_y") {
    const Expression quad = Expression::parse("x*y", "test: exact");
    const Expression f = derive_general_source(
        quad, {Expression::parse("1", "a11"), Expression::parse("x^2", "a12"), Expression::parse("1", "a22")}, {}, 0);
    ExpressionEvaluator derived(f);
    for (const auto& [x, y] : {std::pair{0.3, 0.7}, {0.81, 0.12}}) {
      // grad u = (y, x): A grad u = (y + x^3, x^2 y + x); div = 3x^2 + x^2 = 4 x^2
      CHECK(std::abs(derived(x, y) + 4 * x * x) < 1e-11);
    }
  }
}

// With A and c linear on an affine map, every integrand of the form and of the load is a
// polynomial the default rule integrates exactly, so a linear u is reproduced to rounding
// (tests/rounding_bounds.hpp), Neumann sides (flux (A grad u).n) and Nitsche's sides included.
TEST_CASE("Patch test with variable A and c: linear solutions are reproduced to rounding", "[general]") {
  const std::string problem =
      "exact = \"1 + 2*x - 3*y\"\n"
      "coefficient = [[\"2 + x\", \"0.5*y\"], [\"0.5*y\", \"1.5 + 0.25*x\"]]\n"
      "reaction = \"1 + x\"\n";
  for (int p = 1; p <= 3; ++p) {
    INFO("degree " << p);
    for (const std::string extra : {"", "neumann = [\"right\", \"top\"]\n", "dirichlet_method = \"nitsche\"\n"}) {
      INFO(extra);
      const CaseDescription c = square_case(p, 3, problem + extra);
      const auto space = build_space(c);
      PoissonSolveOptions o;
      o.quadrature = c.quadrature;
      REQUIRE_REPRODUCED(rounding_test::solve_reproducing(space->mesh(), space->geometry(), c.problem, o));
    }
  }
}

TEST_CASE("Optimal rates with variable A and c: tensor p = 1..4 on the NURBS annulus, THB, G1", "[general][rates]") {
  SECTION("tensor (the shipped annulus case: matrix A, reaction c, a Neumann side)") {
    for (int p = 1; p <= 4; ++p) {
      CaseDescription c = shipped("annulus_anisotropic");
      override_case(c, p, 4, "", 0);
      if (p == 1) patch_space(c).rational = false;  // the arcs need degree 2; p = 1 is B-splines on the exact map
      const ConvergeOutcome r = converge_study(c, 4, Ordering::kAmd, nullptr, {});
      const ConvergeLevel& last = r.levels.back();
      INFO("p = " << p << ": L2 rate " << last.l2_rate << ", H1 rate " << last.h1_rate);
      CHECK(last.l2_rate >= p + 1 - 0.2);
      CHECK(last.h1_rate >= p - 0.2);
      CHECK(last.l2_rate < p + 1 + 0.3);
    }
  }
  SECTION("THB on the L-shape, smooth solution") {
    CaseDescription c = load_case_text(
        "[geometry]\ntype = \"lshape\"\n[space]\nfamily = \"thb\"\ndegree = 2\nelements = 4\n[problem]\n"
        "exact = \"sin(2*x)*exp(y)\"\ncoefficient = [[\"2 + x\", \"0.3*y\"], [\"0.3*y\", \"1.5\"]]\nreaction = \"1 + y^2\"\n",
        "thb.toml");
    const ConvergeOutcome r = converge_study(c, 4, Ordering::kAmd, nullptr, {});
    INFO("L2 rate " << r.levels.back().l2_rate << ", H1 rate " << r.levels.back().h1_rate);
    CHECK(r.levels.back().l2_rate >= 3 - 0.2);
    CHECK(r.levels.back().h1_rate >= 2 - 0.2);
  }
  SECTION("G1 on the L-shape mesh with extraordinary vertices (Nitsche's conormal terms)") {
    const ConvergeOutcome r = converge_study(shipped("g1_variable_coefficient"), 3, Ordering::kAmd, nullptr, {});
    INFO("L2 rate " << r.levels.back().l2_rate << ", H1 rate " << r.levels.back().h1_rate);
    CHECK(r.levels.back().l2_rate >= 5 - 0.2);
    CHECK(r.levels.back().h1_rate >= 4 - 0.2);
  }
}

// On a closed surface the coefficient is a scalar a(x, y, z): the derived source is
// -a Laplace_Beltrami(u) - grad(a).P grad(u). With a = 2 the matrix and the source double, so
// the solution is the one of a = 1 up to the rounding of sqrt(2)^2 in the matrix entries
// (kappa(K) ~ 1e3 ulps at this level, docs/G1_POISSON.md: far below 1e-9); with a = 2 + x z
// the rates are the Laplace-Beltrami ones (without the grad(a) term they stall at 0).
TEST_CASE("A scalar coefficient on a closed G1 surface: a = 2 solves as a = 1, a = 2 + xz at optimal rates",
          "[general][surface]") {
  const CaseDescription plain = shipped("g1_sphere_xy");
  CaseDescription doubled = plain;
  doubled.problem.coefficients.diffusion = {Expression::parse("2", "test: coefficient")};
  const auto space = build_space(plain);
  const PoissonSolution a = solve_case(plain, *space, Ordering::kAmd), b = solve_case(doubled, *space, Ordering::kAmd);
  CHECK(std::abs(a.errors->l2 - b.errors->l2) <= 1e-9 * a.errors->l2);
  CHECK(std::abs(a.errors->h1_semi - b.errors->h1_semi) <= 1e-9 * a.errors->h1_semi);
  const ConvergeOutcome r = converge_study(shipped("g1_sphere_coefficient"), 4, Ordering::kAmd, nullptr, {});
  INFO("L2 rate " << r.levels.back().l2_rate << ", H1 rate " << r.levels.back().h1_rate);
  CHECK(r.levels.back().l2_rate >= 5 - 0.2);
  CHECK(r.levels.back().h1_rate >= 4 - 0.2);
}

// The tangential divergence of P A P grad u (solver/surface_source), checked against the
// curvature form of the scalar case: with A = a I it must equal a Laplace_Beltrami(u) +
// grad(a).P grad(u), Laplace_Beltrami(u) = tr H - n.H n - kappa g.n, kappa = -G^{ij} x_ij.n
// (two formulas that share no code path: the first differentiates P along the surface). The
// frames are random. Both sides are sums of a few dozen products of the frame's entries
// through G^{-1}; each product rounds a few times, so they differ by a few hundred eps times
// the size of the terms, which is bounded by the magnitudes below times ||G^{-1}||.
TEST_CASE("The tangential divergence with A = a I is the scalar curvature formula", "[general][surface]") {
  std::srand(7);
  auto random = [] { return 2.0 * std::rand() / RAND_MAX - 1.0; };
  for (int trial = 0; trial < 20; ++trial) {
    SurfaceFrame s;
    s.xu = Eigen::Vector3d(1.5, 0.2 * random(), 0.3 * random());
    s.xv = Eigen::Vector3d(0.2 * random(), 1.2, 0.3 * random());
    s.xuu = Eigen::Vector3d::NullaryExpr([&](Eigen::Index) { return random(); });
    s.xuv = Eigen::Vector3d::NullaryExpr([&](Eigen::Index) { return random(); });
    s.xvv = Eigen::Vector3d::NullaryExpr([&](Eigen::Index) { return random(); });
    const Eigen::Vector3d g = Eigen::Vector3d::NullaryExpr([&](Eigen::Index) { return random(); });
    Eigen::Matrix3d H = Eigen::Matrix3d::NullaryExpr([&](Eigen::Index, Eigen::Index) { return random(); });
    H = (H + H.transpose()).eval();
    const double a = 2 + random();
    const Eigen::Vector3d grad_a = Eigen::Vector3d::NullaryExpr([&](Eigen::Index) { return random(); });
    const Eigen::Matrix3d A = a * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d dA[3] = {grad_a(0) * Eigen::Matrix3d::Identity(), grad_a(1) * Eigen::Matrix3d::Identity(),
                                   grad_a(2) * Eigen::Matrix3d::Identity()};
    Eigen::Matrix2d G;
    G << s.xu.dot(s.xu), s.xu.dot(s.xv), s.xu.dot(s.xv), s.xv.dot(s.xv);
    const Eigen::Matrix2d Gi = G.inverse();
    const Eigen::Vector3d n = s.xu.cross(s.xv).normalized();
    const double kappa = -(Gi(0, 0) * s.xuu.dot(n) + 2 * Gi(0, 1) * s.xuv.dot(n) + Gi(1, 1) * s.xvv.dot(n));
    const double laplace_beltrami = H.trace() - n.dot(H * n) - kappa * g.dot(n);
    const double expected = a * laplace_beltrami + grad_a.dot(g - g.dot(n) * n);
    const double second = s.xuu.norm() + s.xuv.norm() + s.xvv.norm(), first = s.xu.norm() + s.xv.norm();
    const double terms = Gi.norm() * first * (a * (H.norm() * first + second * g.norm() / first) + grad_a.norm() * first * g.norm());
    CHECK(std::abs(tangential_divergence(s, g, H, A, dA) - expected) <= 1000 * 2.2e-16 * terms);
  }
}

// A 3x3 A on a closed surface: its tangential part acts. A = 2 I solves as A = I (the matrix
// and source double, the solution is the same up to the rounding of the factor, as above), and
// the shipped anisotropic case with c = 1 + x^2 converges at the optimal rates (without the
// derivative of P in the source, they stall at 0: checked by hand when it was written).
TEST_CASE("A 3x3 coefficient and a variable reaction on a closed G1 surface: optimal rates", "[general][surface]") {
  const CaseDescription plain = shipped("g1_sphere_xy");
  CaseDescription doubled = plain;
  const Expression two = Expression::parse("2", "test: coefficient"), zero = Expression::parse("0", "test: coefficient");
  doubled.problem.coefficients.diffusion = {two, zero, zero, two, zero, two};
  const auto space = build_space(plain);
  const PoissonSolution a = solve_case(plain, *space, Ordering::kAmd), b = solve_case(doubled, *space, Ordering::kAmd);
  CHECK(std::abs(a.errors->l2 - b.errors->l2) <= 1e-9 * a.errors->l2);
  CHECK(std::abs(a.errors->h1_semi - b.errors->h1_semi) <= 1e-9 * a.errors->h1_semi);
  const ConvergeOutcome r = converge_study(shipped("g1_sphere_anisotropic"), 4, Ordering::kAmd, nullptr, {});
  INFO("L2 rate " << r.levels.back().l2_rate << ", H1 rate " << r.levels.back().h1_rate);
  CHECK(r.levels.back().l2_rate >= 5 - 0.2);
  CHECK(r.levels.back().h1_rate >= 4 - 0.2);
}

// The estimator carries A and c: from a coarse start the adaptive THB loop reaches the optimal
// rate N^(-p/2) on the L-shape's corner singularity.
TEST_CASE("Adaptive THB with a variable coefficient and reaction: H1 error ~ N^(-p/2)", "[general][adaptive]") {
  CaseDescription c = shipped("lshape_adaptive_coefficient");
  c.adapt.max_dofs = 3000;
  const auto steps = adapt_case(c, Ordering::kAmd, {});
  const double rate = fitted_h1_rate(steps, steps.size() / 2);
  INFO(steps.size() << " steps to " << steps.back().dofs << " dofs, rate " << rate);
  CHECK(rate > 1.0 - 0.15);  // p = 2
  // The estimator follows the error: their ratio stays within a factor 2 over the second half.
  const auto ratio = [&](size_t k) { return steps[k].estimator / steps[k].h1_semi; };
  CHECK(ratio(steps.size() - 1) / ratio(steps.size() / 2) < 2.0);
  CHECK(ratio(steps.size() - 1) / ratio(steps.size() / 2) > 0.5);
}

TEST_CASE("A that is not symmetric positive definite, or a negative c, is refused naming the field", "[general][bad-input]") {
  const std::string u = "exact = \"x*y\"\n";
  CHECK_THAT(refusal(u + "coefficient = \"x - 0.5\"\n"),
             Catch::StartsWith("general.toml: [problem] coefficient: the coefficient a = ") &&
                 Catch::Contains("is not positive at ("));
  CHECK_THAT(refusal(u + "coefficient = [[\"1\", \"2\"], [\"2\", \"1\"]]\n"),
             Catch::Contains("[problem] coefficient: the coefficient matrix [[1, 2], [2, 1]] is not positive definite"));
  CHECK_THAT(refusal(u + "coefficient = [[\"1\", \"x\"], [\"y\", \"1\"]]\n"),
             Catch::Contains("[problem] coefficient: not symmetric: a12 = \"x\" and a21 = \"y\" differ at"));
  CHECK_THAT(refusal(u + "coefficient = [[\"1\", \"0\"]]\n"), Catch::Contains("must be an expression (A = a I) or a symmetric 2x2"));
  CHECK_THAT(refusal(u + "reaction = \"y - 0.5\"\n"), Catch::Contains("[problem] reaction: the reaction c = ") &&
                                                         Catch::Contains("is negative"));
  CHECK_THAT(refusal(u + "reaction = -1\n"), Catch::Contains("[problem] reaction: must be >= 0"));
  CHECK_THAT(refusal(u + "coefficient = \"1 + \"\n"), Catch::Contains("[problem] coefficient"));
  // A sound one is not refused.
  CHECK(refusal(u + "coefficient = [[\"2\", \"x\"], [\"x\", \"2\"]]\nreaction = \"y\"\n").empty());
}
