// Volumes from case files (cases/README.md, docs/VOLUMES.md): the shipped cube and thick
// quarter annulus converge at the optimal rates through the pipeline; the isoparametric NURBS
// space on the curved volume contains the linear functions of x, y, z (its weights are the
// volume's refined onto its knots: B-splines on the same volume do not), so the patch test
// holds there; side names and numbers mean the same faces; --degree and --elements apply to
// every direction.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <tuple>

#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "cases/resource_limits.hpp"
#include "solver/amg_preconditioner.hpp"
#include "solver/fast_diagonalization_3d.hpp"
#include "families/tensor/tensor_case.hpp"
#include "studies/pipeline.hpp"
#include "studies/studies.hpp"
#include "solver/poisson_solver.hpp"
#include "cases/spline_space.hpp"
#include "rounding_bounds.hpp"
#include "quadrature/bernstein.hpp"

using namespace knotwork;

namespace {

CaseDescription shipped(const std::string& name) {
  return load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
}

CaseDescription thick_annulus(const std::string& space, const std::string& problem) {
  return load_case_text("[geometry]\ntype = \"thick_quarter_annulus\"\nheight = 2\n[space]\n" + space + "\n[problem]\n" + problem,
                        "volume.toml");
}

}  // namespace

TEST_CASE("The shipped volumes converge at the optimal rates p + 1 and p", "[volume]") {
  // Halving h divides the L2 error by about 2^(p+1) and the H1-seminorm error by 2^p; 0.2 is
  // left for what is still pre-asymptotic at these sizes.
  for (const char* name : {"cube", "thick_quarter_annulus"})
    for (int p : {1, 2}) {
      CaseDescription c = shipped(name);
      space_family(c).override_options(c, p, 2);
      // Degree 1 is below the annulus's arcs: B-splines on the exact volume there.
      if (p == 1) family_section<VolumeSpaceSection>(c).space.rational = false;
      const ConvergeOutcome o = converge_study(c, 3, Ordering::kCholmodDefault, nullptr, {});
      const ConvergeLevel& last = o.levels.back();
      INFO(name << ", p = " << p << ": L2 rate " << last.l2_rate << ", H1 rate " << last.h1_rate);
      CHECK(last.l2_rate >= p + 1 - 0.2);
      CHECK(last.h1_rate >= p - 0.2);
      CHECK(last.cells == 8 * 8 * 8);
    }
}

TEST_CASE("The isoparametric NURBS space on the thick quarter annulus reproduces linear functions", "[volume]") {
  // u = 1 + x - 2y + 3z is harmonic and lies in the NURBS space (the map's coordinates are
  // in it): Dirichlet data on four faces and its flux on two. The Galerkin solution is u only
  // up to the quadrature's error on the rational integrands (measured with 3, 5, 8, 12 Gauss
  // points: 1.5e-4, 3.4e-8, 3.9e-14, 5.0e-15), so the rule is taken fine enough for that error
  // to fall below rounding: then u is reproduced to the suite's rounding bound. In the B-spline
  // space on the same volume it is not: the error is that of an approximation, far above it.
  const std::string problem = "exact = \"1 + x - 2*y + 3*z\"\nneumann = [\"top\", \"back\"]\n";
  const std::string fine = "quadrature_points = 12\nboundary_quadrature_points = 12\n";
  const CaseDescription nurbs = thick_annulus("degree = 2\nelements = 2\n" + fine, problem);
  const auto space = build_space(nurbs);
  REQUIRE(space->mesh().is_rational());
  PoissonSolveOptions options;
  options.quadrature = nurbs.quadrature;
  const rounding_test::Reproduction r = rounding_test::solve_reproducing(space->mesh(), space->geometry(), nurbs.problem, options);
  INFO("NURBS: L2 " << r.errors.l2 << " (bound " << r.l2_bound() << ")");
  CHECK(r.reproduced());
  const CaseDescription bsplines = thick_annulus("degree = 2\nelements = 2\nrational = false\n" + fine, problem);
  const auto b = build_space(bsplines);
  REQUIRE_FALSE(b->mesh().is_rational());
  const rounding_test::Reproduction s = rounding_test::solve_reproducing(b->mesh(), b->geometry(), bsplines.problem, options);
  INFO("B-splines: L2 " << s.errors.l2);
  CHECK(s.errors.l2 > 1e3 * s.l2_bound());
}

