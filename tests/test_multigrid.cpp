// The tensor-product multigrid preconditioner (solver/tensor_multigrid): its hierarchy, and CG
// with it reaching the direct solve's errors in iteration counts bounded in h and p, on maps
// whose coefficients separate (the quarter annulus) and on one where they do not (the L-shape
// patch, where the fast diagonalization needs three times as many).
#include <catch2/catch.hpp>
#include <unsupported/Eigen/KroneckerProduct>
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "basis/tensor/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "cases/spline_space.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "families/tensor/tensor_case.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/tensor_multigrid.hpp"
#include "solver/tensor_operator.hpp"
#include "solver/tensor_rediscretize.hpp"
#include "studies/pipeline.hpp"
#include "studies/studies.hpp"
#include "tests/solver_checks.hpp"

using namespace knotwork;

namespace {

CaseDescription shipped(const std::string& name) {
  return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
}

}  // namespace

TEST_CASE("halved_basis drops every other breakpoint and keeps a sub-space", "[multigrid]") {
  // A graded open knot vector with a double knot at an even breakpoint: it survives halving.
  const BSplineBasis1D fine(3, {0, 0, 0, 0, 0.1, 0.25, 0.4, 0.5, 0.5, 0.6, 0.8, 0.9, 1, 1, 1, 1});
  BSplineBasis1D coarse;
  REQUIRE(halved_basis(fine, coarse));
  REQUIRE(coarse.knots() == std::vector<double>{0, 0, 0, 0, 0.25, 0.5, 0.5, 0.8, 1, 1, 1, 1});
  // Nested: the coarse functions are combinations of fine ones (refinement_matrix refuses
  // otherwise), and the combination is a partition of unity's (rows sum to 1).
  const Eigen::MatrixXd T = Eigen::MatrixXd(refinement_matrix(coarse, fine));
  REQUIRE((T.rowwise().sum().array() - 1).abs().maxCoeff() < 1e-14);
  // An odd number of elements has no coarser level of this hierarchy.
  REQUIRE_FALSE(halved_basis(BSplineBasis1D::open_uniform(2, 0, 1, 5), coarse));
  REQUIRE_FALSE(halved_basis(BSplineBasis1D::open_uniform(2, 0, 1, 1), coarse));
}

// Built through the space's own hook with a deep hierarchy (coarsest level of at most 40 dofs)
// so that h-robustness is tested over many levels, not one coarse solve.
TEST_CASE("Multigrid CG: iterations bounded in h and p over deep hierarchies", "[multigrid][solver]") {
  for (const char* name : {"quarter_annulus", "lshape"}) {
    std::map<int, std::vector<int>> iterations;  // per degree, over n
    for (int p : {2, 4, 6})
      for (int n : {32, 64, 128}) {
        CaseDescription c = shipped(name);
        patch_space(c).degree = {p, p};
        patch_space(c).elements_per_span = {n, n};
        const TensorDiscretization d = build_tensor_discretization(c.geometry, patch_space(c));
        const PatchGeometryMap map(d.mesh, d.patch, PatchGeometryMap::ElementGrid{d.space_u.breakpoints(), d.space_v.breakpoints(), d.first_row});
        const SeparableCoefficients weights = patch_separable_coefficients(d, map);
        const auto space = build_space(c);
        PoissonSolveOptions o;
        o.iterative = true;
        TensorMultigridReport report;
        o.preconditioner = [&](const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
          TensorMultigridOptions options;
          options.coarsest_functions = 40;
          options.block = 8;  // (max(8, 2p + 2)) smaller than the finest levels: no block is the whole domain
          return tensor_multigrid(d.space_u, d.space_v, layout, lower, weights, {}, options, &report);
        };
        const PoissonSolution s = solve_poisson(space->mesh(), space->geometry(), c.problem, o);
        INFO(name << ", p = " << p << ", n = " << n << ": " << s.iterative.iterations << " iterations, "
                  << report.free_dofs.size() << " levels");
        REQUIRE(s.iterative.converged);
        REQUIRE(report.free_dofs.size() >= 3);
        REQUIRE(report.free_dofs.back() <= 40 * 4);
        iterations[p].push_back(s.iterative.iterations);
      }
    // Measured (blocks of 8 and 14 functions): 6, 8-9, 12-13 on the quarter annulus and 11,
    // 12-13, 19 on the L-shape for p = 2, 4, 6, the same for n = 32, 64, 128.
    require_bounded_in_h_and_p(name, iterations, 24);
  }
}

