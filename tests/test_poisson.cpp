#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <omp.h>
#include <Eigen/Eigenvalues>

#include "solver/fast_diagonalization.hpp"
#include "families/tensor/tensor_case.hpp"
#include "studies/pipeline.hpp"
#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "solver/error_norms.hpp"
#include "solver/linear_solver.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/sparsity.hpp"
#include "solver/separable_cells.hpp"
#include "tests/rounding_bounds.hpp"
#include "tests/solver_checks.hpp"

using namespace knotwork;

namespace {

CaseDescription shipped(const std::string& name) {
  return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
}

CaseDescription with_exact(NurbsPatch geometry, int p, int n, const std::string& u) {
  CaseDescription c;
  c.path = "test";
  c.geometry = std::move(geometry);
  c.section.emplace<PatchSpaceSection>();  // family "tensor"
  patch_space(c).degree = {p, p};
  patch_space(c).elements_per_span = {n, n};
  c.problem.exact = differentiate_exact_solution(Expression::parse(u, "test"));
  c.problem.source = c.problem.exact->minus_laplacian;
  c.problem.boundary.assign(4, BoundaryCondition{});
  return c;
}

// A curved polynomial (unit-weight) map: x(s,t) bends through the middle control point.
NurbsPatch bent_patch() {
  NurbsPatch bent;
  bent.basis_u = BSplineBasis1D(2, {0, 0, 0, 1, 1, 1});
  bent.basis_v = BSplineBasis1D(2, {0, 0, 0, 1, 1, 1});
  bent.control_points.resize(9, 2);
  bent.control_points << 0, 0, 0.5, -0.1, 1, 0, -0.1, 0.5, 0.6, 0.4, 1.1, 0.5, 0, 1, 0.5, 1.2, 1, 1;
  bent.weights.setOnes(9);
  return bent;
}

PoissonSolveOptions options_of(const CaseDescription& c) {
  PoissonSolveOptions o;
  o.quadrature = c.quadrature;
  return o;
}

// A solve that should reproduce u (a function of the space): its errors with the rounding bound
// of tests/rounding_bounds.hpp.
rounding_test::Reproduction reproduce(const CaseDescription& c) {
  const auto d = build_space(c);
  return rounding_test::solve_reproducing(d->mesh(), d->geometry(), c.problem, options_of(c));
}


ErrorNorms solve(const CaseDescription& c) {
  const auto d_space = build_space(c);
  const SplineSpace& d = *d_space;
  return *solve_poisson(d.mesh(), d.geometry(), c.problem, options_of(c)).errors;
}

struct Rates {
  double l2, h1;
};
// Observed rates between the last two of `levels` uniform refinements starting at n0.
Rates rates(CaseDescription c, int n0, int levels) {
  std::vector<ErrorNorms> e;
  std::vector<double> h;
  for (int l = 0; l < levels; ++l) {
    patch_space(c).elements_per_span = {n0 << l, n0 << l};
    const auto d_space = build_space(c);
    const SplineSpace& d = *d_space;
    e.push_back(*solve_poisson(d.mesh(), d.geometry(), c.problem, options_of(c)).errors);
    h.push_back(d.mesh_size());
  }
  const size_t a = e.size() - 2, b = e.size() - 1;
  const double lh = std::log(h[a] / h[b]);
  return {std::log(e[a].l2 / e[b].l2) / lh, std::log(e[a].h1_semi / e[b].h1_semi) / lh};
}

}  // namespace

TEST_CASE("Patch test: linear solutions are reproduced to roundoff", "[poisson]") {
  const std::string u = "1 + 2*x - 3*y";
  const NurbsPatch bent = bent_patch();
  for (int p = 2; p <= 4; ++p) {
    INFO("degree " << p);
    // Polynomial maps: grad u . grad v det J is a polynomial of degree <= 2p-1 per direction,
    // integrated exactly by the default p+1 Gauss points, so u_h = u to roundoff.
    for (const NurbsPatch& g : {lshape_patch(), bent}) REQUIRE_REPRODUCED(reproduce(with_exact(g, p, 3, u)));
    // Rational maps: the isoparametric space still contains u, but det J is rational; the
    // patch test holds up to quadrature error, which more points drive to roundoff.
    CaseDescription c = with_exact(quarter_annulus_patch(1, 2), p, 3, u);
    const ErrorNorms coarse_rule = solve(c);
    c.quadrature.points_u = c.quadrature.points_v = 16;
    const rounding_test::Reproduction fine_rule = reproduce(c);
    REQUIRE_REPRODUCED(fine_rule);
    REQUIRE(fine_rule.errors.l2 < coarse_rule.l2);
  }
  // B-splines on an affine map, with Neumann data on two sides.
  CaseDescription c = with_exact(rectangle_patch(-1, 0, 2, 1), 1, 5, u);
  patch_space(c).rational = false;
  c.problem.boundary[1].kind = BoundaryKind::kNeumann;
  c.problem.boundary[2].kind = BoundaryKind::kNeumann;
  REQUIRE_REPRODUCED(reproduce(c));
  // A quadratic polynomial is in every degree-2 space on the square.
  REQUIRE_REPRODUCED(reproduce(with_exact(rectangle_patch(0, 0, 1, 1), 2, 4, "x^2 - x*y + 0.5*y^2")));
}

