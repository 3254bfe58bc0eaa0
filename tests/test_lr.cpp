// The LR family's mesh (basis/lr), checked against the exact-rational LR refinement of
// basis/tmesh/lr_spline (written for the PT-spline studies, from the definition: every
// B-spline a meshline traverses is split, one at a time, in exact arithmetic) fed the same
// meshlines; and by properties that depend on neither: partition of unity, and linear
// independence against the rank of the Bézier coefficients.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "studies/adaptive.hpp"
#include "basis/core/bezier_mesh_checks.hpp"
#include "basis/lr/lr_mesh.hpp"
#include "basis/tmesh/lr_spline.hpp"
#include "cases/case_file.hpp"
#include "dyadic_testing.hpp"

using namespace knotwork;
using knotwork::testing::uniform_knots;

namespace {

// Grid coordinate -> exact parameter on [0, 1] with n0 level-0 elements.
mpq_class exact(int64_t x, int n0) {
  mpz_class num(static_cast<long>(x >> 20)), den(n0);
  den <<= DyadicLrMesh::kGridLevel - 20;
  mpq_class r(num * 1, den);
  r += mpq_class(mpz_class(static_cast<long>(x & ((int64_t(1) << 20) - 1))), mpz_class(n0) << DyadicLrMesh::kGridLevel);
  r.canonicalize();
  return r;
}

using ExactKnots = std::pair<std::vector<mpq_class>, std::vector<mpq_class>>;

std::map<ExactKnots, double> as_exact(const DyadicLrMesh& lr, int n0) {
  std::map<ExactKnots, double> out;
  for (const auto& [f, w] : lr.functions()) {
    ExactKnots k;
    for (int i = 0; i <= lr.degree(0) + 1; ++i) k.first.push_back(exact(f.knots[0][i], n0));
    for (int i = 0; i <= lr.degree(1) + 1; ++i) k.second.push_back(exact(f.knots[1][i], n0));
    out[k] = w;
  }
  return out;
}

// The oracle: the same meshlines into the exact LR mesh, in the order they were inserted
// (a segment that traverses no support yet waits for the others).
std::map<ExactKnots, double> oracle(const DyadicLrMesh& lr, int n0) {
  std::vector<mpq_class> grid;
  for (int e = 0; e <= n0; ++e) grid.push_back(mpq_class(e, n0));
  LrMesh exact_mesh(grid, grid, lr.degree(0), lr.degree(1));
  std::vector<AxisSegment> pending;
  for (const auto& s : lr.inserted())
    pending.push_back({s.direction == 0, exact(s.at, n0), exact(s.from, n0), exact(s.to, n0)});
  while (!pending.empty()) {
    std::vector<AxisSegment> later;
    for (const AxisSegment& s : pending)
      if (!exact_mesh.try_insert(s) && !exact_mesh.has_line_through(s.vertical, s.position, (s.from + s.to) / 2))
        later.push_back(s);
    REQUIRE(later.size() < pending.size());
    pending = std::move(later);
  }
  std::map<ExactKnots, double> out;
  for (const LrBSpline& s : exact_mesh.splines()) out[{s.x, s.y}] = s.weight.get_d();
  return out;
}

}  // namespace

TEST_CASE("LR refinement on the integer grid gives the exact LR B-splines of the same meshlines", "[lr]") {
  for (auto strategy : {DyadicLrMesh::Strategy::kMinimalSpan, DyadicLrMesh::Strategy::kFullSpan,
                        DyadicLrMesh::Strategy::kStructuredMesh})
    for (auto [p, q] : {std::pair{2, 2}, std::pair{3, 2}}) {
      const int n0 = 3;
      DyadicLrMesh lr(uniform_knots(p, n0), uniform_knots(q, n0));
      std::mt19937 rng(17 + p);
      for (int step = 0; step < (strategy == DyadicLrMesh::Strategy::kStructuredMesh ? 3 : 4); ++step) {
        // Refine towards the corner (0, 0): the elements nearest to it, and a few at random.
        std::vector<int> marked;
        const auto& elements = lr.elements();
        for (int e = 0; e < static_cast<int>(elements.size()); ++e)
          if ((elements[e].from[0] == 0 && elements[e].from[1] == 0) || rng() % 11 == 0) marked.push_back(e);
        lr.refine(marked, strategy);
      }
      const auto ours = as_exact(lr, n0);
      const auto theirs = oracle(lr, n0);
      INFO("strategy " << int(strategy) << ", degree " << p << "x" << q << ": " << ours.size() << " B-splines, "
                       << lr.inserted().size() << " meshlines");
      REQUIRE(ours.size() == theirs.size());
      double worst = 0;
      for (const auto& [k, w] : ours) {
        const auto it = theirs.find(k);
        REQUIRE(it != theirs.end());
        worst = std::max(worst, std::abs(w - it->second));
      }
      CHECK(worst < 1e-13);
      const BezierMesh mesh = lr.bezier_mesh();
      CHECK(partition_of_unity_error(mesh) < 1e-13);
      // Independence: what the overloading check says, against the rank of all coefficients.
      const auto dep = DyadicLrMesh::dependence(mesh);
      const long rank = bezier_rank(mesh);
      REQUIRE(rank >= 0);
      CHECK(dep.dependent == mesh.num_functions() - rank);
    }
}