// The production path ([solver] preconditioner = "multigrid", the geometry's separable weights
// in the smoother): CG to the default backward error 1e-15 leaves the direct solve's errors
// (1e-4 relative, as for the fast diagonalization), with Dirichlet elimination and with
// Nitsche's method on three sides and a Neumann one.
TEST_CASE("CG + multigrid: the direct solve's errors", "[multigrid][solver]") {
  for (const bool nitsche : {false, true})
    for (const char* name : {"quarter_annulus", "lshape"})
      for (int p : {2, 3, 5}) {
        CaseDescription c = shipped(name);
        patch_space(c).degree = {p, p};
        patch_space(c).elements_per_span = {64, 64};
        if (nitsche) {
          c.problem.dirichlet_method = DirichletMethod::kNitsche;
          c.problem.boundary[1].kind = BoundaryKind::kNeumann;
        }
        const auto space = build_space(c);
        c.solver.method = "direct";
        const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
        c.solver.method = "iterative";
        c.solver.preconditioner = "multigrid";
        SolverReport report;
        const PoissonSolution cg = solve_case(c, *space, Ordering::kAmd, {}, &report);
        INFO(name << (nitsche ? " (Nitsche)" : "") << ", p = " << p << ": " << cg.iterative.iterations << " iterations");
        REQUIRE(report.preconditioner == "multigrid");
        require_direct_errors(cg, direct);
        REQUIRE(cg.iterative.backward_error <= 1e-15);
        REQUIRE(cg.iterative.iterations <= 20);
      }
}

// A reaction term c u, which the smoother's separable operator reads off the matrix (the
// shift; solver/tensor_multigrid.cpp): without it, c = 1000 took 126 and 146 iterations at
// 64^2, p = 2, on the quarter annulus and the L-shape; with it 5 and 11.
TEST_CASE("CG + multigrid with a reaction term: bounded, the direct solve's errors", "[multigrid][solver]") {
  for (const char* name : {"quarter_annulus", "lshape"}) {
    CaseDescription c = shipped(name);
    patch_space(c).elements_per_span = {64, 64};
    c.problem.reaction = 1000;
    const auto space = build_space(c);
    c.solver.method = "direct";
    const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
    c.solver.method = "iterative";
    c.solver.preconditioner = "multigrid";
    for (const char* matrix : {"assembled", "matrix_free"}) {
      c.solver.matrix = matrix;
      const PoissonSolution cg = solve_case(c, *space, Ordering::kAmd);
      INFO(name << ", " << matrix << ": " << cg.iterative.iterations << " iterations");
      require_direct_errors(cg, direct);
      REQUIRE(cg.iterative.iterations <= 20);
    }
  }
}

