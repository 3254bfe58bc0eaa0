// The two constructions PT-splines are compared with, where they fail and PT-splines do not.
// LR B-splines (basis/lr_spline), checked by properties that do not depend on the refinement
// code: tensor-product B-splines after global lines, partition of unity with their weights,
// each one a polynomial on every cell of the LR-mesh; and the shipped LR-mesh on which they
// are linearly dependent (more of them than the brute-force dimension). Hierarchical
// B-splines (Kraft's selection, written here) on the shipped two-level mesh where they are
// independent but fewer than the dimension.
#include <catch2/catch.hpp>

#include <algorithm>
#include <functional>
#include <map>
#include <random>

#include "basis/tmesh/lr_spline.hpp"
#include "basis/pt/pt_spline.hpp"
#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "cases/case_file.hpp"
#include "tmesh_testing.hpp"

using namespace knotwork;
using knotwork::testing::q;

namespace {

// The LR B-splines as functions (weight 1 each) of a PtSplineBasis, to evaluate them and
// take their per-cell Bernstein coefficients with code that knows nothing of LR refinement.
PtSplineBasis as_functions(const LrMesh& lr) {
  PtSplineBasis B;
  B.m = lr.m();
  B.n = lr.n();
  for (const auto& s : lr.splines()) {
    B.splines.push_back({s.x, s.y});
    B.functions.push_back({{static_cast<int>(B.splines.size()) - 1, mpq_class(1)}});
  }
  return B;
}

long exact_rank(const PtSplineBasis& B, const RectangularPartition& mesh) {
  const int per_cell = (B.m + 1) * (B.n + 1);
  std::vector<SparseRationalRow> rows;
  for (const auto& f : pt_cell_polynomials_exact(B, mesh)) {
    SparseRationalRow r;
    for (const auto& [k, c] : f)
      for (int a = 0; a < per_cell; ++a)
        if (c[a] != 0) r.terms.emplace_back(static_cast<long>(k) * per_cell + a, c[a]);
    rows.push_back(std::move(r));
  }
  return rank_exact(rows, static_cast<long>(mesh.num_cells()) * per_cell);
}

void check_partition_of_unity_and_cells(const LrMesh& lr) {
  const RectangularPartition mesh(lr.cells());
  const PtSplineBasis B = as_functions(lr);
  mpq_class X = 0, Y = 0;  // the rectangle is [0, X] x [0, Y]
  for (const auto& c : mesh.cells()) X = std::max(X, c.x1), Y = std::max(Y, c.y1);
  std::mt19937 rng(3);
  for (int k = 0; k < 40; ++k) {  // points with denominators 97 and 89: never on a knot line
    const mpq_class x = q(std::uniform_int_distribution<long>(1, 96)(rng), 97) * X;
    const mpq_class y = q(std::uniform_int_distribution<long>(1, 88)(rng), 89) * Y;
    mpq_class sum = 0;
    for (size_t f = 0; f < lr.splines().size(); ++f) sum += lr.splines()[f].weight * pt_evaluate(B, f, x, y);
    REQUIRE(sum == 1);
  }
  int not_polynomial = 0;
  for (int f = 0; f < static_cast<int>(B.functions.size()); ++f)
    not_polynomial += !testing::polynomial_per_cell(
        mesh, lr.m(), lr.n(), [&](const mpq_class& x, const mpq_class& y) { return pt_evaluate(B, f, x, y); });
  REQUIRE(not_polynomial == 0);
}

long brute_force_dimension(const RectangularPartition& mesh, int p) {
  return spline_space_dimension(mesh, p, p, p - 1, p - 1, RankMethod::kExact).dimension;
}

std::vector<mpq_class> integers(int to) {
  std::vector<mpq_class> v;
  for (int i = 0; i <= to; ++i) v.push_back(i);
  return v;
}

// Whether the LR-mesh has the cells of cases/tmeshes/`file`, in any order.
bool same_cells(const LrMesh& lr, const std::string& file) {
  auto key = [](const RationalBox& b) { return std::vector<mpq_class>{b.x0, b.y0, b.x1, b.y1}; };
  std::vector<std::vector<mpq_class>> mine, shipped;
  for (const auto& c : lr.cells()) mine.push_back(key(c));
  for (const auto& c : load_partition(KNOTWORK_SOURCE_DIR "/cases/tmeshes/" + file).cells) shipped.push_back(key(c));
  std::sort(mine.begin(), mine.end());
  std::sort(shipped.begin(), shipped.end());
  return mine == shipped;
}

// The meshlines of cases/tmeshes/lr_dependent.toml, in its insertion order.
const std::vector<AxisSegment> kDependent = {{true, q(1, 2), 2, 5},
                                             {false, q(9, 2), q(1, 2), 5},
                                             {true, q(11, 4), 0, q(9, 2)},
                                             {false, q(7, 2), 0, 3},
                                             {false, q(17, 4), q(1, 2), 5}};

}  // namespace