TEST_CASE("A volume's sides by name and by number, and the command-line overrides", "[volume]") {
  const std::string space = "degree = 2\nelements = 2\n";
  const std::string u = "exact = \"sin(x) * exp(y / 2) * (1 + z * z / 3)\"\n";
  const CaseDescription named = thick_annulus(space, u + "neumann = [\"right\", \"back\"]\n");
  const CaseDescription numbered = thick_annulus(space, u + "neumann = [\"2\", \"6\"]\n");
  const auto a = build_space(named), b = build_space(numbered);
  const PoissonSolution sa = solve_poisson(a->mesh(), a->geometry(), named.problem, PoissonSolveOptions{});
  const PoissonSolution sb = solve_poisson(b->mesh(), b->geometry(), numbered.problem, PoissonSolveOptions{});
  CHECK(sa.errors->l2 == sb.errors->l2);
  CHECK(named.problem.boundary[1].kind == BoundaryKind::kNeumann);
  CHECK(named.problem.boundary[5].kind == BoundaryKind::kNeumann);
  // --degree 3 --elements 3: every direction.
  CaseDescription c = thick_annulus("degree = [2, 3, 1]\nelements = [1, 2, 4]\nrational = false\n", u);
  space_family(c).override_options(c, 3, 3);
  const auto s = build_space(c);
  CHECK(s->degree() == std::vector<int>{3, 3, 3});
  CHECK(s->mesh().num_cells() == 27);
  CHECK(s->mesh().num_functions() == 6 * 6 * 6);
}

TEST_CASE("The NURBS space's weight function is the volume's", "[volume]") {
  // build_tensor_volume refines the volume's weights onto the space's knots. Their function
  // sum_i w_i N_i, taken to each cell's Bernstein form by the mesh's own extraction, must equal
  // the volume's denominator evaluated by de Boor's recurrence (volume_point_derivatives), at
  // points inside every cell; both are sums of a few dozen positive terms of size <= 1.
  const CaseDescription c = thick_annulus("degree = [2, 3, 2]\nelements = [2, 1, 3]\n", "exact = \"x\"\n");
  const auto space = build_space(c);
  const BezierMesh& mesh = space->mesh();
  REQUIRE(mesh.is_rational());
  for (int cell = 0; cell < mesh.num_cells(); ++cell) {
    const BezierCell& b = mesh.cell(cell);
    const auto ids = mesh.functions(cell);
    Eigen::VectorXd w(static_cast<Eigen::Index>(ids.size()));
    for (size_t a = 0; a < ids.size(); ++a) w[a] = mesh.weights()[ids[a]];
    const Eigen::VectorXd bernstein = mesh.extraction(cell).transpose() * w;
    for (const std::array<double, 3> t : {std::array<double, 3>{0.5, 0.5, 0.5}, {0.1, 0.8, 0.3}, {0.9, 0.2, 0.7}}) {
      double bu[16], bv[16], bw[16], d[16];
      bernstein_values_and_derivatives(b.degree_u, t[0], bu, d);
      bernstein_values_and_derivatives(b.degree_v, t[1], bv, d);
      bernstein_values_and_derivatives(b.degree_w, t[2], bw, d);
      double value = 0;
      for (int k = 0; k <= b.degree_w; ++k)
        for (int j = 0; j <= b.degree_v; ++j)
          for (int i = 0; i <= b.degree_u; ++i)
            value += bernstein[i + (b.degree_u + 1) * (j + (b.degree_v + 1) * k)] * bu[i] * bv[j] * bw[k];
      const auto p = volume_point_derivatives(
          c.volume, {b.u0 + t[0] * (b.u1 - b.u0), b.v0 + t[1] * (b.v1 - b.v0), b.w0 + t[2] * (b.w1 - b.w0)});
      CHECK(std::abs(value - p.weight) <= 256 * std::numeric_limits<double>::epsilon());
    }
  }
}