// The fast diagonalization sees only the matrix's diagonal; a reaction term enters it as the
// shift of the mass product its eigenvectors diagonalize, from the case's reaction and the
// geometry (families/tensor/patch_separable_coefficients.cpp). At 64^2, p = 2, on the quarter
// annulus and the L-shape, without a reaction CG takes 5 and 32 iterations. With c = 1000 it
// took 65 and 106 before the shift, 19 and 31 with it; with c = 1000 (1 + x^2), 101 and 123
// before, 36 and 35 with it. One shift cannot follow a reaction weight c det J / (a2 b1) that
// varies over the domain (like r^2 on the annulus, by 4; by 20 with the variable c), so the
// bound sits between the two sets of counts, not at the count without a reaction.
TEST_CASE("CG + fast diagonalization with a reaction term: bounded, the direct solve's errors", "[fast_diagonalization][solver]") {
  const std::string exact_annulus = "-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2";
  for (const char* name : {"quarter_annulus", "lshape"})
    for (const char* reaction : {"1000", "\"1000*(1+x^2)\""}) {
      // The case with the reaction (its source derived with it).
      const std::string exact = std::string(name) == "lshape" ? "(x^2+y^2)^(1/3)*sin(2/3*(atan2(-y,-x)+pi))" : exact_annulus;
      CaseDescription c = load_case_text("[geometry]\ntype = \"" + std::string(name) + "\"\n[space]\ndegree = 2\nelements = 64\n[problem]\nexact = \"" +
                             exact + "\"\nreaction = " + reaction + "\n",
                         "reaction.toml");
      const auto space = build_space(c);
      c.solver.method = "direct";
      const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
      c.solver.method = "iterative";
      SolverReport report;
      const PoissonSolution cg = solve_case(c, *space, Ordering::kAmd, {}, &report);
      INFO(name << ", reaction " << reaction << ": " << cg.iterative.iterations << " iterations");
      REQUIRE(report.preconditioner == "fast_diagonalization");
      require_direct_errors(cg, direct);
      REQUIRE(cg.iterative.iterations <= 45);
    }
}

// Where the fast diagonalization (the automatic choice) is far from the operator, the run says
// which preconditioner keeps CG bounded; where it is exact (a separable map), it says nothing.
TEST_CASE("Many CG iterations with the fast diagonalization name multigrid in a note", "[multigrid][solver]") {
  for (const char* name : {"lshape", "quarter_annulus"}) {
    CaseDescription c = shipped(name);
    patch_space(c).elements_per_span = {48, 48};
    c.solver.method = "iterative";
    const auto space = build_space(c);
    SolverReport report;
    const PoissonSolution s = solve_case(c, *space, Ordering::kAmd, {}, &report);
    INFO(name << ": " << s.iterative.iterations << " iterations, note: " << report.note);
    REQUIRE(report.preconditioner == "fast_diagonalization");
    if (std::string(name) == "lshape") {
      REQUIRE(s.iterative.iterations > 15);
      REQUIRE(report.note.find("preconditioner = \"multigrid\"") != std::string::npos);
    } else {
      REQUIRE(s.iterative.iterations <= 15);
      REQUIRE(report.note.empty());
    }
  }
}

// ---- Without a matrix: the operator on the halved spaces, its matrix read back by probing,
// the block residuals from the elements that touch a block, and the V-cycle they make.

namespace {

struct Patch {
  CaseDescription c;
  TensorDiscretization d;
  Eigen::VectorXd weights;
  TensorPatch patch() const { return {&d.space_u, &d.space_v, &weights, &d.geometry_u, &d.geometry_v, &d.geometry_homogeneous}; }
};

Patch patch_of(const std::string& name, int p, int nu, int nv) {
  Patch s;
  s.c = shipped(name);
  patch_space(s.c).degree = {p, p};
  patch_space(s.c).elements_per_span = {nu, nv};
  s.d = build_tensor_discretization(s.c.geometry, patch_space(s.c));
  if (s.d.mesh.is_rational()) s.weights = s.d.mesh.weights();
  return s;
}

// A bound on the rounding of sums of the same products in other orders: m = 8 (2p+1)^2 (p+1)^4
// terms of size at most |K|_inf |x|_inf (as in tests/test_tensor_operator.cpp).
double rounding_bound(int p, double size) {
  return 8.0 * (2 * p + 1) * (2 * p + 1) * std::pow(p + 1, 4) * 2.2e-16 * size;
}

}  // namespace

