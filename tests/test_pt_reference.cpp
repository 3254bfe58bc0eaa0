// The reference PT-spline construction (full extension + elimination of every extended edge),
// checked against the brute-force dimension (a different algorithm: monomials per cell and
// smoothness conditions) and, function by function, against the definition of S(T): each
// function must be one polynomial of bidegree (m, n) on every cell of T, shown by exact
// finite differences of order m + 1 in x and n + 1 in y.
#include <catch2/catch.hpp>

#include <random>

#include "basis/pt_reference.hpp"
#include "basis/spline_dimension.hpp"
#include "cases/case_file.hpp"

using namespace knotwork;

namespace {

mpq_class q(long a, long b = 1) {
  mpq_class r(a, b);
  r.canonicalize();
  return r;
}

// Random hierarchical-style T-meshes: random cells of [0, 1]^2 split in halves, in x or y.
std::vector<RationalBox> random_halvings(std::mt19937& rng, int splits) {
  std::vector<RationalBox> cells{{0, 0, 1, 1}};
  for (int s = 0; s < splits; ++s) {
    const size_t i = std::uniform_int_distribution<size_t>(0, cells.size() - 1)(rng);
    RationalBox a = cells[i], b = a;
    if (rng() % 2) {
      a.x1 = b.x0 = (a.x0 + a.x1) / 2;
    } else {
      a.y1 = b.y0 = (a.y0 + a.y1) / 2;
    }
    cells[i] = a;
    cells.push_back(b);
  }
  return cells;
}

// Largest |finite difference| of order m + 1 along x (and n + 1 along y) of every function
// on equispaced points inside every cell: zero exactly when it is one polynomial there.
bool polynomial_per_cell(const RectangularPartition& mesh, const TensorCombinationBasis& B) {
  for (int f = 0; f < static_cast<int>(B.functions.size()); ++f)
    for (const auto& c : mesh.cells())
      for (int dir = 0; dir < 2; ++dir) {
        const int order = dir == 0 ? B.m + 1 : B.n + 1;
        const int other = dir == 0 ? B.n + 1 : B.m + 1;
        for (int line = 0; line <= other; ++line) {
          std::vector<mpq_class> v;
          for (int i = 0; i <= order; ++i) {
            const mpq_class s = mpq_class(i + 1, order + 2), t = mpq_class(line + 1, other + 2);
            const mpq_class x = c.x0 + (dir == 0 ? s : t) * (c.x1 - c.x0);
            const mpq_class y = c.y0 + (dir == 0 ? t : s) * (c.y1 - c.y0);
            v.push_back(evaluate(B, f, x, y));
          }
          for (int k = 0; k < order; ++k)
            for (int i = 0; i + 1 < static_cast<int>(v.size()) - k; ++i) v[i] = v[i + 1] - v[i];
          if (v[0] != 0) return false;
        }
      }
  return true;
}

}  // namespace

TEST_CASE("Full-extension PT basis: count = brute-force dimension, every function in S(T)", "[pt][dimension]") {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 12; ++trial) {
    const RectangularPartition mesh(random_halvings(rng, 3 + trial % 6));
    for (const auto& [m, n] : {std::pair{1, 1}, std::pair{2, 2}, std::pair{3, 2}}) {
      const TensorCombinationBasis B = pt_full_extension_basis(mesh, m, n);
      const DimensionResult d = spline_space_dimension(mesh, m, n, m - 1, n - 1);
      INFO("trial " << trial << ", " << mesh.num_cells() << " cells, degree " << m << "," << n);
      REQUIRE(static_cast<long>(B.functions.size()) == d.dimension);
      REQUIRE(polynomial_per_cell(mesh, B));
    }
  }
}

TEST_CASE("Full-extension PT basis on the shipped hierarchical T-mesh: 61 bicubic functions", "[pt][dimension]") {
  const PartitionDescription p = load_partition(std::string(KNOTWORK_SOURCE_DIR) + "/cases/tmeshes/hierarchical.toml");
  const RectangularPartition mesh(p.cells);
  const TensorCombinationBasis B = pt_full_extension_basis(mesh, 3, 3);
  REQUIRE(B.functions.size() == 61);  // knotwork dimension's brute force (README)
  REQUIRE(polynomial_per_cell(mesh, B));
  // A tensor grid needs no elimination: every tensor B-spline is a function.
  const RectangularPartition grid({{0, 0, q(1, 2), 1}, {q(1, 2), 0, 1, 1}});
  const TensorCombinationBasis G = pt_full_extension_basis(grid, 2, 2);
  REQUIRE(G.equations == 0);
  REQUIRE(G.functions.size() == 4 * 3);
}
