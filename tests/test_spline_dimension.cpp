#include <catch2/catch.hpp>
#include <map>
#include <random>
#include <set>

#include "basis/tmesh/rectangular_partition.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "tmesh_testing.hpp"

using namespace knotwork;
using knotwork::testing::q;

namespace {

// A tensor grid on the given (strictly increasing) breakpoints.
RectangularPartition grid(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys) {
  std::vector<RationalBox> cells;
  for (size_t j = 0; j + 1 < ys.size(); ++j)
    for (size_t i = 0; i + 1 < xs.size(); ++i) cells.push_back({xs[i], ys[j], xs[i + 1], ys[j + 1]});
  return RectangularPartition(cells);
}

std::vector<mpq_class> random_breaks(std::mt19937& rng, int pieces) {
  std::vector<mpq_class> b{0};
  std::uniform_int_distribution<int> step(1, 9), den(1, 7);
  for (int i = 0; i < pieces; ++i) {
    const int d = den(rng), s = step(rng);  // in gcc's order of the former argument list: see below
    b.push_back(b.back() + q(s, d));
  }
  return b;
}

// Random T-mesh: split random cells at random rational positions (guillotine cuts).
std::vector<RationalBox> random_tmesh(std::mt19937& rng, int splits) {
  std::vector<RationalBox> cells{{0, 0, 1, 1}};
  std::uniform_int_distribution<int> frac(1, 4);
  for (int s = 0; s < splits; ++s) {
    const size_t i = std::uniform_int_distribution<size_t>(0, cells.size() - 1)(rng);
    RationalBox c = cells[i], d = c;
    const mpq_class t = q(frac(rng), 5);
    if (rng() % 2) {
      const mpq_class x = c.x0 + t * (c.x1 - c.x0);
      c.x1 = x;
      d.x0 = x;
    } else {
      const mpq_class y = c.y0 + t * (c.y1 - c.y0);
      c.y1 = y;
      d.y0 = y;
    }
    cells[i] = c;
    cells.push_back(d);
  }
  return cells;
}

}  // namespace

TEST_CASE("Tensor grids: the dimension is the tensor-product B-spline count", "[dimension]") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    const int nx = 1 + trial % 4, ny = 1 + (trial / 4) % 3;
    const int m = 1 + trial % 3, n = 1 + (trial / 3) % 3;
    const int alpha = -1 + static_cast<int>(rng() % (m + 1)), beta = -1 + static_cast<int>(rng() % (n + 1));
    // y before x, in separate declarators: argument order is unspecified (gcc: right to left).
    const std::vector<mpq_class> ys = random_breaks(rng, ny), xs = random_breaks(rng, nx);
    const RectangularPartition g = grid(xs, ys);
    // (m+1) + (nx-1)(m-alpha) univariate functions in x, likewise in y.
    const long expected = (m + 1 + (nx - 1L) * (m - alpha)) * (n + 1 + (ny - 1L) * (n - beta));
    INFO("nx " << nx << " ny " << ny << " m " << m << " n " << n << " alpha " << alpha << " beta " << beta);
    REQUIRE(spline_space_dimension(g, m, n, alpha, beta).dimension == expected);
    if (trial % 4 == 0) REQUIRE(spline_space_dimension(g, m, n, alpha, beta, RankMethod::kExact).dimension == expected);
  }
}

TEST_CASE("Modular rank equals the exact rational rank on random T-meshes", "[dimension]") {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 25; ++trial) {
    const RectangularPartition t(random_tmesh(rng, 4 + trial % 9));
    const int m = 1 + trial % 3;
    const auto fast = spline_space_dimension(t, m, m, m - 1, m - 1);
    const auto exact = spline_space_dimension(t, m, m, m - 1, m - 1, RankMethod::kExact);
    REQUIRE(exact.exact);
    REQUIRE(fast.dimension == exact.dimension);
  }
}

TEST_CASE("Modular rank: a breakpoint whose denominator is a multiple of the primes", "[dimension]") {
  // 2^61 - 1 and 2305843009213693921 are the first two primes of the modular rank: a
  // coordinate with that denominator cannot be reduced modulo them, so the next primes are
  // used (this threw before). Expected: the tensor-product count, as above.
  const mpq_class tiny(mpz_class(1), (mpz_class(1) << 61) - 1);
  const mpq_class other(mpz_class(1), mpz_class("2305843009213693921"));
  const RectangularPartition g = grid({0, tiny, q(1, 2), 1}, {0, other, 1});
  for (int m : {1, 2}) {
    INFO("degree " << m);
    REQUIRE(spline_space_dimension(g, m, m, m - 1, m - 1).dimension == (m + 3) * (m + 2));
  }
}

