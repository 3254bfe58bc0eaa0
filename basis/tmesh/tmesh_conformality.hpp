#pragma once
#include <optional>

#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"

namespace knotwork {

// The dimension of S(m, n, m-1, n-1) over a T-mesh by the smoothing cofactor-conformality
// method (Li, arXiv:1210.5312), independent of the brute-force count on cell polynomials.
// A spline is a global polynomial plus, across every l-edge, a jump (x - x0)^m c(y)
// (vertical) or (y - y0)^n c(x) (horizontal) whose cofactor c is a univariate spline of
// degree n (resp. m) and highest smoothness with knots at the vertices of the l-edge:
// one free coefficient lambda_v per interior vertex, shared by the two lines through it,
// plus a free polynomial part (deg+1 coefficients) on every cross-cut. A ray's cofactor
// starts at its interior end and needs nothing more; a T l-edge's must vanish beyond both
// ends: sum_v lambda_v t_v^j = 0 for j = 0..deg over its vertices (t = the coordinate
// along it). Hence
//   dim = (m+1)(n+1) + sum_cross-cuts (deg+1) + #interior vertices - rank(M)
// with M those moment rows. dim is not topological because rank(M) depends on the
// coordinates: that is dimensional instability.
// Across the lines of `c0` (cross-cuts) the space is only C^0: the jump there is (x - x0) A
// with A of bi-degree (m - 1, n), so a vertex on such a line carries m (or n; m n where two
// meet) cofactor coefficients instead of one, and the cross-cut m (n + 1) free ones.
// `method`: the rank of M over Q (kExact), or modulo two primes (kModular, falling back to Q
// when they disagree; rank mod p <= rank over Q, so the dimension is then an upper bound that
// is exact unless both primes divide a minor). Modular is fast enough for 10^5 cells.
struct ConformalityCount {
  long tensor_part = 0;          // (m+1)(n+1) + sum over cross-cuts of (deg+1)
  long interior_vertices = 0;    // cofactor coefficients: one per interior vertex without C0 lines
  long conformality_rows = 0;    // sum over T l-edges of (deg+1)
  long conformality_rank = 0;    // over Q, or modulo primes (see `method`)
  long dimension = 0;            // tensor_part + interior_vertices - conformality_rank
  // Diagonalizable here means: the T l-edges can be ordered l_1, ..., l_k so that every
  // l~_i (l_i without its intersections with l_1..l_{i-1}) keeps at least deg+1 vertices.
  // M is then block lower triangular with Vandermonde diagonal blocks of full row rank, so
  // rank(M) = conformality_rows and the dimension depends on the topology alone:
  // `formula` = tensor_part + interior_vertices - conformality_rows (without C0 lines).
  // Otherwise nullopt.
  // (Li's own characterization of diagonalizable T-meshes is necessary and sufficient;
  // this ordering test is a sufficient condition, checked greedily from the last l-edge.)
  bool diagonalizable = false;
  std::optional<long> formula;
};

ConformalityCount conformality_count(const PartitionTopology& topology, int m, int n, const C0Lines& c0 = {},
                                     RankMethod method = RankMethod::kExact);

// The ordering test of ConformalityCount::diagonalizable alone (no rank): whether the T
// l-edges can be ordered so that each keeps deg+1 vertices off the earlier ones.
bool diagonalizable_by_ordering(const PartitionTopology& topology, int m, int n);

}  // namespace knotwork
