// The residual estimator on hexahedra (solver/residual_estimator_volume.cpp) and what it stands
// on: the volume map's second derivatives, the face pieces two cells share, the flux jump of a
// known function, the estimator's silence where u_h is exact, and its rate under refinement.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "cases/spline_space.hpp"
#include "rounding_bounds.hpp"
#include "solver/error_norms.hpp"
#include "solver/residual_estimator.hpp"
#include "studies/pipeline.hpp"

using namespace knotwork;

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

CaseDescription volume_case(const std::string& geometry, const std::string& space, const std::string& problem) {
  return load_case_text("[geometry]\n" + geometry + "\n[space]\n" + space + "\n[problem]\n" + problem, "volume.toml");
}

std::string block_file() { return "file = \"" + std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/distorted_block.xml\""; }

}  // namespace

TEST_CASE("Second derivatives of a NURBS volume agree with finite differences", "[volume][estimator]") {
  // The thick quarter annulus is rational: the quotient rule's terms all enter. Central
  // differences with step h err by O(h^2) (truncation) plus O(eps/h^2) (rounding): with
  // h = 1e-4 and coordinates of size 2, about 1e-8 and 4e-8, far inside the margin 1e-5.
  const NurbsVolume volume = thick_quarter_annulus_volume(1.0, 2.0, 1.5);
  BezierMesh mesh;
  BezierCell cell;
  cell.dimension = 3, cell.degree_w = 1;
  cell.u0 = 0.2, cell.u1 = 0.7, cell.v0 = 0.1, cell.v1 = 0.4, cell.w0 = 0.3, cell.w1 = 0.9;
  const int ids[1] = {0};
  mesh.add_cell(cell, ids, mesh.add_extraction(Eigen::MatrixXd::Ones(1, 8)));
  const VolumeGeometryMap map(mesh, volume);
  const double h = 1e-4;
  const double at[3] = {0.31, 0.58, 0.77};
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      // f(+e_a +e_b) - f(+e_a -e_b) - f(-e_a +e_b) + f(-e_a -e_b) = 4 h^2 f_ab (a != b); f_aa from three points.
      Eigen::VectorXd pts[3] = {Eigen::VectorXd(5), Eigen::VectorXd(5), Eigen::VectorXd(5)};
      const double sa[5] = {0, 1, 1, -1, -1}, sb[5] = {0, 1, -1, 1, -1};
      for (int k = 0; k < 5; ++k)
        for (int d = 0; d < 3; ++d) pts[d][k] = at[d] + h * ((d == a ? sa[k] : 0) + (d == b ? sb[k] : 0));
      GeometryAtPoints g;
      map.evaluate_volume(0, pts[0], pts[1], pts[2], g);
      Eigen::MatrixXd second;
      REQUIRE(map.volume_second_derivatives(0, pts[0].head(1), pts[1].head(1), pts[2].head(1), second));
      const int column = a == 0 ? b : a == 1 ? 2 + b : 5;  // uu uv uw vv vw ww
      for (int i = 0; i < 3; ++i) {
        double fd;
        if (a == b) {
          // Points 1 and 4 are at +2h and -2h along a: (f(2h) - 2 f + f(-2h)) / (4 h^2).
          fd = (g.x(1, i) - 2 * g.x(0, i) + g.x(4, i)) / (4 * h * h);
        } else {
          fd = (g.x(1, i) - g.x(2, i) - g.x(3, i) + g.x(4, i)) / (4 * h * h);
        }
        INFO("x_" << i << ", derivative " << "uvw"[a] << "uvw"[b]);
        CHECK(second(0, 6 * i + column) == Approx(fd).margin(1e-5));
      }
    }
}