TEST_CASE("Bilinear C0 splines on a T-mesh: one function per crossing or boundary vertex", "[dimension]") {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 30; ++trial) {
    const auto cells = random_tmesh(rng, 3 + trial % 12);
    // Count, independently, the cell corners that are corners of 4 cells (interior
    // crossings) or lie on the outer boundary; T-nodes (corner of 2 cells) carry nothing.
    std::map<std::pair<mpq_class, mpq_class>, int> corner_count;
    for (const auto& c : cells)
      for (const auto& p : {std::pair{c.x0, c.y0}, std::pair{c.x1, c.y0}, std::pair{c.x0, c.y1}, std::pair{c.x1, c.y1}})
        ++corner_count[p];
    long expected = 0;
    for (const auto& [p, count] : corner_count) {
      const bool boundary = p.first == 0 || p.first == 1 || p.second == 0 || p.second == 1;
      if (boundary || count == 4) ++expected;
    }
    REQUIRE(spline_space_dimension(RectangularPartition(cells), 1, 1, 0, 0).dimension == expected);
  }
}

TEST_CASE("Discontinuous and constant limits", "[dimension]") {
  std::mt19937 rng(14);
  const auto cells = random_tmesh(rng, 10);
  const RectangularPartition t(cells);
  // No smoothness: every cell free.
  REQUIRE(spline_space_dimension(t, 2, 3, -1, -1).dimension == 11 * 12);
  // Degree 0 with C^-1 is piecewise constant; bi-degree (m, n) with C^{m-1}, C^{n-1} on one cell.
  REQUIRE(spline_space_dimension(t, 0, 0, -1, -1).dimension == 11);
  REQUIRE(spline_space_dimension(RectangularPartition({{0, 0, 1, 1}}), 3, 2, 2, 1).dimension == 12);
  REQUIRE_THROWS(spline_space_dimension(t, 2, 2, 2, 1));
}

TEST_CASE("Partitions that are not a tiling are refused, naming the cells", "[dimension]") {
  REQUIRE_THROWS_WITH(RectangularPartition({{0, 0, 1, 1}, {q(1, 2), 0, 2, 1}}), Catch::Contains("cells 0") && Catch::Contains("overlap"));
  REQUIRE_THROWS_WITH(RectangularPartition({{0, 0, 1, 1}, {1, 0, 2, q(1, 2)}}), Catch::Contains("gap"));
  REQUIRE_THROWS_WITH(RectangularPartition({{0, 0, 0, 1}}), Catch::Contains("cell 0") && Catch::Contains("zero"));
  REQUIRE(parse_rational("14/9") == q(14, 9));
  REQUIRE(parse_rational("-0.25") == q(-1, 4));
  REQUIRE(parse_rational("3") == 3);
  REQUIRE_THROWS(parse_rational("1/0"));
  REQUIRE_THROWS(parse_rational("abc"));
  REQUIRE_THROWS(parse_rational("1..2"));
}

#include "basis/tmesh/partition_topology.hpp"

TEST_CASE("Partition topology: Euler's formula and T-node bookkeeping on random T-meshes", "[dimension][topology]") {
  std::mt19937 rng(15);
  for (int trial = 0; trial < 60; ++trial) {
    const auto cells = random_tmesh(rng, 1 + trial % 25);
    const PartitionTopology t = partition_topology(RectangularPartition(cells));
    const long V = static_cast<long>(t.vertices.size()), E = static_cast<long>(t.edges.size());
    // Planar graph of a rectangle cut into F cells: V - E + F = 1 (the outer face excluded).
    REQUIRE(V - E + static_cast<long>(cells.size()) == 1);
    // Every interior end of a knot is a T-node, and every T-node ends exactly one knot.
    using K = PartitionTopology::KnotKind;
    REQUIRE(t.t_nodes() == 2 * t.count(K::kSegment) + t.count(K::kRay));
    for (const auto& v : t.vertices) {  // corners and boundary T-nodes; interior T-nodes and crossings
      if (v.boundary) REQUIRE((v.valence == 2 || v.valence == 3));
      else REQUIRE((v.valence == 3 || v.valence == 4));
    }
    REQUIRE(t.interior_vertices() == t.t_nodes() + t.crossings());
  }
}

TEST_CASE("Tensor grids: topology counts and Weller's Prop. 4.2 equal the brute force", "[dimension][topology]") {
  std::mt19937 rng(16);
  for (int nx = 1; nx <= 4; ++nx)
    for (int ny = 1; ny <= 3; ++ny) {
      // y before x, in separate declarators: argument order is unspecified (gcc: right to left).
      const std::vector<mpq_class> ys = random_breaks(rng, ny), xs = random_breaks(rng, nx);
      const RectangularPartition g = grid(xs, ys);
      const PartitionTopology t = partition_topology(g);
      REQUIRE(t.interior_vertices() == (nx - 1) * (ny - 1));
      REQUIRE(t.interior_edges() == (nx - 1) * ny + nx * (ny - 1));
      REQUIRE(t.count(PartitionTopology::KnotKind::kLine) == (nx - 1) + (ny - 1));
      REQUIRE(t.count(PartitionTopology::KnotKind::kRay) == 0);
      for (int d = 1; d <= 3; ++d)
        REQUIRE(weller_dimension_formula(t, d) == spline_space_dimension(g, d, d, d - 1, d - 1).dimension);
    }
}

