// Multigrid on several patches and volumes (solver/patchwise_multigrid): the coarser level of a
// glued space (its glued functions counted independently, its fixed ones found by their
// indices, its prolongation checked by evaluating both spaces' functions); CG with the V-cycle
// in iteration counts bounded in h and p over deep hierarchies; and the production path
// ([solver] preconditioner = "multigrid", and "auto") leaving the direct solve's errors.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "basis/core/geometry_map.hpp"
#include "basis/core/glue_patches.hpp"
#include "basis/core/multipatch.hpp"
#include "basis/tensor/multipatch_tensor.hpp"
#include "cases/case_file.hpp"
#include "cases/geometry_file.hpp"
#include "cases/spline_space.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "families/tensor/tensor_case.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "solver/expression.hpp"
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

// The functions on the domain's exterior sides (none when `dirichlet` is false), by their indices.
std::vector<bool> exterior_functions(const MultiPatch& domain, const PatchwiseLevel& level, int count, bool dirichlet) {
  std::vector<bool> fixed(count, false);
  if (dirichlet)
    for (const PatchSideRef& s : exterior_sides(domain)) {
      const MultigridPatch& p = level.patches[s.patch];
      for (int i : side_indices(p.bases[0].num_functions(), p.bases[1].num_functions(), s.side)) fixed[p.function[i]] = true;
    }
  return fixed;
}

// The planar level of `numbering` whose fixed functions are those on the domain's exterior
// sides (all free when `dirichlet` is false), with no geometry fit.
PatchwiseLevel level_of(const MultiPatch& domain, const MultiPatchNumbering& numbering, bool dirichlet) {
  PatchwiseLevel level;
  for (size_t k = 0; k < numbering.bases.size(); ++k) {
    const auto& [u, v] = numbering.bases[k];
    const auto first = numbering.number.begin() + numbering.first_function[k];
    level.patches.push_back(planar_multigrid_patch(u, v, {}, {}, std::vector<int>(first, first + u.num_functions() * v.num_functions())));
  }
  level.layout = make_dof_layout(numbering.count, exterior_functions(domain, level, numbering.count, dirichlet));
  return level;
}

// sum_i c_i N_i(u, v) over patch k of `level` (coefficients by the level's function numbers),
// from the bases' Cox-de Boor values.
double evaluate(const PatchwiseLevel& level, size_t k, const Eigen::VectorXd& c, double u, double v) {
  const MultigridPatch& p = level.patches[k];
  const BSplineBasis1D &bu_basis = p.bases[0], &bv_basis = p.bases[1];
  const int pu = bu_basis.degree(), pv = bv_basis.degree(), nu = bu_basis.num_functions();
  const int su = bu_basis.find_span(u), sv = bv_basis.find_span(v);
  std::vector<double> bu(pu + 1), bv(pv + 1);
  bu_basis.evaluate(su, u, bu.data());
  bv_basis.evaluate(sv, v, bv.data());
  double s = 0;
  for (int b = 0; b <= pv; ++b)
    for (int a = 0; a <= pu; ++a) s += c[p.function[(su - pu + a) + nu * (sv - pv + b)]] * bu[a] * bv[b];
  return s;
}

// CG with `preconditioner` to the default backward error 1e-15 leaves CHOLMOD's errors (with
// its default ordering); returns the CG solution.
PoissonSolution cg_as_direct(CaseDescription c, const SplineSpace& space, const char* preconditioner = "multigrid") {
  c.solver.method = "direct";
  const PoissonSolution direct = solve_case(c, space, Ordering::kAuto);
  c.solver.method = "iterative";
  c.solver.preconditioner = preconditioner;
  PoissonSolution cg = solve_case(c, space, Ordering::kAuto);
  INFO(cg.iterative.iterations << " iterations");
  require_direct_errors(cg, direct);
  REQUIRE(cg.iterative.backward_error <= 1e-15);
  return cg;
}

}  // namespace