TEST_CASE("Optimal convergence on the unit square, p = 1..4", "[poisson][rates]") {
  for (int p = 1; p <= 4; ++p) {
    CaseDescription c = shipped("square_sinsin");
    patch_space(c).degree = {p, p};
    patch_space(c).continuity = {-1, -1};
    const Rates r = rates(c, 8, 3);
    INFO("p = " << p << ": L2 rate " << r.l2 << ", H1 rate " << r.h1);
    REQUIRE(r.l2 >= p + 1 - 0.2);
    REQUIRE(r.h1 >= p - 0.2);
    // ... and not better than theory says: the rates are measured, not capped.
    REQUIRE(r.l2 < p + 1 + 0.3);
  }
}

TEST_CASE("Optimal convergence on the quarter annulus, p = 1..4", "[poisson][rates]") {
  for (int p = 1; p <= 4; ++p) {
    CaseDescription c = shipped("quarter_annulus");
    patch_space(c).degree = {p, p};
    patch_space(c).rational = p >= 2;  // degree 1 cannot hold the circle: B-splines on the exact geometry
    const Rates r = rates(c, 8, 3);
    INFO("p = " << p << ": L2 rate " << r.l2 << ", H1 rate " << r.h1);
    REQUIRE(r.l2 >= p + 1 - 0.2);
    REQUIRE(r.h1 >= p - 0.2);
  }
}

TEST_CASE("Mixed Dirichlet/Neumann case converges optimally", "[poisson][rates]") {
  const Rates r = rates(shipped("square_exp_sin"), 4, 3);
  REQUIRE(r.l2 >= 4 - 0.2);
  REQUIRE(r.h1 >= 3 - 0.2);
}

TEST_CASE("L-shape: uniform refinement converges in H1 like h^(2/3)", "[poisson][rates]") {
  const Rates r = rates(shipped("lshape"), 8, 4);
  INFO("H1 rate " << r.h1);
  REQUIRE(std::abs(r.h1 - 2.0 / 3.0) < 0.1);
}

TEST_CASE("Non-uniform refinement toward the L-shape corner beats uniform refinement", "[poisson][rates]") {
  CaseDescription uniform = shipped("lshape");
  patch_space(uniform).elements_per_span = {16, 16};
  const CaseDescription graded = shipped("lshape_graded");
  const auto du_space = build_space(uniform), dg_space = build_space(graded);
  const SplineSpace &du = *du_space, &dg = *dg_space;
  // u: 2 spans x 8 elements + p, +1 for the C0 fold at u = 1/2 (multiplicity p), +1 per inserted
  // knot (p - r = 1); v: 8 elements + p + 6 inserted knots.
  REQUIRE(dg.mesh().num_functions() == (2 * 8 + 2 + 1 + 12) * (8 + 2 + 6));
  REQUIRE(dg.mesh().num_functions() < du.mesh().num_functions());
  const double eu = solve(uniform).h1_semi, eg = solve(graded).h1_semi;
  INFO("uniform " << eu << ", graded " << eg);
  REQUIRE(eg < 0.5 * eu);
}

TEST_CASE("Knot-segment spaces through case files: patch test on the folded L-shape, fewer dofs than uniform", "[poisson][semi-regular]") {
  // Linear u on the L-shape is bilinear in the patch parameters (a bilinear map on each side
  // of the C0 fold), so it lies in the degree-2 knot-segment space: reproduced exactly.
  CaseDescription c = shipped("lshape_knot_segments");
  c.problem.exact = differentiate_exact_solution(Expression::parse("1 + 2*x - 3*y", "test"));
  c.problem.source = c.problem.exact->minus_laplacian;
  REQUIRE_REPRODUCED(reproduce(c));
  // The singular solution: segments toward the corner beat uniform refinement with more dofs.
  const CaseDescription local = shipped("lshape_knot_segments");
  CaseDescription uniform = shipped("lshape");
  patch_space(uniform).elements_per_span = {8, 8};
  const auto dl_space = build_space(local), du_space = build_space(uniform);
  const SplineSpace &du = *du_space, &dl = *dl_space;
  const double el = solve(local).h1_semi, eu = solve(uniform).h1_semi;
  INFO("knot segments: " << dl.mesh().num_functions() << " dofs, H1 " << el << "; uniform: "
                         << du.mesh().num_functions() << " dofs, H1 " << eu);
  REQUIRE(dl.mesh().num_functions() < du.mesh().num_functions());
  REQUIRE(el < eu);
}