TEST_CASE("Matrix-free operator: rows of a box, the whole matrix by probing", "[multigrid][tensor_operator]") {
  for (const char* name : {"square_sinsin", "quarter_annulus"})
    for (int p : {2, 3}) {
      const Patch s = patch_of(name, p, 9, 12);
      const TensorPoissonOperator A(s.patch(), 1.0, 0.3);
      const int nu = s.d.space_u.num_functions(), nv = s.d.space_v.num_functions();
      // The interior functions, as under Dirichlet conditions on every side.
      const TensorPoissonOperator::FunctionBox free{1, nu - 2, 1, nv - 2};
      const Eigen::VectorXd x = Eigen::VectorXd::Random(long(free.count_u) * free.count_v);
      Eigen::VectorXd whole = Eigen::VectorXd::Zero(A.num_functions()), y;
      for (int j = 0; j < free.count_v; ++j)
        for (int i = 0; i < free.count_u; ++i) whole[(1 + i) + long(nu) * (1 + j)] = x[i + long(free.count_u) * j];
      A.apply(whole, y);
      const double bound = rounding_bound(p, y.cwiseAbs().maxCoeff() + A.diagonal().maxCoeff() * (2 * p + 1) * (2 * p + 1));
      for (const TensorPoissonOperator::FunctionBox& rows :
           {TensorPoissonOperator::FunctionBox{1, 3, 1, 4}, {4, 5, 2, 7}, {1, nu - 2, nv - 3, 2}, {nu - 2, 1, 1, nv - 2}}) {
        Eigen::VectorXd r(long(rows.count_u) * rows.count_v);
        A.apply_rows(x.data(), free, rows, r.data());
        double difference = 0;
        for (int j = 0; j < rows.count_v; ++j)
          for (int i = 0; i < rows.count_u; ++i)
            difference = std::max(difference, std::abs(r[i + long(rows.count_u) * j] -
                                                        y[(rows.first_u + i) + long(nu) * (rows.first_v + j)]));
        INFO(name << ", p = " << p << ", rows at " << rows.first_u << ", " << rows.first_v << ": " << difference);
        REQUIRE(difference <= bound);
      }
      Eigen::VectorXd within(x.size());
      A.apply_within(x.data(), free, within.data());
      for (int j = 0; j < free.count_v; ++j)
        for (int i = 0; i < free.count_u; ++i)
          REQUIRE(std::abs(within[i + long(free.count_u) * j] - y[(1 + i) + long(nu) * (1 + j)]) <= bound);
      // Probing: column by column, K e_j = the product with the j-th indicator.
      const Eigen::SparseMatrix<double, Eigen::RowMajor> K = matrix_by_probing(A, free);
      REQUIRE((Eigen::VectorXd(K * x) - within).lpNorm<Eigen::Infinity>() <= bound);
      for (int k : {0, 7, int(x.size()) / 2, int(x.size()) - 1}) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(x.size()), column(x.size());
        e[k] = 1;
        A.apply_within(e.data(), free, column.data());
        REQUIRE((Eigen::VectorXd(K.col(k)) - column).lpNorm<Eigen::Infinity>() <= rounding_bound(p, A.diagonal().maxCoeff()));
      }
    }
}

