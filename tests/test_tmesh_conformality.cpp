// The smoothing cofactor-conformality count, the diagonalizable-mesh formula and dimensional
// instability, all against the brute-force dimension (cell polynomials and smoothness
// conditions, exact rank), which shares no code with them.
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <tuple>

#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "tmesh_testing.hpp"

using namespace knotwork;
using knotwork::testing::q;
using knotwork::testing::random_halvings;

namespace {

long brute_force(const RectangularPartition& mesh, int m, int n) {
  return spline_space_dimension(mesh, m, n, m - 1, n - 1, RankMethod::kExact).dimension;
}

using knotwork::testing::pinwheel_segments;
std::vector<RationalBox> pinwheel(const mpq_class& p) { return testing::pinwheel_with_ray_at(p); }

// What the topology of a T-mesh is, up to coordinates: vertex classes and, per l-edge, its
// kind, direction and number of vertices.
auto signature(const PartitionTopology& t) {
  std::vector<std::tuple<int, bool, size_t>> knots;
  for (const auto& k : t.knots) knots.emplace_back(static_cast<int>(k.kind), k.vertical, k.vertices.size());
  std::sort(knots.begin(), knots.end());
  return std::make_tuple(t.vertices.size(), t.t_nodes(), t.crossings(), t.interior_edges(), knots);
}

std::vector<RationalBox> sorted(std::vector<RationalBox> cells) {
  std::sort(cells.begin(), cells.end(), [](const RationalBox& a, const RationalBox& b) {
    return std::tie(a.x0, a.y0, a.x1, a.y1) < std::tie(b.x0, b.y0, b.x1, b.y1);
  });
  return cells;
}

}  // namespace

TEST_CASE("Segments cut the mesh in any order, including a T-cycle that has no insertion order", "[tmesh]") {
  std::vector<AxisSegment> segs = pinwheel_segments(q(5, 2));
  const auto reference = sorted(pinwheel(q(5, 2)));
  REQUIRE(reference.size() == 21);  // 9 grid cells; the arms and rays add 12 (counted by hand)
  REQUIRE_NOTHROW(RectangularPartition(reference));
  std::mt19937 rng(11);
  for (int t = 0; t < 5; ++t) {
    std::shuffle(segs.begin(), segs.end(), rng);
    const auto cells = sorted(insert_segments(grid_cells({0, 1, 5, 6}, {0, 1, 5, 6}), segs));
    REQUIRE(cells.size() == reference.size());
    for (size_t i = 0; i < cells.size(); ++i)
      REQUIRE((cells[i].x0 == reference[i].x0 && cells[i].y0 == reference[i].y0 && cells[i].x1 == reference[i].x1 &&
               cells[i].y1 == reference[i].y1));
  }
  // Without the arm x = 2 the cycle is open: the arm y = 2 (and the ray y = 7/2) end inside a cell.
  std::vector<AxisSegment> open = pinwheel_segments(q(5, 2));
  open.erase(open.begin() + 3);
  REQUIRE_THROWS_WITH(insert_segments(grid_cells({0, 1, 5, 6}, {0, 1, 5, 6}), open),
                      Catch::Contains("segment 0 (y = 2 from 2 to 5) ends inside cell [1, 1, 5, 5]"));
}

TEST_CASE("Dimensional instability: the pinwheel's dimension jumps where the arms' ratios multiply to 1", "[tmesh]") {
  const PartitionTopology special = partition_topology(RectangularPartition(pinwheel(q(5, 2))));
  for (const mpq_class& p : {q(9, 4), q(5, 2), q(11, 4), q(3), q(7, 2)}) {
    INFO("first ray at x = " << p.get_str());
    const RectangularPartition mesh(pinwheel(p));
    const PartitionTopology topo = partition_topology(mesh);
    REQUIRE(signature(topo) == signature(special));
    // Arm y = 2 has its own end a = 2, the next arm lands at b = 4, the frame line o = 5, the
    // ray at p; the other three arms are the rotations of the special mesh, each with r = 1.
    const mpq_class a = 2, b = 4, o = 5;
    const mpq_class r = (p - a) * (o - a) / ((b - p) * (o - b));
    const long expected = r == 1 ? 30 : 29;  // 29: every moment condition independent (below)
    REQUIRE(brute_force(mesh, 2, 2) == expected);
    const ConformalityCount c = conformality_count(topo, 2, 2);
    REQUIRE(c.dimension == expected);
    REQUIRE(c.conformality_rows == 12);
    REQUIRE(c.tensor_part + c.interior_vertices - c.conformality_rows == 29);
    REQUIRE_FALSE(c.diagonalizable);  // each arm keeps 2 private vertices, deg + 1 = 3 needed
    REQUIRE_FALSE(c.formula.has_value());
  }
}