TEST_CASE("Continuity option: C0 quadratics still converge optimally", "[poisson][rates]") {
  CaseDescription c = shipped("square_sinsin");
  patch_space(c).continuity = {0, 0};
  const Rates r = rates(c, 4, 3);
  REQUIRE(r.l2 >= 3 - 0.2);
  REQUIRE(r.h1 >= 2 - 0.2);
}

TEST_CASE("Analytic geometry map: polar quarter annulus with B-splines converges optimally", "[poisson][rates]") {
  // The same domain as the NURBS quarter annulus, but parametrized by angle uniformly:
  // x = (1+u) cos(pi v / 2), y = (1+u) sin(pi v / 2). The space is plain B-splines.
  const auto polar = [](double u, double v, double* x, double* J) {
    const double r = 1 + u, a = 0.5 * M_PI * v;
    x[0] = r * std::cos(a);
    x[1] = r * std::sin(a);
    J[0] = std::cos(a);
    J[1] = -0.5 * M_PI * r * std::sin(a);
    J[2] = std::sin(a);
    J[3] = 0.5 * M_PI * r * std::cos(a);
  };
  for (int p = 1; p <= 3; ++p) {
    CaseDescription c = with_exact(rectangle_patch(0, 0, 1, 1), p, 4, "-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2");
    patch_space(c).rational = false;
    std::vector<ErrorNorms> e;
    for (int n : {8, 16}) {
      patch_space(c).elements_per_span = {n, n};
      const auto d_space = build_space(c);
      const SplineSpace& d = *d_space;
      const AnalyticGeometryMap g(d.mesh(), polar);
      e.push_back(*solve_poisson(d.mesh(), g, c.problem, options_of(c)).errors);
    }
    const double l2_rate = std::log2(e[0].l2 / e[1].l2), h1_rate = std::log2(e[0].h1_semi / e[1].h1_semi);
    INFO("p = " << p << ": L2 rate " << l2_rate << ", H1 rate " << h1_rate);
    REQUIRE(l2_rate >= p + 1 - 0.2);
    REQUIRE(h1_rate >= p - 0.2);
  }
}

TEST_CASE("A solver kept across solves on one mesh skips the second analysis", "[poisson][solver]") {
  CaseDescription c = shipped("square_sinsin");
  const auto d_space = build_space(c);
  const SplineSpace& d = *d_space;
  PoissonSolveOptions o = options_of(c);
  o.solver = std::make_shared<SparseCholesky>();
  const PoissonSolution first = solve_poisson(d.mesh(), d.geometry(), c.problem, o);
  c.problem.source = Expression::parse("1", "test");  // another load, same matrix pattern
  c.problem.exact.reset();
  for (auto& bc : c.problem.boundary) {
    bc.from_exact = false;
    bc.value = Expression::parse("0", "test");
  }
  const PoissonSolution second = solve_poisson(d.mesh(), d.geometry(), c.problem, o);
  REQUIRE(first.cholesky.analyses == 1);
  REQUIRE(second.cholesky.analyses == 1);
  REQUIRE(second.timings.analysis == 0);
  REQUIRE(first.timings.analysis > 0);
  // The second solution is right too: -Laplace(u) = 1 with u = 0 on the unit square has
  // u(1/2, 1/2) = 0.0736713... (Fourier series); the centre is the top-right corner of cell
  // (7, 7) of the 16 x 16 mesh.
  Eigen::VectorXd one(1);
  one << 1.0;
  const double centre = evaluate_solution(d.mesh(), d.geometry(), second.coefficients, 7 + 16 * 7, one, one)(0, 0);
  REQUIRE(centre == Approx(0.0736713).epsilon(1e-4));
}

TEST_CASE("CHOLMOD reuses the symbolic analysis while the pattern stays", "[poisson][solver]") {
  const int n = 50;
  Eigen::SparseMatrix<double> A(n, n);  // lower triangle of a tridiagonal SPD matrix
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 4.0);
    if (i + 1 < n) t.emplace_back(i + 1, i, -1.0);
  }
  A.setFromTriplets(t.begin(), t.end());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1, 2);
  for (Ordering o : {Ordering::kAmd, Ordering::kMetis, Ordering::kNesdis}) {
    SparseCholesky chol(o);
    chol.factorize(A);
    Eigen::VectorXd x = chol.solve(b);
    const Eigen::SparseMatrix<double> full = A.selfadjointView<Eigen::Lower>();
    REQUIRE((full * x - b).norm() < 1e-12);
    A *= 2.0;  // new values, same pattern
    chol.factorize(A);
    REQUIRE(chol.stats().analyses == 1);
    x = chol.solve(b);
    REQUIRE((Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Lower>()) * x - b).norm() < 1e-12);
    A /= 2.0;
  }
  Eigen::SparseMatrix<double> bad = A;
  bad.coeffRef(3, 3) = -10;
  SparseCholesky chol;
  REQUIRE_THROWS_WITH(chol.factorize(bad), Catch::Contains("not positive definite"));
}

