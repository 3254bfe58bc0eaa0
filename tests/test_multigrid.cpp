// The tensor-product multigrid preconditioner (solver/tensor_multigrid): its hierarchy, and CG
// with it reaching the direct solve's errors in iteration counts bounded in h and p, on maps
// whose coefficients separate (the quarter annulus) and on one where they do not (the L-shape
// patch, where the fast diagonalization needs three times as many).
#include <catch2/catch.hpp>
#include <algorithm>
#include <map>

#include "basis/tensor/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "cases/spline_space.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "families/tensor/tensor_case.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/tensor_multigrid.hpp"
#include "studies/pipeline.hpp"
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
    // 12-13, 19 on the L-shape for p = 2, 4, 6, the same for n = 32, 64, 128. Bounded in h:
    // the finest mesh needs at most two more than the coarsest; and in p: no count above 24.
    for (const auto& [p, counts] : iterations) {
      INFO(name << ", p = " << p << ": " << counts[0] << ", " << counts[1] << ", " << counts[2]);
      REQUIRE(counts.back() <= counts.front() + 2);
      REQUIRE(*std::max_element(counts.begin(), counts.end()) <= 24);
    }
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