TEST_CASE("Rediscretized operator: the Galerkin operator on affine elements, the same domain on curved ones",
          "[multigrid][tensor_operator]") {
  const double pi = std::acos(-1.0);
  for (const auto& [name, area] : std::vector<std::pair<const char*, double>>{{"square_sinsin", 1.0}, {"quarter_annulus", 3 * pi / 4}})
    for (int p : {2, 4}) {
      const Patch s = patch_of(name, p, 8, 12);
      const TensorPoissonOperator fine(s.patch(), 1.0, 0.0);
      const std::unique_ptr<TensorPoissonOperator> coarse = rediscretized_operator(fine, true, true);
      REQUIRE(coarse);
      REQUIRE(coarse->space_u().num_elements() == 4);
      REQUIRE(coarse->space_v().num_elements() == 6);
      // The coarse space's coordinate function x = sum (X_a / W_a) R_a (the geometry and the
      // weights moved by knot removal; on the square, whose map x = u is affine on the whole
      // patch and keeps its factors with no net, the Greville abscissae): int |grad x|^2 is the
      // domain's area, as on the fine one.
      const bool square = std::string(name) == "square_sinsin";
      REQUIRE(coarse->uniform_factors() == square);
      Eigen::VectorXd coordinate;
      if (square) {
        const BSplineBasis1D& u = coarse->space_u();
        coordinate.resize(coarse->num_functions());
        for (int j = 0; j < coarse->space_v().num_functions(); ++j)
          for (int i = 0; i < u.num_functions(); ++i) {
            double g = 0;
            for (int k = 1; k <= p; ++k) g += u.knots()[i + k] / p;
            coordinate[i + long(u.num_functions()) * j] = g;
          }
      } else {
        coordinate = coarse->net().col(0).cwiseQuotient(coarse->net().col(2));
      }
      Eigen::VectorXd y;
      coarse->apply(coordinate, y);
      INFO(name << ", p = " << p << ": x^T K x = " << coordinate.dot(y));
      // (Exact rules on the square; the annulus's rational integrand to the rule's error,
      // as in tests/test_tensor_operator.cpp.)
      REQUIRE(std::abs(coordinate.dot(y) - area) <= (std::string(name) == "quarter_annulus" ? 1e-7 : 1e-12) * area);
      if (!square) continue;
      // Affine elements, exact quadrature: K_c = P^T K P for P the refinement (the spaces nest).
      REQUIRE(fine.all_elements_affine());
      const Eigen::SparseMatrix<double> Pu = refinement_matrix(coarse->space_u(), fine.space_u()),
                                        Pv = refinement_matrix(coarse->space_v(), fine.space_v());
      const Eigen::SparseMatrix<double> P = Eigen::kroneckerProduct(Pv, Pu);
      const Eigen::VectorXd xc = Eigen::VectorXd::Random(coarse->num_functions());
      Eigen::VectorXd yc, yf;
      coarse->apply(xc, yc);
      fine.apply(P * xc, yf);
      const Eigen::VectorXd galerkin = P.transpose() * yf;
      INFO("|K_c x - P^T K P x| = " << (yc - galerkin).lpNorm<Eigen::Infinity>());
      REQUIRE((yc - galerkin).lpNorm<Eigen::Infinity>() <= 16 * rounding_bound(p, fine.diagonal().maxCoeff() * 4));
    }
  // A net that does not live on the coarser elements (one interior control point moved): no
  // rediscretized level, and no multigrid without a matrix (it would have to store the matrix).
  Patch s = patch_of("square_sinsin", 2, 8, 8);
  s.d.geometry_homogeneous(5 + 10 * 5, 0) += 1e-3;
  const auto moved = std::make_shared<TensorPoissonOperator>(s.patch(), 1.0, 0.0);
  REQUIRE_FALSE(rediscretized_operator(*moved, true, true));
  const int n = moved->num_functions();
  std::vector<bool> fixed(n, false);
  for (int j = 0; j < 10; ++j)
    for (int i = 0; i < 10; ++i) fixed[i + 10 * j] = i == 0 || j == 0 || i == 9 || j == 9;
  const DofLayout layout = make_dof_layout(n, fixed);
  TensorMultigridOptions options;
  options.coarsest_functions = 10;
  REQUIRE_FALSE(tensor_multigrid(moved, layout, Eigen::VectorXd::Ones(layout.num_free()), {}, options));
}

