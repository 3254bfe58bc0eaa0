// THB-splines (basis/thb), checked against an oracle written here from the definition
// (Giannelli, Jüttler, Speleers 2012): Kraft's selection over full per-level knot vectors
// and the truncation done with global refinement matrices, every function expanded in the
// finest level's tensor B-splines and evaluated by de Boor. The family's cell-by-cell
// construction must give the same functions at random points; and, independently of any
// construction, partition of unity, linear independence and the nesting of spaces.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cmath>
#include <random>
#include <set>

#include "studies/adaptive.hpp"
#include "studies/pipeline.hpp"
#include "families/tensor/tensor_case.hpp"
#include "basis/core/bezier_mesh_checks.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/thb/thb_hierarchy.hpp"
#include "cases/case_file.hpp"
#include "dyadic_testing.hpp"

using namespace knotwork;
using knotwork::testing::uniform_knots;

namespace {

// The oracle: THB functions as coefficient vectors over the finest level's tensor B-splines.
struct OracleThb {
  int p, q, n0, levels;
  std::vector<BSplineBasis1D> u, v;  // per level
  Eigen::MatrixXd coefficients;      // functions x (finest u functions * finest v functions)

  // cell_in[l](i, j): level-l cell (i, j) lies in Omega^l (is a cell of level l or finer).
  OracleThb(int p_, int q_, int n0_, const std::vector<std::set<std::pair<int, int>>>& refined)
      : p(p_), q(q_), n0(n0_), levels(static_cast<int>(refined.size()) + 1) {
    for (int l = 0; l < levels; ++l) {
      u.push_back(BSplineBasis1D::open_uniform(p, 0, 1, n0 << l));
      v.push_back(BSplineBasis1D::open_uniform(q, 0, 1, n0 << l));
    }
    auto in_omega = [&](int l, int i, int j) {  // all ancestors refined
      for (int k = l; k > 0; --k) {
        i >>= 1, j >>= 1;
        if (!refined[k - 1].count({i, j})) return false;
      }
      return true;
    };
    auto refined_at = [&](int l, int i, int j) { return l < levels - 1 && refined[l].count({i, j}) > 0; };
    // support of B-spline k of an open uniform basis with n elements: elements [k-p, k+1) clipped
    auto support = [](int k, int deg, int n) { return std::pair<int, int>{std::max(0, k - deg), std::min(n, k + 1)}; };
    std::vector<Eigen::VectorXd> functions;  // at the current level
    for (int l = 0; l < levels; ++l) {
      const int nu = u[l].num_functions(), nv = v[l].num_functions(), ne = n0 << l;
      auto contained = [&](int a, int b, bool finer) {
        const auto su = support(a, p, ne), sv = support(b, q, ne);
        for (int i = su.first; i < su.second; ++i)
          for (int j = sv.first; j < sv.second; ++j)
            if (finer ? !(in_omega(l, i, j) && refined_at(l, i, j)) : !in_omega(l, i, j)) return false;
        return true;
      };
      if (l > 0) {
        // Truncation: coarser functions in this level's B-splines, minus those inside Omega^l.
        const Eigen::MatrixXd Tu = Eigen::MatrixXd(refinement_matrix(u[l - 1], u[l]));
        const Eigen::MatrixXd Tv = Eigen::MatrixXd(refinement_matrix(v[l - 1], v[l]));
        for (auto& f : functions) {
          const Eigen::Map<const Eigen::MatrixXd> C(f.data(), u[l - 1].num_functions(), v[l - 1].num_functions());
          Eigen::MatrixXd F = Tu * C * Tv.transpose();
          for (int a = 0; a < nu; ++a)
            for (int b = 0; b < nv; ++b)
              if (contained(a, b, false)) F(a, b) = 0;
          f = Eigen::Map<Eigen::VectorXd>(F.data(), F.size());
        }
      }
      for (int a = 0; a < nu; ++a)
        for (int b = 0; b < nv; ++b)
          if (contained(a, b, false) && !contained(a, b, true)) {
            Eigen::VectorXd e = Eigen::VectorXd::Zero(nu * nv);
            e[a + nu * b] = 1;
            functions.push_back(e);
          }
    }
    coefficients.resize(functions.size(), functions.empty() ? 0 : functions[0].size());
    for (size_t k = 0; k < functions.size(); ++k) coefficients.row(k) = functions[k].transpose();
  }