TEST_CASE("An inline NURBS volume is the built-in one written out", "[volume]") {
  // The thick quarter annulus's knots, control points (to 17 digits) and weights as
  // [geometry] type = "nurbs": the same space, the same solve, the same errors bit for bit.
  const NurbsVolume v = thick_quarter_annulus_volume(1, 2, 2);
  std::ostringstream text;
  text.precision(17);
  text << "[geometry]\ntype = \"nurbs\"\ndegrees = [" << v.bases[0].degree() << ", " << v.bases[1].degree() << ", "
       << v.bases[2].degree() << "]\n";
  for (int k = 0; k < 3; ++k) {
    text << "knots_" << "uvw"[k] << " = [";
    for (size_t i = 0; i < v.bases[k].knots().size(); ++i) text << (i ? ", " : "") << v.bases[k].knots()[i];
    text << "]\n";
  }
  text << "control_points = [";
  for (Eigen::Index i = 0; i < v.control_points.rows(); ++i)
    text << (i ? ", " : "") << "[" << v.control_points(i, 0) << ", " << v.control_points(i, 1) << ", " << v.control_points(i, 2) << "]";
  text << "]\nweights = [";
  for (Eigen::Index i = 0; i < v.weights.size(); ++i) text << (i ? ", " : "") << v.weights[i];
  const std::string rest = "]\n[space]\ndegree = 2\nelements = 2\n[problem]\nexact = \"sin(x) * exp(y / 2) * (1 + z * z / 3)\"\n"
                           "neumann = [\"back\"]\n";
  const CaseDescription inline_case = load_case_text(text.str() + rest, "inline.toml");
  const CaseDescription built_in = thick_annulus("degree = 2\nelements = 2\n", "exact = \"sin(x) * exp(y / 2) * (1 + z * z / 3)\"\nneumann = [\"back\"]\n");
  REQUIRE(inline_case.is_volume());
  const auto a = build_space(inline_case), b = build_space(built_in);
  const PoissonSolution sa = solve_poisson(a->mesh(), a->geometry(), inline_case.problem, PoissonSolveOptions{});
  const PoissonSolution sb = solve_poisson(b->mesh(), b->geometry(), built_in.problem, PoissonSolveOptions{});
  CHECK(sa.errors->l2 == sb.errors->l2);
  CHECK(sa.errors->h1_semi == sb.errors->h1_semi);
  // Bad inline volumes: too few control points, a third knot vector that is not open.
  CHECK_THROWS_WITH(load_case_text("[geometry]\ntype = \"nurbs\"\ndegrees = 1\nknots_u = [0, 0, 1, 1]\nknots_v = [0, 0, 1, 1]\n"
                                   "knots_w = [0, 0, 1, 1]\ncontrol_points = [[0, 0, 0]]\n" + rest.substr(2),
                                   "few.toml"),
                    Catch::Contains("[geometry] control_points: control_points has 1 points but the knot vectors need 2 x 2 x 2 = 8"));
  CHECK_THROWS_WITH(load_case_text("[geometry]\ntype = \"nurbs\"\ndegrees = 1\nknots_u = [0, 0, 1, 1]\nknots_v = [0, 0, 1, 1]\n"
                                   "knots_w = [0, 1, 1]\ncontrol_points = [[0, 0, 0]]\n" + rest.substr(2),
                                   "open.toml"),
                    Catch::Contains("[geometry] knots_w"));
}