// The V-cycle without a matrix against the assembled one, through the driver, with deep
// hierarchies: on affine elements its levels are the Galerkin ones, so CG takes the same
// iterations (one more or less: rounding); on curved ones the counts stay bounded in h and p.
// Both reach the direct solve's errors.
TEST_CASE("Multigrid without a matrix: the assembled V-cycle's iterations", "[multigrid][solver][tensor_operator]") {
  for (const char* name : {"square_sinsin", "quarter_annulus", "lshape"}) {
    std::map<int, std::vector<int>> iterations;
    for (int p : {2, 4})
      // (At p = 4 on 128^2 the square's L2 error, 9e-13, is at the rounding floor, where CG and
      // CHOLMOD differ by more than the 1e-4 require_direct_errors allows.)
      for (int n : p == 2 ? std::vector<int>{32, 64, 128} : std::vector<int>{16, 32, 64}) {
        CaseDescription c = shipped(name);
        patch_space(c).degree = {p, p};
        patch_space(c).elements_per_span = {n, n};
        const auto space = build_space(c);
        const TensorDiscretization d = build_tensor_discretization(c.geometry, patch_space(c));
        const PatchGeometryMap map(d.mesh, d.patch, PatchGeometryMap::ElementGrid{d.space_u.breakpoints(), d.space_v.breakpoints(), d.first_row});
        const SeparableCoefficients weights = patch_separable_coefficients(d, map);
        TensorMultigridOptions options;
        options.coarsest_functions = 40;
        options.block = 8;
        PoissonSolveOptions o;
        o.iterative = true;
        o.quadrature = c.quadrature;  // the L-shape's error rule, as the direct solve's
        TensorMultigridReport assembled_report, free_report;
        o.preconditioner = [&](const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
          return tensor_multigrid(d.space_u, d.space_v, layout, lower, weights, {}, options, &assembled_report);
        };
        const PoissonSolution assembled = solve_poisson(space->mesh(), space->geometry(), c.problem, o);
        std::shared_ptr<const MatrixFreePoisson> op = space->matrix_free_operator(1.0, 0.0, c.quadrature);
        REQUIRE(op);
        o.matrix_free = [op] { return op; };
        o.preconditioner = [&](const DofLayout& layout, const Eigen::SparseMatrix<double>& diagonal) {
          return tensor_multigrid(std::dynamic_pointer_cast<const TensorPoissonOperator>(op), layout, diagonal.diagonal(),
                                  weights, options, &free_report);
        };
        const PoissonSolution free = solve_poisson(space->mesh(), space->geometry(), c.problem, o);
        c.solver.method = "direct";
        const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
        INFO(name << ", p = " << p << ", n = " << n << ": " << free.iterative.iterations << " iterations without a matrix, "
                  << assembled.iterative.iterations << " with; " << free_report.free_dofs.size() << " levels, "
                  << free_report.without_matrix << " without a matrix");
        REQUIRE(free.matrix_nonzeros == 0);
        REQUIRE(free_report.free_dofs == assembled_report.free_dofs);
        REQUIRE(free_report.without_matrix == int(free_report.free_dofs.size()) - 1);
        require_direct_errors(free, direct);
        if (std::string(name) == "square_sinsin")
          REQUIRE(std::abs(free.iterative.iterations - assembled.iterative.iterations) <= 1);
        iterations[p].push_back(free.iterative.iterations);
      }
    require_bounded_in_h_and_p(name, iterations, 24);
  }
}

// "auto" takes multigrid for CG without a matrix on affine elements from 2M functions (the
// measured crossing with the fast diagonalization), and says so; below, and on curved
// elements, the fast diagonalization.
TEST_CASE("auto: multigrid without a matrix from 2M functions on affine elements", "[multigrid][solver]") {
  for (const auto& [name, n, expected] : std::vector<std::tuple<const char*, int, const char*>>{
           {"square_sinsin", 256, "fast_diagonalization"},
           {"square_sinsin", 1448, "multigrid"},  // 2 102 500 functions
           {"quarter_annulus", 1448, "fast_diagonalization"}}) {
    CaseDescription c = shipped(name);
    patch_space(c).elements_per_span = {n, n};
    const auto space = build_space(c);
    SolverReport report;
    const PoissonSolution s = solve_case(c, *space, Ordering::kAmd, {}, &report);
    INFO(name << " at " << n << "^2: " << report.preconditioner << ", " << s.iterative.iterations << " iterations; " << report.note);
    REQUIRE(report.method == "iterative");
    REQUIRE(report.preconditioner == expected);
    REQUIRE(report.matrix_free == (std::string(name) == "square_sinsin"));
    REQUIRE((report.note.find("multigrid, since CG runs without a matrix") != std::string::npos) ==
            (std::string(expected) == "multigrid"));
    REQUIRE(s.iterative.converged);
  }
}