TEST_CASE("A numerically singular matrix is refused, a well-conditioned one refined", "[poisson][solver]") {
  // The 1D Laplacian (tridiagonal 2, -1) plus eps * I: its smallest eigenvalue is
  // eps + 4 sin^2(pi / (2 (n + 1))) ~ 1e-5 for n = 400, so the condition number is about
  // 4e5 and the refinement correction about 1e-11.
  const int n = 400;
  auto laplacian = [&](double shift, double coupling) {
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n; ++i) {
      t.emplace_back(i, i, 2.0 + shift);
      if (i + 1 < n) t.emplace_back(i + 1, i, -coupling);
    }
    Eigen::SparseMatrix<double> A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
  };
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
  SparseCholesky good;
  good.factorize(laplacian(0, 1));
  const Eigen::VectorXd x = good.solve(b);
  REQUIRE(good.stats().refinement_correction < 1e-8);
  Eigen::SparseMatrix<double> full = laplacian(0, 1);
  full = Eigen::SparseMatrix<double>(full.selfadjointView<Eigen::Lower>());
  REQUIRE((full * x - b).norm() <= 1e-10 * b.norm());

  // The Gram matrix of 4 vectors in R^6 of which the last two differ by delta in a
  // direction of their own (plus the identity on the other unknowns). Measured: at delta =
  // 1e-5 the eigenvalue ratio is 6.5e-13 and the correction 1.7e-10; at delta = 1e-7 the
  // ratio is 1.0e-16, CHOLMOD still factors it, and the correction is 0.28.
  auto gram = [&](double delta) {
    Eigen::MatrixXd B(6, 4);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 3; ++c) B(r, c) = std::sin(1.0 + c + (1.3 + 0.7 * c) * r);
    for (int r = 0; r < 6; ++r) B(r, 3) = B(r, 2) + delta * std::cos(0.3 + 2.1 * r);
    const Eigen::MatrixXd G = B.transpose() * B;
    std::vector<Eigen::Triplet<double>> t;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c <= r; ++c) t.emplace_back(r, c, G(r, c));
    for (int i = 4; i < n; ++i) t.emplace_back(i, i, 1.0);
    Eigen::SparseMatrix<double> A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
  };
  SparseCholesky ill;
  ill.factorize(gram(1e-5));
  REQUIRE_NOTHROW(ill.solve(b));
  REQUIRE(ill.stats().refinement_correction < 1e-6);
  SparseCholesky bad;
  REQUIRE_NOTHROW(bad.factorize(gram(1e-7)));
  const Eigen::VectorXd& rhs = b;
  REQUIRE_THROWS_WITH(bad.solve(rhs), Catch::Contains("numerically singular"));
}

TEST_CASE("Threaded results are bitwise reproducible run to run, and error norms whatever the threads", "[poisson]") {
  // Cells are shared among threads in a fixed way and sums run in a fixed order: the same
  // solve twice gives the same bits, and the error norms of one coefficient vector do not
  // depend on the number of threads (per-cell sums added in cell order).
  const CaseDescription c =
      with_exact(quarter_annulus_patch(1, 2), 3, 12, "-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2 + sin(3*x)*cos(2*y)");
  const auto space = build_space(c);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
  const PoissonSolution a = solve_poisson(space->mesh(), space->geometry(), c.problem, options_of(c));
  const PoissonSolution b = solve_poisson(space->mesh(), space->geometry(), c.problem, options_of(c));
  REQUIRE((a.coefficients.array() == b.coefficients.array()).all());
  REQUIRE(a.errors->l2 == b.errors->l2);
  REQUIRE(a.errors->h1_semi == b.errors->h1_semi);
  std::vector<ErrorNorms> norms;
  for (int t : {1, 2, 3}) {
    omp_set_num_threads(t);
    norms.push_back(error_norms(space->mesh(), space->geometry(), a.coefficients, *c.problem.exact, c.quadrature));
  }
  omp_set_num_threads(threads);
  for (const ErrorNorms& n : norms) {
    REQUIRE(n.l2 == norms[0].l2);
    REQUIRE(n.h1_semi == norms[0].h1_semi);
  }
  REQUIRE(norms[0].l2 == a.errors->l2);
}