TEST_CASE("The coarser level of a glued space: its functions, its fixed ones, and the prolongation on every patch",
          "[multigrid][multipatch]") {
  // The plus (some patches stored transposed or reversed) and the ring (interfaces running both
  // ways, a patch glued across the seam), p = 3, from 4 to 2 elements per span:
  // - coarser_level finds the glued functions by their traces; their number is that of the
  //   space with 2 elements per span as basis/tensor glues it;
  // - with the exterior sides' functions fixed, exactly the coarse functions on those sides
  //   (found by their indices) are fixed;
  // - a random coarse function's fine coefficients P c evaluate to it at random points of every
  //   patch, so a glued function's coefficients agree with every patch that holds it. Both sums
  //   have (p + 1)^2 = 16 terms of size at most 1 (a partition of unity times coefficients in
  //   [-1, 1]; P's rows are convex weights): they agree to 64 eps.
  for (const char* name : {"ring_4patches.txt", "plus_12patches.txt"}) {
    const MultiPatch domain = read_geometry_file(std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/" + name);
    TensorSpaceOptions o;
    o.degree = {3, 3};
    o.elements_per_span = {4, 4};
    const MultiPatchNumbering fine_numbers = number_multipatch_functions(domain, o);
    o.elements_per_span = {2, 2};
    const int coarse_count = number_multipatch_functions(domain, o).count;
    for (bool dirichlet : {false, true}) {
      INFO(name << (dirichlet ? ", exterior sides fixed" : ", all free"));
      PatchwiseLevel fine = level_of(domain, fine_numbers, dirichlet), coarse;
      REQUIRE(coarser_level(fine, coarse));
      const int nc = static_cast<int>(coarse.layout.dof.size());
      REQUIRE(nc == coarse_count);
      const std::vector<bool> fixed = exterior_functions(domain, coarse, nc, dirichlet);
      for (int f = 0; f < nc; ++f) REQUIRE((coarse.layout.dof[f] < 0) == fixed[f]);
      REQUIRE(fine.prolongation.rows() == fine.layout.num_free());
      REQUIRE(fine.prolongation.cols() == coarse.layout.num_free());
      std::mt19937 random(7);
      std::uniform_real_distribution<double> uniform(-1, 1), unit(0, 1);
      Eigen::VectorXd c = Eigen::VectorXd::Zero(nc);
      for (int f = 0; f < nc; ++f)
        if (coarse.layout.dof[f] >= 0) c[f] = uniform(random);
      Eigen::VectorXd free_c(coarse.layout.num_free());
      for (int d = 0; d < coarse.layout.num_free(); ++d) free_c[d] = c[coarse.layout.function_of_dof[d]];
      const Eigen::VectorXd free_f = fine.prolongation * free_c;
      Eigen::VectorXd f = Eigen::VectorXd::Zero(fine_numbers.count);
      for (int d = 0; d < fine.layout.num_free(); ++d) f[fine.layout.function_of_dof[d]] = free_f[d];
      double worst = 0;
      for (size_t k = 0; k < fine.patches.size(); ++k) {
        const std::vector<double> &ku = fine.patches[k].bases[0].knots(), &kv = fine.patches[k].bases[1].knots();
        for (int n = 0; n < 40; ++n) {
          const double u = ku.front() + (ku.back() - ku.front()) * unit(random);
          const double v = kv.front() + (kv.back() - kv.front()) * unit(random);
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
          PatchwiseLevel finest;
          for (size_t k = 0; k < d.patches.size(); ++k) {
            const TensorDiscretization& t = d.patches[k];
            const PatchGeometryMap map(t.mesh, t.patch,
                                       PatchGeometryMap::ElementGrid{t.space_u.breakpoints(), t.space_v.breakpoints(), 0});
            finest.patches.push_back(
                planar_multigrid_patch(t.space_u, t.space_v, patch_separable_coefficients(t, map), {}, d.global_function[k]));
          }
          finest.layout = layout;
          PatchwiseMultigridOptions options;
          options.block = 8;               // (max(8, 2p + 2)) smaller than the finest patches: no block is a whole patch
          options.coarsest_functions = 0;  // down to one element per span
          return patchwise_multigrid(std::move(finest), lower, options, &report);
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
    require_bounded_in_h_and_p(name, iterations, 16);
  }
}

// Under mpirun a process fits the patches it does not hold from their maps alone
// (patch_separable_coefficients(NurbsPatch, ...)); the fit must be the one the patch's grid map
// gives, and the reaction's shift too. The two evaluate the same Jacobians by different
// arithmetic (the map's Bezier cells, de Boor on the NURBS): they differ by rounding, a few
// ulps of each coefficient, which the log-least-squares fit averages; 1e-12 relative leaves two
// orders of magnitude over that and is far below any difference of the map.
TEST_CASE("A patch's separable fit from its map alone is the one its grid map gives", "[multigrid][multipatch]") {
  for (const char* name : {"multipatch_plus", "multipatch_ring"}) {
    CaseDescription c = shipped(name);
    TensorSpaceOptions& o = patch_space(c);
    o.degree = {3, 3};
    o.elements_per_span = {6, 6};
    c.problem.reaction = 10;
    const MultiPatchTensorDiscretization d = build_multipatch_tensor(c.domain, o);
    for (size_t k = 0; k < d.patches.size(); ++k) {
      const TensorDiscretization& t = d.patches[k];
      const PatchGeometryMap map(t.mesh, t.patch, PatchGeometryMap::ElementGrid{t.space_u.breakpoints(), t.space_v.breakpoints(), 0});
      const SeparableCoefficients from_cells = patch_separable_coefficients(t, map, &c.problem);
      const SeparableCoefficients from_map = patch_separable_coefficients(c.domain.patches[k], t.space_u, t.space_v, &c.problem);
      INFO(name << ", patch " << k);
      const std::vector<double>* pairs[4][2] = {{&from_cells.a1, &from_map.a1}, {&from_cells.b1, &from_map.b1},
                                                {&from_cells.a2, &from_map.a2}, {&from_cells.b2, &from_map.b2}};
      for (const auto& pair : pairs) {
        REQUIRE(pair[0]->size() == pair[1]->size());
        REQUIRE(!pair[0]->empty());
        for (size_t i = 0; i < pair[0]->size(); ++i) REQUIRE((*pair[1])[i] == Approx((*pair[0])[i]).epsilon(1e-12));
      }
      REQUIRE(from_cells.shift > 0);
      REQUIRE(from_map.shift == Approx(from_cells.shift).epsilon(1e-12));
    }
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
        INFO(name << (nitsche ? " (Nitsche)" : "") << ", p = " << p);
        const PoissonSolution cg = cg_as_direct(c, *space);
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

// The smoother's separable operator knows only the geometry: a reaction term is read off the
// matrix (the shift), and a varying diffusion is left to the diagonal scaling. Without the
// shift, c = 1000 made CG stall on the plus (no convergence in 1 000 iterations).
TEST_CASE("Multigrid on several patches with a reaction and a varying diffusion: bounded, the direct solve's errors",
          "[multigrid][multipatch][solver]") {
  for (int variant = 0; variant < 3; ++variant) {
    CaseDescription c = shipped("multipatch_plus");
    patch_space(c).elements_per_span = {32, 32};
    if (variant != 1) c.problem.reaction = variant == 0 ? 1000.0 : 1e6;
    if (variant == 1) c.problem.coefficients.diffusion = {Expression::parse("1 + 100*x^2", "test: coefficient")};
    const auto space = build_space(c);
    INFO("variant " << variant);
    const PoissonSolution cg = cg_as_direct(c, *space);
    // Measured: 5 to 7 iterations over the three variants.
    REQUIRE(cg.iterative.iterations <= 16);
  }
}

// Seven cubes glued face to face, three of them turned (the Fichera corner): the same checks
// in 3D, with the finest level built as the family builds it.
// The per-patch fast diagonalization (additive Schwarz, families/tensor) takes a reaction term
// from the case as each patch's shift (solver/fast_diagonalization.hpp). Without it, c = 1000 on
// the plus at 32 elements per span did not converge in 1 000 CG iterations; with it, 28.
TEST_CASE("The per-patch fast diagonalization with a reaction term: bounded, the direct solve's errors",
          "[fast_diagonalization][multipatch][solver]") {
  CaseDescription c = shipped("multipatch_plus");
  patch_space(c).elements_per_span = {32, 32};
  c.problem.reaction = 1000;
  const auto space = build_space(c);
  REQUIRE(cg_as_direct(c, *space, "fast_diagonalization").iterative.iterations <= 60);
}

TEST_CASE("Multigrid on glued volumes: the coarser level's functions, bounded iterations, the direct solve's errors",
          "[multigrid][volume][multipatch][solver]") {
  CaseDescription c = shipped("fichera_patches");
  TensorVolumeOptions& o = family_section<VolumeSpaceSection>(c).space;
  // The finest level of the space with `n` elements per cube side and its glued numbering.
  auto finest_level = [&](int p, int n, GluedPatches& glued) {
    o.degree = {p, p, p};
    o.elements_per_span = {n, n, n};
    std::vector<TensorVolumeDiscretization> cubes;
    std::vector<const BezierMesh*> meshes;
    for (const NurbsVolume& v : c.volume_domain.patches) cubes.push_back(build_tensor_volume(v, o));
    for (const TensorVolumeDiscretization& d : cubes) meshes.push_back(&d.mesh);
    glued = glue_volumes(c.volume_domain, meshes);
    PatchwiseLevel level;
    for (size_t k = 0; k < cubes.size(); ++k)
      level.patches.push_back(volume_multigrid_patch(cubes[k].space, volume_separable_coefficients(cubes[k]), glued.global_function[k]));
    return level;
  };
  {
    // The glued functions coarser_level finds are those basis/core glues at half the elements.
    GluedPatches fine_glue, coarse_glue;
    PatchwiseLevel fine = finest_level(2, 8, fine_glue), coarse;
    fine.layout = make_dof_layout(fine_glue.mesh.num_functions(), std::vector<bool>(fine_glue.mesh.num_functions(), false));
    finest_level(2, 4, coarse_glue);
    REQUIRE(coarser_level(fine, coarse));
    REQUIRE(static_cast<int>(coarse.layout.dof.size()) == coarse_glue.mesh.num_functions());
  }
  std::map<int, std::vector<int>> iterations;
  for (int p : {2, 3})
    for (int n : {4, 8, 16}) {
      GluedPatches glued;
      PatchwiseLevel finest = finest_level(p, n, glued);
      const auto space = build_space(c);
      PatchwiseMultigridReport report;
      PoissonSolveOptions solve;
      solve.iterative = true;
      solve.preconditioner = [&](const DofLayout& layout, const Eigen::SparseMatrix<double>& lower) {
        finest.layout = layout;
        PatchwiseMultigridOptions options;
        options.block = 8;               // (max(8, 2p + 2)) smaller than the finest cubes
        options.coarsest_functions = 0;  // down to one element per cube side
        return patchwise_multigrid(finest, lower, options, &report);
      };
      const PoissonSolution s = solve_poisson(space->mesh(), space->geometry(), c.problem, solve);
      INFO("p = " << p << ", n = " << n << ": " << s.iterative.iterations << " iterations, " << report.free_dofs.size()
                  << " levels");
      REQUIRE(s.iterative.converged);
      REQUIRE(report.free_dofs.size() == static_cast<size_t>(std::log2(n)) + 1);
      iterations[p].push_back(s.iterative.iterations);
    }
  // Measured: 5, 7, 7 (p = 2) and 5, 7, 10 (p = 3). At p = 3 the cubes of 4 and 8 elements are
  // mostly band (3 functions beside each interface face), solved exactly; the production path
  // takes 7, 7, 10 at 8, 16, 32 elements, and the one-volume multigrid 10 on the cube at p = 3
  // (docs/SOLVERS.md): bounded in h at p = 2, and no count above 16.
  require_bounded_in_h_and_p("fichera_patches", {{2, iterations[2]}}, 16);
  REQUIRE(*std::max_element(iterations[3].begin(), iterations[3].end()) <= 16);
  // The production path, and "auto" (38 000 functions at p = 2, 16 elements per cube side).
  o.degree = {2, 2, 2};
  o.elements_per_span = {16, 16, 16};
  const auto space = build_space(c);
  cg_as_direct(c, *space);
  c.solver.method = c.solver.preconditioner = "auto";
  SolverReport chosen;
  solve_case(c, *space, Ordering::kAuto, {}, &chosen);
  REQUIRE(chosen.method == "iterative");
  REQUIRE(chosen.preconditioner == "multigrid");
}
