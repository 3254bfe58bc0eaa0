// The trivariate tensor multigrid (solver/tensor_multigrid_3d): its sparse building blocks
// against Eigen's products, CG with it in iteration counts bounded in h over deep hierarchies
// on a curved NURBS volume, the direct solve's errors through the pipeline (assembled, and
// without a matrix on one affine map), and the refusal of a hierarchy that does not coarsen.
// Under PETSc: tests/mpi/check_multigrid_shell.py ("mpi: multigrid shell, volume").
#include <catch2/catch.hpp>
#include <unsupported/Eigen/KroneckerProduct>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "basis/core/input_error.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "cases/spline_space.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "families/tensor/tensor_case.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/tensor_multigrid_3d.hpp"
#include "solver/tensor_multigrid_levels.hpp"
#include "studies/pipeline.hpp"
#include "tests/solver_checks.hpp"

using namespace knotwork;

namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();

CaseDescription shipped(const std::string& name) {
  return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
}

// A random matrix of n x n with entries within `band` of the diagonal.
Eigen::SparseMatrix<double> random_band(int n, int band, std::mt19937& rng) {
  std::uniform_real_distribution<double> value(-1, 1);
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i)
    for (int j = std::max(0, i - band); j <= std::min(n - 1, i + band); ++j) t.emplace_back(i, j, value(rng));
  Eigen::SparseMatrix<double> m(n, n);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

}  // namespace

TEST_CASE("Volume multigrid's blocks: the whole matrix from its triangle, P^T A P along each direction", "[multigrid][volume]") {
  using multigrid_levels::RowMatrix;
  std::mt19937 rng(7);
  const std::array<int, 3> n{7, 5, 6}, degree{2, 1, 3};
  // A symmetric matrix with the tensor pattern of functions i + n0 (j + n1 k) that couple
  // within degree[d] per direction: B_w (x) B_v (x) B_u + its transpose.
  const Eigen::SparseMatrix<double> bu = random_band(n[0], degree[0], rng), bv = random_band(n[1], degree[1], rng),
                                    bw = random_band(n[2], degree[2], rng);
  Eigen::SparseMatrix<double> B = Eigen::kroneckerProduct(bw, Eigen::kroneckerProduct(bv, bu)).eval();
  const Eigen::SparseMatrix<double> A = Eigen::SparseMatrix<double>(B.transpose()) + B;
  const Eigen::SparseMatrix<double> lower = A.triangularView<Eigen::Lower>();
  RowMatrix whole;
  multigrid_levels::whole_from_lower(lower, n[0], n[1], degree, whole);
  // Entries copied, not computed: equal.
  REQUIRE(Eigen::MatrixXd(whole) == Eigen::MatrixXd(A));
  // Q = I (x) .. P .. (x) I along each direction, against Eigen's sparse products; the sums
  // differ in order only: within (terms) eps (|Q|^T |A| |Q|) entrywise.
  for (int dir = 0; dir < 3; ++dir) {
    const int coarse = n[dir] - 2;
    Eigen::SparseMatrix<double> P = random_band(n[dir], 1, rng).leftCols(coarse);
    const RowMatrix Prow = P;
    std::array<Eigen::SparseMatrix<double>, 3> factor;
    for (int d = 0; d < 3; ++d) {
      factor[d].resize(n[d], n[d]);
      factor[d].setIdentity();
    }
    factor[dir] = P;
    const Eigen::SparseMatrix<double> Q = Eigen::kroneckerProduct(factor[2], Eigen::kroneckerProduct(factor[1], factor[0])).eval();
    const Eigen::MatrixXd expected = Eigen::MatrixXd(Q.transpose()) * Eigen::MatrixXd(A) * Eigen::MatrixXd(Q);
    const Eigen::MatrixXd scale =
        Eigen::MatrixXd(Q.cwiseAbs().transpose()) * Eigen::MatrixXd(A.cwiseAbs()) * Eigen::MatrixXd(Q.cwiseAbs());
    RowMatrix result;
    multigrid_levels::galerkin_direction(whole, n, Prow, dir, result);
    INFO("direction " << dir);
    REQUIRE(result.rows() == expected.rows());
    const double terms = 3.0 * 105 * 3;  // products per entry, at most: P column x A row (5 x 3 x 7) x P row
    REQUIRE(((Eigen::MatrixXd(result) - expected).cwiseAbs() - terms * eps * scale).maxCoeff() <= 0);
  }
}