TEST_CASE("LR B-splines: global lines give the tensor-product B-splines", "[lr]") {
  for (int p : {1, 2, 3}) {
    LrMesh lr(integers(3), integers(2), p, p);
    lr.insert({true, q(3, 2), 0, 2});
    lr.insert({false, q(1, 2), 0, 3});
    // Knots 0 1 3/2 2 3 in x and 0 1/2 1 2 in y, open: (4 + p) (3 + p) B-splines, weight 1.
    REQUIRE(lr.splines().size() == static_cast<size_t>((4 + p) * (3 + p)));
    for (const auto& s : lr.splines()) REQUIRE(s.weight == 1);
    check_partition_of_unity_and_cells(lr);
  }
}

TEST_CASE("LR B-splines: partition of unity and polynomial pieces on random LR refinements", "[lr]") {
  std::mt19937 rng(17);
  for (int t = 0; t < 6; ++t) {
    const int p = 2 + t % 2;
    LrMesh lr(integers(5), integers(5), p, p);
    int inserted = 0;
    for (int k = 0; k < 60 && inserted < 6; ++k) {
      // Split a random B-spline's support at the midpoint of one of its knot intervals.
      const LrBSpline s = lr.splines()[rng() % lr.splines().size()];
      const bool vertical = rng() % 2;
      const auto& t_knots = vertical ? s.x : s.y;
      const auto& other = vertical ? s.y : s.x;
      const size_t i = rng() % (t_knots.size() - 1);
      if (t_knots[i] == t_knots[i + 1]) continue;
      mpq_class c = (t_knots[i] + t_knots[i + 1]) / 2;
      c.canonicalize();
      try {
        lr.insert({vertical, c, other.front(), other.back()});
        ++inserted;
      } catch (const std::invalid_argument&) {  // refused: the mesh is left as it was
      }
    }
    INFO("refinement " << t << ", degree " << p << ", " << lr.inserted().size() << " meshlines");
    REQUIRE(inserted > 0);
    check_partition_of_unity_and_cells(lr);
  }
}

TEST_CASE("LR B-splines with C0 lines: the fold stays a knot of full multiplicity, partition of unity", "[lr]") {
  std::mt19937 rng(23);
  for (int p : {2, 3}) {
    LrMesh lr(integers(4), integers(4), p, p, C0Lines{{2}, {}});
    for (int k = 0; k < 8; ++k) {
      const bool vertical = rng() % 2;
      const mpq_class at = q(2 * static_cast<long>(rng() % 4) + 1, 2);  // 1/2, 3/2, 5/2, 7/2
      const mpq_class from = rng() % 2, to = from + 3;
      lr.try_insert({vertical, at, from, to});  // refusals leave the mesh as it was
    }
    INFO("degree " << p << ", " << lr.inserted().size() << " meshlines");
    REQUIRE(!lr.inserted().empty());
    for (const auto& s : lr.splines())
      if (s.x.front() < 2 && 2 < s.x.back()) REQUIRE(std::count(s.x.begin(), s.x.end(), mpq_class(2)) == p);
    check_partition_of_unity_and_cells(lr);
  }
  REQUIRE_THROWS_WITH(LrMesh(integers(4), integers(4), 2, 2, C0Lines{{q(5, 2)}, {}}), Catch::Contains("not an interior line"));
}