TEST_CASE("A rank's rows are the serial matrix's rows over its cells, whole, in PETSc's two blocks", "[poisson][mpi]") {
  // Under mpirun each rank integrates its cells straight into its rows (rank_rows_pattern);
  // the reference is the serial lower-triangle assembly over the same cells, mirrored. Both
  // add the same cell terms in the same order, so they agree to the bit; the pattern must hold
  // every entry any cell makes in an owned row (other ranks add theirs there).
  const CaseDescription c =
      with_exact(quarter_annulus_patch(1, 2), 3, 6, "-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2 + sin(3*x)*cos(2*y)");
  const auto space = build_space(c);
  const BezierMesh& mesh = space->mesh();
  std::vector<bool> fixed;
  const Eigen::VectorXd g = project_dirichlet_data(mesh, space->geometry(), c.problem, c.quadrature, fixed);
  const DofLayout layout = make_dof_layout(mesh.num_functions(), fixed);
  const int n = layout.num_free(), nc = mesh.num_cells();
  const PoissonForm form = poisson_form(c.problem);
  // Which dofs share a cell, counted from the cells themselves.
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> coupled = Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>::Zero(n, n);
  for (int cell = 0; cell < mesh.num_cells(); ++cell)
    for (int f : mesh.functions(cell))
      for (int h : mesh.functions(cell))
        if (layout.dof[f] >= 0 && layout.dof[h] >= 0) coupled(layout.dof[f], layout.dof[h]) = true;
  std::vector<int> identity(n);
  for (int d = 0; d < n; ++d) identity[d] = d;
  const int threads = omp_get_max_threads();
  for (const int t : {1, 2})
    for (const int ranks : {1, 2, 3})
      for (int rank = 0; rank < ranks; ++rank) {
        omp_set_num_threads(t);
        const CellRange cells{nc * rank / ranks, nc * (rank + 1) / ranks};
        const int first = n * rank / ranks, last = n * (rank + 1) / ranks;
        Eigen::SparseMatrix<double> K = lower_pattern_matrix(mesh, layout);
        Eigen::VectorXd serial_rhs, rows_rhs;
        assemble_poisson(mesh, space->geometry(), form, layout, g, c.quadrature, K, serial_rhs, nullptr, cells);
        const Eigen::MatrixXd lower = K;  // mirrored: the whole matrix of these cells
        const Eigen::MatrixXd F = lower + lower.transpose() - Eigen::MatrixXd(lower.diagonal().asDiagonal());
        RankRows r = rank_rows_pattern(mesh, layout, identity, first, last, cells);
        assemble_poisson(mesh, space->geometry(), form, layout, g, c.quadrature, r, rows_rhs, cells);
        omp_set_num_threads(threads);
        INFO(t << " threads, rank " << rank << " of " << ranks);
        REQUIRE((rows_rhs.array() == serial_rhs.array()).all());
        REQUIRE(r.first == first);
        REQUIRE(r.last == last);
        const OwnedRows& o = r.owned;
        const double* off_values = o.values.data() + o.diagonal_nonzeros();
        const double* halo_values = o.values.data() + r.halo_offset();
        for (int i = 0; i < n; ++i) {
          // The row as a dense vector from the blocks (or the halo), and its pattern.
          Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
          std::vector<int> columns;
          if (i >= first && i < last) {
            for (int k = o.diagonal_start[i - first]; k < o.diagonal_start[i - first + 1]; ++k) {
              REQUIRE(o.diagonal_cols[k] + first >= first);
              REQUIRE(o.diagonal_cols[k] + first < last);
              columns.push_back(o.diagonal_cols[k] + first), row[o.diagonal_cols[k] + first] = o.values[k];
            }
            for (int k = o.off_start[i - first]; k < o.off_start[i - first + 1]; ++k) {
              REQUIRE((o.off_cols[k] < first || o.off_cols[k] >= last));
              columns.push_back(o.off_cols[k]), row[o.off_cols[k]] = off_values[k];
            }
            std::sort(columns.begin(), columns.end());
            // Exactly the columns any cell couples to row i (rank_rows_pattern's own blocks ascend).
            std::vector<int> expected;
            for (int j = 0; j < n; ++j)
              if (coupled(i, j)) expected.push_back(j);
            REQUIRE(columns == expected);
            REQUIRE(std::is_sorted(o.diagonal_cols.begin() + o.diagonal_start[i - first],
                                   o.diagonal_cols.begin() + o.diagonal_start[i - first + 1]));
            REQUIRE(std::is_sorted(o.off_cols.begin() + o.off_start[i - first], o.off_cols.begin() + o.off_start[i - first + 1]));
          } else {
            REQUIRE(r.halo_start[i] <= r.halo_start[i + 1]);
            for (int k = r.halo_start[i]; k < r.halo_start[i + 1]; ++k) row[r.halo_cols[k]] = halo_values[k];
          }
          // The values: the serial ones to the bit, nothing of this rank's cells left out.
          REQUIRE((row.array() == F.row(i).transpose().array()).all());
        }
      }
}

// The case solved on one space by CHOLMOD and then by CG (CG's choices in *report).
std::pair<PoissonSolution, PoissonSolution> direct_and_cg(CaseDescription c, const SplineSpace& space,
                                                          SolverReport* report) {
  c.solver.method = "direct";
  PoissonSolution direct = solve_case(c, space, Ordering::kAmd);
  c.solver.method = "iterative";
  return {std::move(direct), solve_case(c, space, Ordering::kAmd, {}, report)};
}