TEST_CASE("Knot classification on a mesh with a line, a ray and a segment", "[dimension][topology]") {
  // [0,4]^2 cut by the line x = 2, the ray y = 2 from x = 0 to x = 2, and inside [2,4]^2 ...
  // the segment x = 3 between the horizontal rays y = 1 and y = 3 from x = 4.
  const std::vector<RationalBox> cells = {{0, 0, 2, 2}, {0, 2, 2, 4}, {2, 0, 4, 1}, {2, 3, 4, 4},
                                          {2, 1, 3, 3}, {3, 1, 4, 3}};
  const PartitionTopology t = partition_topology(RectangularPartition(cells));
  using K = PartitionTopology::KnotKind;
  REQUIRE(t.count(K::kLine) == 1);     // x = 2
  REQUIRE(t.count(K::kRay) == 3);      // y = 2 (from the left side), y = 1 and y = 3 (from the right side)
  REQUIRE(t.count(K::kSegment) == 1);  // x = 3, between y = 1 and y = 3
  REQUIRE(t.t_nodes() == 5);
  REQUIRE(t.crossings() == 0);
}

TEST_CASE("Weller's formula needs its hypotheses: a short knot segment breaks it", "[dimension][topology]") {
  // 3 x 3 grid on [0,3]^2 plus the segment x = 3/2, 1 <= y <= 2 splitting the centre cell.
  // For d = 2 the segment has 2 vertices < d + 2: no C^1 biquadratic has a jump along it
  // (its jump c(y) (x - 3/2)_+^2 needs a quadratic c with double roots at y = 1 and y = 2),
  // so the dimension stays (3 + 2)^2 = 25, while the formula counts 25 + 3*3 - 5*2 = 24.
  std::vector<RationalBox> cells;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      if (!(i == 1 && j == 1)) cells.push_back({i, j, i + 1, j + 1});
  cells.push_back({1, 1, q(3, 2), 2});
  cells.push_back({q(3, 2), 1, 2, 2});
  const RectangularPartition part(cells);
  const PartitionTopology t = partition_topology(part);
  REQUIRE(t.count(PartitionTopology::KnotKind::kSegment) == 1);
  REQUIRE(spline_space_dimension(part, 2, 2, 1, 1, RankMethod::kExact).dimension == 25);
  REQUIRE(weller_dimension_formula(t, 2) == 24);
}

// A vanished T l-edge carries no extra freedom: inserting it leaves the brute-force dimension
// unchanged; one vertex more than the threshold adds one function (V - (m+1), docs/MATH.md §3).
TEST_CASE("Vanished T l-edges: no extra freedom, one more vertex adds one function", "[dimension][topology]") {
  auto grid_with_segment = [](bool with_segment) {
    std::vector<RationalBox> cells;
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        if (with_segment && j == 1 && (i == 1 || i == 2)) {  // y = 3/2 from x = 1 to x = 3
          cells.push_back({i, 1, i + 1, q(3, 2)});
          cells.push_back({i, q(3, 2), i + 1, 2});
          continue;
        }
        cells.push_back({i, j, i + 1, j + 1});
      }
    return RectangularPartition(cells);
  };
  const RectangularPartition plain = grid_with_segment(false), refined = grid_with_segment(true);
  const PartitionTopology topo = partition_topology(refined);
  REQUIRE(topo.count(PartitionTopology::KnotKind::kSegment) == 1);  // 3 vertices: x = 1, 2, 3
  for (int m = 1; m <= 3; ++m) {
    const long before = spline_space_dimension(plain, m, m, m - 1, m - 1).dimension;
    const long after = spline_space_dimension(refined, m, m, m - 1, m - 1).dimension;
    INFO("degree " << m << ": " << before << " -> " << after);
    if (m >= 2) {
      REQUIRE(topo.vanished_segments(m, m) == 1);
      REQUIRE(after == before);
    } else {
      REQUIRE(topo.vanished_segments(m, m) == 0);
      REQUIRE(after == before + 1);
    }
  }
}

// A C0 knot line of a tensor grid is a knot of multiplicity m: the tensor count with it.
TEST_CASE("Brute-force dimension with C0 lines: the tensor count with full-multiplicity knots", "[dimension]") {
  std::vector<RationalBox> cells;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 4; ++i) cells.push_back({i, j, i + 1, j + 1});
  const RectangularPartition grid(cells);
  for (int m = 1; m <= 3; ++m)
    for (int n = 1; n <= 3; ++n) {
      INFO("degree " << m << "x" << n);
      // x: 3 interior lines, x = 2 of multiplicity m; y: 2 interior lines, y = 1 of multiplicity n.
      const long x_functions = (2 + m) + m + 1, y_functions = (1 + n) + n + 1;
      REQUIRE(spline_space_dimension(grid, m, n, m - 1, n - 1, RankMethod::kModular, C0Lines{{2}, {1}}).dimension ==
              x_functions * y_functions);
      REQUIRE(spline_space_dimension(grid, m, n, m - 1, n - 1, RankMethod::kModular, C0Lines{{2}, {}}).dimension ==
              x_functions * (2 + n + 1));
    }
}