TEST_CASE("refine_bspline: a B-spline is the sum of its refined pieces", "[lr]") {
  // Cox-de Boor by recursion on the definition, written here.
  std::function<mpq_class(const std::vector<mpq_class>&, const mpq_class&)> value =
      [&](const std::vector<mpq_class>& t, const mpq_class& x) -> mpq_class {
    if (t.size() == 2) return t[0] <= x && x < t[1] ? 1 : 0;
    const std::vector<mpq_class> left(t.begin(), t.end() - 1), right(t.begin() + 1, t.end());
    const size_t p = t.size() - 2;
    mpq_class v = 0;
    if (t[p] != t[0]) v += (x - t[0]) / (t[p] - t[0]) * value(left, x);
    if (t[p + 1] != t[1]) v += (t[p + 1] - x) / (t[p + 1] - t[1]) * value(right, x);
    return v;
  };
  const std::vector<mpq_class> fine = {0, 0, 0, q(1, 3), q(1, 2), q(1, 2), 1, q(3, 2), 2, q(5, 2), 3, 3, 3};
  const std::vector<std::vector<mpq_class>> coarse = {
      {0, 0, 0, 1}, {0, q(1, 2), 2, 3}, {q(1, 2), q(1, 2), q(3, 2), 3}, {1, 2, 3, 3}, {0, 0, 1, 3}};
  for (const auto& t : coarse) {
    const auto pieces = refine_bspline(t, fine);
    REQUIRE(pieces.size() > 1);
    for (long k = 1; k < 60; ++k) {  // x = 3k/61 hits no knot
      const mpq_class x = q(3 * k, 61);
      mpq_class sum = 0;
      for (const auto& [window, c] : pieces) sum += c * value({fine.begin() + window, fine.begin() + window + 4}, x);
      REQUIRE(sum == value(t, x));
    }
  }
  REQUIRE_THROWS(refine_bspline({0, 1, 1, 1}, fine));  // 1 is a simple knot of `fine`
}

TEST_CASE("LR B-splines: a meshline that splits no support is refused", "[lr]") {
  LrMesh lr(integers(4), integers(4), 2, 2);
  // Length 1 < the height 3 of every support it crosses.
  REQUIRE_THROWS_WITH(lr.insert({true, q(5, 2), 1, 2}), Catch::Contains("not an LR refinement"));
  REQUIRE_THROWS_WITH(lr.insert({true, 7, 0, 4}), Catch::Contains("leaves the rectangle"));
  // A refused meshline leaves nothing behind. The y-supports of the biquadratic B-splines
  // are [0,1], [0,2], [0,3], [1,4], [2,4], [3,4]: x = 5/2 from 0 to 1/2 and from 1/2 to 1
  // contain none and are refused, though together they would contain [0, 1].
  REQUIRE_THROWS_WITH(lr.insert({true, q(5, 2), 0, q(1, 2)}), Catch::Contains("not an LR refinement"));
  REQUIRE_THROWS_WITH(lr.insert({true, q(5, 2), q(1, 2), 1}), Catch::Contains("not an LR refinement"));
  REQUIRE(lr.splines().size() == 36);  // the 6 x 6 biquadratic tensor B-splines of the 4 x 4 grid
  REQUIRE(lr.inserted().empty());
}

TEST_CASE("The shipped LR-mesh: 89 dependent LR B-splines, 88 independent PT-splines", "[lr][pt]") {
  LrMesh lr(integers(5), integers(5), 3, 3);
  for (const auto& s : kDependent) lr.insert(s);
  REQUIRE(same_cells(lr, "lr_dependent.toml"));  // the case file's T-mesh

  const RectangularPartition mesh(lr.cells());
  const long dim = brute_force_dimension(mesh, 3);
  REQUIRE(dim == 88);
  check_partition_of_unity_and_cells(lr);  // so they all lie in S(T)...
  REQUIRE(lr.splines().size() == 89);      // ...and are more than its dimension: dependent
  REQUIRE(exact_rank(as_functions(lr), mesh) == 88);

  const PtSplineBasis pt = pt_spline_basis(mesh, 3, 3);
  REQUIRE(static_cast<long>(pt.functions.size()) == dim);
  REQUIRE(exact_rank(pt, mesh) == dim);
  REQUIRE(pt_smoothness_residual(to_double(pt_cell_polynomials_exact(pt, mesh)), mesh, 3, 3) <= 1e-11);
}