TEST_CASE("BoomerAMG on a volume runs with the options for 3D, the user's after them", "[volume]") {
  CaseDescription c = shipped("cube");
  space_family(c).override_options(c, 2, 6);
  const RunOutcome direct = run_study(c, Ordering::kAuto, nullptr, {});
  c.solver.method = "iterative";
  c.solver.preconditioner = kBoomerAmgName;
  const RunOutcome amg = run_study(c, Ordering::kAuto, nullptr, {});
  CHECK(amg.solver.preconditioner == kBoomerAmgName);
  CHECK(amg.solver.petsc_options == kBoomerAmgVolumeOptions);
  // CG stops at a backward error of 1e-15 (the default tolerance); with kappa(K) below 1e4 at
  // this size the algebraic error is below 1e-11 of |u_h|_1, far below 1e-8 of the error.
  CHECK(amg.solution.iterative.iterations <= 25);
  CHECK(std::abs(amg.solution.errors->h1_semi - direct.solution.errors->h1_semi) <= 1e-8 * direct.solution.errors->h1_semi);
  // The user's options follow (PETSc keeps the last value of an option given twice).
  c.solver.petsc_options = "-pc_hypre_boomeramg_coarsen_type Falgout -pc_hypre_boomeramg_agg_nl 0";
  const RunOutcome theirs = run_study(c, Ordering::kAuto, nullptr, {});
  CHECK(theirs.solver.petsc_options == std::string(kBoomerAmgVolumeOptions) + " " + c.solver.petsc_options);
  CHECK(std::abs(theirs.solution.errors->h1_semi - direct.solution.errors->h1_semi) <= 1e-8 * direct.solution.errors->h1_semi);
  // Planar domains keep hypre's defaults.
  CaseDescription square = load_case_text("[geometry]\ntype = \"rectangle\"\n[space]\ndegree = 2\nelements = 8\n[problem]\n"
                                          "exact = \"sin(x) * y\"\n[solver]\nmethod = \"iterative\"\npreconditioner = \"boomeramg\"\n",
                                          "square.toml");
  CHECK(run_study(square, Ordering::kAuto, nullptr, {}).solver.petsc_options.empty());
}

TEST_CASE("The volume memory guard covers the measured CG runs without refusing them", "[volume]") {
  // Measured on this project's machine (docs/VOLUMES.md): CG + BoomerAMG with the 3D options on
  // the cube at p = 2, 128^3 elements (2 197 000 unknowns), peaked at 12.6 GB; at p = 3, 64^3
  // (300 763), at 4.16 GB. The estimate must cover each, and stay within twice it, so that a
  // run that fits in 24 GB is not refused.
  const auto cube = [](int p, int n) { return std::array<double, 2>{double(n) * n * n, std::pow(double(n + p), 3)}; };
  for (const auto& [p, n, measured] : {std::tuple{2, 128, 12.6e9}, std::tuple{3, 64, 4.16e9}}) {
    const auto [cells, functions] = cube(p, n);
    const double estimate = volume_iterative_bytes(cells, functions, {p, p, p}, kBoomerAmgName, false);
    INFO("p = " << p << ", " << n << "^3: estimate " << estimate / 1e9 << " GB, measured " << measured / 1e9 << " GB");
    CHECK(estimate >= measured);
    CHECK(estimate <= 2 * measured);
  }
  // CG with the fast diagonalization (the default from 10 000 functions): 11.8 GB at 200^3,
  // p = 2 (8 242 408 unknowns); 1.02 GB at 64^3, p = 3; 0.21 GB at 48^3, p = 2
  // (docs/PERFORMANCE.md, "Volumes"). The preconditioner's own storage is counted apart.
  for (const auto& [p, n, measured] : {std::tuple{2, 200, 11.8e9}, std::tuple{3, 64, 1.02e9}, std::tuple{2, 48, 0.21e9}}) {
    const auto [cells, functions] = cube(p, n);
    const double m = n + p;
    const double estimate = volume_structured_bytes(functions, {p, p, p}, fast_diagonalization_3d_bytes({m, m, m}));
    INFO("p = " << p << ", " << n << "^3: estimate " << estimate / 1e9 << " GB, measured " << measured / 1e9 << " GB");
    CHECK(estimate >= measured);
    CHECK(estimate <= 2 * measured);
  }
  // CG without a matrix on the cube (an affine volume: what "auto" takes there since
  // 2026-12-07): 5.88 GB at 256^3, p = 2 (17 173 512 unknowns), 2.60 GB at 192^3, 0.95 GB at
  // 128^3, 0.20 GB at 64^3; 0.93 GB at 96^3, p = 3, 0.39 GB at 64^3 (docs/PERFORMANCE.md,
  // "Volumes: CG without a matrix", remeasured after the Dirichlet projection stopped copying
  // its entries and CG stopped embedding the free dofs).
  for (const auto& [p, n, measured] : {std::tuple{2, 256, 5.88e9}, std::tuple{2, 192, 2.60e9}, std::tuple{2, 128, 0.95e9},
                                       std::tuple{2, 64, 0.20e9}, std::tuple{3, 96, 0.93e9}, std::tuple{3, 64, 0.39e9}}) {
    const auto [cells, functions] = cube(p, n);
    const double m = n + p;
    const double estimate = volume_matrix_free_bytes(functions, 6.0 * n * n, {p, p, p}, fast_diagonalization_3d_bytes({m, m, m}));
    INFO("p = " << p << ", " << n << "^3 without a matrix: estimate " << estimate / 1e9 << " GB, measured " << measured / 1e9 << " GB");
    CHECK(estimate >= measured);
    CHECK(estimate <= 2 * measured);
  }
}