// Through solve_poisson with a deep hierarchy (coarsest level of at most 60 dofs, blocks of
// max(6, 2p + 2) functions) so that every refinement adds a level: on the thick quarter annulus
// (NURBS, curved, two Neumann faces), the smoother's blocks with the space's geometry fit.
TEST_CASE("Volume multigrid CG: iterations bounded in h over deep hierarchies", "[multigrid][volume][solver]") {
  std::map<int, std::vector<int>> iterations;
  for (int p : {2, 3})
    for (int elements : {4, 8, 16, 32}) {
      CaseDescription c = shipped("thick_quarter_annulus");
      space_family(c).override_options(c, p, elements);
      const TensorVolumeDiscretization d = build_tensor_volume(c.volume, family_section<VolumeSpaceSection>(c).space);
      const VolumeGeometryMap map(d.mesh, d.volume);
      PoissonSolveOptions o;
      o.iterative = true;
      TensorMultigridReport report;
      o.preconditioner = [&](const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
        TensorMultigridOptions options;
        options.coarsest_functions = 60;
        options.block = 6;
        return tensor_multigrid_3d(d.space, layout, lower, volume_separable_coefficients(d), {}, 2, options, &report);
      };
      const PoissonSolution s = solve_poisson(d.mesh, map, c.problem, o);
      INFO("p = " << p << ", " << elements << "^3 elements: " << s.iterative.iterations << " iterations, "
                  << report.free_dofs.size() << " levels");
      REQUIRE(s.iterative.converged);
      REQUIRE(report.free_dofs.size() >= 2);
      REQUIRE(report.free_dofs.back() <= 60 * 8);
      iterations[p].push_back(s.iterative.iterations);
    }
  // Measured: 5, 8, 7, 8 (p = 2) and 5, 6, 10, 10 (p = 3) for 4^3 to 32^3 elements, two to five
  // levels. Bounded: the last refinement adds at most two, and none needs more than 16.
  for (const auto& [p, counts] : iterations) {
    INFO("p = " << p << ": " << counts[0] << ", " << counts[1] << ", " << counts[2] << ", " << counts[3]);
    REQUIRE(counts[3] <= counts[2] + 2);
    REQUIRE(*std::max_element(counts.begin(), counts.end()) <= 16);
  }
}

// The production path ([solver] preconditioner = "multigrid": the geometry fit in the blocks):
// CG to the default backward error 1e-15 leaves the direct solve's errors, with the Dirichlet
// projection and with Nitsche's method.
TEST_CASE("CG + multigrid on volumes: the direct solve's errors", "[multigrid][volume][solver]") {
  for (const bool nitsche : {false, true})
    for (int p : {2, 3}) {
      CaseDescription c = shipped("thick_quarter_annulus");
      space_family(c).override_options(c, p, 16);
      if (nitsche) c.problem.dirichlet_method = DirichletMethod::kNitsche;
      const auto space = build_space(c);
      c.solver.method = "direct";
      const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
      c.solver.method = "iterative";
      c.solver.preconditioner = "multigrid";
      SolverReport report;
      const PoissonSolution cg = solve_case(c, *space, Ordering::kAmd, {}, &report);
      INFO((nitsche ? "Nitsche" : "projection") << ", p = " << p << ": " << cg.iterative.iterations << " iterations");
      REQUIRE(report.preconditioner == "multigrid");
      require_direct_errors(cg, direct);
      REQUIRE(cg.iterative.backward_error <= 1e-15);
      REQUIRE(cg.iterative.iterations <= 20);
    }
}