namespace {

// Kraft's hierarchical B-splines of degree p on the integer grid [0, N]^2 refined once (in
// halves) on the coarse cells `refined`: the level-0 B-splines whose support is not inside
// the refined region and the level-1 ones whose support is. Also the T-mesh's cells.
struct TwoLevelHb {
  PtSplineBasis functions;
  std::vector<RationalBox> cells;
};
TwoLevelHb two_level_hb(int N, int p, const std::vector<std::pair<int, int>>& refined) {
  auto is_refined = [&](int i, int j) {
    return std::find(refined.begin(), refined.end(), std::pair{i, j}) != refined.end();
  };
  TwoLevelHb hb;
  hb.functions.m = hb.functions.n = p;
  for (int level = 0; level < 2; ++level) {
    const int cells = N << level;  // per direction, each of width 1 / 2^level
    std::vector<mpq_class> knots(p, 0);
    for (int k = 0; k <= cells; ++k) knots.push_back(q(k, 1 << level));
    knots.insert(knots.end(), p, mpq_class(N));
    for (int i = 0; i < cells + p; ++i)
      for (int j = 0; j < cells + p; ++j) {
        bool inside = true;  // the support's coarse cells all refined
        for (int a = std::max(0, i - p); a <= std::min(cells - 1, i); ++a)
          for (int b = std::max(0, j - p); b <= std::min(cells - 1, j); ++b)
            inside = inside && is_refined(a >> level, b >> level);
        if (inside != (level == 1)) continue;
        hb.functions.splines.push_back({{knots.begin() + i, knots.begin() + i + p + 2},
                                        {knots.begin() + j, knots.begin() + j + p + 2}});
        hb.functions.functions.push_back({{static_cast<int>(hb.functions.splines.size()) - 1, mpq_class(1)}});
      }
  }
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) {
      if (!is_refined(i, j)) {
        hb.cells.push_back({i, j, i + 1, j + 1});
        continue;
      }
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          hb.cells.push_back({q(2 * i + a, 2), q(2 * j + b, 2), q(2 * i + a + 1, 2), q(2 * j + b + 1, 2)});
    }
  return hb;
}

}  // namespace

TEST_CASE("Dokken-Lyche-Pettersen's LR-mesh: the 82 LR B-splines of the LRsplines library, dimension 81", "[lr][pt]") {
  // cases/tmeshes/lr_dependent_dlp.toml. The expected knot vectors and weights are those the
  // LRsplines library (SINTEF) lists for this mesh (test/LinearIndep/Pettersen_InitPaper.lr):
  // 82 B-splines, all of weight 1 but these nine.
  LrMesh lr({0, 1, 2, 3, 6, 8, 9, 10}, {0, 1, 2, 4, 6, 7, 8}, 2, 2);
  for (const AxisSegment& s : std::vector<AxisSegment>{
           {false, 3, 3, 9}, {true, 5, 2, 7}, {true, 7, 2, 6}, {false, 5, 1, 7}, {true, 4, 1, 5}})
    lr.insert(s);
  using Knots = std::vector<mpq_class>;
  const std::map<std::pair<Knots, Knots>, mpq_class> weights = {
      {{{5, 6, 7, 8}, {2, 3, 4, 6}}, q(17, 20)}, {{{6, 7, 8, 9}, {2, 3, 4, 6}}, q(2, 3)},
      {{{2, 3, 5, 6}, {2, 4, 5, 6}}, q(13, 16)}, {{{2, 3, 5, 6}, {4, 5, 6, 7}}, q(3, 4)},
      {{{3, 5, 6, 7}, {3, 4, 5, 6}}, q(11, 60)}, {{{3, 4, 5, 6}, {2, 3, 4, 5}}, q(11, 60)},
      {{{4, 5, 6, 7}, {2, 3, 4, 5}}, q(11, 20)}, {{{3, 4, 6, 8}, {1, 2, 3, 4}}, q(1, 5)},
      {{{2, 3, 4, 6}, {1, 2, 4, 5}}, q(1, 2)}};
  REQUIRE(lr.splines().size() == 82);
  int weighted = 0;
  for (const auto& s : lr.splines()) {
    const auto w = weights.find({s.x, s.y});
    INFO(s.x[0] << " " << s.x[1] << " " << s.x[2] << " " << s.x[3] << " x " << s.y[0] << " " << s.y[1] << " " << s.y[2]
                << " " << s.y[3]);
    REQUIRE(s.weight == (w == weights.end() ? mpq_class(1) : w->second));
    weighted += w != weights.end();
  }
  REQUIRE(weighted == 9);
  REQUIRE(same_cells(lr, "lr_dependent_dlp.toml"));
  REQUIRE(lr.cells().size() == 61);  // the library's element count

  const RectangularPartition mesh(lr.cells());
  REQUIRE(brute_force_dimension(mesh, 2) == 81);
  check_partition_of_unity_and_cells(lr);
  REQUIRE(exact_rank(as_functions(lr), mesh) == 81);  // 82 in S(T), dependent, spanning
  const PtSplineBasis pt = pt_spline_basis(mesh, 2, 2);
  REQUIRE(pt.functions.size() == 81);
  REQUIRE(exact_rank(pt, mesh) == 81);
}