TEST_CASE("CG + fast diagonalization: the direct solve's errors, in iterations bounded in h and p", "[poisson][solver]") {
  // The algebraic error must not show in the discretization error: at the default backward
  // error 1e-15 the L2 and H1 errors agree with CHOLMOD's to 1e-4 (relative). The preconditioner
  // folds in the separable part of the geometry; the quarter annulus's stiffness coefficients
  // separate exactly (c11 = r(u)/r'(u) theta'(v), c22 = r'(u)/r(u) / theta'(v)), so up to the
  // element-wise sampling of the weights P is K, and CG needs a handful of iterations for
  // every h and p (it needed 38-46 with the parameter-domain Laplacian alone).
  for (int p : {2, 3, 4, 5})
    for (int n : {8, 16, 32}) {
      CaseDescription c = shipped("quarter_annulus");
      patch_space(c).degree = {p, p};
      patch_space(c).elements_per_span = {n, n};
      const auto space = build_space(c);
      SolverReport report;
      const auto [direct, cg] = direct_and_cg(c, *space, &report);
      INFO("p = " << p << ", n = " << n << ": " << cg.iterative.iterations << " iterations");
      REQUIRE(report.preconditioner == "fast_diagonalization");
      require_direct_errors(cg, direct);
      REQUIRE(cg.iterative.backward_error <= 1e-15);
      REQUIRE(cg.iterative.iterations <= 8);
    }
}

// With Nitsche's method no function is eliminated, and the univariate factors gain the 1D
// Nitsche terms at the ends whose sides are Dirichlet (NitscheEnds): P stays a tensor-product
// operator, positive definite, and close to K. Measured 8-13 iterations (5-7 with the
// projection); the bound asserts they do not grow with h or p. Without the 1D terms the
// factors are singular on the constants: PETSc's CG stopped (DIVERGED_INDEFINITE_PC), and this
// test fails on the iteration bound.
TEST_CASE("CG + fast diagonalization with Nitsche's method: the direct solve's errors in bounded iterations",
          "[poisson][solver][nitsche]") {
  for (int p : {2, 3, 5})
    for (int n : {8, 32}) {
      CaseDescription c = shipped("quarter_annulus");
      patch_space(c).degree = {p, p};
      patch_space(c).elements_per_span = {n, n};
      c.problem.dirichlet_method = DirichletMethod::kNitsche;
      c.problem.boundary[1].kind = BoundaryKind::kNeumann;  // one Neumann side: no end term there
      const auto space = build_space(c);
      SolverReport report;
      const auto [direct, cg] = direct_and_cg(c, *space, &report);
      INFO("p = " << p << ", n = " << n << ": " << cg.iterative.iterations << " iterations");
      REQUIRE(report.preconditioner == "fast_diagonalization");
      REQUIRE(cg.num_free == cg.num_functions);
      require_direct_errors(cg, direct);
      REQUIRE(cg.iterative.iterations <= 16);
    }
}

TEST_CASE("The separable fit of the geometry's coefficients reproduces separable ones", "[poisson][solver]") {
  // c(i, j) = f(i) g(j) is fitted exactly (up to rounding); a non-separable c is fitted by
  // positive factors whose product matches c in the geometric mean.
  const int nu = 5, nv = 4;
  std::vector<double> c11, c22;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      c11.push_back((1.0 + i) * std::exp(0.3 * j));
      c22.push_back(2.0 / (1.0 + i * i) + 0.1 * j * i);  // not separable
    }
  const SeparableCoefficients s = SeparableCoefficients::fit(nu, nv, c11, c22);
  double log_error = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      REQUIRE(s.a1[i] * s.b1[j] == Approx(c11[i + nu * j]).epsilon(1e-13));
      REQUIRE(s.a2[i] > 0);
      REQUIRE(s.b2[j] > 0);
      log_error += std::log(s.a2[i] * s.b2[j] / c22[i + nu * j]);
    }
  REQUIRE(std::abs(log_error) < 1e-12);  // least squares on log c: the residuals sum to zero
}

TEST_CASE("CG + BoomerAMG serves a family without structure, and says so", "[poisson][solver]") {
  CaseDescription c = shipped("lshape_knot_segments");
  const auto space = build_space(c);
  SolverReport report;
  const auto [direct, cg] = direct_and_cg(c, *space, &report);
  c.solver.method = "iterative";
  REQUIRE(report.preconditioner == "boomeramg");
  REQUIRE(report.note.find("boomeramg") != std::string::npos);
  require_direct_errors(cg, direct);
  c.solver.preconditioner = "jacobi";
  const PoissonSolution jacobi = solve_case(c, *space, Ordering::kAmd, {}, &report);
  REQUIRE(report.preconditioner == "jacobi");
  REQUIRE(report.note.empty());
  REQUIRE(jacobi.errors->h1_semi == Approx(direct.errors->h1_semi).epsilon(1e-4));
  c.solver.preconditioner = "fast_diagonalization";
  REQUIRE_THROWS_WITH(solve_case(c, *space, Ordering::kAmd), Catch::Contains("does not apply to family"));
}