// On one affine map (the cube) the levels are the operator on the halved spaces, which there is
// the Galerkin operator: the assembled V-cycle up to rounding, and the same errors.
TEST_CASE("Volume multigrid without a matrix: the assembled one's iterations, the direct solve's errors",
          "[multigrid][volume][solver]") {
  for (int p : {2, 3}) {
    CaseDescription c = shipped("cube");
    space_family(c).override_options(c, p, 32);
    const auto space = build_space(c);
    c.solver.method = "direct";
    const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
    c.solver.method = "iterative";
    c.solver.preconditioner = "multigrid";
    c.solver.matrix = "assembled";
    const PoissonSolution assembled = solve_case(c, *space, Ordering::kAmd);
    c.solver.matrix = "matrix_free";
    SolverReport report;
    const PoissonSolution free = solve_case(c, *space, Ordering::kAmd, {}, &report);
    INFO("p = " << p << ": " << assembled.iterative.iterations << " iterations assembled, " << free.iterative.iterations
                << " without a matrix");
    REQUIRE(report.matrix_free);
    REQUIRE(std::abs(free.iterative.iterations - assembled.iterative.iterations) <= 1);
    REQUIRE(free.iterative.iterations >= 3);  // 34^3 functions: several levels, no block is the whole cube
    require_direct_errors(free, direct);
  }
}

// A reaction term: the volume multigrid reads it off each level's operator (assembled, or
// without a matrix), the fast diagonalization from the case (solver/fast_diagonalization_3d.hpp).
// Without the shift, c = 1000 at 16^3, p = 2, took multigrid 81 CG iterations on the cube and
// more than 1 000 on the thick quarter annulus, the fast diagonalization 30 and 89 (against 2
// and 18 without a reaction).
TEST_CASE("CG on volumes with a reaction term: multigrid and the fast diagonalization stay bounded", "[multigrid][volume][solver]") {
  for (const char* name : {"cube", "thick_quarter_annulus"}) {
    CaseDescription c = shipped(name);
    space_family(c).override_options(c, 2, 16);
    c.problem.reaction = 1000;
    const auto space = build_space(c);
    c.solver.method = "direct";
    const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
    c.solver.method = "iterative";
    for (const char* preconditioner : {"multigrid", "fast_diagonalization"})
      for (const char* matrix : {"assembled", "matrix_free"}) {
        if (std::string(name) != "cube" && std::string(matrix) == "matrix_free") continue;  // NURBS: assembled only
        c.solver.preconditioner = preconditioner;
        c.solver.matrix = matrix;
        const PoissonSolution cg = solve_case(c, *space, Ordering::kAmd);
        INFO(name << ", " << preconditioner << ", " << matrix << ": " << cg.iterative.iterations << " iterations");
        require_direct_errors(cg, direct);
        REQUIRE(cg.iterative.iterations <= 20);
      }
  }
}

// Where "auto" takes multigrid on planar patches (CG without a matrix from 2M functions), a
// volume keeps the fast diagonalization, measured faster there (docs/SOLVERS.md).
TEST_CASE("auto on a volume of 2M functions without a matrix: the fast diagonalization", "[multigrid][volume][solver]") {
  CaseDescription c = shipped("cube");
  space_family(c).override_options(c, 2, 128);  // 130^3 = 2 197 000 functions
  const auto space = build_space(c);
  SolverReport report;
  const PoissonSolution s = solve_case(c, *space, Ordering::kAmd, {}, &report);
  INFO(report.preconditioner << ", " << s.iterative.iterations << " iterations; " << report.note);
  REQUIRE(report.method == "iterative");
  REQUIRE(report.matrix_free);
  REQUIRE(report.preconditioner == "fast_diagonalization");
  REQUIRE(s.iterative.converged);
}

TEST_CASE("Volume multigrid refuses what it cannot do, naming the key", "[multigrid][volume]") {
  SECTION("an odd element count that stops the hierarchy above what a factorization should take") {
    CaseDescription c = shipped("cube");
    space_family(c).override_options(c, 2, 37);  // 39^3 = 59 319 functions, no coarser level
    c.solver.method = "iterative";
    c.solver.preconditioner = "multigrid";
    const auto space = build_space(c);
    CHECK_THROWS_WITH(solve_case(c, *space, Ordering::kAmd),
                      Catch::Contains("[solver] preconditioner: \"multigrid\" halves the element count") &&
                          Catch::Contains("stops at 50653") && Catch::Contains("\"fast_diagonalization\""));
  }
}