TEST_CASE("Hexahedra meet on face pieces: whole faces on a tensor grid, one piece per overlap across a hanging face",
          "[volume][estimator]") {
  // A tensor grid of n^3 cells has 3 n^2 (n - 1) interior faces, each whole on both sides.
  const CaseDescription c = volume_case("type = \"box\"", "degree = 1\nelements = [2, 3, 4]", "exact = \"0\"");
  const auto space = build_space(c);
  const std::vector<CellInterface> faces = interfaces_from_parameter_boxes(space->mesh());
  CHECK(faces.size() == size_t(1 * 3 * 4 + 2 * 2 * 4 + 2 * 3 * 3));
  for (const CellInterface& e : faces) {
    CHECK((e.a_from == 0 && e.a_to == 1 && e.a_from_t == 0 && e.a_to_t == 1));
    CHECK((e.b_from == 0 && e.b_to == 1 && e.b_from_t == 0 && e.b_to_t == 1));
    CHECK(e.side_b == (e.side_a == kSideRight ? kSideLeft : e.side_a == kSideTop ? kSideBottom : kSideFront));
  }
  // One cell [0,1]^3 against four cells [1,2] x [0,1/2 or 1/2,1] x [0,1/2 or 1/2,1]: four
  // pieces, each a quarter of the big cell's right face (v, w) and the whole left face of a small one.
  BezierMesh mesh;
  const int ids[1] = {0};
  const int x = mesh.add_extraction(Eigen::MatrixXd::Ones(1, 8));
  BezierCell big;
  big.dimension = 3, big.degree_w = 1, big.w1 = 1;
  big.boundary = {0, -1, 0, 0, 0, 0};
  mesh.add_cell(big, ids, x);
  for (int k = 0; k < 4; ++k) {
    BezierCell small = big;
    small.u0 = 1, small.u1 = 2;
    small.v0 = 0.5 * (k % 2), small.v1 = small.v0 + 0.5;
    small.w0 = 0.5 * (k / 2), small.w1 = small.w0 + 0.5;
    const int sides[6] = {k % 2 ? -1 : 0, 0, k % 2 ? 0 : -1, -1, k / 2 ? -1 : 0, k / 2 ? 0 : -1};
    for (int s = 0; s < 6; ++s) small.boundary[s] = static_cast<std::int16_t>(sides[s]);
    mesh.add_cell(small, ids, x);
  }
  const std::vector<CellInterface> pieces = interfaces_from_parameter_boxes(mesh);
  int across = 0;
  double area = 0;
  for (const CellInterface& e : pieces) {
    if (e.cell_a != 0) continue;  // the small cells' faces among themselves
    ++across;
    CHECK(e.side_a == kSideRight);
    CHECK(e.side_b == kSideLeft);
    const BezierCell& s = mesh.cell(e.cell_b);
    CHECK(e.a_from == s.v0);  // big's face coordinates are v and w in [0, 1]
    CHECK(e.a_to == s.v1);
    CHECK(e.a_from_t == s.w0);
    CHECK(e.a_to_t == s.w1);
    CHECK((e.b_from == 0 && e.b_to == 1 && e.b_from_t == 0 && e.b_to_t == 1));
    area += (e.a_to - e.a_from) * (e.a_to_t - e.a_from_t);
  }
  CHECK(across == 4);
  CHECK(area == 1.0);
  CHECK(pieces.size() == 4 + 4);  // and the small cells meet each other on four faces
}

TEST_CASE("The face jumps of a hat function equal their integral by hand", "[volume][estimator]") {
  // Trilinear elements on [0,1]^3 with 2 cells per direction, u_h the hat function of the
  // centre: on each cell a product of three linear factors, harmonic (no interior residual).
  // Across the face x = 1/2, y, z in [0, 1/2], its gradient jumps by 16 y z in x only, so
  // int |jump|^2 = 256 (int_0^1/2 y^2 dy)^2 = 4/9 on each of the 12 interior faces, each of
  // diameter sqrt(2)/2: the jump part is 12 (sqrt(2)/2)(4/9) = 8 sqrt(2)/3. The estimator's
  // face rule (3 x 3 points) integrates the quartic exactly; the sums are of a few hundred
  // positive terms, each a few dozen roundings of O(1) numbers: 1e3 eps relative bounds them.
  const CaseDescription c = volume_case("type = \"box\"", "degree = 1\nelements = 2", "exact = \"0\"");
  const auto space = build_space(c);
  const BezierMesh& mesh = space->mesh();
  REQUIRE(mesh.num_functions() == 27);
  // The centre's function: the one worth 1 at the centre, which is corner (1,1,1) of cell 0.
  int centre = -1;
  for (int f : mesh.functions(0)) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(27);
    e[f] = 1;
    const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
    if (std::abs(evaluate_volume_solution(mesh, space->geometry(), e, 0, one, one, one)(0, 0) - 1) < 1e-14) centre = f;
  }
  REQUIRE(centre >= 0);
  Eigen::VectorXd hat = Eigen::VectorXd::Zero(27);
  hat[centre] = 1;
  const ErrorIndicators ind = residual_indicators(mesh, space->geometry(), hat, c.problem);
  const double expected = 8 * std::sqrt(2.0) / 3;
  CHECK(std::abs(ind.jump_part - expected) <= 1e3 * kEps * expected);
  CHECK(ind.residual_part <= 1e3 * kEps * expected);
  CHECK(ind.neumann_part == 0);
  CHECK(ind.dirichlet_part == 0);
  // Each cell has three interior faces: half of each is its share, 3 (1/2)(sqrt(2)/2)(4/9).
  for (int cell = 0; cell < 8; ++cell) CHECK(std::abs(ind.eta_squared[cell] - expected / 8) <= 1e3 * kEps * expected);
}