// How far a map's (and A's) stiffness coefficients are from a product (separability_spread),
// against closed forms: 1 for the rectangle and the annulus (their coefficients are products
// of a function of u and one of v), and on the unit square with A = R diag(1, 100) R^T, R a
// rotation by 45 degrees, the best product is A's diagonal (50.5 both) and P^-1/2 A P^-1/2 =
// [1, b; b, 1] with b = 49.5 / 50.5, whose eigenvalues' ratio (1 + b) / (1 - b) is 100.
TEST_CASE("separability_spread: 1 where the coefficients separate, the closed form where they do not", "[multigrid]") {
  const double eps = 2.2e-16;
  REQUIRE(std::abs(separability_spread(rectangle_patch(0, 0, 2, 3)) - 1) <= 64 * eps);
  REQUIRE(std::abs(separability_spread(quarter_annulus_patch(1, 2)) - 1) <= 1e3 * eps);
  const std::vector<Expression> rotated{Expression::parse("50.5", "test"), Expression::parse("49.5", "test"),
                                        Expression::parse("50.5", "test")};
  REQUIRE(std::abs(separability_spread(rectangle_patch(0, 0, 1, 1), rotated) / 100 - 1) <= 1e3 * eps);
  // The scalar A = 1 + x on the square is a function of u alone: still separable.
  REQUIRE(std::abs(separability_spread(rectangle_patch(0, 0, 1, 1), {Expression::parse("1 + x", "test")}) - 1) <= 1e3 * eps);
  // A scalar A = 1 + 10 x y is not: (1 + 10 x y) against its best product over the grid.
  REQUIRE(separability_spread(rectangle_patch(0, 0, 1, 1), {Expression::parse("1 + 10*x*y", "test")}) > 1.5);
  // A map that folds, or an A that is not positive definite: no fit (the assembly refuses them).
  REQUIRE(std::isinf(separability_spread(rectangle_patch(0, 0, 1, 1), {Expression::parse("x - 0.5", "test")})));
}

// "auto" takes multigrid instead of the fast diagonalization where the map does not separate,
// from 200 000 functions (families/tensor/tensor_family.cpp, measured: docs/SOLVERS.md): the
// L-shape just below and just above, the quarter annulus above.
TEST_CASE("auto: multigrid where the map does not separate, from 200 000 functions", "[multigrid][solver]") {
  for (const auto& [name, n, expected] : std::vector<std::tuple<const char*, int, const char*>>{
           {"lshape", 300, "fast_diagonalization"},   // 182 710 functions
           {"lshape", 320, "multigrid"},              // 207 690
           {"quarter_annulus", 448, "fast_diagonalization"}}) {  // 202 500
    CaseDescription c = shipped(name);
    patch_space(c).elements_per_span = {n, n};
    const auto space = build_space(c);
    INFO(name << " at " << n << ": " << space->mesh().num_functions() << " functions");
    REQUIRE((space->mesh().num_functions() >= 200000) == (n != 300));
    SolverReport report;
    const PoissonSolution s = solve_case(c, *space, Ordering::kAmd, {}, &report);
    INFO(report.preconditioner << ", " << s.iterative.iterations << " iterations; " << report.note);
    REQUIRE(report.method == "iterative");
    REQUIRE(report.preconditioner == expected);
    REQUIRE((report.note.find("since the map does not separate") != std::string::npos) == (std::string(expected) == "multigrid"));
    REQUIRE(s.iterative.converged);
  }
}

// A study whose levels "auto" solved differently says which level took what.
TEST_CASE("converge names each run of levels' solver when they differ", "[multigrid][converge]") {
  auto level = [](const char* method, const char* preconditioner, bool matrix_free) {
    ConvergeLevel l;
    l.solver.method = method;
    l.solver.preconditioner = preconditioner;
    l.solver.matrix_free = matrix_free;
    return l;
  };
  REQUIRE(iterative_solvers_summary({level("direct", "", false)}).empty());
  REQUIRE(iterative_solvers_summary({level("direct", "", false), level("iterative", "fast_diagonalization", true),
                                     level("iterative", "fast_diagonalization", true)}) ==
          "CG + fast_diagonalization (no matrix)");
  REQUIRE(iterative_solvers_summary({level("iterative", "fast_diagonalization", true),
                                     level("iterative", "fast_diagonalization", true),
                                     level("iterative", "multigrid", true)}) ==
          "CG: fast_diagonalization (no matrix) on levels 0-1; multigrid (no matrix) on level 2");
}
