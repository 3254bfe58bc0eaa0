// The reference PT-spline construction (full extension + elimination of every extended edge),
// checked against the brute-force dimension (a different algorithm: monomials per cell and
// smoothness conditions) and, function by function, against the definition of S(T): each
// function must be one polynomial of bidegree (m, n) on every cell of T, shown by exact
// finite differences of order m + 1 in x and n + 1 in y.
#include <catch2/catch.hpp>

#include <random>

#include "basis/pt/pt_reference.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "cases/case_file.hpp"
#include "tmesh_testing.hpp"

using namespace knotwork;
using knotwork::testing::q;
using knotwork::testing::random_halvings;

namespace {

// Every function of the basis, one polynomial per cell (exact finite differences).
bool polynomial_per_cell(const RectangularPartition& mesh, const TensorCombinationBasis& B) {
  for (int f = 0; f < static_cast<int>(B.functions.size()); ++f)
    if (!testing::polynomial_per_cell(mesh, B.m, B.n, [&](const mpq_class& x, const mpq_class& y) { return evaluate(B, f, x, y); }))
      return false;
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
  REQUIRE(B.functions.size() == 61);  // knotwork dimension's brute force (docs/GUIDE.md)
  REQUIRE(polynomial_per_cell(mesh, B));
  // A tensor grid needs no elimination: every tensor B-spline is a function.
  const RectangularPartition grid({{0, 0, q(1, 2), 1}, {q(1, 2), 0, 1, 1}});
  const TensorCombinationBasis G = pt_full_extension_basis(grid, 2, 2);
  REQUIRE(G.equations == 0);
  REQUIRE(G.functions.size() == 4 * 3);
}