TEST_CASE("BoomerAMG iterations stay bounded as h shrinks, Jacobi's grow like 1/h", "[poisson][solver]") {
  // Multigrid theory: a count independent of h for the Laplacian; diagonal scaling leaves the
  // condition number ~ h^-2, so CG needs ~ 1/h iterations (doubling per halving of h).
  CaseDescription c = shipped("lshape_knot_segments");
  c.solver.method = "iterative";
  c.solver.tolerance = 1e-10;  // away from the rounding floor, where counts are clean
  c.solver.max_iterations = 5000;
  std::vector<int> amg, jacobi;
  for (int level = 1; level < 4; ++level) {
    const auto space = build_space(c, level);
    c.solver.preconditioner = "boomeramg";
    amg.push_back(solve_case(c, *space, Ordering::kAmd).iterative.iterations);
    c.solver.preconditioner = "jacobi";
    jacobi.push_back(solve_case(c, *space, Ordering::kAmd).iterative.iterations);
  }
  INFO("BoomerAMG " << amg[0] << " " << amg[1] << " " << amg[2] << ", Jacobi " << jacobi[0] << " " << jacobi[1] << " "
                    << jacobi[2]);
  REQUIRE(*std::max_element(amg.begin(), amg.end()) <= 1.5 * *std::min_element(amg.begin(), amg.end()));
  REQUIRE(amg[2] <= 25);
  REQUIRE(jacobi[2] >= 1.6 * jacobi[1]);
}

TEST_CASE("PETSc options reach BoomerAMG, and options it does not use are refused", "[poisson][solver][bad-input]") {
  CaseDescription c = shipped("lshape_knot_segments");
  const auto space = build_space(c);
  c.solver.method = "iterative";
  c.solver.preconditioner = "boomeramg";
  c.solver.petsc_options = "-pc_hypre_boomeramg_strong_threshold 0.5 -pc_hypre_boomeramg_max_levels 3";
  REQUIRE(solve_case(c, *space, Ordering::kAmd).iterative.converged);
  c.solver.petsc_options = "-pc_hypre_boomeramg_strong_treshold 0.5";
  REQUIRE_THROWS_WITH(solve_case(c, *space, Ordering::kAmd),
                      Catch::Contains("[solver] petsc_options: -pc_hypre_boomeramg_strong_treshold: not an option"));
  c.solver.petsc_options = "pc_hypre_boomeramg_max_levels 3";
  REQUIRE_THROWS_WITH(solve_case(c, *space, Ordering::kAmd), Catch::Contains("is not a PETSc option"));
  c.solver.petsc_options = "-pc_hypre_boomeramg_max_levels many";
  REQUIRE_THROWS_WITH(solve_case(c, *space, Ordering::kAmd), Catch::Contains("[solver] petsc_options"));
}

TEST_CASE("Cells of product functions are integrated from univariate tables: the dense path's solution", "[poisson]") {
  // Tensor, knot-segment and PT functions are products f(u) g(v) on every cell (each row of
  // the extraction factors); G1 functions in general are not. The same case solved with the
  // univariate tables and with the dense C * B path on every cell agrees to rounding.
  for (const char* name : {"quarter_annulus", "lshape", "lshape_knot_segments", "square_knot_segments",
                           "lshape_adaptive_pt", "g1_three_quads", "g1_sphere_xy"}) {
    INFO(name);
    CaseDescription c = shipped(name);
    const auto space = build_space(c);
    const SeparableMesh separable(space->mesh());
    const long factored = std::count(separable.separable.begin(), separable.separable.end(), 1);
    const bool g1 = std::string(name).rfind("g1_", 0) == 0;
    if (!g1) REQUIRE(factored == space->mesh().num_distinct_extractions());
    PoissonSolveOptions dense = options_of(c), tables = options_of(c);
    dense.quadrature.separable_cells = false;
    const PoissonSolution a = solve_poisson(space->mesh(), space->geometry(), c.problem, dense);
    const PoissonSolution b = solve_poisson(space->mesh(), space->geometry(), c.problem, tables);
    REQUIRE((a.coefficients - b.coefficients).norm() <= 1e-11 * a.coefficients.norm());
    REQUIRE(b.errors->l2 == Approx(a.errors->l2).epsilon(1e-9));
    REQUIRE(b.errors->h1_semi == Approx(a.errors->h1_semi).epsilon(1e-9));
  }
}