TEST_CASE("The LR mesh with 89 B-splines in a space of dimension 88 is found dependent", "[lr]") {
  // cases/tmeshes/lr_dependent.toml (test_lr_and_hb checks the 88 against the brute-force
  // dimension), degree 3 on [0, 5]^2; the boundary extension is off to keep the mesh as published.
  std::vector<double> breaks{0, 1, 2, 3, 4, 5};
  DyadicLrMesh lr(DyadicKnots(3, breaks, {1, 1, 1, 1}), DyadicKnots(3, breaks, {1, 1, 1, 1}));
  const std::vector<std::array<double, 4>> lines{
      {0, 0.5, 2, 5}, {1, 4.5, 0.5, 5}, {0, 2.75, 0, 4.5}, {1, 3.5, 0, 3}, {1, 4.25, 0.5, 5}};
  std::vector<DyadicLrMesh::Segment> segments;
  for (const auto& [d, at, from, to] : lines) {
    const int dir = static_cast<int>(d);
    segments.push_back({dir, lr.grid(dir, at), lr.grid(1 - dir, from), lr.grid(1 - dir, to)});
  }
  lr.insert(segments, false);
  REQUIRE(lr.num_functions() == 89);
  const auto dep = DyadicLrMesh::dependence(lr.bezier_mesh());
  CHECK(dep.overloaded > 0);
  CHECK(dep.dependent == 1);
  CHECK(dep.element >= 0);
  CHECK(bezier_rank(lr.bezier_mesh()) == 88);
  // A point refinement cannot reach is refused, not moved to the nearest grid point.
  CHECK_THROWS_AS(lr.grid(0, 1.0 / 3), std::invalid_argument);
  CHECK(lr.parameter(0, lr.grid(0, 2.75)) == 2.75);
  // A meshline that traverses no support is refused.
  CHECK_THROWS_AS(lr.insert({{0, lr.grid(0, 0.25), lr.grid(1, 0), lr.grid(1, 0.5)}}), std::invalid_argument);
}

TEST_CASE("Adaptive LR on the L-shape: H1 error ~ N^(-p/2), every space reproduces quadratics", "[lr][adaptive]") {
  CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/lshape_adaptive_lr.toml");
  c.adapt.steps = 40;
  c.adapt.max_dofs = 6000;
  // The same spaces solving for a quadratic, which they contain: the Dirichlet projection onto
  // the boundary traces (kept independent by the meshline extension) and the solve are exact.
  const auto poly_file = std::filesystem::temp_directory_path() / "knotwork_test_lr_quadratic.toml";
  {
    std::ifstream in(c.path);
    std::ofstream out(poly_file);
    for (std::string line; std::getline(in, line);)
      out << (line.rfind("exact =", 0) == 0 ? "exact = \"x^2 + 2*x*y - y^2 + x\"" : line) << "\n";
  }
  const CaseDescription quadratic = load_case(poly_file.string());
  double worst = 0;
  const std::vector<AdaptiveStep> steps = adapt_case(c, Ordering::kAmd, {}, [&](const AdaptiveStepView& v) {
    const PoissonSolution s = solve_case(quadratic, v.space, Ordering::kAmd, {});
    worst = std::max(worst, s.errors->h1_semi);
  });
  std::filesystem::remove(poly_file);
  REQUIRE(steps.back().dofs >= 6000);
  CHECK(worst < 1e-10);
  CHECK(fitted_h1_rate(steps, steps.size() / 2) >= 1 - 0.15);
}
