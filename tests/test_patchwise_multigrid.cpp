// Multigrid on several patches (solver/patchwise_multigrid): the prolongation between two
// uniform refinements of a glued space, checked by evaluating both spaces' functions; CG with
// the V-cycle in iteration counts bounded in h and p over deep hierarchies; and the production
// path ([solver] preconditioner = "multigrid", and "auto") leaving the direct solve's errors.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "basis/core/geometry_map.hpp"
#include "basis/core/multipatch.hpp"
#include "basis/tensor/multipatch_tensor.hpp"
#include "cases/case_file.hpp"
#include "cases/geometry_file.hpp"
#include "cases/spline_space.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "families/tensor/tensor_case.hpp"
#include "solver/patchwise_multigrid.hpp"
#include "solver/poisson_solver.hpp"
#include "studies/pipeline.hpp"
#include "studies/studies.hpp"
#include "tests/solver_checks.hpp"

using namespace knotwork;

namespace {

CaseDescription shipped(const std::string& name) {
  return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
}

// The level of `numbering` whose fixed functions are those on the domain's exterior sides (all
// free when `dirichlet` is false); geometry left empty.
PatchwiseLevel level_of(const MultiPatch& domain, const MultiPatchNumbering& numbering, bool dirichlet) {
  PatchwiseLevel level;
  std::vector<bool> fixed(numbering.count, false);
  for (size_t k = 0; k < numbering.bases.size(); ++k) {
    const auto& [u, v] = numbering.bases[k];
    const auto first = numbering.number.begin() + numbering.first_function[k];
    level.patches.push_back({u, v, {}, {}, std::vector<int>(first, first + u.num_functions() * v.num_functions())});
  }
  if (dirichlet)
    for (const PatchSideRef& s : exterior_sides(domain)) {
      const MultigridPatch& p = level.patches[s.patch];
      for (int i : side_indices(p.u.num_functions(), p.v.num_functions(), s.side)) fixed[p.function[i]] = true;
    }
  level.layout = make_dof_layout(numbering.count, fixed);
  return level;
}

// sum_i c_i N_i(u, v) over patch k of `level` (coefficients by the level's function numbers),
// from the bases' Cox-de Boor values.
double evaluate(const PatchwiseLevel& level, size_t k, const Eigen::VectorXd& c, double u, double v) {
  const MultigridPatch& p = level.patches[k];
  const int pu = p.u.degree(), pv = p.v.degree(), nu = p.u.num_functions();
  const int su = p.u.find_span(u), sv = p.v.find_span(v);
  std::vector<double> bu(pu + 1), bv(pv + 1);
  p.u.evaluate(su, u, bu.data());
  p.v.evaluate(sv, v, bv.data());
  double s = 0;
  for (int b = 0; b <= pv; ++b)
    for (int a = 0; a <= pu; ++a) s += c[p.function[(su - pu + a) + nu * (sv - pv + b)]] * bu[a] * bv[b];
  return s;
}

// CG iterations per degree over three refinements: bounded in h (the finest needs at most two
// more than the coarsest) and in p (none above 16).
void require_bounded_in_h_and_p(const std::string& name, const std::map<int, std::vector<int>>& iterations) {
  for (const auto& [p, counts] : iterations) {
    INFO(name << ", p = " << p << ": " << counts[0] << ", " << counts[1] << ", " << counts[2]);
    REQUIRE(counts.back() <= counts.front() + 2);
    REQUIRE(*std::max_element(counts.begin(), counts.end()) <= 16);
  }
}

}  // namespace