TEST_CASE("A row of an extraction matrix factors exactly when it is a product", "[poisson]") {
  Eigen::MatrixXd cu(3, 3), cv(2, 2);
  cu << 1, 0.5, 0.25, 0, 0.5, 0.5, 0, 0, 0.25;
  cv << 0.7, 0.3, 0, 1;
  Eigen::MatrixXd C(6, 6);  // rows a_u + 3 a_v, columns b_u + 3 b_v
  for (int av = 0; av < 2; ++av)
    for (int au = 0; au < 3; ++au)
      for (int bv = 0; bv < 2; ++bv)
        for (int bu = 0; bu < 3; ++bu) C(au + 3 * av, bu + 3 * bv) = cu(au, bu) * cv(av, bv);
  SeparableExtraction rows;
  REQUIRE(factor_separable(C, 2, 1, rows));
  for (int a = 0; a < 6; ++a)
    for (int bv = 0; bv < 2; ++bv)
      for (int bu = 0; bu < 3; ++bu) REQUIRE(rows.u(a, bu) * rows.v(a, bv) == Approx(C(a, bu + 3 * bv)).margin(1e-15));
  C(4, 0) += 1e-6;  // a sum of two products is not one
  REQUIRE_FALSE(factor_separable(C, 2, 1, rows));
}

// Nitsche's method is consistent: the exact solution satisfies the discrete equations, so a
// solution in the space is reproduced to roundoff, whatever the penalty. A wrong sign or a
// missing boundary term breaks this (the projection is exact here too, so it is no witness).
TEST_CASE("Nitsche's method: solutions in the space are reproduced to roundoff", "[poisson][nitsche]") {
  const NurbsPatch bent = bent_patch();
  for (int p = 2; p <= 4; ++p)
    for (double penalty : {1.01, 2.0, 50.0}) {
      INFO("degree " << p << ", penalty factor " << penalty);
      for (const NurbsPatch& g : {lshape_patch(), bent}) {
        CaseDescription c = with_exact(g, p, 3, "1 + 2*x - 3*y");
        c.problem.dirichlet_method = DirichletMethod::kNitsche;
        c.problem.nitsche_penalty = penalty;
        REQUIRE_REPRODUCED(reproduce(c));
      }
      // A quadratic on the square, Dirichlet by Nitsche on two sides and Neumann on the others.
      CaseDescription c = with_exact(rectangle_patch(-1, 0, 2, 1), p, 4, "x^2 - x*y + 0.5*y^2 + 3");
      patch_space(c).rational = false;
      c.problem.dirichlet_method = DirichletMethod::kNitsche;
      c.problem.nitsche_penalty = penalty;
      c.problem.boundary[1].kind = BoundaryKind::kNeumann;
      c.problem.boundary[2].kind = BoundaryKind::kNeumann;
      REQUIRE_REPRODUCED(reproduce(c));
    }
}

// Theory (Nitsche 1971; for splines Embar, Dolbow, Harari 2010): with a penalty above the
// inverse-inequality bound the method converges at the optimal rates, h^(p+1) in L2 and h^p in
// H1, with data that do not vanish on the boundary.
TEST_CASE("Nitsche's method converges optimally on the quarter annulus, p = 1..4", "[poisson][nitsche][rates]") {
  for (int p = 1; p <= 4; ++p) {
    CaseDescription c = shipped("quarter_annulus");
    patch_space(c).degree = {p, p};
    patch_space(c).rational = p >= 2;
    c.problem.dirichlet_method = DirichletMethod::kNitsche;
    const Rates r = rates(c, 8, 3);
    INFO("p = " << p << ": L2 rate " << r.l2 << ", H1 rate " << r.h1);
    REQUIRE(r.l2 >= p + 1 - 0.2);
    REQUIRE(r.h1 >= p - 0.2);
  }
}

// The penalty on each boundary cell is factor * 2 lambda, lambda the largest ratio of the
// squared normal derivative on the cell's Dirichlet sides to the squared gradient over the
// cell. Above factor 1 the form is coercive: the matrix is positive definite. The bound must
// also not be loose by orders of magnitude: far below it the form is indefinite (the symmetric
// consistency terms win), which is what the eigenvalue estimate is for.
TEST_CASE("Nitsche's penalty: positive definite above the local bound, indefinite far below it", "[poisson][nitsche]") {
  for (int p : {2, 4}) {
    auto smallest_eigenvalue = [&](double factor) {
      CaseDescription c = with_exact(quarter_annulus_patch(1, 2), p, 3, "x*y");
      c.problem.dirichlet_method = DirichletMethod::kNitsche;
      c.problem.nitsche_penalty = factor;
      const auto d_space = build_space(c);
      PoissonSolveOptions o = options_of(c);
      Eigen::MatrixXd K;
      o.on_system = [&](const Eigen::SparseMatrix<double>& lower, const Eigen::VectorXd&) {
        K = Eigen::MatrixXd(Eigen::SparseMatrix<double>(lower.selfadjointView<Eigen::Lower>()));
      };
      try {
        solve_poisson(d_space->mesh(), d_space->geometry(), c.problem, o);
      } catch (const std::exception&) {  // an indefinite matrix may stop the Cholesky factorization
      }
      REQUIRE(K.rows() == d_space->mesh().num_functions());  // Nitsche: no function is fixed
      return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
    };
    INFO("degree " << p);
    REQUIRE(smallest_eigenvalue(1.01) > 0);
    REQUIRE(smallest_eigenvalue(0.05) < 0);
  }
}