  Eigen::VectorXd values(double x, double y) const {
    const BSplineBasis1D &U = u.back(), &V = v.back();
    Eigen::VectorXd bu = Eigen::VectorXd::Zero(U.num_functions()), bv = Eigen::VectorXd::Zero(V.num_functions());
    const int su = U.find_span(x), sv = V.find_span(y);
    U.evaluate(su, x, bu.data() + su - p);
    V.evaluate(sv, y, bv.data() + sv - q);
    Eigen::VectorXd tensor(bu.size() * bv.size());
    for (int b = 0; b < bv.size(); ++b) tensor.segment(b * bu.size(), bu.size()) = bu * bv[b];
    return coefficients * tensor;
  }
};

double bernstein(int p, int a, double t) {
  double binomial = 1;
  for (int k = 1; k <= a; ++k) binomial = binomial * (p - a + k) / k;
  return binomial * std::pow(t, a) * std::pow(1 - t, p - a);
}

// Values of every function of a BezierMesh at a parameter point, from its Bézier form.
Eigen::VectorXd mesh_values(const BezierMesh& mesh, double x, double y) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(mesh.num_functions());
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    if (x < cell.u0 || x >= cell.u1 || y < cell.v0 || y >= cell.v1) continue;
    const double s = (x - cell.u0) / (cell.u1 - cell.u0), t = (y - cell.v0) / (cell.v1 - cell.v0);
    Eigen::VectorXd B((cell.degree_u + 1) * (cell.degree_v + 1));
    for (int b = 0; b <= cell.degree_v; ++b)
      for (int a = 0; a <= cell.degree_u; ++a)
        B[a + (cell.degree_u + 1) * b] = bernstein(cell.degree_u, a, s) * bernstein(cell.degree_v, b, t);
    const Eigen::VectorXd v = mesh.extraction(c) * B;
    const auto ids = mesh.functions(c);
    for (size_t k = 0; k < ids.size(); ++k) out[ids[k]] += v[k];
    return out;
  }
  FAIL("no cell holds (" << x << ", " << y << ")");
  return out;
}

// A hierarchy refined at random (without grading), and the refined cells per level.
std::pair<ThbHierarchy, std::vector<std::set<std::pair<int, int>>>> random_hierarchy(int p, int q, int n0, int levels,
                                                                                     unsigned seed) {
  ThbHierarchy h(uniform_knots(p, n0), uniform_knots(q, n0), 0);
  std::vector<std::set<std::pair<int, int>>> refined;
  std::mt19937 rng(seed);
  for (int l = 0; l + 1 < levels; ++l) {
    const ThbHierarchy::Basis b = h.build();
    std::vector<ThbCell> marked;
    for (const ThbCell& c : b.leaves)
      if (c.level == l && c.i < (n0 << l) * 2 / 3 && rng() % 3 != 0) marked.push_back(c);
    h.refine(marked);
    refined.emplace_back();
    for (const ThbCell& c : marked) refined.back().insert({int(c.i), int(c.j)});
  }
  return {h, refined};
}

}  // namespace

TEST_CASE("THB functions built cell by cell equal the truncated basis built from the definition", "[thb]") {
  for (auto [p, q, seed] : {std::tuple{2, 2, 1u}, std::tuple{3, 2, 2u}, std::tuple{1, 3, 3u}, std::tuple{3, 3, 4u}}) {
    auto [h, refined] = random_hierarchy(p, q, 4, 4, seed);
    const ThbHierarchy::Basis b = h.build();
    const OracleThb oracle(p, q, 4, refined);
    REQUIRE(b.mesh.num_functions() == oracle.coefficients.rows());
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0, 1);
    double worst = 0;
    for (int k = 0; k < 200; ++k) {
      const double x = unit(rng), y = unit(rng);
      worst = std::max(worst, (mesh_values(b.mesh, x, y) - oracle.values(x, y)).cwiseAbs().maxCoeff());
    }
    INFO("p = " << p << ", q = " << q << ", " << b.mesh.num_functions() << " functions on " << b.mesh.num_cells() << " cells");
    CHECK(worst < 1e-12);
    CHECK(partition_of_unity_error(b.mesh) < 1e-13);
    CHECK(bezier_rank(b.mesh) == b.mesh.num_functions());
  }
}

TEST_CASE("THB spaces are nested under refinement: the coarse functions lie in the refined span", "[thb]") {
  auto [h, refined] = random_hierarchy(2, 2, 3, 3, 7);
  const ThbHierarchy::Basis coarse = h.build();
  ThbHierarchy finer = h;
  std::vector<ThbCell> marked;
  for (size_t c = 0; c < coarse.leaves.size(); c += 3) marked.push_back(coarse.leaves[c]);
  finer.refine(marked);
  const ThbHierarchy::Basis fine = finer.build();
  // Least squares of the coarse functions' values in the fine ones at many points: zero residual.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  const int points = 3 * fine.mesh.num_functions();
  Eigen::MatrixXd A(points, fine.mesh.num_functions()), B(points, coarse.mesh.num_functions());
  for (int k = 0; k < points; ++k) {
    const double x = unit(rng), y = unit(rng);
    A.row(k) = mesh_values(fine.mesh, x, y).transpose();
    B.row(k) = mesh_values(coarse.mesh, x, y).transpose();
  }
  const Eigen::MatrixXd X = A.colPivHouseholderQr().solve(B);
  CHECK((A * X - B).cwiseAbs().maxCoeff() < 1e-11);
}