TEST_CASE("The prolongation between two refinements of a glued space is the coarse function, on every patch",
          "[multigrid][multipatch]") {
  // The plus (some patches stored transposed or reversed) and the ring (interfaces running both
  // ways, a patch glued across the seam): a random coarse function's fine coefficients P c
  // evaluate to it at random points of every patch, so the shared functions' rows agree with
  // every patch that holds them. Both sums have (p + 1)^2 = 16 terms of size at most 1 (a
  // partition of unity times coefficients in [-1, 1], and P's rows are convex weights): they
  // agree to 64 eps. With the exterior sides' functions fixed, exactly the coarse functions on
  // those sides become fixed (found by their indices, independently of link_coarser).
  for (const char* name : {"plus_12patches.txt", "ring_4patches.txt"}) {
    const MultiPatch domain = read_geometry_file(std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/" + name);
    TensorSpaceOptions o;
    o.degree = {3, 3};
    o.elements_per_span = {4, 4};
    const MultiPatchNumbering fine_numbers = number_multipatch_functions(domain, o);
    o.elements_per_span = {2, 2};
    const MultiPatchNumbering coarse_numbers = number_multipatch_functions(domain, o);
    for (bool dirichlet : {false, true}) {
      INFO(name << (dirichlet ? ", exterior sides fixed" : ", all free"));
      PatchwiseLevel fine = level_of(domain, fine_numbers, dirichlet), coarse = level_of(domain, coarse_numbers, false);
      const DofLayout expected = level_of(domain, coarse_numbers, dirichlet).layout;
      link_coarser(fine, coarse);
      REQUIRE(coarse.layout.dof == expected.dof);
      REQUIRE(fine.prolongation.rows() == fine.layout.num_free());
      REQUIRE(fine.prolongation.cols() == coarse.layout.num_free());
      std::mt19937 random(7);
      std::uniform_real_distribution<double> uniform(-1, 1), unit(0, 1);
      Eigen::VectorXd c = Eigen::VectorXd::Zero(coarse_numbers.count);
      for (int f = 0; f < coarse_numbers.count; ++f)
        if (coarse.layout.dof[f] >= 0) c[f] = uniform(random);
      Eigen::VectorXd free_c(coarse.layout.num_free());
      for (int d = 0; d < coarse.layout.num_free(); ++d) free_c[d] = c[coarse.layout.function_of_dof[d]];
      const Eigen::VectorXd free_f = fine.prolongation * free_c;
      Eigen::VectorXd f = Eigen::VectorXd::Zero(fine_numbers.count);
      for (int d = 0; d < fine.layout.num_free(); ++d) f[fine.layout.function_of_dof[d]] = free_f[d];
      double worst = 0;
      for (size_t k = 0; k < fine.patches.size(); ++k) {
        const MultigridPatch& p = fine.patches[k];
        const double u0 = p.u.knots().front(), u1 = p.u.knots().back(), v0 = p.v.knots().front(), v1 = p.v.knots().back();
        for (int n = 0; n < 40; ++n) {
          const double u = u0 + (u1 - u0) * unit(random), v = v0 + (v1 - v0) * unit(random);
          worst = std::max(worst, std::abs(evaluate(fine, k, f, u, v) - evaluate(coarse, k, c, u, v)));
        }
      }
      INFO("largest difference " << worst);
      REQUIRE(worst <= 64 * std::numeric_limits<double>::epsilon());
    }
  }
}

// Deep hierarchies (down to one element per geometry span) built here as the family builds
// them, so that h-robustness is tested over many levels and not one coarse solve.
TEST_CASE("Multigrid on several patches: CG iterations bounded in h and p", "[multigrid][multipatch][solver]") {
  for (const char* name : {"multipatch_plus", "multipatch_ring"}) {
    std::map<int, std::vector<int>> iterations;
    // From meshes whose patches are several blocks wide and more than the strip: the strip
    // holds p functions beside each interface, so the sizes grow with p.
    for (int p : {2, 4, 6})
      for (int n : {8 << (p - 2) / 2, 16 << (p - 2) / 2, 32 << (p - 2) / 2}) {
        CaseDescription c = shipped(name);
        TensorSpaceOptions& o = patch_space(c);
        o.degree = {p, p};
        o.elements_per_span = {n, n};
        const auto space = build_space(c);
        const MultiPatchTensorDiscretization d = build_multipatch_tensor(c.domain, o);
        PatchwiseMultigridReport report;
        PoissonSolveOptions solve;
        solve.iterative = true;
        solve.preconditioner = [&](const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
          std::vector<PatchwiseLevel> levels(1);
          for (size_t k = 0; k < d.patches.size(); ++k) {
            const TensorDiscretization& t = d.patches[k];
            const PatchGeometryMap map(t.mesh, t.patch,
                                       PatchGeometryMap::ElementGrid{t.space_u.breakpoints(), t.space_v.breakpoints(), 0});
            levels[0].patches.push_back({t.space_u, t.space_v, patch_separable_coefficients(t, map), {}, d.global_function[k]});
          }
          levels[0].layout = layout;
          TensorSpaceOptions coarse = o;
          while (coarse.elements_per_span[0] > 1) {
            coarse.elements_per_span = {coarse.elements_per_span[0] / 2, coarse.elements_per_span[1] / 2};
            const MultiPatchNumbering numbers = number_multipatch_functions(c.domain, coarse);
            PatchwiseLevel next;
            for (size_t k = 0; k < numbers.bases.size(); ++k) {
              const auto& [u, v] = numbers.bases[k];
              const auto first = numbers.number.begin() + numbers.first_function[k];
              next.patches.push_back({u, v, coarser_fit(levels.back().patches[k], u, v), {},
                                      std::vector<int>(first, first + u.num_functions() * v.num_functions())});
            }
            link_coarser(levels.back(), next);
            levels.push_back(std::move(next));
          }
          PatchwiseMultigridOptions options;
          options.block = 8;  // (max(8, 2p + 2)) smaller than the finest patches: no block is a whole patch
          return patchwise_multigrid(std::move(levels), lower, options, &report);
        };
        const PoissonSolution s = solve_poisson(space->mesh(), space->geometry(), c.problem, solve);
        INFO(name << ", p = " << p << ", n = " << n << ": " << s.iterative.iterations << " iterations, "
                  << report.free_dofs.size() << " levels");
        REQUIRE(s.iterative.converged);
        REQUIRE(report.free_dofs.size() == static_cast<size_t>(std::log2(n)) + 1);
        REQUIRE(report.strip_dofs.size() + 1 == report.free_dofs.size());
        iterations[p].push_back(s.iterative.iterations);
      }
    // Measured: 7, 7, 7 (p = 2, n = 8..32), 9, 10, 10 (p = 4, n = 16..64) and 13, 13, 14 (p = 6,
    // n = 32..128) on the plus; 6, 7, 7, then 8, 9, 9, then 12, 12, 13 on the ring.
    require_bounded_in_h_and_p(name, iterations);
  }
}

// The production path: the family's levels (coarsest at most 3 000 free dofs) and separable
// fits. CG to the default backward error 1e-15 leaves the direct solve's errors, with the
// Dirichlet functions eliminated and with Nitsche's method.
TEST_CASE("CG + multigrid on several patches: the direct solve's errors, and auto takes it", "[multigrid][multipatch][solver]") {
  for (const auto& [nitsche, p] : {std::pair{false, 3}, std::pair{true, 2}})
    for (const char* name : {"multipatch_plus", "multipatch_ring", "multipatch_lshape"}) {
        CaseDescription c = shipped(name);
        patch_space(c).degree = {p, p};
        const int n = std::string(name) == "multipatch_plus" ? 32 : 64;
        patch_space(c).elements_per_span = {n, n};
        if (nitsche) c.problem.dirichlet_method = DirichletMethod::kNitsche;
        const auto space = build_space(c);
        c.solver.method = "direct";
        const PoissonSolution direct = solve_case(c, *space, Ordering::kAmd);
        c.solver.method = "iterative";
        c.solver.preconditioner = "multigrid";
        const PoissonSolution cg = solve_case(c, *space, Ordering::kAmd);
        INFO(name << (nitsche ? " (Nitsche)" : "") << ", p = " << p << ": " << cg.iterative.iterations << " iterations");
        require_direct_errors(cg, direct);
        REQUIRE(cg.iterative.backward_error <= 1e-15);
        REQUIRE(cg.iterative.iterations <= 16);
        // "auto" takes CG with it from 10 000 functions (these spaces have 13 000 to 18 000).
        if (nitsche) continue;
        REQUIRE(space->mesh().num_functions() >= 10000);
        c.solver.method = c.solver.preconditioner = "auto";
        SolverReport report;
        solve_case(c, *space, Ordering::kAmd, {}, &report);
        REQUIRE(report.method == "iterative");
        REQUIRE(report.preconditioner == "multigrid");
      }
}