TEST_CASE("Hierarchical B-splines: complete on a refined block, incomplete on the shipped mesh", "[hb][pt]") {
  // A refined 2 x 2 block: the hierarchical B-splines are a basis (65 = dimension).
  const TwoLevelHb block = two_level_hb(5, 3, {{1, 1}, {2, 1}, {1, 2}, {2, 2}});
  const RectangularPartition block_mesh(block.cells);
  REQUIRE(block.functions.functions.size() == 65);
  REQUIRE(brute_force_dimension(block_mesh, 3) == 65);
  REQUIRE(exact_rank(block.functions, block_mesh) == 65);

  // The 3 x 3 block without its corner (cases/tmeshes/hierarchical_hb_incomplete.toml).
  const TwoLevelHb hb = two_level_hb(5, 3, {{1, 1}, {2, 1}, {3, 1}, {1, 2}, {2, 2}, {3, 2}, {1, 3}, {2, 3}});
  auto key = [](const RationalBox& b) { return std::vector<mpq_class>{b.x0, b.y0, b.x1, b.y1}; };
  std::vector<std::vector<mpq_class>> mine, shipped;
  for (const auto& c : hb.cells) mine.push_back(key(c));
  for (const auto& c : load_partition(KNOTWORK_SOURCE_DIR "/cases/tmeshes/hierarchical_hb_incomplete.toml").cells)
    shipped.push_back(key(c));
  std::sort(mine.begin(), mine.end());
  std::sort(shipped.begin(), shipped.end());
  REQUIRE(mine == shipped);
  const RectangularPartition mesh(hb.cells);
  const long dim = brute_force_dimension(mesh, 3);
  REQUIRE(dim == 70);
  REQUIRE(hb.functions.functions.size() == 69);
  REQUIRE(exact_rank(hb.functions, mesh) == 69);  // independent, one short: incomplete
  int not_polynomial = 0;  // ...and in the space: each one polynomial per cell
  for (int f = 0; f < 69; ++f)
    not_polynomial += !testing::polynomial_per_cell(
        mesh, 3, 3, [&](const mpq_class& x, const mpq_class& y) { return pt_evaluate(hb.functions, f, x, y); });
  REQUIRE(not_polynomial == 0);

  const PtSplineBasis pt = pt_spline_basis(mesh, 3, 3);
  REQUIRE(static_cast<long>(pt.functions.size()) == dim);
  REQUIRE(exact_rank(pt, mesh) == dim);
  REQUIRE(pt_smoothness_residual(to_double(pt_cell_polynomials_exact(pt, mesh)), mesh, 3, 3) <= 1e-11);
}