TEST_CASE("Graded THB refinement keeps the mesh T-admissible of class m", "[thb]") {
  for (int m : {2, 3}) {
    ThbHierarchy h(uniform_knots(2, 4), uniform_knots(2, 4), m);
    // Refine the cell at the corner (0, 0) six times: the grading spreads outwards.
    for (int step = 0; step < 6; ++step) {
      const ThbHierarchy::Basis b = h.build();
      std::vector<ThbCell> corner;
      for (const ThbCell& c : b.leaves)
        if (c.i == 0 && c.j == 0) corner.push_back(c);
      REQUIRE(corner.size() == 1);
      h.refine(corner);
    }
    // T-admissibility of class m (Buffa, Giannelli 2016): on every leaf, the THB functions
    // that do not vanish come from at most m successive levels (functions are numbered
    // level by level, functions_per_level of each).
    const ThbHierarchy::Basis b = h.build();
    std::vector<int> level_of(b.mesh.num_functions());
    int id = 0;
    for (size_t l = 0; l < b.functions_per_level.size(); ++l)
      for (int k = 0; k < b.functions_per_level[l]; ++k) level_of[id++] = static_cast<int>(l);
    int widest = 0;
    for (int c = 0; c < b.mesh.num_cells(); ++c) {
      int lo = 1 << 20, hi = -1;
      for (int f : b.mesh.functions(c)) lo = std::min(lo, level_of[f]), hi = std::max(hi, level_of[f]);
      widest = std::max(widest, hi - lo + 1);
    }
    INFO("class " << m);
    CHECK(widest <= m);
    CHECK(partition_of_unity_error(b.mesh) < 1e-13);
  }
}

TEST_CASE("Adaptive THB on the L-shape: H1 error ~ N^(-p/2)", "[thb][adaptive]") {
  CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/lshape_adaptive_thb.toml");
  c.adapt.steps = 40;
  c.adapt.max_dofs = 8000;
  const std::vector<AdaptiveStep> steps = adapt_case(c, Ordering::kAmd, {});
  REQUIRE(steps.back().dofs >= 8000);
  // Theory (Buffa, Giannelli 2016; Gantner et al. 2017): optimal rate p/2 = 1 in dofs.
  CHECK(fitted_h1_rate(steps, steps.size() / 2) >= 1 - 0.15);
}

TEST_CASE("THB and LR spaces draw their cells' sides as knot lines, each side once", "[thb][lr]") {
  for (const char* name : {"lshape_adaptive_thb.toml", "lshape_adaptive_lr.toml"}) {
    const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name);
    const auto space = build_space(c);
    // 4 x 2 cells: bottom and left sides of all 8, the top sides of 4 and the right sides of 2.
    const KnotLines k = space->presentation().knot_lines();
    CHECK(k.lines.size() == 8 * 2 + 4 + 2);
    // Their ends are cell corners of the physical L-shape: inside [-1, 1]^2. The L-shape is
    // bilinear, so every side is a segment, drawn by its two ends.
    for (const auto& line : k.lines) {
      CHECK(line.cwiseAbs().maxCoeff() <= 1 + 1e-12);
      CHECK(line.rows() == 2);
    }
  }
  // On the exact quarter annulus 1 <= r <= 2 (u radial, v angular) the radial sides are
  // segments and the angular ones arcs of circles: sampled, each point at the arc's radius.
  CaseDescription c = load_case_text(
      "[geometry]\ntype = \"quarter_annulus\"\ninner_radius = 1.0\nouter_radius = 2.0\n"
      "[space]\nfamily = \"thb\"\ndegree = 2\nelements = 3\n[problem]\nexact = \"x*y\"\n", "annulus_thb");
  const auto space = build_space(c);
  const KnotLines k = space->presentation().knot_lines();
  REQUIRE(k.lines.size() == 3 * 3 * 2 + 3 + 3);
  int arcs = 0, segments = 0;
  for (const auto& line : k.lines) {
    const Eigen::VectorXd r = line.rowwise().norm();
    if (line.rows() == 2) {  // a radial segment: its ends at one angle
      ++segments;
      CHECK(std::abs(line(0, 0) * line(1, 1) - line(0, 1) * line(1, 0)) < 1e-14 * r.maxCoeff() * r.maxCoeff());
    } else {
      ++arcs;
      CHECK(line.rows() == 9);
      CHECK(r.maxCoeff() - r.minCoeff() < 1e-14 * r.maxCoeff());
    }
  }
  CHECK(segments == 3 * 4);  // the radial sides: 3 elements along u, at 4 angles
  CHECK(arcs == 3 * 4);
}

TEST_CASE("A refined space that would not fit in memory is refused before it is built", "[thb][lr]") {
  const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/lshape_adaptive_thb.toml");
  CHECK_NOTHROW(check_refined_memory(c, 1e5, "THB"));
  CHECK_THROWS_WITH(check_refined_memory(c, 1e10, "THB"),
                    Catch::Contains("[adapt]") && Catch::Contains("a refined space of 1e+10 THB cells of degree 2x2"));
}