TEST_CASE("Extra knots on a volume: the cells they cut, the dimension, the patch test", "[volume]") {
  // insert_knots_w = [0.1, 0.25] on the unit cube, degree 2, 2 elements per direction: the
  // breakpoints along w become 0, 0.1, 0.25, 0.5, 1 (4 elements, 4 + 2 = 6 functions at C^1),
  // so 4 x 4 x 6 functions and 2 x 2 x 4 cells; u = 1 + x - 2y + 3z (harmonic, in the space)
  // is reproduced to the suite's rounding bound. A knot outside (0, 1) is refused.
  const CaseDescription c = load_case_text(
      "[geometry]\ntype = \"box\"\n[space]\ndegree = 2\nelements = 2\ninsert_knots_w = [0.1, 0.25]\n"
      "[problem]\nexact = \"1 + x - 2*y + 3*z\"\n",
      "graded.toml");
  const auto space = build_space(c);
  CHECK(space->mesh().num_functions() == 4 * 4 * 6);
  REQUIRE(space->mesh().num_cells() == 16);
  std::vector<double> w_breaks;
  for (int e = 0; e < space->mesh().num_cells(); ++e) w_breaks.push_back(space->mesh().cell(e).w0);
  std::sort(w_breaks.begin(), w_breaks.end());
  w_breaks.erase(std::unique(w_breaks.begin(), w_breaks.end()), w_breaks.end());
  CHECK(w_breaks == std::vector<double>{0, 0.1, 0.25, 0.5});
  const rounding_test::Reproduction r = rounding_test::solve_reproducing(space->mesh(), space->geometry(), c.problem);
  INFO("L2 " << r.errors.l2 << " (bound " << r.l2_bound() << ")");
  CHECK(r.reproduced());
  CHECK_THROWS_WITH(load_case_text("[geometry]\ntype = \"box\"\n[space]\ndegree = 2\nelements = 2\ninsert_knots_u = [1.5]\n"
                                   "[problem]\nexact = \"x\"\n",
                                   "outside.toml"),
                    Catch::Contains("[space] insert_knots_u: knot 1.5 is not inside the parameter domain (0, 1)"));
}