TEST_CASE("The estimator on hexahedra vanishes where u_h is exact", "[volume][estimator]") {
  // u_h = u up to rounding (tests/rounding_bounds.hpp); the estimator applied to the difference is
  // at most an inverse-inequality constant times its H1 seminorm over the smallest cell: 1e3 / h
  // is the stated bound, as for the planar estimator (tests/test_adaptive.cpp).
  const auto check = [](const CaseDescription& c, double h) {
    const auto space = build_space(c);
    PoissonSolveOptions options;
    options.quadrature = c.quadrature;
    const rounding_test::Reproduction r = rounding_test::solve_reproducing(space->mesh(), space->geometry(), c.problem, options);
    REQUIRE_REPRODUCED(r);
    const double bound = 1e3 / h * r.h1_bound();
    const ErrorIndicators ind = residual_indicators(space->mesh(), space->geometry(), r.coefficients, c.problem);
    INFO("eta " << std::sqrt(ind.total()) << " (bound " << bound << "), residual " << ind.residual_part << ", jumps "
                << ind.jump_part << ", Neumann " << ind.neumann_part << ", Dirichlet " << ind.dirichlet_part);
    CHECK(std::sqrt(ind.total()) <= bound);
    CHECK(ind.max_gradient_jump <= bound);
  };
  SECTION("a triquadratic u on the cube, Neumann data on two faces") {
    // In the space of degree 2; -Laplace u = -2y + 2 is the source; C1 across every face.
    check(volume_case("type = \"box\"", "degree = 2\nelements = 3",
                      "exact = \"x^2*y - z^2 + 3*x*y*z\"\nneumann = [\"2\", \"6\"]"), 1.0 / 3);
  }
  SECTION("the same with Nitsche's method, whose trace is u's too") {
    check(volume_case("type = \"box\"", "degree = 2\nelements = 3",
                      "exact = \"x^2*y - z^2 + 3*x*y*z\"\ndirichlet_method = \"nitsche\""), 1.0 / 3);
  }
  SECTION("a linear u on the distorted block: the map's Hessian must cancel u_h's") {
    // u o F is in the B-spline space (tests/test_volume_files.cpp, the patch test); its
    // reference Hessian is the map's Hessian applied to grad u, which the estimator subtracts.
    check(volume_case(block_file(), "degree = 2\nelements = 2\nquadrature_points = 12", "exact = \"1 + x - 2*y + 3*z\""), 0.5);
  }
}

TEST_CASE("The estimator on hexahedra falls with the H1 error at the rate h^p", "[volume][estimator]") {
  // For a smooth u the residual estimator is equivalent to the H1-seminorm error (reliable and
  // efficient up to oscillation, which is of higher order): both fall like h^p, and their ratio
  // settles. Checked on the cube and on the curved thick quarter annulus with Neumann faces
  // (B-splines on the NURBS volume: the estimator needs a polynomial space).
  struct Run {
    std::string geometry, space, problem;
  };
  const Run runs[] = {
      {"type = \"box\"", "degree = 2", "exact = \"sin(pi*x)*sin(pi*y)*sin(pi*z)\""},
      {"type = \"box\"", "degree = 3", "exact = \"sin(pi*x)*sin(pi*y)*sin(pi*z)\""},
      {"type = \"thick_quarter_annulus\"", "degree = 2\nrational = false",
       "exact = \"sin(x)*exp(y/2)*cos(z)\"\nneumann = [\"right\", \"back\"]"},
  };
  for (const Run& run : runs) {
    double eta[3], error[3];
    const int n[3] = {2, 4, 8};
    for (int level = 0; level < 3; ++level) {
      const CaseDescription c = volume_case(run.geometry, run.space + "\nelements = " + std::to_string(n[level]), run.problem);
      const auto space = build_space(c);
      const PoissonSolution s = solve_case(c, *space, Ordering::kAmd, {});
      const ErrorIndicators ind = residual_indicators(space->mesh(), space->geometry(), s.coefficients, c.problem);
      eta[level] = std::sqrt(ind.total());
      error[level] = s.errors->h1_semi;
    }
    const int p = run.space.find("degree = 3") != std::string::npos ? 3 : 2;
    const double eta_rate = std::log2(eta[1] / eta[2]), error_rate = std::log2(error[1] / error[2]);
    INFO(run.geometry << ", p = " << p << ": eta " << eta[0] << " " << eta[1] << " " << eta[2] << " (rate " << eta_rate
                      << "), |e|_1 " << error[0] << " " << error[1] << " " << error[2] << " (rate " << error_rate << ")");
    // The rates within 0.25 of p (pre-asymptotic at 8^3), and the ratio eta / |e|_1 settled:
    // it changes by less than a quarter from 4^3 to 8^3, and eta bounds the error (reliability
    // with a constant of order one) without overestimating it by more than 50.
    CHECK(eta_rate >= p - 0.25);
    CHECK(error_rate >= p - 0.25);
    const double ratio_4 = eta[1] / error[1], ratio_8 = eta[2] / error[2];
    CHECK(std::abs(ratio_8 / ratio_4 - 1) < 0.25);
    CHECK(ratio_8 > 1);
    CHECK(ratio_8 < 50);
  }
}

TEST_CASE("The estimator on hexahedra refuses a rational space", "[volume][estimator]") {
  const CaseDescription c = volume_case("type = \"thick_quarter_annulus\"", "degree = 2\nelements = 2", "exact = \"x\"");
  const auto space = build_space(c);
  REQUIRE(space->mesh().is_rational());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(space->mesh().num_functions());
  CHECK_THROWS_WITH(residual_indicators(space->mesh(), space->geometry(), zero, c.problem),
                    Catch::Contains("polynomial (non-rational) space"));
}