TEST_CASE("An unlucky prime: the pinwheel moved off its special point by a multiple of the prime", "[tmesh]") {
  // Over Q the ray is not at 5/2, r != 1 and the dimension is 29 (above); modulo 2^61 - 1
  // it is at 5/2 and the rank drops by one. The two primes disagree, and the modular method
  // must then answer over Q rather than fail (it threw before).
  const RectangularPartition mesh(pinwheel(testing::unlucky_ray_foot()));
  const DimensionResult fast = spline_space_dimension(mesh, 2, 2, 1, 1, RankMethod::kModular);
  REQUIRE(fast.exact);
  REQUIRE(fast.dimension == 29);
  REQUIRE(brute_force(mesh, 2, 2) == 29);
  REQUIRE(conformality_count(partition_topology(mesh), 2, 2).dimension == 29);
}

TEST_CASE("Cofactor count = brute-force dimension, and the formula holds on every diagonalizable mesh", "[tmesh]") {
  std::mt19937 rng(5);
  int diagonalizable = 0, not_diagonalizable = 0;
  for (int t = 0; t < 24; ++t) {
    const RectangularPartition mesh(random_halvings(rng, 6 + t));
    const PartitionTopology topo = partition_topology(mesh);
    for (int m = 1; m <= 3; ++m)
      for (int n = 1; n <= 3; ++n) {
        INFO("mesh " << t << ", degree " << m << "x" << n);
        const long dim = brute_force(mesh, m, n);
        const ConformalityCount c = conformality_count(topo, m, n);
        REQUIRE(c.dimension == dim);
        if (c.formula) {
          ++diagonalizable;
          REQUIRE(*c.formula == dim);
        } else {
          ++not_diagonalizable;
        }
      }
  }
  // Both branches were exercised (measured: most of these meshes are diagonalizable at
  // degree 1, few at degree 3).
  REQUIRE(diagonalizable > 0);
  REQUIRE(not_diagonalizable > 0);
}

TEST_CASE("On a tensor grid the formula is the tensor-product B-spline count", "[tmesh]") {
  // Cross-cuts only: (m + 1 + interior x lines)(n + 1 + interior y lines).
  const RectangularPartition grid(grid_cells({0, q(1, 3), 1, q(7, 4), 3}, {0, q(2, 5), 1}));
  for (int m = 1; m <= 3; ++m)
    for (int n = 1; n <= 3; ++n) {
      const ConformalityCount c = conformality_count(partition_topology(grid), m, n);
      REQUIRE(c.diagonalizable);
      REQUIRE(c.formula.value() == (m + 1 + 3) * (n + 1 + 1));
      REQUIRE(brute_force(grid, m, n) == (m + 1 + 3) * (n + 1 + 1));
    }
}

TEST_CASE("Across C0 lines too: the cofactor count modulo primes = the brute-force dimension", "[tmesh]") {
  // The PT-splines of a one-patch L-shape are only C0 across the fold u = 1/2, a cross-cut;
  // their certificate uses this count. Random halvings of a 2 x 2 grid (or of a 3 x 2 grid
  // with both interior x lines C0) keep the grid's lines as cross-cuts; a vertex where two C0
  // lines cross carries m n cofactor coefficients.
  std::mt19937 rng(17);
  int with_t_edges = 0;
  for (int t = 0; t < 16; ++t) {
    const bool wide = t % 2 == 1;
    const std::vector<mpq_class> xs = wide ? std::vector<mpq_class>{0, q(1, 3), q(1, 2), 1} : std::vector<mpq_class>{0, q(1, 2), 1};
    C0Lines c0;
    c0.x = {q(1, 2)};
    if (wide) c0.x.push_back(q(1, 3));
    if (t % 4 == 3) c0.y = {q(1, 2)};
    const RectangularPartition mesh(random_halvings(rng, 8 + 2 * t, grid_cells(xs, {0, q(1, 2), 1})));
    const PartitionTopology topo = partition_topology(mesh);
    with_t_edges += topo.count(PartitionTopology::KnotKind::kSegment) > 0;
    for (int m = 1; m <= 3; ++m)
      for (int n = 1; n <= 3; ++n) {
        INFO("mesh " << t << ", degree " << m << "x" << n);
        const long dim = spline_space_dimension(mesh, m, n, m - 1, n - 1, RankMethod::kExact, c0).dimension;
        REQUIRE(conformality_count(topo, m, n, c0, RankMethod::kModular).dimension == dim);
        REQUIRE(conformality_count(topo, m, n, c0, RankMethod::kExact).dimension == dim);
      }
  }
  REQUIRE(with_t_edges >= 8);  // the rows of T l-edges were exercised, not only cross-cuts
  // A tensor grid: a C0 line is a knot of multiplicity m (x) or n (y).
  const RectangularPartition grid(grid_cells({0, q(1, 3), 1, q(7, 4), 3}, {0, q(2, 5), 1}));
  C0Lines fold;
  fold.x = {1};
  fold.y = {q(2, 5)};
  for (int m = 1; m <= 3; ++m)
    for (int n = 1; n <= 3; ++n)
      REQUIRE(conformality_count(partition_topology(grid), m, n, fold, RankMethod::kModular).dimension ==
              (m + 1 + 3 + (m - 1)) * (n + 1 + 1 + (n - 1)));
}
