// First use of the G1 spaces by the Poisson pipeline (groundwork for the G1 Poisson issue):
// the geometry is itself a G1 spline (the least-squares fit of the mesh's faces), so every
// linear function of the physical coordinates lies in the discrete space and the Galerkin
// solution must reproduce it to rounding (a patch test across extraordinary vertices).
#include <catch2/catch.hpp>

#include "basis/g1/g1_basis.hpp"
#include "solver/poisson_solver.hpp"
#include "tests/g1_test_meshes.hpp"
#include "tests/rounding_bounds.hpp"

using namespace knotwork;
using namespace knotwork::test;

TEST_CASE("Poisson on a G1 space reproduces linear solutions around extraordinary vertices", "[g1][poisson]") {
  for (const auto& [m, k] : {std::pair{three_quads(), 4}, std::pair{fan(5), 4}, std::pair{fan(6), 3}}) {
    const GluingData g = symmetric_gluing(m);
    const G1Basis basis = g1_basis(m, g, k, 1);
    const BezierMesh bm = g1_bezier_mesh(m, basis);
    const Eigen::MatrixX3d fit = g1_fit_bilinear(m, basis);
    const auto control = g1_cell_bernstein(bm, fit);
    std::vector<BezierGeometryCell> cells(bm.num_cells());
    for (int c = 0; c < bm.num_cells(); ++c) {
      cells[c].degree_u = cells[c].degree_v = k;
      cells[c].points = control[c].leftCols(2);
    }
    const BezierCellsGeometryMap geometry(cells);
    // The fitted map is regular: positive Jacobian determinant at the Gauss points.
    double worst = INFINITY;
    for (int c = 0; c < bm.num_cells(); ++c) {
      GeometryAtPoints at;
      geometry.evaluate_at_rule(c, k + 1, k + 1, at);
      for (Eigen::Index i = 0; i < at.jacobian.rows(); ++i)
        worst = std::min(worst, at.jacobian(i, 0) * at.jacobian(i, 3) - at.jacobian(i, 1) * at.jacobian(i, 2));
    }
    REQUIRE(worst > 0);

    PoissonProblem problem;
    problem.exact = differentiate_exact_solution(Expression::parse("1 + 2*x - 3*y", "test"));
    problem.source = problem.exact->minus_laplacian;
    problem.boundary = {BoundaryCondition{}};  // Dirichlet from the exact solution on id 0
    INFO(m.num_faces() << " faces, k = " << k << "; min det J " << worst);
    REQUIRE_REPRODUCED(rounding_test::solve_reproducing(bm, geometry, problem));
  }
}
