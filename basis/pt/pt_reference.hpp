#pragma once
#include <gmpxx.h>

#include <utility>
#include <vector>

#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// The reference construction for PT-splines (groundwork for the PT-spline issue): extend
// every edge of the T-mesh to the full tensor mesh of all its x and y coordinates, whose
// spline space S(m, n, m-1, n-1) is the tensor-product B-splines on simple knots, then
// eliminate every extended edge (Extended Edge Elimination with all edges extended): a
// combination of tensor B-splines lies in S(T) exactly when, across each segment of a full
// grid line inside a cell of T, the jump of its m-th x-derivative (vertical lines) or n-th
// y-derivative (horizontal lines) vanishes. The null space of those equations, computed
// over Q, is a basis of S(T). Not local; the minimal-extension construction will be tested
// against it.
struct TensorCombinationBasis {
  int m = 0, n = 0;
  std::vector<mpq_class> knots_x, knots_y;  // open knot vectors with simple interior knots
  int nx = 0, ny = 0;                        // tensor B-splines per direction
  // Each function: (a + nx * b, coefficient) of the tensor B-spline N_a(x) M_b(y).
  std::vector<std::vector<std::pair<int, mpq_class>>> functions;
  long equations = 0, rank = 0;  // of the elimination system
};

// Highest smoothness only (alpha = m - 1, beta = n - 1). Throws std::invalid_argument for
// m or n < 1.
TensorCombinationBasis pt_full_extension_basis(const RectangularPartition& mesh, int m, int n);

// Value of one function of the basis at (x, y) inside the full tensor mesh, exactly.
mpq_class evaluate(const TensorCombinationBasis& basis, int function, const mpq_class& x, const mpq_class& y);

}  // namespace knotwork
